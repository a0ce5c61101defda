"""A parameter keeps one name from the protocol to the method: the walk of the tabu radius of
novelty-ts, the campaign setting a protocol arm, train.launch, the CLI and the method all carry.

The walk reads the code (Python, launch files, shell scripts; not tests, docs, results or the
protocol files, which are the data the walk starts from): in Python every string constant that is
a setting's name or option (`"tabu_m"`, `"--tabu-m"`), every keyword and parameter name; in launch
files every `<arg name=...>` and option in an expression; in shell every `NAME:=` and `--option`.
An option is read as its setting (`--tabu-m` is `tabu_m`). What it finds must be one name in at
most six files."""

import ast
import glob
import os
import re

REPO = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
OPTION = re.compile(r"(?<![\w-])--(tabu[\w-]*)|\b(tabu\w*):=|<arg name=\"(tabu\w*)\"")


def _setting(s: str) -> str:
    return s.lstrip("-").replace("-", "_")


def spellings(path: str, stem: str = "tabu") -> set:
    """The setting names a file spells (see the module's docstring)."""
    text = open(path, encoding="utf-8", errors="replace").read()
    if not path.endswith(".py"):
        return {_setting(next(g for g in m.groups() if g)) for m in OPTION.finditer(text)}
    out = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            if re.fullmatch(rf"(--)?{stem}[\w-]*", node.value):
                out.add(_setting(node.value))
            out |= {m.group(1) for m in re.finditer(rf"\b({stem}\w*):=", node.value)}
        elif isinstance(node, ast.keyword) and node.arg and node.arg.startswith(stem):
            out.add(node.arg)
        elif isinstance(node, ast.arg) and node.arg.startswith(stem):
            out.add(node.arg)
    return out


def code_files(root: str = REPO):
    pats = ["catkin_ws/src/*/src/**/*.py", "catkin_ws/src/*/nodes/*", "launch/*.launch", "scripts/**/*.sh"]
    pats += ["catkin_ws/src/*/launch/*.launch", "scripts/**/*.py"]
    seen = set()
    for pat in pats:
        for p in sorted(glob.glob(os.path.join(root, pat), recursive=True)):
            if os.path.isfile(p) and os.path.realpath(p) not in seen:  # launch/ is asg_bringup's, linked
                seen.add(os.path.realpath(p))
                yield p


def walk(root: str = REPO, stem: str = "tabu") -> dict:
    """{file (relative): the names it spells} for every code file that spells one."""
    out = {}
    for p in code_files(root):
        names = spellings(p, stem)
        if names:
            out[os.path.relpath(p, root)] = names
    return out


def test_the_tabu_radius_has_one_name_in_at_most_six_files(tmp_path):
    w = walk()
    names = set().union(*w.values())
    assert names == {"tabu_m"}, w
    assert len(w) <= 6, sorted(w)
    # the walk sees a second name (the mutation): a launch file and a script that spell it otherwise
    (tmp_path / "launch").mkdir()
    (tmp_path / "scripts").mkdir()
    (tmp_path / "launch" / "t.launch").write_text('<arg name="tabu" default="2" />\n')
    (tmp_path / "scripts" / "t.sh").write_text("roslaunch x t.launch tabu_radius:=2 --tabu-m 3\n")
    (tmp_path / "scripts" / "t.py").write_text('f(tabu_m=2)\nsettings["tabu"] = 1\n')
    assert walk(str(tmp_path)) == {
        os.path.join("launch", "t.launch"): {"tabu"},
        os.path.join("scripts", "t.py"): {"tabu", "tabu_m"},
        os.path.join("scripts", "t.sh"): {"tabu_radius", "tabu_m"},
    }

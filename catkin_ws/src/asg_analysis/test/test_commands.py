"""The one way into the analysis (asg_analysis.commands): its table is the package's commands, no
module has an entry point of its own, and `python3 -m asg_analysis` dispatches, lists and refuses."""

import ast
import glob
import os
import subprocess
import sys

from asg_analysis import commands

PKG = os.path.join(os.path.dirname(os.path.abspath(commands.__file__)))


def entry_points(root=PKG):
    """{module (under asg_analysis): (has run, has main, has a __main__ block)} read from the source."""
    out = {}
    for path in sorted(glob.glob(os.path.join(root, "*.py")) + glob.glob(os.path.join(root, "studies", "*.py"))):
        rel = os.path.relpath(path, root)[:-3].replace(os.sep, ".")
        if rel in ("__main__", "commands") or rel.endswith("__init__"):
            continue
        tree = ast.parse(open(path, encoding="utf-8").read())
        top = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
        guard = any(isinstance(n, ast.If) and "__main__" in ast.unparse(n.test) for n in tree.body)
        out[rel] = ("run" in top, "main" in top, guard)
    return out


def problems(root=PKG, table=None):
    table = commands.COMMANDS if table is None else table
    listed = {m for m, _ in table.values()}
    out = []
    for mod, (run, main, guard) in entry_points(root).items():
        if main or guard:
            out.append(f"{mod}: an entry point of its own (main() or a __main__ block)")
        if run and mod not in listed:
            out.append(f"{mod}: run() but not in asg_analysis.commands")
    out += [f"{m}: listed but has no run()" for m in sorted(listed) if not entry_points(root).get(m, (False,))[0]]
    out += [f"{n}: not its module's name" for n, (m, _) in table.items() if n != m.split(".")[-1].replace("_", "-")]
    return out


def test_the_table_is_the_package_s_commands(tmp_path):
    assert problems() == []
    # the check sees each kind of slip (mutations in a copy of a package)
    (tmp_path / "studies").mkdir()
    (tmp_path / "a.py").write_text("def run(argv=None):\n    return 0\n")
    (tmp_path / "studies" / "b.py").write_text("def main(argv=None):\n    return 0\n")
    (tmp_path / "c.py").write_text("import sys\nif __name__ == '__main__':\n    sys.exit(0)\n")
    table = {"a": ("a", ""), "d": ("d", ""), "e": ("c", "")}
    assert problems(str(tmp_path), table) == [
        "c: an entry point of its own (main() or a __main__ block)",
        "studies.b: an entry point of its own (main() or a __main__ block)",
        "c: listed but has no run()",
        "d: listed but has no run()",
        "e: not its module's name",
    ]


def test_the_entry_point_lists_dispatches_and_refuses():
    def py(*args):
        return subprocess.run([sys.executable, "-m", "asg_analysis", *args], capture_output=True, text=True)

    r = py("--help")
    assert r.returncode == 0 and all(f"  {n} " in r.stdout for n in commands.COMMANDS), r.stdout
    r = py("nope")
    assert r.returncode == 2 and "no command 'nope'" in r.stderr
    r = py("study", "--help")
    assert r.returncode == 0 and r.stdout.startswith("usage: python3 -m asg_analysis study")
    assert commands.call("stats", ["--help"]) == 0
    assert py().returncode == 2  # no command: the list, and a usage error

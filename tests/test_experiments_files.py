"""Issue #94 item 4: experiments/ as bases with overrides. A file names its base(s) (`base:`) and
overrides their keys (asg_agent.records.experiment.effective); each file is its base updated by its
own keys, a cycle or a missing base is refused naming the file, a campaign stores the effective
experiment, and every file of experiments/ is used by something else of the repository."""

import functools
import glob
import os
import re
import sys

import pytest
import yaml

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
for _pkg in ("asg_agent", "asg_perception", "asg_scenario"):
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", _pkg, "src"))
from asg_agent.records.experiment import ExperimentError, effective, load_experiment  # noqa: E402

EXPERIMENTS = os.path.join(REPO, "experiments")
#: experiment files (a study's protocol-*.yaml and study-*.yaml beside them are not)
FILES = sorted(
    p
    for p in glob.glob(os.path.join(EXPERIMENTS, "*.yaml"))
    if not os.path.basename(p).startswith(("protocol-", "study-"))
)
SCENARIO = os.path.join(REPO, "scenarios", "exp1.yaml")


def own(path) -> dict:
    with open(path, encoding="utf-8") as f:
        return yaml.safe_load(f)


def test_every_file_is_its_base_updated_by_its_own_keys():
    composed = [p for p in FILES if "base" in own(p)]
    assert len(composed) >= 20 and len(FILES) - len(composed) >= 6
    for path in FILES:
        mine = own(path)
        want = {}
        for name in [mine["base"]] if isinstance(mine.get("base"), str) else mine.get("base", []):
            want.update(effective(os.path.join(EXPERIMENTS, name)))
        for k, v in mine.items():
            if k == "base":
                continue
            assert k == "name" or want.get(k) != v, f"{os.path.basename(path)}: {k} repeats its base's value"
            want[k] = {**want[k], **v} if isinstance(v, dict) and isinstance(want.get(k), dict) else v
        assert effective(path) == want, path
        assert want["name"] == os.path.basename(path)[: -len(".yaml")]
        # what a campaign stores: the file as read, or the effective mapping of a file with a base
        exp = load_experiment(path)
        if "base" in mine:
            assert yaml.safe_load(exp.text) == want
        else:
            assert exp.text == open(path, encoding="utf-8").read()


def test_files_given_to_an_older_trees_loader_have_no_base():
    # scripts/repro/bench_before_after.sh runs its EXPERIMENT on the tree of an older commit too,
    # whose loader knows no `base`: the files its recipes name stay whole
    texts = [
        open(p, encoding="utf-8").read() for p in glob.glob(os.path.join(REPO, "docs", "**", "*.md"), recursive=True)
    ]
    script = open(os.path.join(REPO, "scripts", "repro", "bench_before_after.sh"), encoding="utf-8").read()
    named = {
        m for t in texts + [script] for m in re.findall(r"bench_before_after\.sh [^\n]*?experiments/([\w.-]+\.yaml)", t)
    }
    named |= set(re.findall(r"\$\{5:-\$REPO/experiments/([\w.-]+\.yaml)\}", script))
    assert {"exp1-channels-last.yaml", "exp1-gt.yaml"} <= named
    for name in named:
        assert "base" not in own(os.path.join(EXPERIMENTS, name)), name


def write(folder, name, text):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(text)
    return str(folder / name)


def test_a_base_is_merged_key_by_key_and_replaced_elsewhere(tmp_path):
    write(
        tmp_path,
        "a.yaml",
        f"name: a\nscenario: {SCENARIO}\nepisode_steps: 4\n"
        "textural_free: {fog_visibility_m: [25.0, 500.0], cloud_cover: [0.0, 1.0]}\n",
    )
    write(tmp_path, "b.yaml", "base: a.yaml\nname: b\nepisode_steps: 3\n")
    c = write(tmp_path, "c.yaml", "base: [a.yaml, b.yaml]\nname: c\ntextural_free: {cloud_cover: [0.5, 1.0]}\n")
    got = effective(c)
    assert got == {
        "name": "c",
        "scenario": SCENARIO,
        "episode_steps": 3,  # b's, applied after a's
        "textural_free": {"fog_visibility_m": [25.0, 500.0], "cloud_cover": [0.5, 1.0]},
    }
    exp = load_experiment(c)
    assert (exp.name, exp.episode_steps, exp.textural_free) == (
        "c",
        3,
        [("fog_visibility_m", 25.0, 500.0), ("cloud_cover", 0.5, 1.0)],
    )
    # the campaign stores the effective experiment, headed by the files it came from
    assert exp.text.startswith("# c.yaml over its bases (a.yaml, b.yaml)") and yaml.safe_load(exp.text) == got
    # the same experiment written out whole loads the same
    whole = write(tmp_path, "whole.yaml", exp.text)
    assert {k: v for k, v in vars(load_experiment(whole)).items() if k not in ("text", "source")} == {
        k: v for k, v in vars(exp).items() if k not in ("text", "source")
    }


def test_a_base_in_another_folder_keeps_its_relative_paths(tmp_path):
    rel = os.path.relpath(SCENARIO, tmp_path / "bases")
    write(tmp_path / "bases", "a.yaml", f"name: a\nscenario: {rel}\nstack: s.launch\n")
    b = write(tmp_path / "mine", "b.yaml", "base: ../bases/a.yaml\nname: b\n")
    got = effective(b)
    assert os.path.normpath(os.path.join(tmp_path / "mine", got["scenario"])) == SCENARIO
    assert got["stack"] == "../bases/s.launch"
    write(tmp_path / "bases", "n.yaml", f"name: n\nscenario: {SCENARIO}\nstack: depth\n")
    assert effective(write(tmp_path / "mine", "m.yaml", "base: ../bases/n.yaml\n"))["stack"] == "depth"


def test_a_cycle_or_a_missing_base_is_refused_naming_the_file(tmp_path):
    a = write(tmp_path, "a.yaml", "base: b.yaml\nname: a\n")
    write(tmp_path, "b.yaml", "base: a.yaml\nname: b\n")
    with pytest.raises(ExperimentError, match=re.escape(r"a cycle of bases (a.yaml -> b.yaml -> a.yaml)")):
        load_experiment(a)
    me = write(tmp_path, "me.yaml", "base: [me.yaml]\nname: me\n")
    with pytest.raises(ExperimentError, match=re.escape(f"{me}: base me.yaml: a cycle of bases (me.yaml -> me.yaml)")):
        effective(me)
    gone = write(tmp_path, "gone.yaml", "base: nowhere.yaml\nname: gone\n")
    with pytest.raises(ExperimentError, match=re.escape(f"{gone}: base nowhere.yaml: no such file")):
        load_experiment(gone)
    for bad in ("[]", "5", "''", "{a: 1}", "[a.yaml, 3]", "null"):
        p = write(tmp_path, "bad.yaml", f"base: {bad}\nname: bad\n")
        with pytest.raises(ExperimentError, match=re.escape(f"{p}: base: ")):
            load_experiment(p)
    # a diamond is no cycle: two bases of one base
    write(tmp_path, "root.yaml", f"name: root\nscenario: {SCENARIO}\n")
    write(tmp_path, "l.yaml", "base: root.yaml\nepisode_steps: 2\n")
    write(tmp_path, "r.yaml", "base: root.yaml\nepisode_steps: 3\n")
    d = write(tmp_path, "d.yaml", "base: [l.yaml, r.yaml]\nname: d\n")
    assert load_experiment(d).episode_steps == 3
    assert load_experiment(d).text.startswith("# d.yaml over its bases (root.yaml, l.yaml, r.yaml)")


#: where a file of experiments/ may be used, and the kinds of file read there (results/: plans and manifests)
PLACES = {
    "experiments": (".yaml",),
    "launch": (".launch", ".xml"),
    "stacks": (".launch",),
    "scripts": (".sh", ".py", ".cmake"),
    "tests": (".py", ".test", ".yaml", ".sh"),
    "docs": (".md", ".json", ".yaml"),
    os.path.join("catkin_ws", "src"): (".py", ".launch", ".test", ".yaml", ".sh"),
    "results": (".txt", ".yaml", ".md"),
}


@functools.lru_cache(maxsize=1)
def corpus() -> dict:
    """{path: text} of every file where a file of experiments/ may be named (not this test's own),
    with each brace list (`protocol-distinct-v4-{exp3,exp6}.yaml`) written out as well."""
    out = {os.path.join(REPO, "README.md"): open(os.path.join(REPO, "README.md"), encoding="utf-8").read()}
    for place, exts in PLACES.items():
        for folder, dirs, files in os.walk(os.path.join(REPO, place)):  # not into linked folders
            dirs[:] = [d for d in dirs if d not in ("build", "devel", "__pycache__")]
            for f in files:
                path = os.path.join(folder, f)
                if f.endswith(exts) and path != os.path.realpath(__file__):
                    with open(path, encoding="utf-8", errors="replace") as fh:
                        text = fh.read()
                    for pre, alts, post in re.findall(r"([\w.-]*)\{([\w.,-]+)\}([\w.-]*)", text):
                        text += "\n" + " ".join(pre + a + post for a in alts.split(","))
                    out[path] = text
    return out


def named(name: str, text: str) -> bool:
    """Whether `text` names the file experiments/`name` (by itself, or as experiments/NAME; not
    scenarios/NAME)."""
    for m in re.finditer(rf"(?<![\w.-]){re.escape(name)}(?!\.?[\w-])", text):
        if text[m.start() - 1 : m.start()] != "/" or text[: m.start()].endswith("experiments/"):
            return True
    return False


def unused(names) -> list:
    """The files of experiments/ among `names` that no other file names; a protocol or study file
    whose own header names the command that runs it is used (it is where a study starts)."""
    out = []
    for name in names:
        path = os.path.join(EXPERIMENTS, name)
        if any(named(name, t) for p, t in corpus().items() if p != path):
            continue
        mine = corpus().get(path, "")
        if name.startswith(("protocol-", "study-")) and re.search(
            rf"python3 -m [\w.]+ \w+ experiments/{re.escape(name)}", mine
        ):
            continue
        out.append(name)
    return out


def test_every_file_of_experiments_is_used():
    names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(EXPERIMENTS, "*.yaml")))
    assert len(names) >= 50
    assert unused(names) == []
    # the check finds a file nothing names, and reads no scenario file's name as an experiment's
    assert unused(["exp1-nobody.yaml"]) == ["exp1-nobody.yaml"]
    assert not named("exp1.yaml", "scenario: ../scenarios/exp1.yaml") and named("exp1.yaml", "base: exp1.yaml")
    assert named("exp1.yaml", "experiment:=$(find asg_bringup)/experiments/exp1.yaml")
    assert not named("exp1-depth-rc.yaml", "exp1-depth-rc.yaml.bak") and not named("exp1.yaml", "myexp1.yaml")

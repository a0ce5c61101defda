"""docs/your-stack.md's commands fit together as written (issue #95 item 6), read without ROS:
each section's commands ask only for the workers that section launched, every experiment a command
names exists and the section says its action space, an experiment the page writes states one, and
the gap_nav commands beside today's figure run the experiment that figure was measured with.
(The commands themselves run in tests/your_stack.test, tests/registered_stacks.test and
tests/test_your_stack_recipe.py.)"""

import os
import re
import shlex
import sys

import yaml

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for _pkg in ("asg_agent", "asg_perception", "asg_scenario"):  # the experiment loader (no ROS)
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", _pkg, "src"))
from asg_agent.records.experiment import effective  # noqa: E402

DOC = os.path.join(REPO, "docs", "your-stack.md")


def sections(text=None):
    """{heading: (its prose, its bash commands, continuation lines joined)}."""
    text = text if text is not None else open(DOC, encoding="utf-8").read()
    out = {}
    for part in re.split(r"\n(?=## )", text):
        head = part.split("\n", 1)[0]
        blocks = re.findall(r"```bash\n(.*?)```", part, re.S)
        cmds = [" ".join(line.split()) for b in blocks for line in b.replace("\\\n", " ").splitlines() if line.strip()]
        prose = re.sub(r"```.*?```", "", part, flags=re.S)
        out[head] = (prose, cmds)
    return out


def launched_workers(cmds):
    """The worker namespaces a section's commands start (worker.launch's ns, default worker_0)."""
    out = set()
    for c in cmds:
        if "worker.launch" in c and c.split()[0] == "roslaunch":
            m = re.search(r"\bns:=(\S+)", c)
            out.add(m.group(1) if m else "worker_0")
    return out


def asked_workers(cmd):
    words = shlex.split(cmd.split(" #")[0])
    if "--workers" not in words:
        return set()
    w = words[words.index("--workers") + 1]
    return {f"worker_{i}" for i in range(int(w))} if w.isdigit() else {x.strip("/") for x in w.split(",")}


def experiments_named(cmd):
    return [os.path.join(REPO, m) for m in re.findall(r"(experiments/[\w.-]+\.yaml)", cmd)]


def problems(text=None):
    found = []
    for head, (prose, cmds) in sections(text).items():
        have = launched_workers(cmds)
        for c in cmds:
            if re.match(r"(/usr/bin/)?python3 -m asg_agent\.cli\.(campaign|baseline)", c):
                missing = asked_workers(c) - have
                if missing and have:
                    found.append(
                        f"{head}: `{c[:60]}...` asks for {sorted(missing)}; the section launched {sorted(have)}"
                    )
            for path in experiments_named(c):
                if not os.path.isfile(path):
                    found.append(f"{head}: {os.path.relpath(path, REPO)} does not exist")
                    continue
                space = effective(path).get("action_space", "absolute")  # a file with a base: its effective keys
                if f"`{space}`" not in prose:
                    found.append(
                        f"{head}: {os.path.relpath(path, REPO)} runs the `{space}` action space; the section does not say so"
                    )
            if c.startswith("printf") and "exp1-my-stack" in c and "action_space:" not in c:
                found.append(f"{head}: the experiment it writes states no action_space")
    return found


def test_the_pages_commands_fit_together():
    assert problems() == []


def test_the_checks_see_each_kind_of_mismatch():
    text = open(DOC, encoding="utf-8").read()
    # the states the issue found: two workers asked after one launched; gap_nav's absolute experiment
    one = text.replace("roslaunch asg_bringup worker.launch ns:=worker_1 stack:=depth &\n", "")
    assert any("asks for ['worker_1']" in p for p in problems(one))
    quiet = text.replace("in the `route-wide` action space\n(`experiments/exp1-gap-nav-route-wide.yaml`", "(`x`")
    assert any("exp1-gap-nav-route-wide.yaml runs the `route-wide`" in p for p in problems(quiet)), problems(quiet)
    bare = text.replace("\\naction_space: route-wide\\nroute_lateral_m: 10.0", "")
    assert any("states no action_space" in p for p in problems(bare))


def test_gap_nav_runs_the_experiment_of_todays_figure():
    proto = yaml.safe_load(open(os.path.join(REPO, "experiments", "protocol-distinct-v4-gapnav.yaml")))
    measured = proto["arms"]["default"]["experiment"]
    (prose, cmds) = next(v for k, v in sections().items() if "gap_nav" in k and "ordinary" in k)
    train = [c for c in cmds if c.startswith("bash scripts/train.sh")]
    assert train and all(measured in c for c in train), (measured, train)
    assert "Today's default on gap_nav" in prose

"""Issue #68 item 2: `roslaunch launch/train.launch experiment:=FILE` takes the stack under test
from the experiment or refuses before any node starts, naming the argument. roslaunch runs the
launch file's check (a param's command: `rosrun asg_agent launch_check`) while it reads the file,
so `--dump-params` (no master, no node) shows what a real launch would do first."""

import os
import subprocess

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
LAUNCH = os.path.join(REPO, "launch", "train.launch")


def dump(*args):
    env = dict(os.environ, ROS_HOSTNAME="127.0.0.1", ROS_MASTER_URI="http://127.0.0.1:1")  # no master is needed
    return subprocess.run(
        ["roslaunch", "--dump-params", LAUNCH, *args], capture_output=True, text=True, timeout=120, env=env
    )


def test_an_experiment_of_another_stack_is_refused_naming_the_argument():
    exp = os.path.join(REPO, "experiments", "exp1-gt.yaml")  # perception: ground_truth
    r = dump(f"experiment:={exp}")
    out = r.stdout + r.stderr
    assert "perception:=ground_truth is the experiment's, the launch has perception:=unet" in out, out
    assert "Cannot load command parameter [asg_launch_check]" in out
    assert "/worker_0/" not in r.stdout  # nothing of the workers was read: the file was refused
    # the argument it names makes it launch
    ok = dump(f"experiment:={exp}", "perception:=ground_truth")
    assert "asg_launch_check: 'ok" in ok.stdout and "/worker_0/" in ok.stdout, ok.stdout + ok.stderr


def test_a_bf16_experiment_without_its_backend_is_refused_naming_unet_backend():
    # the usage the launch file documents, with the bf16 fast mode's experiment
    r = dump(f"experiment:={os.path.join(REPO, 'experiments', 'exp1-bf16.yaml')}")
    out = r.stdout + r.stderr
    assert "unet_backend:=bf16 is the experiment's, the launch has unet_backend:=(empty: polyphase)" in out, out
    assert "/worker_0/" not in r.stdout


def test_the_default_experiment_launches_as_it_is():
    r = dump()
    assert "asg_launch_check: 'ok" in r.stdout and "/worker_0/" in r.stdout, r.stdout + r.stderr


def test_the_pages_train_launch_commands_pass_the_check():
    """Each `roslaunch ... train.launch ...` of the README's and docs/' bash blocks, as written
    ($PWD: the repository; commands with other shell variables left out), passes the launch check:
    the gap_nav spread command lost it when the default experiment became exp1-route-wide.yaml."""
    import glob
    import re

    pages = [os.path.join(REPO, "README.md")] + sorted(glob.glob(os.path.join(REPO, "docs", "*.md")))
    commands = []
    for page in pages:
        for block in re.findall(r"```bash\n(.*?)```", open(page, encoding="utf-8").read(), re.S):
            for line in block.replace("\\\n", " ").splitlines():
                if re.search(r"roslaunch (\S+ )?\S*train\.launch", line):
                    words = line.split("train.launch", 1)[1].split("&")[0].split("#")[0].split()
                    args = [w.replace("$PWD", REPO) for w in words if ":=" in w]
                    if not any("$" in a for a in args):
                        commands.append((os.path.basename(page), args))
    assert any("stack:=gap_nav" in args for _, args in commands), commands
    for page, args in commands:
        r = dump(*args)
        assert "asg_launch_check: 'ok" in r.stdout, (page, args, (r.stdout + r.stderr)[-800:])

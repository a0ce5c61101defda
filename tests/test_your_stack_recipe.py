"""Issue #68 item 1: a new user's commands work as docs/your-stack.md writes them. Steps 4-8 of
its install-space recipe run on a sim-time master, from the install space that
scripts/ci/check_install.py made, with a user's free-running stack (gap_nav copied and renamed
my_stack): the page's own commands (tests/doc_recipe.py), only the sizes and the job placeholder
changed, through scripts/repro/your_stack_install.sh."""

import os
import subprocess
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "tests"))

import doc_recipe  # noqa: E402


def page():
    with open(doc_recipe.DOC, encoding="utf-8") as f:
        return f.read()


def test_the_script_runs_the_pages_commands_with_only_the_named_words_changed():
    steps = doc_recipe.step_blocks(page())
    script = doc_recipe.script(page(), layouts=2, scenarios=4)
    for s in doc_recipe.STEPS:
        for line in steps[s]:
            changed = line.replace("--layouts 300", "--layouts 2").replace("scenarios:=150", "scenarios:=4")
            changed = changed.replace(" JOB ", " 0 ")
            assert changed in script, (s, line)
    # step 4 starts the worker on simulated time, step 7 the campaign; the page's run_scenario is there
    assert "worker.launch stack:=$REG sim_time:=true & BG+=($!)" in script
    assert "rosrun asg_scenario run_scenario" in script and "train.launch stack:=$REG sim_time:=true" in script
    # the campaign step 8 reads is the one step 7 makes: train.launch's default method names it
    launch = open(os.path.join(REPO, "launch", "train.launch"), encoding="utf-8").read()
    method = launch.split('<arg name="method" default="', 1)[1].split('"', 1)[0]
    assert f"exp1-my-stack-{method}-s0" in " ".join(steps[8])


def test_steps_4_to_8_run_as_written_on_a_sim_time_master(tmp_path):
    r = subprocess.run(
        ["bash", os.path.join(REPO, "scripts", "repro", "your_stack_install.sh"), str(tmp_path), "2", "4", "free"],
        capture_output=True,
        text=True,
        timeout=2400,
    )
    out = r.stdout + r.stderr
    assert r.returncode == 0, out[-4000:]
    assert "== steps 4-8 ran as the page writes them" in out
    assert "RECIPE FAILED" not in out and "no action server" not in out

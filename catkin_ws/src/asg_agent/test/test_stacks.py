"""records.stacks: stacks registered by a launch file (issue #55), read and checked without ROS."""

import json
import os

import pytest

from asg_agent.records import stacks
from asg_agent.records.experiment import ExperimentError, load_experiment

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_the_three_registered_stacks_read_as_their_files_say():
    paper = stacks.load("paper")
    assert (paper.name, paper.mode, paper.acks, paper.command, paper.sim_time) == (
        "paper",
        "lockstep",
        True,
        "vehicle_command",
        False,
    )
    assert paper.nodes == [("planner", "segmenter"), ("planner",)]  # by perception: U-Net or labels
    assert paper.builtin and paper.path == os.path.realpath(os.path.join(REPO, "stacks", "paper.launch"))
    depth = stacks.load("depth")
    assert (depth.command, depth.identity, depth.nodes) == ("twist", ["depth_stack/arcs"], [("depth_stack",)])
    gap = stacks.load(os.path.join(REPO, "stacks", "gap_nav.launch"))
    assert (gap.name, gap.mode, gap.acks, gap.sim_time) == ("gap_nav", "free", False, True)


def registration(tmp_path, body, *more):
    blocks = "".join(f'<rosparam ns="stack">\n{b}\n</rosparam>\n' for b in (body,) + more)
    p = tmp_path / "mine.launch"
    p.write_text(f"<launch>\n{blocks}<node pkg='x' type='y' name='drive' />\n</launch>\n")
    return str(p)


GOOD = "name: mine\nnodes: [drive]\nmode: free\nacks: false\ncommand: twist\nsim_time: true"


@pytest.mark.parametrize(
    "body, said",
    [
        ("nodes: [drive]", "name: required"),
        ("name: mine\nnodes: []", "nodes: required, a non-empty list"),
        ("name: mine\nnodes: [drive]\nmode: fast", "mode: 'fast', must be lockstep or free"),
        ("name: mine\nnodes: [drive]\nacks: false", "acks: false needs mode: free"),
        ("name: mine\nnodes: [drive]\ncommand: joystick", "command: 'joystick'"),
        ("name: mine\nnodes: [drive]\nsim_time: 1", "sim_time: 1, must be true or false"),
        ("name: mine\nnodes: [drive]\nspeed: 3", "speed: unknown key"),
        ("name: mine\nnodes: [drive]\nworker: {lockstep: false}", "worker: lockstep: not a scene worker parameter"),
        ("name: $(arg who)\nnodes: [drive]", "substitutions"),
        ("name: mine\nnodes: [drive\n", "not valid YAML"),
    ],
)
def test_a_bad_registration_is_refused_naming_the_file_and_the_key(tmp_path, body, said):
    path = registration(tmp_path, body)
    with pytest.raises(stacks.RegistrationError) as e:
        stacks.read(path)
    assert said in str(e.value) and path in str(e.value)


def test_blocks_of_one_file_agree_but_on_nodes_and_worker(tmp_path):
    ok = stacks.read(registration(tmp_path, GOOD, GOOD.replace("[drive]", "[drive, cloud]")))
    assert ok.nodes == [("drive",), ("drive", "cloud")]
    with pytest.raises(stacks.RegistrationError, match="block 2 differs from the first in sim_time"):
        stacks.read(registration(tmp_path, GOOD, GOOD.replace("sim_time: true", "sim_time: false")))
    empty = tmp_path / "none.launch"
    empty.write_text("<launch><node pkg='x' type='y' name='z' /></launch>")
    with pytest.raises(stacks.RegistrationError, match='no <rosparam ns="stack">'):
        stacks.read(str(empty))


def test_an_experiment_names_its_stack_by_name_or_by_file(tmp_path):
    with open(os.path.join(REPO, "experiments", "exp1-depth.yaml"), encoding="utf-8") as f:
        depth = f.read().replace("../scenarios/", os.path.join(REPO, "scenarios") + "/")
    mine = registration(tmp_path, GOOD)
    (tmp_path / "e.yaml").write_text(depth.replace("stack: depth", "stack: mine.launch"))
    exp = load_experiment(str(tmp_path / "e.yaml"))  # relative to the experiment's folder
    assert (exp.stack, exp.stack_file, exp.sim_time) == ("mine", os.path.realpath(mine), True)
    assert load_experiment(os.path.join(REPO, "experiments", "exp1-depth.yaml")).stack == "depth"
    (tmp_path / "f.yaml").write_text(depth.replace("stack: depth", "stack: nobody"))
    with pytest.raises(ExperimentError, match="'nobody' is not a registered stack .*depth.*paper"):
        load_experiment(str(tmp_path / "f.yaml"))
    (tmp_path / "g.yaml").write_text(depth.replace("stack: depth", "stack: gone.launch"))
    with pytest.raises(ExperimentError, match="gone.launch: no such launch file"):
        load_experiment(str(tmp_path / "g.yaml"))


def test_a_baseline_takes_a_users_stack_by_its_registration_file(tmp_path):
    # `baseline run --stack` (docs/your-stack.md's recipe): a label, a registered name, or a
    # registration file anywhere, whose rows are stored under the name it registers
    from asg_agent.cli.baseline import out_path, stack_label

    assert stack_label("flawed") == "flawed" and stack_label("gap_nav") == "gap_nav"
    assert stack_label(registration(tmp_path, GOOD)) == "mine"
    assert out_path("exp1", stack_label(registration(tmp_path, GOOD)), str(tmp_path)).endswith("exp1/mine.jsonl")
    with pytest.raises(ValueError, match=r"--stack 'nobody': one of ground_truth, .*registration launch file"):
        stack_label("nobody")


def test_the_baseline_summary_takes_a_registered_stacks_rows(tmp_path):
    # Issue #55: `baseline summary` (results/baseline/<exp>.json) lists a registered stack's rows
    # beside the labels', read from the ground-truth root as the depth stack's are; a registered
    # stack with no rows adds nothing.
    from asg_agent.cli.baseline import STACKS, out_path, summarize

    def write(stack, terms):
        path = out_path("expx", stack, str(tmp_path))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            for k, t in enumerate(terms):
                row = dict(layout=k, termination=t, proxy=1.0, plr=1.0, yaw_term=0.0, sim_time=10.0, stack=stack)
                row.update(collision_with="bush" if t == "COLLISION" else "", error="")
                f.write(json.dumps(row) + "\n")

    write("ground_truth", ["SUCCESS", "SUCCESS", "COLLISION"])
    write("gap_nav", ["SUCCESS", "COLLISION"])
    s = summarize("expx", str(tmp_path / "elsewhere"), str(tmp_path))
    assert sorted(s["stacks"]) == ["gap_nav", "ground_truth"]
    assert s["stacks"]["gap_nav"]["runs"] == 2 and s["stacks"]["gap_nav"]["collisions"] == 1
    assert [r["gap_nav_termination"] for r in s["per_layout"][:2]] == ["SUCCESS", "COLLISION"]
    assert s["per_layout"][2]["gap_nav"] is None and s["per_layout"][2]["depth"] is None
    assert "gap_nav" not in STACKS

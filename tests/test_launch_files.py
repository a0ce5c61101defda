"""Every launch file in launch/ parses and resolves its includes (`roslaunch --nodes`, no master
needed), and the campaign launch files wire the stacks they promise. A comment holding "--" is
invalid XML and made replay.launch unusable until this test existed."""

import glob
import os
import subprocess

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
LAUNCH = sorted(glob.glob(os.path.join(REPO, "launch", "*.launch")))
REQUIRED_ARGS = {"replay.launch": ["bag:=run.bag"]}  # args without a default


def roslaunch(*args):
    env = dict(os.environ, ROS_HOSTNAME="127.0.0.1", ROS_IP="127.0.0.1")
    p = subprocess.run(["roslaunch", *args], capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 0, p.stdout + p.stderr
    return p.stdout


def test_there_are_launch_files():
    assert len(LAUNCH) >= 6


@pytest.mark.parametrize("path", LAUNCH, ids=os.path.basename)
def test_launch_file_parses(path):
    nodes = roslaunch("--nodes", path, *REQUIRED_ARGS.get(os.path.basename(path), []))
    assert nodes.strip(), f"{path}: no nodes"


def _experiment(body: str) -> str:
    """An experiment file of Exp. 1's scene with `body`'s keys (in a temporary folder)."""
    import tempfile

    folder = tempfile.mkdtemp()
    path = os.path.join(folder, "exp.yaml")
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"name: exp\nscenario: {os.path.join(REPO, 'scenarios', 'exp1.yaml')}\n" + body)
    return path


def test_train_launch_starts_n_workers_and_the_campaign():
    path = os.path.join(REPO, "launch", "train.launch")
    nodes = roslaunch("--nodes", path, "workers:=3").split()
    # 3 workers under test with the U-Net, and 2 reference workers after them: the unflawed U-Net, ground truth
    assert [n for n in nodes if n.endswith("/scene_worker")] == [f"/worker_{i}/scene_worker" for i in range(5)]
    assert [n for n in nodes if n.endswith("/segmenter")] == [f"/worker_{i}/segmenter" for i in range(4)]
    assert "/campaign" in nodes
    args = roslaunch("--args", "/campaign", path, "workers:=3")
    # Issue #36: three-stack attribution by default, the unflawed U-Net on worker_3, ground truth on worker_4
    assert "--workers 3" in args and "--reward auto" in args
    assert "--reference full=1 --reference ground_truth=1 --full-model full" in args
    import yaml

    # train.launch refuses a model its experiment does not name (issue #68): an experiment of flawed_lite
    lite = _experiment("model: flawed_lite\n")
    params = yaml.safe_load(roslaunch("--dump-params", path, "workers:=3", "model:=flawed_lite", f"experiment:={lite}"))
    assert params["/worker_3/segmenter/model"] == "full_lite" and "/worker_4/segmenter/model" not in params
    assert params["/worker_4/scene_worker/publish_labels"] is True
    for single in ("true", "ground_truth"):  # round 3's single-reference mode stays selectable
        args = roslaunch("--args", "/campaign", path, "workers:=3", f"attribution:={single}")
        assert "--reference-workers 2" in args and "--reference " not in args
    nodes = roslaunch("--nodes", path, "workers:=3", "attribution:=false").split()
    assert [n for n in nodes if n.endswith("/scene_worker")] == [f"/worker_{i}/scene_worker" for i in range(3)]
    assert "--reference-workers" not in roslaunch("--args", "/campaign", path, "attribution:=false")


def test_differential_launch_runs_two_stacks_and_a_reference_campaign():
    path = os.path.join(REPO, "launch", "differential.launch")
    params = roslaunch("--dump-params", path, "model:=flawed", "ref_model:=full")
    models = {
        line.split(":")[0]: line.split(":")[1].strip()
        for line in params.splitlines()
        if line.endswith(("flawed", "full")) and "/segmenter/model" in line
    }
    assert models == {
        "/worker_0/segmenter/model": "flawed",
        "/worker_1/segmenter/model": "flawed",
        "/worker_2/segmenter/model": "full",
        "/worker_3/segmenter/model": "full",
    }
    args = roslaunch("--args", "/campaign", path, "scenarios:=42")
    assert "--workers 2 --reference-workers 2" in args and "--scenarios 42" in args


def test_train_launch_gives_every_worker_under_test_the_backend():
    # Issue #24: the inference backend is part of the stack's identity (experiment `unet_backend`).
    import yaml

    path = os.path.join(REPO, "launch", "train.launch")
    cl = os.path.join(REPO, "experiments", "exp1-channels-last.yaml")  # the launch checks its experiment's backend
    params = yaml.safe_load(
        roslaunch("--dump-params", path, "workers:=3", "unet_backend:=channels_last", f"experiment:={cl}")
    )
    assert [params[f"/worker_{i}/segmenter/backend"] for i in range(3)] == ["channels_last"] * 3
    params = yaml.safe_load(roslaunch("--dump-params", path, "workers:=2"))
    # unset: empty, which the segmenter reads as the shipped default (asg_perception.numerics)
    assert params["/worker_0/segmenter/backend"] == ""
    diff = os.path.join(REPO, "launch", "differential.launch")
    params = yaml.safe_load(roslaunch("--dump-params", diff, "unet_backend:=channels_last"))
    assert [params[f"/worker_{i}/segmenter/backend"] for i in range(4)] == ["channels_last"] * 4


def test_the_experiment_backends_are_the_segmenters():
    import sys

    for pkg in ("asg_agent", "asg_perception", "asg_scenario"):
        sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", pkg, "src"))
    from asg_agent.records.experiment import DEFAULT_UNET_BACKEND, UNET_BACKENDS, ExperimentError, load_experiment
    from asg_perception.numerics import BACKENDS, DEFAULT_BACKEND

    # one home (asg_perception.numerics): the others are that object, not a copy of it
    assert UNET_BACKENDS is BACKENDS and DEFAULT_UNET_BACKEND is DEFAULT_BACKEND
    # the launch files state no backend of their own: empty, the segmenter's default
    for launch in ("worker.launch", "train.launch", "differential.launch"):
        text = open(os.path.join(REPO, "launch", launch)).read()
        assert '<arg name="unet_backend" default=""' in text, launch
    exp = os.path.join(REPO, "experiments", "exp1.yaml")
    assert load_experiment(exp).unet_backend == DEFAULT_BACKEND
    assert load_experiment(os.path.join(REPO, "experiments", "exp1-channels-last.yaml")).unet_backend == "channels_last"
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        bad = os.path.join(d, "bad.yaml")
        with open(bad, "w") as f:
            f.write(
                open(exp)
                .read()
                .replace(
                    "scenario: ../scenarios/exp1.yaml", f"scenario: {os.path.join(REPO, 'scenarios', 'exp1.yaml')}"
                )
                + "unet_backend: fp8\n"
            )
        with pytest.raises(ExperimentError, match="unet_backend: 'fp8', must be one of"):
            load_experiment(bad)


def _flatten(d, prefix=""):
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flatten(v, f"{prefix}{k}/"))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _doc_defaults(doc, section):
    """`| `key` | unit | default | ...` rows of a markdown section: key -> default (YAML-parsed)."""
    import re

    import yaml

    text = open(os.path.join(REPO, "docs", doc)).read().split(section, 1)[1].split("\n## ", 1)[0]
    out = {}
    for m in re.finditer(r"^\| ((?:`[^`]+`(?:, )?)+) \| [^|]* \| ([^|]+) \|", text, re.M):
        cell = m.group(2).strip().strip("`")
        for key in re.findall(r"`([^`]+)`", m.group(1)):
            out[key.lstrip("~")] = yaml.safe_load(cell)  # a generated table names them ~key
    return out


@pytest.mark.parametrize(
    "config, doc, section",
    [
        ("catkin_ws/src/asg_sim/config/scene_worker.yaml", "simulator.md", "## scene_worker node"),
        ("catkin_ws/src/asg_planner/config/planner.yaml", "planner.md", "## planner node"),
        ("catkin_ws/src/asg_depth_stack/config/depth_stack.yaml", "your-stack.md", "## depth_stack node"),
    ],
)
def test_every_node_default_has_one_home_and_the_docs_quote_it(config, doc, section):
    # Issue #26: a node's defaults live in its YAML; the docs' parameter table quotes every one of
    # them with the same value (a test, not a second home).
    import yaml

    values = _flatten(yaml.safe_load(open(os.path.join(REPO, config))))
    documented = _doc_defaults(doc, section)
    missing = sorted(set(values) - set(documented))
    assert not missing, f"docs/{doc} does not document {missing} of {config}"
    # "required": the node has no default of its own; the YAML gives the one that runs
    wrong = {k: (values[k], documented[k]) for k in values if documented[k] not in ("required", values[k])}
    assert not wrong, f"docs/{doc} quotes other defaults than {config} (yaml, docs): {wrong}"


def test_worker_launch_takes_the_worker_defaults_from_the_yaml():
    # Issue #26: worker.launch passes render_threads, command_timeout and odom_every_tick only when
    # given, so the YAML is their one home; given, they override it.
    import yaml

    path = os.path.join(REPO, "launch", "worker.launch")
    values = yaml.safe_load(open(os.path.join(REPO, "catkin_ws/src/asg_sim/config/scene_worker.yaml")))
    params = yaml.safe_load(roslaunch("--dump-params", path))
    for key in ("lockstep", "render_threads", "command_timeout", "odom_every_tick", "ack_timeout"):
        assert params[f"/worker_0/scene_worker/{key}"] == values[key], key
    params = yaml.safe_load(roslaunch("--dump-params", path, "command_timeout:=5.0", "lockstep:=false"))
    assert params["/worker_0/scene_worker/command_timeout"] == 5.0
    # issue #55: the stack's registration decides the mode; lockstep:= overrides it, for the worker
    # and the stack's client alike
    assert params["/worker_0/stack/mode"] == "free"
    assert yaml.safe_load(roslaunch("--dump-params", path))["/worker_0/stack/mode"] == "lockstep"


def test_each_depth_registration_loads_its_own_parameters_through_worker_launch():
    # issue #67: worker.launch passed its default depth_config to every registration it includes
    # (pass_all_args), so depth_rc and the other release candidates ran the release's parameters,
    # and the stack pairs compared depth with itself. Each registration's own file must arrive.
    import yaml

    config = os.path.join(REPO, "catkin_ws", "src", "asg_depth_stack", "config")
    pairs = {"depth": "depth_stack.yaml", "depth_rc": "depth_stack_rc.yaml", "depth_rc4": "depth_stack_rc4.yaml"}
    loaded = {}
    for stack, name in pairs.items():
        params = yaml.safe_load(
            roslaunch("--dump-params", os.path.join(REPO, "launch", "worker.launch"), f"stack:={stack}")
        )
        want = yaml.safe_load(open(os.path.join(config, name)))
        got = {
            k: {key.rsplit("/", 1)[1]: v for key, v in params.items() if key.startswith(f"/worker_0/depth_stack/{k}/")}
            for k in ("arcs", "grid")
        }
        assert got == {k: want[k] for k in ("arcs", "grid")}, stack
        loaded[stack] = got
    assert loaded["depth_rc"]["arcs"]["clearance"] != loaded["depth"]["arcs"]["clearance"]
    assert loaded["depth_rc4"]["grid"]["step_height"] != loaded["depth"]["grid"]["step_height"]
    # a depth_config given to worker.launch still replaces the registration's own
    other = os.path.join(config, "depth_stack_rc.yaml")
    params = yaml.safe_load(
        roslaunch(
            "--dump-params", os.path.join(REPO, "launch", "worker.launch"), "stack:=depth", f"depth_config:={other}"
        )
    )
    assert params["/worker_0/depth_stack/arcs/clearance"] == loaded["depth_rc"]["arcs"]["clearance"]

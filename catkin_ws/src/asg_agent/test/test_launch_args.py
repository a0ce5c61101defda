"""Issue #53: the experiment file decides the workers' stack (scripts/train.sh asks
asg_agent.cli.launch_args), a contradiction is refused, and bf16 is refused where it would be
emulated; the campaign's summary names the stack's numerics; replay refuses a bf16 run on another
ISA with the command that reruns it on the default numerics."""

import json
import os

import pytest

from asg_agent.records.experiment import ExperimentError
from asg_agent.cli import launch_args as la
from asg_perception import numerics as nm

REPO = la.REPO


def exp(name):
    return f"experiment:={os.path.join(REPO, 'experiments', name)}"


def test_the_experiment_alone_sets_the_workers_stack():
    out = la.launch_args([exp("exp1-channels-last.yaml"), "seed:=3"])
    assert "unet_backend:=channels_last" in out and "model:=flawed" in out and "stack:=paper" in out
    assert f"planner_config:={os.path.join(REPO, 'catkin_ws/src/asg_planner/config/planner.yaml')}" in out
    # the default experiment: the default numerics
    assert f"unet_backend:={nm.DEFAULT_BACKEND}" in la.launch_args([])
    out = la.launch_args([exp("exp1-hf1.yaml")])
    assert "model:=flawed_hf1" in out
    # what the command line gives is not repeated; agreeing values are accepted
    assert la.launch_args([exp("exp1.yaml"), "model:=flawed", f"unet_backend:={nm.DEFAULT_BACKEND}"]) == [
        a for a in la.launch_args([exp("exp1.yaml")]) if not a.startswith(("model:=", "unet_backend:="))
    ]
    assert "unet_backend:=" not in " ".join(la.launch_args([exp("exp1.yaml"), "unet_backend:="]))
    # ground truth and the depth stack: only what they use
    assert [a.split(":=")[0] for a in la.launch_args([exp("exp1-depth.yaml")])] == ["stack"]
    # a stack registered by a file (issue #55): by its name where it is one of stacks/, and the
    # master's simulated time where its registration asks for it
    assert la.launch_args([exp("exp1-gap-nav.yaml")]) == ["stack:=gap_nav", "sim_time:=true"]
    assert la.launch_args([exp("exp1-gap-nav.yaml"), f"stack:={REPO}/stacks/gap_nav.launch"]) == ["sim_time:=true"]
    with pytest.raises(ExperimentError, match="stack:=depth contradicts the experiment's stack gap_nav"):
        la.launch_args([exp("exp1-gap-nav.yaml"), "stack:=depth"])


def test_a_contradiction_is_refused_naming_both():
    with pytest.raises(ExperimentError, match="model:=full contradicts the experiment's model flawed"):
        la.launch_args([exp("exp1.yaml"), "model:=full"])
    if nm.native_bf16():
        with pytest.raises(ExperimentError, match="unet_backend:=bf16 contradicts the experiment's unet_backend"):
            la.launch_args([exp("exp1-channels-last.yaml"), "unet_backend:=bf16"])
    assert la.main([exp("exp1.yaml"), "model:=full"]) == 2


def test_bf16_is_refused_where_the_cpu_would_emulate_it(monkeypatch):
    monkeypatch.setattr(la, "refuse_emulated", lambda b: nm.refuse_emulated(b, {"avx2", "avx", "sse4_1"}))
    with pytest.raises(ExperimentError, match="no native bf16.*25x slower"):
        la.launch_args([exp("exp1-bf16.yaml")])
    assert la.launch_args([exp("exp1.yaml")])  # the default runs anywhere


def test_the_summary_names_the_numerics_and_bf16_findings_replay_only_on_their_isa():
    from asg_agent.cli.campaign import stack_line

    fp32 = {
        "stack": "paper",
        "perception": "unet",
        "model": "flawed",
        "planner_config": "planner.yaml",
        "numerics": "channels_last isa=AVX512_CORE threads=1 torch=1.13.0a0",
    }
    line = stack_line({"settings": json.dumps(fp32)})
    assert "U-Net flawed (channels_last isa=AVX512_CORE" in line and "bf16" not in line
    bf = dict(fp32, numerics="bf16 isa=AVX512_CORE_AMX threads=1 torch=1.13.0a0")
    assert "replay bit for bit only where oneDNN runs AVX512_CORE_AMX" in stack_line({"settings": json.dumps(bf)})


def test_the_summary_names_the_scene_generator():
    from asg_agent.cli.campaign import generator_line

    settings = {
        "method_config": {"band": 10.0, "share": 1.0},
        "reward": "proxy",
        "experiment_repo_file": "experiments/exp1.yaml",
    }
    camp = {"method": "route-random", "seed": 3, "experiment": "exp1", "settings": json.dumps(settings)}
    assert generator_line(camp) == (
        "scene generator: route-random (band 10 m, share 1), reward proxy, experiment experiments/exp1.yaml, seed 3"
    )
    td3 = {
        "method": "td3-per-asp",
        "seed": 0,
        "experiment": "exp1-route",
        "settings": json.dumps({"reward": "collision"}),
    }
    assert generator_line(td3) == "scene generator: td3-per-asp, reward collision, experiment exp1-route, seed 0"


def test_replay_refuses_a_bf16_run_on_another_isa(monkeypatch, capsys):
    from asg_agent.ros import replay

    bf = {"numerics": "bf16 isa=AVX512_CORE_AMX threads=1 torch=1.13.0a0"}
    monkeypatch.setattr(nm, "cpu_flags", lambda: frozenset({"avx2", "avx", "sse4_1"}))
    assert "this CPU has no native bf16" in replay.bf16_refusal(bf)
    epyc = {"avx2", "avx", "sse4_1", "avx512f", "avx512bw", "avx512vl", "avx512dq", "avx512_vnni", "avx512_bf16"}
    monkeypatch.setattr(nm, "cpu_flags", lambda: frozenset(epyc))
    assert "oneDNN runs AVX512_CORE_BF16 here" in replay.bf16_refusal(bf)
    assert replay.bf16_refusal({"numerics": "bf16 isa=AVX512_CORE_BF16 threads=1 torch=1.13.0a0"}) == ""
    assert replay.bf16_refusal({"numerics": "channels_last isa=AVX2 threads=1 torch=1.13.0a0"}) == ""
    # the refusal comes before any worker is brought up, with the rerun command
    from asg_agent.records.store import Store

    db = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"replay_bf16_{os.getpid()}.sqlite")
    s = Store(db)
    s.create_campaign("c", "random", "exp1", "", 0, bf)
    rc = replay.main([db, "c", "0"])
    err = capsys.readouterr().err
    os.remove(db)
    # issue #68: the exit code alone also passes without the refusal ("campaign 'c' has no job 0"):
    # the reason and the rerun command are what is asserted
    assert rc == 2
    assert "the campaign ran the bf16 fast mode on oneDNN AVX512_CORE_AMX" in err, err
    assert f"rosrun asg_agent replay {db} c 0 --default-numerics" in err, err
    assert "has no job" not in err

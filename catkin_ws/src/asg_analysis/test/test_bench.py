"""bench: per-scenario breakdown from stage readings (asg_analysis.bench) and the campaign's own
stage timers."""

import json
import os
import subprocess
import sys

import pytest

AGENT_TEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "asg_agent", "test")
sys.path.insert(0, AGENT_TEST)  # the agent's in-process stand-in (stand_in/), beside its tests
import stand_in  # noqa: E402

from asg_analysis.bench import table
from asg_agent.records.stage_costs import breakdown


def reading(node, runs, cpu, **stages):
    return {
        "node": node,
        "runs": runs,
        "cpu_seconds": cpu,
        "seconds": {k: v[0] for k, v in stages.items()},
        "calls": {k: v[1] for k, v in stages.items()},
    }


def test_breakdown_subtracts_first_readings_and_divides_by_scenarios():
    first = {
        ("/worker_0", "scene_worker"): reading("scene_worker", 3, 10.0, render=(1.0, 10), wait=(5.0, 10)),
        ("/worker_0", "segmenter"): reading("segmenter", 3, 20.0, inference=(3.0, 100), decode=(0.1, 100)),
        ("/worker_0", "planner"): reading("planner", 3, 4.0, votes=(0.5, 100), plan=(0.2, 50)),
    }
    last = {
        ("/worker_0", "scene_worker"): reading("scene_worker", 13, 14.0, render=(3.0, 110), wait=(25.0, 210)),
        ("/worker_0", "segmenter"): reading("segmenter", 13, 38.0, inference=(19.0, 1100), decode=(0.3, 1100)),
        ("/worker_0", "planner"): reading("planner", 13, 6.0, votes=(1.5, 1100), plan=(0.6, 450)),
    }
    agent = {"seconds": {"update": 0.5, "store": 0.1}, "calls": {"update": 10, "store": 10}, "cpu": 1.0}
    b = breakdown(first, last, agent, scenarios=10, wall=36.0, sim_seconds=160.0, workers=1)
    assert b["rate_per_hour"] == pytest.approx(1000.0)
    assert b["per_scenario_s"]["scene_worker.render"] == pytest.approx(0.2)
    assert b["per_scenario_s"]["segmenter.inference"] == pytest.approx(1.6)
    assert b["frames_per_scenario"] == pytest.approx(100.0)
    assert b["inference_ms_per_frame"] == pytest.approx(16.0)
    # one worker: one core's worth of inference; 3600 / (100 x 0.016) = 2250 an hour
    assert b["inference_bound_per_hour"] == pytest.approx(2250.0)
    assert b["fraction_of_bound"] == pytest.approx(1000.0 / 2250.0)
    # waited 2.0 s a scenario; the stack worked 1.6 + 0.02 + 0.1 + 0.04 = 1.76 s of it
    assert b["transport_and_waiting_s"] == pytest.approx(2.0 - 1.76)
    assert "| of which transport and scheduling (wait - stack work on the critical path) | 0.240 |" in table([b], ["x"])
    assert b["cpu_per_scenario_s"]["segmenter"] == pytest.approx(1.8)
    assert b["sim_s_per_wall_s_per_worker"] == pytest.approx(160.0 / 36.0)
    md = table([b], ["one"])
    assert "| segmenter: U-Net inference | 1.600 |" in md
    assert "**1000**" in md


def test_breakdown_refuses_an_empty_run():
    with pytest.raises(ValueError):
        breakdown({}, {}, {"seconds": {}, "calls": {}, "cpu": 0.0}, scenarios=0, wall=1.0, sim_seconds=0, workers=1)


def test_campaign_times_its_own_stages(tmp_path):
    """A stand-in-worker campaign: every stage of its loop was timed and the report is written
    (without ROS the node readings are absent, the agent's own stages present)."""
    out = tmp_path / "stages.json"
    exp = os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "experiments", "exp1.yaml")
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "stand_in.campaign",
            exp,
            "--fake-workers",
            "2",
            "--scenarios",
            "30",
            "--store",
            str(tmp_path / "s.sqlite"),
            "--no-progress",
            "--method",
            "td3-per-asp",
            "--stage-report",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        env=stand_in.environ(),
    )
    assert r.returncode == 0, r.stderr
    rep = json.loads(out.read_text())
    assert rep["scenarios"] == 30 and rep["workers"] == 2
    for stage in ("propose", "proxy", "store", "dispatch", "wait", "checkpoint"):
        assert rep["per_scenario_s"][f"agent.{stage}"] > 0, stage
    assert rep["cpu_per_scenario_s"]["agent"] > 0


def test_before_after_takes_medians_and_ranges_of_each_side():
    from asg_analysis.bench import before_after, before_after_sentence

    def run(rate, cpu):
        return {"rate_per_hour": rate, "stacks": {"under test": {"cpu_per_scenario_s": cpu}}}

    c = before_after(
        [run(3000, 1.5), run(2700, 1.4), run(3100, 1.3)], [run(2900, 1.45), run(2800, 1.6), run(3200, 1.2)]
    )
    assert c["before"]["rate"] == (3000, 2700, 3100) and c["after"]["rate"] == (2900, 2800, 3200)
    assert c["before"]["cpu"] == (1.4, 1.3, 1.5) and abs(c["cpu_ratio"] - 1.45 / 1.4) < 1e-12
    assert abs(c["rate_ratio"] - 2900 / 3000) < 1e-12
    assert before_after_sentence(c).startswith(
        "scenarios an hour, median (range): before 3,000 (2,700-3,100), after 2,900 (2,800-3,200), after / before 0.967"
    )

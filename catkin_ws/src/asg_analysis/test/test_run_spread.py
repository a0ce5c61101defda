"""analysis.run_spread: how often a free-running stack's outcomes repeat (issue #55)."""

import gzip
import json

import pytest

from asg_analysis.studies import run_spread


def export(path, outcomes):
    with gzip.open(path, "wt", encoding="utf-8") as f:
        f.write(json.dumps({"campaign": {"name": "c"}}) + "\n")
        for job, (term, proxy) in enumerate(outcomes):
            f.write(json.dumps({"job": job, "termination": term, "proxy": proxy}) + "\n")


def rerun(path, outcomes):
    with open(path, "w", encoding="utf-8") as f:
        for job, (term, proxy) in outcomes.items():
            f.write(json.dumps({"job": job, "termination": term, "proxy": proxy}) + "\n")


def test_counts_the_scenarios_whose_verdict_repeats_and_the_failures_that_fail_again(tmp_path):
    export(tmp_path / "e.jsonl.gz", [("COLLISION", 1.5), ("SUCCESS", 1.1), ("SUCCESS", 3.2), ("SUCCESS", 1.0)])
    reps = [
        {0: ("COLLISION", 1.4), 1: ("SUCCESS", 1.2), 2: ("SUCCESS", 2.9)},  # job 2 passes this time
        {0: ("COLLISION", 1.6), 1: ("SUCCESS", 1.1), 2: ("SUCCESS", 3.4)},
        {0: ("COLLISION", 1.5), 1: ("SIM_TIMEOUT", 2.0), 2: ("SUCCESS", 2.8)},  # job 1 fails this time
    ]
    paths = []
    for k, r in enumerate(reps):
        rerun(tmp_path / f"r{k}.jsonl", r)
        paths.append(str(tmp_path / f"r{k}.jsonl"))
    s = run_spread.spread(str(tmp_path / "e.jsonl.gz"), paths)
    assert (s["scenarios"], s["repetitions"], s["repeat"]) == (3, 3, 1)  # job 3 was not rerun
    assert s["stored_failures"] == 2
    assert s["failures_fail_again"] == {"always": 1, "sometimes": 1, "never": 0}
    ranges = {p["job"]: p["proxy_range"] for p in s["per_scenario"]}
    assert ranges[0] == pytest.approx(0.2) and ranges[2] == pytest.approx(0.6) and ranges[1] == pytest.approx(0.9)
    assert s["proxy_range_max"] == pytest.approx(0.9)
    assert "| c | 3 x 3 | 1 of 3 (33 %, " in run_spread.markdown(s)


def test_repetitions_that_do_not_hold_the_same_scenarios_are_refused(tmp_path):
    export(tmp_path / "e.jsonl.gz", [("SUCCESS", 1.0), ("SUCCESS", 1.0)])
    rerun(tmp_path / "a.jsonl", {0: ("SUCCESS", 1.0), 1: ("SUCCESS", 1.0)})
    rerun(tmp_path / "b.jsonl", {0: ("SUCCESS", 1.0)})
    with pytest.raises(ValueError, match=r"jobs \[1\] are missing from some repetitions"):
        run_spread.spread(str(tmp_path / "e.jsonl.gz"), [str(tmp_path / "a.jsonl"), str(tmp_path / "b.jsonl")])
    assert run_spread.run([str(tmp_path / "e.jsonl.gz"), str(tmp_path / "a.jsonl"), str(tmp_path / "b.jsonl")]) == 2

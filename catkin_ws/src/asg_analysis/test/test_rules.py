"""Issue #78: rules over a scene's generic attributes learnt from a campaign's rows
(asg_analysis.rules learn), one finding per distinct place, and their check on fresh samples."""

import json
import os
import re
import sys

import numpy as np
import pytest

from asg_agent.records.experiment import load_experiment
from asg_analysis import rules

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
WIDE = os.path.join(REPO, "experiments", "exp1-route-wide.yaml")
AGENT_TEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "asg_agent", "test")
sys.path.insert(0, AGENT_TEST)  # the agent's in-process stand-in (stand_in/), beside its tests


def _rows(exp, n, seed, hidden, repeat_first=0):
    """Rows of uniform layouts; a made-up stack fails (a flaw finding) where `hidden` holds, on
    the first obstacle that makes it hold; `repeat_first` extra copies of the first finding."""
    from asg_agent.search.surrogate import ObstacleFeatures

    f = ObstacleFeatures(exp)
    rng = np.random.default_rng(seed)
    a = rng.uniform(-1.0, 1.0, (n, exp.action_dim))
    xy = exp.positions_of(a)
    hold = hidden.holds(f.of_actions(a), f.names())
    meshes = [f.classes[c] for c in f.cls]
    rows = []
    for j in range(n):
        row = {
            "job": j,
            "termination": "COLLISION" if hold[j] else "SUCCESS",
            "attribution": "flaw" if hold[j] else "not_candidate",
            "positions": xy[j].tolist(),
            "meshes": meshes,
            "collision_with": j % len(meshes) if hold[j] else None,
            "trajectory_xy": [[20.0, 20.0], [80.0, 80.0]],
            "textural": {},
        }
        rows.append(row)
    first = next(r for r in rows if r["attribution"] == "flaw")
    rows += [dict(first, job=n + k) for k in range(repeat_first)]
    return rows


def test_learn_finds_the_hidden_rule_and_a_place_found_many_times_weighs_as_one():
    from asg_agent.search.rules import Condition, Rule
    from asg_agent.search.surrogate import ObstacleFeatures

    exp = load_experiment(WIDE)
    f = ObstacleFeatures(exp)
    feature = f"{f.classes[1]} d<4m q3"
    hidden = Rule((Condition(feature, True, 1.0),))
    rows = _rows(exp, 1200, 1, hidden, repeat_first=300)
    res = rules.learn(rows, exp, "flaw")
    assert res["findings"] == sum(r["attribution"] == "flaw" for r in rows)
    assert res["distinct"] < res["findings"] - 250  # the 300 repeats count once
    top = res["rules"][0]
    assert [feature, ">=", 1.0] in top["rule"]["conditions"]
    assert top["precision"] >= 2 * res["base_rate"] and top["share_of_distinct"] > 0.9
    shown = rules.lines(res)
    assert any("distinct findings in" in line for line in shown)
    # the screen reads in words, its terms said once above the rules, no `q3` or `d<4m` shorthand
    assert sum(rules.TERMS in line for line in shown) == 1
    assert not any(re.search(r"\bq[1-4]\b|d<\d", line) for line in shown[1:]), shown
    assert "third quarter" in "\n".join(shown)
    # rules are only what the tree can say: nothing when nothing is found
    none = rules.learn([dict(r, attribution="not_candidate", termination="SUCCESS") for r in rows], exp, "flaw")
    assert none["rules"] == [] and none["findings"] == 0


def test_check_gives_precision_base_rate_exact_intervals_and_fisher():
    def rows(k, n):
        return [
            {"job": j, "termination": "COLLISION" if j < k else "SUCCESS", "attribution": "flaw" if j < k else "pass"}
            for j in range(n)
        ]

    res = rules.check(rows(30, 100), rows(8, 100), "flaw")
    assert res["precision"] == 0.30 and res["base_rate"] == 0.08 and res["ratio"] == pytest.approx(3.75)
    lo, hi = res["precision_ci"]
    assert 0.21 < lo < 0.30 < hi < 0.41  # Clopper-Pearson 95 %: 0.2124-0.3998
    assert res["fisher_p"] < 1e-3
    # an ERROR is no sample
    assert rules.check(rows(30, 100) + [{"job": 100, "termination": "ERROR"}], rows(8, 100))["rule_scenarios"] == 100


def test_the_command_line_learns_from_exports_and_names_bad_input(tmp_path, capsys):
    import gzip

    from asg_agent.search.rules import Condition, Rule
    from asg_agent.search.surrogate import ObstacleFeatures

    exp = load_experiment(WIDE)
    hidden = Rule((Condition(f"{ObstacleFeatures(exp).classes[0]} d<4m q2", True, 1.0),))
    path = tmp_path / "c.jsonl.gz"
    camp = {
        "name": "c",
        "seed": 0,
        "experiment_text": "x",
        "settings": json.dumps({"experiment_repo_file": "experiments/exp1-route-wide.yaml", "reward": "flaw"}),
    }
    with gzip.open(path, "wt") as f:
        f.write(json.dumps({"campaign": camp}) + "\n")
        for r in _rows(exp, 600, 2, hidden):
            f.write(json.dumps(r) + "\n")
    out = tmp_path / "rules.json"
    assert rules.run(["learn", str(path), "--out", str(out)]) == 0
    assert "4 m from the route in its second quarter" in capsys.readouterr().out  # in words
    assert json.load(open(out))["rules"]
    assert rules.run(["learn", str(tmp_path / "none.jsonl.gz")]) == 2
    assert "No such file" in capsys.readouterr().err
    assert rules.run(["learn", "--store", str(tmp_path / "none.sqlite")]) == 2
    assert "none.sqlite: no such file" in capsys.readouterr().err


def test_learn_reads_the_store_campaign_that_ran_last(tmp_path, capsys):
    from stand_in.fake_pool import FakePool
    from asg_agent.campaign.loop import Campaign
    from asg_agent.campaign.config import CampaignConfig
    from asg_agent.records.store import Store
    from asg_agent.search.methods import make_method

    exp = load_experiment(WIDE)
    path = str(tmp_path / "s.sqlite")
    for name, seed in (("first", 1), ("second", 2)):
        c = Campaign(
            CampaignConfig(
                name=name,
                experiment=exp,
                method=make_method("random", exp, seed),
                store=Store(path),
                pool=FakePool(2, seed=seed),
                total=40,
                seed=seed,
                checkpoint="/x",
                settings={"experiment_file": WIDE},
            )
        )
        c._checkpoint = lambda: None
        c.start()
        c.run(poll_timeout=0.0)
    assert rules.run(["learn", "--store", path]) == 0
    out = capsys.readouterr().out
    assert out.startswith("rules of second (failure findings:") and "in 40 scenarios" in out
    assert rules.run(["learn", "--store", path, "--campaign", "first"]) == 0
    assert capsys.readouterr().out.startswith("rules of first")

"""Issue #78: distinct findings (scoring/places.py), the search that avoids the places already
found (`novelty-ts`), the sampler that knows only a rule (`rule-sampler`), and the campaign that
counts and shows distinct findings first."""

import json
import os

import numpy as np
import pytest

from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.config import CampaignConfig
from asg_agent.records.experiment import load_experiment
from asg_agent.records.store import Store
from asg_agent.scoring import attribution as attr
from asg_agent.scoring.places import NO_CONTACT, DistinctPlaces, count_distinct, distinct_flags, place, place_of_row
from asg_agent.search.methods import make_method
from asg_agent.search.rules import Condition, Rule, load_rule
from asg_scenario.layout import RouteFrame, mesh_of_instances

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
WIDE = os.path.join(REPO, "experiments", "exp1-route-wide.yaml")


def test_a_place_is_the_obstacle_hit_or_where_a_run_without_contact_ended():
    meshes, pos = ["a", "b", "b"], [[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]
    assert place(meshes, pos, 2, [[0, 0], [9, 9]]) == ("b", 5.0, 6.0)
    assert place(meshes, pos, None, [[0, 0], [9, 8]]) == (NO_CONTACT, 9.0, 8.0)
    with pytest.raises(ValueError, match="collision_with 3 names no obstacle of 3"):
        place(meshes, pos, 3, [[0, 0]])
    row = {
        "meshes": meshes,
        "positions": pos,
        "collision_with": 1,
        "termination": "COLLISION",
        "trajectory_xy": [[0, 0]],
    }
    assert place_of_row(row) == ("b", 3.0, 4.0)
    # a timeout's place is where it ended, whatever an old row says it touched
    assert place_of_row(dict(row, termination="STUCK_TIMEOUT"))[0] == NO_CONTACT


def test_distinct_means_at_least_r_from_every_earlier_distinct_place_of_its_class():
    p = [("b", 0.0, 0.0), ("b", 1.99, 0.0), ("b", 2.0, 0.0), ("a", 0.0, 0.0), ("b", 3.5, 0.0), ("b", 1.0, 0.0)]
    # 1.99 m from the first: the same; 2 m: new; another class at the same point: new; 3.5 m is 1.5 m
    # from the third (kept), so the same; the last is within 2 m of both
    assert distinct_flags(p, 2.0) == [True, False, True, True, False, False]
    assert count_distinct(p, 1.0) == 4 and count_distinct(p, 5.0) == 2  # 1 m: 2.0 is 0.01 m from 1.99
    seen = DistinctPlaces(2.0)
    for q in p:
        seen.add(q)
    again = DistinctPlaces.from_state(json.loads(json.dumps(seen.state_dict())))
    assert len(again) == 3 and list(again.near("b", [[1.0, 0.0], [9.0, 9.0]])) == [True, False]
    with pytest.raises(ValueError, match="radius 0"):
        DistinctPlaces(0.0)


def _toy(exp):
    """A made-up stack the methods are not told: it fails on the first obstacle of the scenario's
    second class that stands within 2 m of the route in its middle half, and hits it there."""
    rf, meshes = RouteFrame(exp.scenario), mesh_of_instances(exp.scenario)
    second = sorted(set(meshes))[1]

    def run(a):
        xy = exp.to_positions(a)
        rel = xy - rf.start
        t, d = rel @ rf.along / rf.length**2, rel @ rf.normal
        for k in range(len(meshes)):
            if meshes[k] == second and abs(d[k]) < 2.0 and 0.25 < t[k] < 0.75:
                return 1.0, (meshes[k], float(xy[k, 0]), float(xy[k, 1])), True
        return 0.0, (NO_CONTACT, 80.0, 80.0), False

    return run


def _search(name, exp, seed, n=160, **options):
    run, m, places = _toy(exp), make_method(name, exp, seed, budget=n, options=options or None), []
    for job in range(n):
        a = m.propose(job, 0, 0, None)
        reward, where, finding = run(a)
        m.outcome(job, where, finding)
        m.observe(job, 0, 0, None, a, reward, None, True)
        if finding:
            places.append(where)
    return m, places


def test_novelty_ts_finds_the_failure_in_more_places_than_round_6s_search():
    # round 6's surrogate-ts refines its first hits: many findings, few places. novelty-ts keeps
    # no obstacle on a place already found and refreshes its parents: more distinct findings,
    # at every seed, and more than uniform sampling finds
    exp = load_experiment(WIDE)
    for seed in (1, 2):
        _, old = _search("surrogate-ts", exp, seed)
        m, new = _search("novelty-ts", exp, seed)
        _, rnd = _search("random", exp, seed)
        assert len(old) > len(new)  # the old one repeats itself
        assert count_distinct(new) > count_distinct(old) and count_distinct(new) > count_distinct(rnd), (
            count_distinct(old),
            count_distinct(new),
            count_distinct(rnd),
        )
        # every finding after the first ones is new: the tabu holds
        assert count_distinct(new) >= 0.8 * len(new)
        assert len(m.parents) == count_distinct(new) and sum(m.children) > 0


def test_novelty_ts_is_a_function_of_its_seed_and_resumes_exactly():
    exp = load_experiment(WIDE)
    run = _toy(exp)

    def go(resume_at=None):
        m = make_method("novelty-ts", exp, 5, budget=80, options={"tabu_m": 3.0})
        out = []
        for job in range(80):
            if job == resume_at:
                state = json.loads(json.dumps(m.state_dict()))
                m = make_method("novelty-ts", exp, 5, budget=80, options={"tabu_m": 3.0})
                m.load_state_dict(state)
            a = m.propose(job, 0, 0, None)
            r, where, finding = run(a)
            m.outcome(job, where, finding)
            if job == resume_at:  # an outcome told before the cut is kept by the checkpoint
                state = json.loads(json.dumps(m.state_dict()))
                m = make_method("novelty-ts", exp, 5, budget=80, options={"tabu_m": 3.0})
                m.load_state_dict(state)
            m.observe(job, 0, 0, None, a, r, None, True)
            out.append(a)
        return np.stack(out), m

    (a, ma), (b, _), (c, mc) = go(), go(), go(resume_at=40)
    assert np.array_equal(a, b) and np.array_equal(a, c)
    assert ma.tabu.state_dict() == mc.tabu.state_dict() and ma.config()["tabu_m"] == 3.0


def test_novelty_ts_names_no_class_size_or_place():
    src = open(os.path.join(REPO, "catkin_ws/src/asg_agent/src/asg_agent/search/novelty.py")).read().lower()
    from asg_scenario.catalogue import mesh_names

    for name in mesh_names():
        assert name not in src, name


def test_rule_sampler_draws_only_layouts_that_satisfy_its_rule(tmp_path):
    exp = load_experiment(WIDE)
    m0 = make_method("surrogate-ts", exp, 0)
    names = m0.features.names()
    cls = m0.features.classes[1]
    rule = Rule((Condition(f"{cls} d<2m q2", True, 1.0), Condition(f"{m0.features.classes[0]} d<2m q2", False, 1.0)))
    f = tmp_path / "rule.json"
    f.write_text(json.dumps({"rules": [{"rule": rule.to_dict()}]}))
    assert load_rule(str(f)) == rule
    m = make_method("rule-sampler", exp, 3, options={"rule_file": str(f)})
    got = np.stack([m.propose(j, 0, 0, None) for j in range(60)])
    assert rule.holds(m0.features.of_actions(got), names).all()
    # the same sampler without the rule (random) satisfies it rarely
    rnd = np.stack([make_method("random", exp, 3).propose(j, 0, 0, None) for j in range(300)])
    assert rule.holds(m0.features.of_actions(rnd), names).mean() < 0.3
    # a function of (seed, job)
    again = make_method("rule-sampler", exp, 3, options={"rule_file": str(f)})
    assert np.array_equal(again.propose(7, 0, 0, None), got[7])
    # bad rules are named
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"conditions": [["no such feature", ">=", 1]]}))
    with pytest.raises(ValueError, match="no feature 'no such feature'"):
        make_method("rule-sampler", exp, 3, options={"rule_file": str(bad)})
    bad.write_text(json.dumps({"conditions": [[f"{cls} d<2m q2", "==", 1]]}))
    with pytest.raises(ValueError, match="operator '=='"):
        load_rule(str(bad))
    bad.write_text("{")
    with pytest.raises(ValueError, match="not JSON"):
        load_rule(str(bad))
    with pytest.raises(ValueError, match="needs a rule file"):
        make_method("rule-sampler", exp, 3)
    impossible = tmp_path / "never.json"
    impossible.write_text(json.dumps({"conditions": [[f"{cls} d<2m q2", ">=", 99]]}))
    with pytest.raises(ValueError, match="holds for none of"):
        make_method("rule-sampler", exp, 3, options={"rule_file": str(impossible)}).propose(0, 0, 0, None)


def test_a_campaign_tells_its_search_each_place_and_counts_distinct_findings_in_job_order():
    exp = load_experiment(WIDE)
    store = Store(":memory:")
    collide = {3, 4, 7, 11, 15}
    m = make_method("novelty-ts", exp, 2, budget=20)
    told = []
    outcome = m.outcome
    m.outcome = lambda job, where, finding: (told.append((job, where, finding)), outcome(job, where, finding))
    c = Campaign(
        CampaignConfig(
            name="d",
            experiment=exp,
            method=m,
            store=store,
            pool=FakePool(2, collide_jobs=collide),
            total=20,
            seed=2,
            checkpoint="/x",
            slots=4,
            reward="flaw",
            references={attr.FULL: FakePool(1, gain=0.0, prefix="f"), attr.TRUTH: FakePool(1, gain=0.0, prefix="g")},
        )
    )
    c._checkpoint = lambda: None
    c.start()
    c.run(poll_timeout=0.0)
    assert [t[0] for t in told] == list(range(20))  # in job order
    rows = {r["job"]: dict(r) for r in store.rows("d")}
    flaw = {j for j, r in rows.items() if r["attribution"] == "flaw"}
    assert collide <= flaw and {t[0] for t in told if t[2]} == flaw  # the flaw findings, and only they
    from asg_agent.campaign.findings import distinct_summary, findings

    found = findings(store, "d")
    assert [f["job"] for f in found] == sorted(flaw)
    for f in found:  # the store's summary and the search see the same place
        assert f["place"] == [t[1] for t in told if t[0] == f["job"]][0]
    d = distinct_summary(found)
    assert c.status()["findings"] == len(flaw) and c.status()["distinct"] == d["distinct"][2.0]
    from asg_agent.cli.campaign import BAR_FIELDS, bar_fields, bar_text

    # the bar names the reward whose findings it counts, how many are distinct, the rate and the
    # re-runs: at most six fields, the flaw count once, the paper's proxy off it under another reward
    text = bar_text(c.status())
    assert text.startswith(f"flaw findings {len(flaw)}  distinct {d['distinct'][2.0]} (2 m)  ")
    assert " rerun " in text and "proxy" not in text and " model " not in text and text.count("flaw") == 1
    full = dict(c.status(), errors=2, coverage={"covered": 4, "known": 67}, diff_best=1.5, reward="differential")
    assert len(bar_fields(full)) <= BAR_FIELDS == 6 and "covered 4/67" in bar_text(full) and " 2 err" in bar_text(full)
    proxy = dict(c.status(), reward="proxy", findings=0, distinct=0)  # route-random's reward:=proxy
    assert bar_text(proxy).startswith("proxy findings 0  distinct 0 (2 m)  ") and "best proxy " in bar_text(proxy)
    assert d["distinct"][1.0] >= d["distinct"][2.0] >= d["distinct"][5.0] >= 1


def test_a_rule_reads_in_words_with_counts_bins_and_quarters_spelt_out():
    r = Rule(
        (
            Condition("barberry d>=20m q1", True, 1.5),
            Condition("barberry d<2m q2", False, 0.5),
            Condition("juniper shadow d<4m", True, 0.5),
            Condition("juniper d<4m q3", False, 2.5),
        )
    )
    assert r.words((2.0, 4.0, 7.0, 10.0, 20.0)) == (
        "2 or more barberries 20 m or more from the route in its first quarter; and no barberry within 2 m of "
        "the route in its second quarter; and a juniper whose shadow comes between 2 and 4 m from the route; "
        "and at most 2 junipers between 2 and 4 m from the route in its third quarter"
    )
    assert Rule((Condition("action[16]", True, 0.5),)).words() == "action[16] >= 0.5"  # no place feature: as written

"""Three-stack attribution (issue #36): the rule on its own, and a campaign with stand-in stacks
under test, `full` and `ground_truth` that fail on chosen jobs: every class, the reverse cases,
the candidate rule (a non-candidate is never re-run, a candidate always is, on every reference),
a resume with reference runs still out, and a search that does not depend on its references."""

import json
import os

import pytest

from asg_agent.records.experiment import load_experiment
from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.config import CampaignConfig, FunctionCallback
from asg_agent.records.store import Store
from asg_agent.scoring import attribution as attr
from asg_agent.scoring.attribution import RunOutcome as R
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")

OK = R("SUCCESS", 1.1)  # clear
NEAR = R("SUCCESS", 2.5)  # passes, not clear
HIGH = R("SUCCESS", 3.2)  # a finding by the proxy
HIT = R("COLLISION", 0.9)
STUCK = R("STUCK_TIMEOUT", 1.4)


@pytest.mark.parametrize(
    "test,full,truth,want",
    [
        (HIT, OK, OK, "flaw"),
        (HIGH, OK, OK, "flaw"),
        (STUCK, OK, OK, "flaw"),
        (HIT, HIT, OK, "model"),
        (HIT, HIGH, NEAR, "model"),
        (HIT, OK, HIT, "stack"),
        (HIT, HIT, HIGH, "stack"),
        (HIT, NEAR, OK, "unclear"),
        (HIT, OK, NEAR, "unclear"),
        (NEAR, HIT, OK, "reverse"),
        (OK, OK, STUCK, "reverse"),
        (NEAR, NEAR, OK, "pass"),
        (R("ERROR", None), OK, OK, "error"),
        (HIT, R("ERROR", None), OK, "error"),
    ],
)
def test_every_class_of_the_rule(test, full, truth, want):
    assert attr.classify(test, {attr.FULL: full, attr.TRUTH: truth}) == want


def test_single_reference_mode_and_the_candidate_rule():
    assert attr.classify(HIT, {attr.TRUTH: OK}) == "perception"
    assert attr.classify(HIT, {attr.TRUTH: NEAR}) == "unclear"
    assert attr.classify(HIGH, {attr.TRUTH: HIGH}) == "stack"
    assert attr.classify(OK, {attr.TRUTH: HIT}) == "reverse"
    with pytest.raises(ValueError, match="ground_truth"):
        attr.classify(HIT, {attr.FULL: OK})
    # Candidates: every failure, and passes at or above CANDIDATE; never an ERROR.
    assert attr.is_candidate("COLLISION", 0.5) and attr.is_candidate("OUT_OF_BOUNDS", 1.0)
    assert attr.is_candidate("SUCCESS", attr.CANDIDATE) and not attr.is_candidate("SUCCESS", attr.CANDIDATE - 1e-6)
    assert not attr.is_candidate("ERROR", None) and not attr.is_candidate("SUCCESS", None)
    # Whatever fails is a candidate, so the rule can miss no flaw, model or stack finding.
    for term in attr.FAILED_TERMINATIONS + ("SUCCESS",):
        for proxy in (0.5, 1.9, 2.0, 2.9, 3.0, 7.0):
            if attr.fails(term, proxy):
                assert attr.is_candidate(term, proxy)


# Stand-in stacks (FakePool: a wiggle of `gain` m per nearby obstacle; collide_jobs end halfway in a
# collision). With gain 0 a run follows the optimal path: proxy about 1, clear.
TEST_COLLIDES = {3, 5, 7, 9}
FULL_COLLIDES = {5, 9, 13}
TRUTH_COLLIDES = {7, 9, 11}
WANT = {3: "flaw", 5: "model", 7: "stack", 9: "stack"}


def three_stack(tmp_path, name, candidates="failures", total=24, store=None, pools=None):
    exp = load_experiment(EXP)
    store = store or Store(str(tmp_path / "s.sqlite"))
    pools = pools or (
        FakePool(2, seed=1, gain=0.0, collide_jobs=TEST_COLLIDES),
        FakePool(1, seed=2, gain=0.0, prefix="fake_full", collide_jobs=FULL_COLLIDES),
        FakePool(1, seed=3, gain=0.0, prefix="fake_gt", collide_jobs=TRUTH_COLLIDES),
    )
    c = Campaign(
        CampaignConfig(
            name=name,
            experiment=exp,
            method=make_method("random", exp, 5, budget=total),
            store=store,
            pool=pools[0],
            total=total,
            seed=5,
            checkpoint=str(tmp_path / f"{name}.ckpt"),
            slots=4,
            references={attr.FULL: pools[1], attr.TRUTH: pools[2]},
            candidates=candidates,
        )
    )
    return c, store, pools


def test_candidates_run_on_every_reference_and_nothing_else_does(tmp_path):
    c, store, (test, full, truth) = three_stack(tmp_path, "f")
    seen = []
    c.add_callback(FunctionCallback(attributed=lambda job, label, counts: seen.append((job, label))))
    c.start()
    s = c.run(poll_timeout=0.0)
    rows = {r["job"]: dict(r) for r in store.rows("f")}
    assert sorted(rows) == list(range(24))
    candidates = {j for j, r in rows.items() if attr.is_candidate(r["termination"], r["proxy"])}
    assert candidates == TEST_COLLIDES  # every other run is clear
    # A candidate runs once on each reference, a non-candidate on none.
    assert sorted(full.submitted) == sorted(candidates) and sorted(truth.submitted) == sorted(candidates)
    for j, r in rows.items():
        if j in candidates:
            assert r["attribution"] == WANT[j], (j, r["attribution"])
            runs = json.loads(r["reference_runs"])
            assert set(runs) == {attr.FULL, attr.TRUTH}
            assert runs[attr.FULL]["termination"] == ("COLLISION" if j in FULL_COLLIDES else "SUCCESS")
            assert runs[attr.TRUTH]["termination"] == ("COLLISION" if j in TRUTH_COLLIDES else "SUCCESS")
            assert json.loads(r["reference"])["termination"] == runs[attr.TRUTH]["termination"]
        else:
            assert r["attribution"] == attr.NOT_CANDIDATE and r["reference_runs"] is None
        assert r["reward"] == r["proxy"]  # the search learns from the stack under test alone
    # Job 11 (ground truth collides, the stack under test does not) is a reverse case the rule
    # does not see: it was not re-run, and the summary says how many were not.
    assert s["classes"]["flaw"] == 1 and s["classes"]["model"] == 1 and s["classes"]["stack"] == 2
    assert s["classes"][attr.NOT_CANDIDATE] == 20 and s["classes"][attr.PENDING] == 0
    assert c.status()["classes"] == s["classes"]
    assert sorted(seen) == sorted((j, WANT[j]) for j in candidates)


def test_every_scenario_rerun_finds_the_reverse_cases(tmp_path):
    c, store, (test, full, truth) = three_stack(tmp_path, "a", candidates="all")
    c.start()
    s = c.run(poll_timeout=0.0)
    rows = {r["job"]: dict(r) for r in store.rows("a")}
    assert sorted(full.submitted) == list(range(24)) == sorted(truth.submitted)
    assert rows[11]["attribution"] == "reverse" and rows[13]["attribution"] == "reverse"
    assert s["classes"]["reverse"] == 2 and s["classes"]["pass"] == 24 - 4 - 2
    assert s["classes"][attr.NOT_CANDIDATE] == 0


def test_a_resume_reruns_the_references_still_out_and_the_search_ignores_them(tmp_path):
    c, store, _ = three_stack(tmp_path, "r")
    c.start()
    c.run(poll_timeout=0.0)
    before = {r["job"]: (r["attribution"], r["reference_runs"]) for r in store.rows("r")}
    # As if stopped while jobs 3 and 7 were on the reference workers.
    store.db.execute("UPDATE scenarios SET attribution = 'pending', reference_runs = NULL WHERE job IN (3, 7)")
    c2, _, (_, full, truth) = three_stack(tmp_path, "r", store=store)
    c2.resume()
    c2.run(poll_timeout=0.0)
    assert sorted(full.submitted) == [3, 7] == sorted(truth.submitted)
    after = {r["job"]: (r["attribution"], r["reference_runs"]) for r in store.rows("r")}
    assert after == before
    # The same seed without any reference stack proposes and stores the same scenarios.
    exp = load_experiment(EXP)
    plain = Campaign(
        CampaignConfig(
            name="p",
            experiment=exp,
            method=make_method("random", exp, 5, budget=24),
            store=store,
            pool=FakePool(2, seed=9, gain=0.0, collide_jobs=TEST_COLLIDES),
            total=24,
            seed=5,
            checkpoint=str(tmp_path / "p.ckpt"),
            slots=4,
        )
    )
    plain.start()
    plain.run(poll_timeout=0.0)
    assert store.content_digest("p") == store.content_digest("r")


@pytest.mark.parametrize(
    "references, extra, match",
    [
        ({attr.FULL: 1}, dict(slots=2), "ground_truth"),
        ({"mine": 1}, dict(slots=2), "roles"),
        ({attr.TRUTH: 1}, dict(candidates="some"), "candidates"),
        ({attr.TRUTH: 1}, dict(reward="differential"), "every scenario"),
    ],
)
def test_reference_roles_and_rules_are_checked(references, extra, match):
    exp = load_experiment(EXP)
    with pytest.raises(ValueError, match=match):
        Campaign(
            CampaignConfig(
                name="x",
                experiment=exp,
                method=make_method("random", exp, 0, budget=4),
                store=None,
                pool=FakePool(1),
                total=4,
                seed=0,
                checkpoint="/tmp/x",
                references={role: FakePool(n) for role, n in references.items()},
                **extra,
            )
        )


def test_export_and_summary_show_the_classes(tmp_path):
    from asg_agent.records.export import counts, export, read_export

    c, store, _ = three_stack(tmp_path, "e")
    c.start()
    s = c.run(poll_timeout=0.0)
    export(store, "e", str(tmp_path / "e.jsonl.gz"))
    _, rows = read_export(str(tmp_path / "e.jsonl.gz"))
    assert counts(rows)["classes"] == s["classes"]
    assert {r["job"]: r["attribution"] for r in rows if r["attribution"] in attr.FINDINGS} == WANT
    assert all(set(r["reference_runs"]) == {attr.FULL, attr.TRUTH} for r in rows if r["job"] in WANT)

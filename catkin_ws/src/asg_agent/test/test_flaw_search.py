"""Issue #67: the search that learns what exposes the flaw: the route-wide action space, the `flaw`
reward (attribution's verdicts as a signal) and `surrogate-ts` (credit per obstacle, Thompson
sampling)."""

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
from asg_agent.scoring import rewards as rw
from asg_agent.search.methods import make_method
from asg_scenario.layout import RouteFrame
from stand_ins import refused

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
WIDE = os.path.join(REPO, "experiments", "exp1-route-wide.yaml")


def _route_coords(exp, xy):
    r = RouteFrame(exp.scenario)
    rel = np.asarray(xy, float) - r.start
    return rel @ r.along / r.length**2, rel @ r.normal


def test_route_wide_reaches_the_square_between_the_safety_radii_and_keeps_half_in_the_band():
    exp = load_experiment(WIDE)
    assert exp.action_space == "route-wide"
    r = RouteFrame(exp.scenario)
    lo, hi = r.t_range
    # half of the lateral range is the band, linear in it; the ends reach the farthest corner
    v = np.linspace(-1.0, 1.0, 401)
    d = exp.lateral_m(v)
    assert np.allclose(d[np.abs(v) <= 0.5], 20.0 * v[np.abs(v) <= 0.5])
    assert d[-1] == pytest.approx(r.edge_m) and d[0] == pytest.approx(-r.edge_m) and r.edge_m > 50.0
    assert np.all(np.diff(d) > 0)  # one to one
    # what it cannot reach (issue #78; experiment.py says so): the corners whose projection on the
    # route falls behind the start's safety radius or beyond the goal's, a quarter of the square
    # outside the safety discs; and uniform obstacles clipped onto the border
    rng = np.random.default_rng(5)
    sq = rng.uniform(0.0, exp.size, (200000, 2))
    op = exp.scenario["operational"]
    outside = (np.hypot(*(sq - r.start).T) > op["safety_radius"]) & (
        np.hypot(sq[:, 0] - op["goal_x"], sq[:, 1] - op["goal_y"]) > op["safety_radius"]
    )
    ts, _ = _route_coords(exp, sq)
    unreachable = outside & ((ts < lo) | (ts > hi))
    assert 0.24 < unreachable.sum() / outside.sum() < 0.26
    u, v = rng.uniform(-1.0, 1.0, (2, 20000))
    raw = r.start + (lo + (u + 1.0) / 2.0 * (hi - lo))[:, None] * r.along + exp.lateral_m(v)[:, None] * r.normal
    assert 0.12 < ((raw < 0.0) | (raw > exp.size)).any(axis=1).mean() < 0.14
    # any point of the square between the safety radii is some action's place (to 1 mm)
    pts = rng.uniform(0.0, exp.size, (300, 2))
    t, dd = _route_coords(exp, pts)
    pts, t, dd = pts[(t > lo) & (t < hi)], t[(t > lo) & (t < hi)], dd[(t > lo) & (t < hi)]
    u = (t - lo) / (hi - lo) * 2.0 - 1.0
    grid = np.linspace(-1.0, 1.0, 200001)
    vv = np.interp(dd, exp.lateral_m(grid), grid)
    n = exp.position_dim // 2
    for k in range(0, len(pts) - n, n):
        action = np.stack([u[k : k + n], vv[k : k + n]], axis=1).ravel()
        assert np.abs(exp.to_positions(action) - pts[k : k + n]).max() < 2e-3
    # uniform actions: about half the obstacles in the band, the rest spread out to the edge
    far = exp.positions_of(rng.uniform(-1.0, 1.0, (500, exp.action_dim)))
    _, side = _route_coords(exp, far.reshape(-1, 2))
    assert 0.45 < np.mean(np.abs(side) <= 10.0 + 1e-6) < 0.6 and np.abs(side).max() > 40.0


def test_flaw_reward_is_one_for_a_flaw_finding_graded_below_half_for_a_near_one_zero_when_full_fails():
    assert rw.flaw_reward("flaw", 1.2, 0.0, "SUCCESS", 1.1, 3.0) == 1.0
    assert rw.flaw_reward("model", 1.2, 0.0, "COLLISION", 0.9, 0.0) == 0.0
    assert rw.flaw_reward("stack", 4.0, 0.0, "STUCK_TIMEOUT", 4.0, 0.0) == 0.0
    g = rw.flaw_reward("unclear", 3.5, 0.2, "SUCCESS", 2.5, 2.0)
    assert 0.0 < g < rw.GRADED_CAP
    # larger as the stack under test does worse than `full` did on the same layout
    assert rw.flaw_reward("pass", 2.2, 2.0, "SUCCESS", 1.2, 4.0) > rw.flaw_reward("pass", 2.2, 3.5, "SUCCESS", 2.0, 4.0)
    assert rw.flaw_reward("pass", 9.0, 0.0, "SUCCESS", 0.0, 9.0) < rw.GRADED_CAP
    assert rw.flaw_reward("pass", 1.0, 5.0, "SUCCESS", 2.0, 3.0) == 0.0  # did better than full: nothing


def _campaign(name, exp, method, store, total, collide=(), workers=2):
    c = Campaign(
        CampaignConfig(
            name=name,
            experiment=exp,
            method=method,
            store=store,
            pool=FakePool(workers, collide_jobs=collide),
            total=total,
            seed=method.seed,
            checkpoint="/x",
            slots=4,
            reward="flaw",
            references={attr.FULL: FakePool(1, gain=0.0, prefix="f"), attr.TRUTH: FakePool(1, gain=0.0, prefix="g")},
        )
    )
    c._checkpoint = lambda: None
    c.start()
    c.run(poll_timeout=0.0)
    return list(store.rows(name))


def test_a_campaign_learns_from_the_flaw_reward_of_its_candidates():
    exp = load_experiment(WIDE)
    store = Store(":memory:")
    collide = {2, 5, 9}  # the stand-in stack under test collides on these; its references do not
    rows = _campaign("f", exp, make_method("random", exp, 1, budget=12), store, 12, collide)
    assert len(rows) == 12
    assert all(r["attribution"] == "flaw" for r in rows if r["job"] in collide)
    for r in rows:
        if r["attribution"] == "flaw":
            assert r["reward"] == 1.0
        elif r["attribution"] == attr.NOT_CANDIDATE:
            assert r["reward"] == rw.NON_CANDIDATE_FLAW
        else:
            assert 0.0 <= r["reward"] < rw.GRADED_CAP and json.loads(r["reference_runs"])["full"]
    assert "the flaw reward needs the 'full' reference" in str(refused(exp, store, "flaw", [attr.TRUTH], "g"))


def _wide_features(m, actions):
    return m.features.of_actions(np.asarray(actions))


def test_surrogate_ts_learns_which_obstacles_earn_the_reward_from_results_alone():
    # A made-up rule the method is not told: the reward is how many obstacles of the scenario's
    # second class stand within 2 m of the route in its second quarter, minus a penalty for the
    # first class near the route. The share of such obstacles among its proposals grows.
    exp = load_experiment(WIDE)
    m = make_method("surrogate-ts", exp, 3, budget=200)
    assert m.init_random == 20
    names = m.features.names()
    good = [k for k, s in enumerate(names) if s.startswith(m.features.classes[1]) and s.endswith("d<2m q2")]
    bad = [k for k, s in enumerate(names) if s.startswith(m.features.classes[0]) and ("d<2m" in s or "d<4m" in s)]
    assert len(good) == 1 and len(bad) == 2 * 4 + 2  # four quarters and the shadow, two bins each

    def reward(a):
        f = _wide_features(m, [a])[0]
        return float(f[good].sum() - 0.5 * f[bad].sum() > 0.5)

    got = []
    for job in range(200):
        a = m.propose(job, 0, 0, None)
        got.append(reward(a))
        m.observe(job, 0, 0, None, a, got[-1], None, True)
    early, late = np.mean(got[:20]), np.mean(got[-60:])
    assert late > 0.5 and late > 4 * max(early, 0.05), (early, late)
    # the rule's own cell has its class's largest credit (credits compare within a class's block:
    # the block's cells sum to the class's count in every layout, and its weights sum to zero)
    cls = m.features.classes[1]
    assert names.index(m.credit(1, within=cls)[0][0]) == good[0]
    block = [k for k, s in enumerate(names) if s.startswith(cls + " ") and " q" in s]
    assert len(block) == 4 * m.features.n_lat and abs(m.model.coef_[block].sum()) < 1e-6


def test_surrogate_ts_is_a_function_of_its_seed_and_resumes_exactly():
    exp = load_experiment(WIDE)

    def run(n, resume_at=None):
        m = make_method("surrogate-ts", exp, 9, budget=100)
        out = []
        for job in range(n):
            if job == resume_at:
                state = m.state_dict()
                m = make_method("surrogate-ts", exp, 9, budget=100)
                m.load_state_dict(json.loads(json.dumps(state)))
            a = m.propose(job, 0, 0, None)
            m.observe(job, 0, 0, None, a, float(np.sin(7.0 * a[:4]).sum()), None, True)
            out.append(a)
        return np.stack(out)

    a, b, c = run(40), run(40), run(40, resume_at=25)
    assert np.array_equal(a, b) and np.array_equal(a, c)
    assert not np.array_equal(
        a, np.stack([make_method("surrogate-ts", exp, 8).propose(j, 0, 0, None) for j in range(40)])
    )


def test_surrogate_ts_names_no_class_size_or_place():
    # learns, does not know: the method's source names none of the scenario's classes, and its
    # features are the same for every class of any scenario
    src = open(os.path.join(REPO, "catkin_ws/src/asg_agent/src/asg_agent/search/surrogate.py")).read().lower()
    from asg_scenario.catalogue import mesh_names

    for name in mesh_names():
        assert name not in src, name
    for f in ("exp1.yaml", "exp2.yaml", "exp4.yaml"):
        exp = load_experiment(os.path.join(REPO, "experiments", f))
        m = make_method("surrogate-ts", exp, 0)
        per = m.features.per_class
        assert m.features.dim == len(m.features.classes) * per + exp.action_dim - exp.position_dim
        assert {s.split(" ", 1)[1] for s in m.features.names()[:per]} == {
            s.split(" ", 1)[1] for s in m.features.names()[per : 2 * per]
        } or len(m.features.classes) == 1


# -- any stack pair (issue #67): a registration names its reference; regressions ----------------


def test_a_registration_names_its_reference_and_a_pair_is_classed_regression_or_shared():
    from asg_agent.records import stacks

    rc = stacks.load("depth_rc")
    assert rc.reference == "depth" and rc.reference_file == stacks.resolve("depth")
    assert stacks.load("depth").reference_file == ""
    o = attr.RunOutcome
    release = attr.RELEASE
    assert attr.classify(o("COLLISION", 1.1), {release: o("SUCCESS", 1.2)}) == "regression"
    assert attr.classify(o("COLLISION", 1.1), {release: o("COLLISION", 1.0)}) == "shared"
    assert attr.classify(o("SUCCESS", 3.5), {release: o("SUCCESS", 2.5)}) == "unclear"
    assert attr.classify(o("SUCCESS", 1.5), {release: o("STUCK_TIMEOUT", 1.0)}) == "reverse"
    assert attr.classify(o("SUCCESS", 2.1), {release: o("SUCCESS", 2.1)}) == "pass"
    assert attr.classify(o("ERROR", None), {release: o("SUCCESS", 1.0)}) == "error"
    with pytest.raises(ValueError, match="'ground_truth' or the 'release' reference"):
        attr.classify(o("COLLISION", 1.1), {attr.FULL: o("SUCCESS", 1.0)})


def test_the_registration_refuses_a_reference_that_is_not_a_stack(tmp_path):
    from asg_agent.records import stacks

    body = open(os.path.join(REPO, "stacks", "depth_rc.launch")).read()
    for ref, msg in (("nowhere", "'nowhere' is not a registered stack"), ("[1, 2]", "reference: \\[1, 2\\], must be")):
        f = tmp_path / "r.launch"
        f.write_text(body.replace("reference: depth", f"reference: {ref}"))
        with pytest.raises(stacks.RegistrationError, match=msg):
            stacks.read(str(f)).reference_file


def test_train_sh_adds_the_release_and_the_launch_check_refuses_a_pair_without_one():
    from asg_agent.cli.launch_args import launch_args
    from asg_agent.records import stacks
    from asg_agent.records.experiment import ExperimentError

    rc = os.path.join(REPO, "experiments", "exp1-depth-rc.yaml")
    assert launch_args([f"experiment:={rc}"]) == ["stack:=depth_rc", f"release_stack:={stacks.resolve('depth')}"]
    assert (
        launch_args([f"experiment:={rc}", "attribution:=release", "stack:=depth_rc", "release_stack:=depth"], True)
        == []
    )
    with pytest.raises(
        ExperimentError,
        match="release_stack:=.*depth.launch is the experiment's, the launch has release_stack:=gap_nav",
    ):
        launch_args([f"experiment:={rc}", "attribution:=release", "stack:=depth_rc", "release_stack:=gap_nav"], True)
    with pytest.raises(ExperimentError, match="depth names none"):
        launch_args([f"experiment:={os.path.join(REPO, 'experiments', 'exp1-depth.yaml')}", "attribution:=release"])


def test_a_pair_campaign_learns_from_its_regressions():
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1-depth-rc-wide.yaml"))
    store = Store(":memory:")
    collide = {1, 4}
    c = Campaign(
        CampaignConfig(
            name="p",
            experiment=exp,
            method=make_method("surrogate-ts", exp, 2, budget=12),
            store=store,
            pool=FakePool(2, collide_jobs=collide),
            total=12,
            seed=2,
            checkpoint="/x",
            slots=4,
            reward="regression",
            references={attr.RELEASE: FakePool(1, gain=0.0, prefix="r")},
        )
    )
    c._checkpoint = lambda: None
    c.start()
    c.run(poll_timeout=0.0)
    rows = list(store.rows("p"))
    assert len(rows) == 12 and all(
        r["attribution"] == "regression" and r["reward"] == 1.0 for r in rows if r["job"] in collide
    )
    assert all(r["reward"] == rw.NON_CANDIDATE_FLAW for r in rows if r["attribution"] == attr.NOT_CANDIDATE)
    assert all(
        r["reference"] is None and "release" in json.loads(r["reference_runs"]) for r in rows if r["reference_runs"]
    )
    assert "the regression reward needs the 'release' reference" in str(
        refused(exp, store, "regression", [attr.TRUTH], "q")
    )


def test_a_flaw_campaign_cut_with_candidates_pending_resumes_each_scenario_once(tmp_path):
    # found resuming the v3 pilot: a stored candidate whose references were still out at the cut
    # was proposed again on resume and run a second time ("already holds job N")
    import sys

    sys.path.insert(0, os.path.dirname(__file__))
    from stand_ins import DyingPool, Interrupt

    exp = load_experiment(WIDE)
    store = Store(str(tmp_path / "s.sqlite"))

    def make(name, pool, seed_refs):
        refs = {
            attr.FULL: FakePool(1, seed=seed_refs, gain=0.0, prefix="f"),
            attr.TRUTH: FakePool(1, seed=seed_refs + 1, gain=0.0, prefix="g"),
        }
        c = Campaign(
            CampaignConfig(
                name=name,
                experiment=exp,
                method=make_method("surrogate-ts", exp, 4, budget=30),
                store=store,
                pool=pool,
                total=30,
                seed=4,
                checkpoint=str(tmp_path / f"{name}.ckpt"),
                slots=4,
                checkpoint_every=1,
                reward="flaw",
                references=refs,
                collision_bonus=2.0,
            )
        )
        return c

    ref = make("ref", FakePool(2, seed=1, collide_jobs={3, 7, 12, 20}), 10)
    ref.start()
    ref.run(poll_timeout=0.0)
    cut = make("cut", DyingPool(17, workers=2, seed=2, collide_jobs={3, 7, 12, 20}), 20)
    cut.start()
    with pytest.raises(Interrupt):
        cut.run(poll_timeout=0.0)
    assert store.pending_references("cut")  # candidates were still out at the cut
    again = make("cut", FakePool(2, seed=3, collide_jobs={3, 7, 12, 20}), 30)
    again.resume()
    again.run(poll_timeout=0.0)
    assert store.jobs("cut") == list(range(30))
    assert store.content_digest("cut") == store.content_digest("ref")

"""Issue #37's arms and statistics: route-biased random layouts, and the statistics over seeds."""

import json
import os

import numpy as np
import pytest

from asg_agent.records.experiment import load_experiment
from asg_agent.search.methods import make_method
from stand_ins import refused

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")


def _xy(exp, action):
    return (np.asarray(action[: exp.position_dim], float).reshape(-1, 2) + 1.0) * 0.5 * exp.size


def test_route_random_puts_every_obstacle_in_its_band_and_repeats():
    exp = load_experiment(EXP)
    op = exp.scenario["operational"]
    a, b = np.array([op["start_x"], op["start_y"]]), np.array([op["goal_x"], op["goal_y"]])
    m = make_method("route-random", exp, 4, options={"band": 3.0})
    for job in range(50):
        xy = _xy(exp, m.propose(job, 0, 0, None))
        t = ((xy - a) @ (b - a)) / ((b - a) @ (b - a))
        d = np.abs(np.cross(b - a, xy - a)) / np.linalg.norm(b - a)
        assert (d <= 3.0 + 1e-3).all()
        # beyond the safety radius around start and goal (obstacles there are removed)
        assert (np.linalg.norm(xy - a, axis=1) >= op["safety_radius"] - 3.01).all()
        assert (np.linalg.norm(xy - b, axis=1) >= op["safety_radius"] - 3.01).all()
        assert ((t > 0) & (t < 1)).all()
    again = make_method("route-random", exp, 4, options={"band": 3.0})
    assert np.array_equal(m.propose(17, 3, 2, None), again.propose(17, 0, 0, None))  # (seed, job) alone
    assert not np.array_equal(m.propose(17, 0, 0, None), m.propose(18, 0, 0, None))
    # share 0: uniform layouts, most obstacles far from the route
    far = make_method("route-random", exp, 4, options={"band": 3.0, "share": 0.0})
    xy = np.concatenate([_xy(exp, far.propose(j, 0, 0, None)) for j in range(50)])
    d = np.abs(np.cross(b - a, xy - a)) / np.linalg.norm(b - a)
    assert (d > 3.0).mean() > 0.8
    with pytest.raises(ValueError, match="band"):
        make_method("route-random", exp, 0, options={"band": 0.0})


def test_failure_modes_of_findings():
    from asg_agent.records import failure_modes as fm
    from asg_scenario.layout import with_positions

    exp = load_experiment(EXP)
    n = exp.position_dim // 2
    # Obstacle 0 on the route's left at 60 % of it, obstacle 1 on its right at 30 %, the rest far away.
    a, b = np.array([20.0, 20.0]), np.array([80.0, 80.0])
    normal = np.array([-1.0, 1.0]) / np.sqrt(2.0)
    pos = [a + 0.6 * (b - a) + 2.0 * normal, a + 0.3 * (b - a) - 3.0 * normal] + [
        [5.0 + 3 * k, 95.0] for k in range(n - 2)
    ]
    pos = [list(map(float, p)) for p in pos]
    req = with_positions(exp.scenario, pos)
    meshes = [l["mesh_name"] for l in req["structural"]["layouts"] for _ in l["instances"]]
    line = [list(a + s * (b - a)) for s in np.linspace(0.0, 0.58, 60)]
    hit = {"termination": "COLLISION", "collision_with": 0, "trajectory_xy": line, "positions": pos, "meshes": meshes}
    m = fm.mode(hit, req)
    assert m[0] == meshes[0] and m[1] == 2 and m[2] == "left" and m[3] in ("shadow", "lit")
    m1 = fm.mode(dict(hit, collision_with=1), req)
    assert m1[:3] == (meshes[1], 2, "right")  # the failure point, not the obstacle, sets `along`
    weave = [
        list(a + s * (b - a) + (4.0 * np.sin(np.pi * s) if 0.2 < s < 0.4 else 0.0) * normal)
        for s in np.linspace(0, 1, 80)
    ]
    high = {
        "termination": "SUCCESS",
        "collision_with": None,
        "trajectory_xy": weave,
        "positions": pos,
        "meshes": meshes,
    }
    assert fm.mode(high, req)[:3] == ("none", 1, "none")  # farthest from the route at 30 %
    assert fm.distinct([m, m, m1]) == 2
    assert fm.cells(["juniper", "barberry", "juniper"]) == (2 * 3 + 1) * fm.ROUTE_BINS * 2
    assert fm.coverage([m, m1], ["juniper", "barberry"]) == 2 / 56


def test_shadow_ahead_is_the_point_by_point_answer():
    """shadow_ahead asks about its 20 x 11 grid at once (asg_scenario.votes.shadow_mask): the
    same answer as asking in_cast_shadow point by point, on random layouts, suns and trajectories."""
    from asg_agent.records.scenes import shadow_ahead
    from asg_scenario.layout import with_positions
    from asg_scenario.votes import in_cast_shadow

    def by_point(req, xy, i):
        j = min(len(xy) - 1, i + 10)
        h = xy[j] - xy[i] if j > i else xy[i] - xy[max(0, i - 10)]
        if np.linalg.norm(h) < 1e-6:
            return False
        h = h / np.linalg.norm(h)
        n = np.array([-h[1], h[0]])
        return any(
            in_cast_shadow(req, *(xy[i] + a * h + b * n)) for a in np.arange(1.0, 20.5) for b in np.arange(-5.0, 5.5)
        )

    exp = load_experiment(EXP)
    rng = np.random.default_rng(3)
    answers = []
    for _ in range(60):
        req = with_positions(exp.scenario, rng.uniform(0.0, 100.0, (exp.position_dim // 2, 2)).tolist())
        req["textural"].update(sun_inclination_deg=float(rng.uniform(3, 60)), sun_yaw_deg=float(rng.uniform(0, 360)))
        xy = np.cumsum(rng.normal(0.3, 0.4, (80, 2)), axis=0) + 20.0
        for i in (0, 40, 79):
            answers.append(shadow_ahead(req, xy, i))
            assert answers[-1] is by_point(req, xy, i)
    assert 0 < sum(answers) < len(answers)


def test_dense_rewards_see_how_close_a_run_came():
    from stand_in.fake_pool import FakePool
    from asg_agent.campaign.loop import Campaign
    from asg_agent.campaign.config import CampaignConfig
    from asg_agent.records.store import Store
    from asg_agent.scoring import attribution as attr
    from asg_agent.scoring import rewards as rw
    from asg_scenario.layout import with_positions

    exp = load_experiment(EXP)
    n = exp.position_dim // 2
    req = with_positions(exp.scenario, [[50.0, 50.0]] + [[5.0 + 3 * k, 95.0] for k in range(n - 1)])
    r0 = rw._discs(req, [])[0, 2]  # the obstacle at (50, 50): its collision radius
    # Passing it 3 m off its disc, at 5 m/s along x: clearance 3, time to collision: none ahead.
    xy = np.stack([np.arange(30.0, 70.0, 0.5), np.full(80, 50.0 + r0 + 3.0)], axis=1)
    assert rw.min_clearance(req, xy) == pytest.approx(3.0)
    assert rw.min_time_to_collision(req, xy) == rw.TTC_RANGE
    # Straight at it at 5 m/s (0.5 m a 10 Hz sample), from 12 m off its disc to contact.
    x = np.arange(50.0 - r0 - 12.0, 50.0, 0.5)
    head_on = np.stack([x, np.full(len(x), 50.0)], axis=1)
    assert rw.min_clearance(req, head_on) == 0.0 and rw.min_time_to_collision(req, head_on) == 0.0
    # its last heading sample is 12 - 4 x 0.5 = 10.5 m from the disc: 2.1 s
    assert rw.min_time_to_collision(req, head_on[:5]) == pytest.approx(10.5 / 5.0, abs=1e-6)
    assert rw.clearance_reward(1.0, 0.0) == 1.0 + rw.DENSE_WEIGHT and rw.clearance_reward(1.0, 9.0) == 1.0
    assert rw.ttc_reward(1.2, 1.5) == pytest.approx(1.2 + rw.DENSE_WEIGHT * 0.5)
    assert rw.regret_reward(1.5, 0.0, 1.0, 5.0) == pytest.approx(0.5 + rw.DENSE_WEIGHT)
    # In a campaign: the stored reward is the proxy plus the dense term, and regret needs `full` on every run.
    store = Store(":memory:")
    for reward in ("clearance", "ttc"):
        c = Campaign(
            CampaignConfig(
                name=reward,
                experiment=exp,
                method=make_method("random", exp, 1, budget=12),
                store=store,
                pool=FakePool(2),
                total=12,
                seed=1,
                checkpoint="/x",
                slots=2,
                reward=reward,
            )
        )
        c._checkpoint = lambda: None  # nothing to resume here
        c.start()
        c.run(poll_timeout=0.0)
        rows = list(store.rows(reward))
        assert len(rows) == 12 and all(r["reward"] >= r["proxy"] for r in rows)
        assert any(r["reward"] > r["proxy"] for r in rows)
    assert "every scenario" in str(refused(exp, store, "regret", [attr.FULL, attr.TRUTH], "g"))
    c = Campaign(
        CampaignConfig(
            name="g",
            experiment=exp,
            method=make_method("random", exp, 1, budget=8),
            store=store,
            pool=FakePool(2),
            total=8,
            seed=1,
            checkpoint="/x",
            slots=2,
            reward="regret",
            references={attr.FULL: FakePool(1, gain=0.0, prefix="f"), attr.TRUTH: FakePool(1, prefix="g")},
            candidates="all",
        )
    )
    c._checkpoint = lambda: None
    c.start()
    c.run(poll_timeout=0.0)
    rows = list(store.rows("g"))
    assert len(rows) == 8 and all(r["reward"] is not None and r["attribution"] for r in rows)
    # proxy - full's proxy, plus the clearance lost, at most DENSE_WEIGHT either way
    lost = [r["reward"] - (r["proxy"] - json.loads(r["reference_runs"])["full"]["proxy"]) for r in rows]
    assert all(abs(v) <= rw.DENSE_WEIGHT + 1e-9 for v in lost) and any(abs(v) > 1e-6 for v in lost)


def test_the_route_action_space_places_obstacles_along_the_route_and_random_on_it_is_route_random():
    # issue #54: the search's route-relative action space (experiments/exp1-route.yaml)
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1-route.yaml"))
    assert exp.action_space == "route" and exp.route_lateral_m == 10.0
    op = exp.scenario["operational"]
    a, b = np.array([op["start_x"], op["start_y"]]), np.array([op["goal_x"], op["goal_y"]])
    n = exp.position_dim // 2
    # the corners of the action box: start end and goal end of the band, both sides
    for u, v in ((-1.0, -1.0), (1.0, 1.0), (0.0, 0.0)):
        xy = exp.to_positions(np.tile([u, v], n))
        t = ((xy - a) @ (b - a)) / ((b - a) @ (b - a))
        d = np.cross(b - a, xy - a) / np.linalg.norm(b - a)  # signed: left of the route > 0
        assert np.allclose(d, v * 10.0, atol=1e-3)
        lo = op["safety_radius"] / np.linalg.norm(b - a)
        assert np.allclose(t, lo + (u + 1) / 2 * (1 - 2 * lo), atol=1e-4)
    # the request is a valid scene, positions to 1 mm
    req = exp.request(np.full(exp.action_dim, 0.3), 7)
    assert req["name"] == "exp1-route-7"
    # uniform random actions in this space are route-random's band-10 layouts, in distribution
    rnd = make_method("random", exp, 3)
    rr = make_method("route-random", load_experiment(EXP), 3, options={"band": 10.0})
    xa = np.concatenate([exp.to_positions(rnd.propose(j, 0, 0, None)) for j in range(400)])
    xb = np.concatenate([_xy(exp, rr.propose(j, 0, 0, None)) for j in range(400)])
    for xy in (xa, xb):
        d = np.abs(np.cross(b - a, xy - a)) / np.linalg.norm(b - a)
        assert d.max() <= 10.0 + 1e-3 and 4.0 < d.mean() < 6.0
    # route-random places obstacles itself: it refuses an experiment of another action space
    with pytest.raises(ValueError, match="action_space must be absolute"):
        make_method("route-random", exp, 0)
    with pytest.raises(ValueError, match="absolute action space"):
        exp.to_action(xa[:n])


def test_experiment_action_space_keys_are_checked(tmp_path):
    from asg_agent.records.experiment import ExperimentError

    scen = os.path.join(REPO, "scenarios", "exp1.yaml")
    for body, msg in (
        ("action_space: polar\n", "action_space: 'polar', must be one of absolute, route"),
        ("action_space: route\nroute_lateral_m: -2\n", "route_lateral_m: -2, must be a number in (0, 1000] m"),
        ("route_lateral_m: 5\n", "route_lateral_m: only with action_space route or route-wide"),
    ):
        f = tmp_path / "e.yaml"
        f.write_text(f"name: e\nscenario: {scen}\n" + body)
        with pytest.raises(ExperimentError, match=msg.replace("(", r"\(").replace(")", r"\)").replace("]", r"\]")):
            load_experiment(str(f))

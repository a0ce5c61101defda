"""The searches inside a campaign: the TD3 variants, CMA-ES and MAP-Elites, TensorBoard files, free
weather and terrain from the action, replayed reference runs, signals."""

import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.config import CampaignConfig, FunctionCallback
from asg_agent.records.experiment import ExperimentError, load_experiment
import stand_in
from stand_in.fake_pool import FakePool
from asg_agent.search.methods import make_method
from asg_agent.records.store import Store
from asg_agent.search.td3 import TD3Config
from asg_scenario import validate_scenario


from stand_ins import EXP, REPO, SMALL


@pytest.mark.parametrize(
    "method,per,asp",
    [("td3-per-asp", True, True), ("td3-per", True, False), ("td3-asp", False, True), ("td3", False, False)],
)
def test_td3_methods_are_what_their_names_say_and_anneal_beta_over_the_campaign(method, per, asp):
    # Issue #25: "td3" is plain TD3 (no scale-free objective, which exists for the penalty), and
    # beta reaches 1 at the campaign's last batch, not after 20,000 batches a campaign never draws.
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1.yaml"))
    cfg = TD3Config(**SMALL, updates_per_step=2)
    m = make_method(method, exp, 3, budget=1000, td3_config=cfg)
    c = m.agent.config
    assert (c.per, c.asp, c.normalize_q) == (per, asp, asp)
    assert cfg.per and cfg.asp and cfg.per_beta_steps == 0  # the caller's config is left as it was
    if per:
        assert c.per_beta_steps == (1000 - SMALL["start_steps"]) * 2
        buf = m.agent.buffer
        buf.samples = c.per_beta_steps - 1
        assert buf.beta() < 1.0
        buf.samples += 1
        assert buf.beta() == 1.0


def read_scalars(folder):
    """tag -> {step: value} from the TFRecord event files of a TensorBoard log folder."""
    import glob
    import struct
    from tensorboardX.proto import event_pb2

    out = {}
    for path in sorted(glob.glob(os.path.join(folder, "events.out.tfevents.*"))):
        with open(path, "rb") as f:
            while True:
                head = f.read(8)
                if len(head) < 8:
                    break
                n = struct.unpack("<Q", head)[0]
                f.read(4)
                data = f.read(n)
                f.read(4)
                e = event_pb2.Event()
                e.ParseFromString(data)
                for v in e.summary.value:
                    out.setdefault(v.tag, {})[e.step] = v.simple_value
    return out


def test_tensorboard_log_holds_every_scenario_and_the_agent_figures(tmp_path):
    """Issue #25: per-scenario and per-update scalars as TensorBoard event files: one proxy per
    job equal to the store's, the attribution counts, and the agent's losses, PER beta (rising)
    and actor saturation once it learns."""
    from asg_agent.campaign.tensorboard_log import TensorBoardLog

    store = Store(str(tmp_path / "t.sqlite"))
    exp = load_experiment(EXP)
    log = TensorBoardLog(str(tmp_path / "tb"))
    c = Campaign(
        CampaignConfig(
            name="t",
            experiment=exp,
            method=make_method("td3-per-asp", exp, 5, budget=60, td3_config=TD3Config(**SMALL)),
            store=store,
            pool=FakePool(2, seed=2, gain=6.0),
            total=60,
            seed=5,
            checkpoint=str(tmp_path / "t.ckpt"),
            slots=4,
            references={"ground_truth": FakePool(2, seed=12, gain=1.5, prefix="fake_ref")},
            candidates="all",
            callbacks=[FunctionCallback(scenario=log.scenario)],
        )
    )
    c.start()
    c.run(poll_timeout=0.0)
    log.close()
    sc = read_scalars(str(tmp_path / "tb"))
    rows = {r["job"]: r for r in store.rows("t")}
    assert sorted(sc["scenario/proxy"]) == list(range(60))
    for job, v in sc["scenario/proxy"].items():
        assert v == pytest.approx(rows[job]["proxy"], rel=1e-6)
    s = store.summary("t")
    assert sc["findings/perception"][59] == s["perception_ge3"] and sc["findings/stack"][59] == s["stack_ge3"]
    assert sc["findings/proxy_ge3"][59] == sum(r["proxy"] >= 3 for r in rows.values())
    # issue #78: the campaign's findings (here the proxy reward's) and their distinct places, first
    from asg_agent.campaign.findings import distinct_summary, findings

    d = distinct_summary(findings(store, "t"))
    assert sc["findings/of_reward"][59] == d["findings"] == sc["findings/proxy_ge3"][59] > 0
    assert sc["findings/distinct"][59] == d["distinct"][2.0] and sorted(sc["findings/distinct"]) == list(range(60))
    beta = [sc["agent/per_beta"][k] for k in sorted(sc["agent/per_beta"])]
    assert len(beta) > 10 and beta == sorted(beta) and beta[-1] > beta[0]
    assert {"agent/critic_loss", "agent/q", "agent/actor_loss", "agent/asp_weight", "agent/actor_saturation"} <= set(sc)
    assert all(0.0 <= v <= 1.0 for v in sc["agent/actor_saturation"].values())


def test_cmaes_climbs_a_smooth_objective_with_jobs_in_flight():
    # Issue #25: CMA-ES from the `cma` package behind the search interface, with 4 jobs in flight
    # (proposals run ahead of rewards, as in a campaign): the reward of its proposals rises.
    exp = load_experiment(EXP)
    m = make_method("cmaes", exp, 1, budget=600)
    target = np.linspace(-0.6, 0.6, exp.action_dim)
    reward = lambda a: -float(np.sum((np.asarray(a) - target) ** 2))  # noqa: E731
    flight, got = [], []
    for job in range(600):
        a = m.propose(job, job // 5, job % 5, None)
        flight.append((job, a))
        if len(flight) > 4:
            j, aj = flight.pop(0)
            m.observe(j, j // 5, j % 5, None, aj, reward(aj), None, False)
            got.append(reward(aj))
    assert m.generations > 20
    assert np.mean(got[-50:]) > 0.2 * np.mean(got[:50])  # closer to 0 (the best) by far
    assert np.mean(got[-50:]) > -0.5


def test_map_elites_fills_its_archive_and_keeps_the_best_of_each_cell():
    # Issue #25: MAP-Elites (ribs' grid archive, iso+line emitter) behind the search interface,
    # 4 jobs in flight. The descriptors are computed from the layout and the driven path; a path
    # that swerves 6 m lands in the 6-7 m cell, and the archive keeps each cell's best.
    exp = load_experiment(EXP)
    m = make_method("map-elites", exp, 1, budget=400)
    assert m.init_random == 40
    start, goal = np.array(m.states.start), np.array(m.states.goal)
    normal = np.array([-1.0, 1.0]) / np.sqrt(2.0)
    reward = lambda a: float(np.sum(np.asarray(a)))  # noqa: E731

    def next_state(a, swerve):
        path = np.array([start, (start + goal) / 2 + swerve * normal, goal])
        return m.states.build(a, path, 1)

    flight = []
    for job in range(400):
        a = m.propose(job, job // 5, job % 5, None)
        assert a.shape == (exp.action_dim,) and np.all(np.abs(a) <= 1.0)
        flight.append((job, a))
        if len(flight) > 4:
            j, aj = flight.pop(0)
            m.observe(j, j // 5, j % 5, None, aj, reward(aj), next_state(aj, j % 12), False)
    d = m.descriptors(np.zeros(exp.action_dim), np.array([start, (start + goal) / 2 + 6.5 * normal, goal]))
    assert d[1] == pytest.approx(6.5, abs=0.01)
    # every obstacle at the landscape's centre (50, 50) stands on the route
    assert d[0] == exp.action_dim // 2
    data = m.archive.data()
    assert len(data["objective"]) == len(set(map(tuple, data["index"].reshape(-1, 1)))) > 12
    assert set(np.round(data["measures"][:, 1]).astype(int)) >= set(range(1, 11))
    # later elites were mutated towards the reward: the best beats the best random layout by far
    assert m.archive.stats.obj_max > 2.0


def test_map_elites_tells_its_emitter_every_result_and_proposes_as_before():
    """Issue #80: MAP-Elites added results to the archive and never told the emitter, which works
    only while the emitter learns nothing (IsoLineEmitter). Each result now goes through the
    archive's add and the emitter's tell, as ribs' Scheduler.tell does for a batch. A counting
    emitter sees every result in job order with the add's info; and the proposals of a seeded run
    are those of the archive-only update that shipped (the same layouts, so the same digest)."""
    import hashlib

    exp = load_experiment(EXP)
    start = None

    def run(m, told=None):
        nonlocal start
        start = np.array(m.states.start), np.array(m.states.goal)
        if told is not None:
            tell = m.emitter.tell

            def counting(solution, objective, measures, add_info, **fields):
                told.append((solution.copy(), float(objective[0]), int(add_info["status"][0])))
                return tell(solution, objective, measures, add_info, **fields)

            m.emitter.tell = counting
        h, flight, fed = hashlib.sha256(), [], []
        for job in range(160):
            a = m.propose(job, job // 5, job % 5, None)
            h.update(a.tobytes())
            flight.append((job, a))
            if len(flight) > 3:
                j, aj = flight.pop(0)
                path = np.array([start[0], (start[0] + start[1]) / 2 + (j % 9) * np.array([0.7, -0.7]), start[1]])
                m.observe(j, j // 5, j % 5, None, aj, float(np.sum(aj)), m.states.build(aj, path, 1), False)
                fed.append(aj)
        return h.hexdigest(), fed

    told = []
    shipped = make_method("map-elites", exp, 7, budget=400)
    digest, fed = run(shipped, told)
    assert len(told) == len(fed) == 157 and all(np.array_equal(t[0][0], f) for t, f in zip(told, fed))
    assert {t[2] for t in told} >= {0, 1, 2}  # not added, improved, new cell: the add's own info

    # the archive-only update of round 6 (add_single, no tell), on the same seed
    class AddOnly(type(shipped)):
        def observe(self, job, episode, step, state, action, reward, next_state, done):
            n = self.exp.action_dim
            path = (
                (np.asarray(next_state[n : n + 2 * self.states.n_path], np.float64).reshape(-1, 2) + 1.0)
                * 0.5
                * self.exp.size
            )
            self.archive.add_single(np.asarray(action, np.float64), float(reward), self.descriptors(action, path))
            return {}

    old = AddOnly(exp, 7, init_random=shipped.init_random)
    assert run(old)[0] == digest


def test_replayed_reference_run_is_checked_against_what_attribution_stored(capsys):
    # Issue #25: `replay_ros STORE CAMPAIGN JOB --perception ground_truth` replays an attributed
    # row's reference run; it counts as reproduced only when the termination, the proxy and the
    # kept positions (campaign.kept_xy) equal what attribution stored.
    import argparse
    from asg_agent.campaign.dispatch import Outcome
    from asg_agent.records.store import kept_xy
    from asg_agent.scoring.proxy import compute, placed_mask
    from asg_agent.ros.replay import check_reference_run

    exp = load_experiment(EXP)
    request = exp.request(np.linspace(-0.9, 0.9, exp.action_dim), 5)
    t = np.arange(0, 16.0, 1 / 60.0)
    traj = np.zeros((len(t), 5), np.float32)
    traj[:, 0], traj[:, 1], traj[:, 2] = t, 20 + 3.0 * t, 20 + 3.0 * t
    vis = [0.5] * (exp.action_dim // 2)
    o = Outcome(0, "/worker_2", "SUCCESS", sim_time=16.0, trajectory=traj, visibility=vis)
    terms = compute(request, traj[:, 0], traj[:, 1:3], traj[:, 4], vis, "SUCCESS", placed_mask(request, []))
    ref = {"termination": "SUCCESS", "proxy": terms.proxy, "trajectory_xy": kept_xy(traj)}
    a = argparse.Namespace(bag="")
    assert check_reference_run(a, request, ref, o) == 0
    assert "REPRODUCED (the reference run)" in capsys.readouterr().out
    moved = traj.copy()
    moved[300, 1] += 0.05  # one kept sample 5 cm off
    assert (
        check_reference_run(
            a, request, ref, Outcome(0, "/worker_2", "SUCCESS", sim_time=16.0, trajectory=moved, visibility=vis)
        )
        == 1
    )
    assert "NOT REPRODUCED" in capsys.readouterr().out
    assert check_reference_run(a, request, dict(ref, termination="COLLISION"), o) == 1


def test_an_experiment_with_free_weather_sets_it_from_the_action(tmp_path):
    # Issue #27: experiments/exp5.yaml frees the fog's visibility and the cloud cover; the action
    # is the 16 position values and then one value per free attribute, scaled to its range.
    exp = load_experiment(os.path.join(REPO, "experiments", "exp5.yaml"))
    assert (exp.position_dim, exp.action_dim) == (16, 18)
    a = np.zeros(18, np.float32)
    a[16], a[17] = -1.0, 1.0
    req = exp.request(a, 3)
    assert req["textural"]["fog_visibility_m"] == 25.0 and req["textural"]["cloud_cover"] == 1.0
    assert req["textural"]["sun_inclination_deg"] == exp.scenario["textural"]["sun_inclination_deg"]
    a[16] = 0.0
    assert exp.request(a, 3)["textural"]["fog_visibility_m"] == 262.5
    assert np.array_equal(exp.to_positions(a), load_experiment(EXP).to_positions(a[:16]))
    # every search runs on it, deterministic whatever the workers' order
    for method in ("random", "cmaes", "map-elites", "td3-per-asp"):
        m = make_method(method, exp, 1, budget=40, td3_config=TD3Config(**SMALL))
        c = Campaign(
            CampaignConfig(
                name=method,
                experiment=exp,
                method=m,
                store=Store(str(tmp_path / f"{method}.sqlite")),
                pool=FakePool(2, seed=1),
                total=12,
                seed=1,
                checkpoint=str(tmp_path / f"{method}.ckpt"),
                slots=4,
            )
        )
        c.start()
        c.run()
        rows = list(c.store.rows(method))
        fog = [json.loads(r["request"])["textural"]["fog_visibility_m"] for r in rows]
        assert len(rows) == 12 and all(25.0 <= f <= 500.0 for f in fog) and len(set(fog)) > 3
    bad = tmp_path / "bad.yaml"
    text = load_experiment(os.path.join(REPO, "experiments", "exp5.yaml")).text  # effective: exp5 has a base
    text = text.replace("../scenarios/exp1.yaml", os.path.join(REPO, "scenarios", "exp1.yaml"))
    for broken, fixed, message in (
        ("cloud_cover: [0.0, 1.0]", "cloud_cover: [0.0, 1.5]", "textural_free.cloud_cover: [0.0, 1.5] must satisfy"),
        ("cloud_cover: [0.0, 1.0]", "cloud_cover: thick", "textural_free.cloud_cover: 'thick', must be [lo, hi]"),
        ("fog_visibility_m: [25.0, 500.0]", "ground_texture_seed: [0, 9]", "textural_free.ground_texture_seed: not a"),
    ):
        bad.write_text(text.replace(broken, fixed))
        with pytest.raises(ExperimentError, match=re.escape(message)):
            load_experiment(str(bad))


def test_an_experiment_with_free_terrain_sets_it_from_the_action(tmp_path):
    # Issue #27: experiments/exp6.yaml frees the rolling ground's amplitude, every hill's height
    # and position after the obstacles and the weather: 16 + 2 + 1 + 3 + 6 values.
    exp = load_experiment(os.path.join(REPO, "experiments", "exp6.yaml"))
    assert (exp.position_dim, exp.hills, exp.terrain_dim, exp.action_dim) == (16, 3, 10, 28)
    a = np.zeros(28, np.float32)
    a[18] = 1.0  # amplitude: the top of [0, 1.5]
    a[19:22] = (-1.0, 0.0, 1.0)  # hill heights in [-3, 3]
    a[22:28] = (-1.0, -1.0, 0.0, 0.5, 1.0, 1.0)  # hill positions over [0, 100]
    req = exp.request(a, 4)
    t = req["structural"]["terrain"]
    assert t["amplitude_m"] == 1.5 and t["wavelength_m"] == 30.0 and t["seed"] == 1
    assert [h["height_m"] for h in t["hills"]] == [-3.0, 0.0, 3.0]
    assert [(h["x"], h["y"]) for h in t["hills"]] == [(0.0, 0.0), (50.0, 75.0), (100.0, 100.0)]
    assert [h["radius_m"] for h in t["hills"]] == [10.0, 10.0, 8.0]
    assert exp.scenario["structural"]["terrain"]["amplitude_m"] == 0.6  # the experiment's own is untouched
    validate_scenario(req)  # every request the search can make is a valid scene
    assert np.array_equal(exp.to_positions(a), load_experiment(EXP).to_positions(a[:16]))
    m = make_method("td3-per-asp", exp, 1, budget=40, td3_config=TD3Config(**SMALL))
    c = Campaign(
        CampaignConfig(
            name="t",
            experiment=exp,
            method=m,
            store=Store(str(tmp_path / "t.sqlite")),
            pool=FakePool(2, seed=1),
            total=12,
            seed=1,
            checkpoint=str(tmp_path / "t.ckpt"),
        )
    )
    c.start()
    c.run()
    amps = [json.loads(r["request"])["structural"]["terrain"]["amplitude_m"] for r in c.store.rows("t")]
    assert len(amps) == 12 and all(0.0 <= v <= 1.5 for v in amps) and len(set(amps)) > 3
    bad = tmp_path / "bad.yaml"
    text = open(os.path.join(REPO, "experiments", "exp6.yaml")).read()
    text = text.replace("../scenarios/exp6.yaml", os.path.join(REPO, "scenarios", "exp6.yaml"))
    for broken, fixed, message in (
        ("amplitude_m: [0.0, 1.5]", "amplitude_m: [0.0, 4.0]", "terrain_free.amplitude_m: hi 4 m is too steep"),
        ("hill_height_m: [-3.0, 3.0]", "hill_height_m: [-5.0, 3.0]", "is too steep for the smallest hill"),
        ("hill_positions: true", "hill_positions: 1", "terrain_free.hill_positions: 1, must be true or false"),
        ("hill_positions: true", "slope: [0, 1]", "terrain_free.slope: unknown key"),
    ):
        bad.write_text(text.replace(broken, fixed))
        with pytest.raises(ExperimentError, match=re.escape(message)):
            load_experiment(str(bad))
    flat = tmp_path / "flat.yaml"
    flat.write_text(
        text.replace(os.path.join(REPO, "scenarios", "exp6.yaml"), os.path.join(REPO, "scenarios", "exp1.yaml"))
    )
    with pytest.raises(ExperimentError, match="need hills in the scenario"):
        load_experiment(str(flat))


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_campaign_as_ctrl_c_does_even_in_the_background(tmp_path, sig):
    # A campaign started with `&` by a non-interactive shell inherits SIGINT ignored; kill's
    # SIGTERM ended it at once. Both now save its state and end it with status 130.
    env = stand_in.environ()  # the stand-in and the agent's sources first on PYTHONPATH
    cmd = [sys.executable, "-m", "stand_in.campaign", EXP, "--fake-workers", "2", "--scenarios", "400"]
    cmd += ["--store", str(tmp_path / "s.sqlite"), "--name", "s", "--no-progress", "--method", "td3-per-asp"]
    store = Store(str(tmp_path / "s.sqlite"))
    p = subprocess.Popen(
        cmd,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),  # as a background job
    )
    deadline = time.time() + 120
    while store.count("s") < 20 and time.time() < deadline and p.poll() is None:
        time.sleep(0.01)
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err[-2000:]
    assert "interrupted; `--resume` continues it" in err
    assert 20 <= store.count("s") < 400 and store.integrity_ok()

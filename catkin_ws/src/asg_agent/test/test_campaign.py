"""Campaign loop with the in-process pool: determinism whatever the workers' order, exactly-once
storage, retries, resume after an interruption and after kill -9 of the campaign process."""

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
from asg_agent.campaign.experiment import ExperimentError, load_experiment
from asg_agent.campaign.fake_pool import FakePool
from asg_agent.search.methods import make_method
from asg_agent.campaign.store import Store, StoreError, park, unpark
from asg_agent.search.td3 import TD3Config
from asg_scenario import validate_scenario

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")
SMALL = dict(hidden=32, batch_size=16, start_steps=20)


def campaign(tmp_path, name, pool, total=40, method="td3-per-asp", seed=7, store=None):
    exp = load_experiment(EXP)
    store = store or Store(str(tmp_path / "store.sqlite"))
    m = make_method(method, exp, seed, budget=total, td3_config=TD3Config(**SMALL))
    return Campaign(name, exp, m, store, pool, total, seed, str(tmp_path / f"{name}.ckpt"), slots=4, checkpoint_every=1)


class Interrupt(Exception):
    pass


class DyingPool(FakePool):
    """Raises after `die_after` outcomes, as a killed process would stop mid-episode."""

    def __init__(self, die_after, **kw):
        super().__init__(**kw)
        self.die_after, self.seen = die_after, 0

    def poll(self, timeout):
        out = super().poll(timeout)
        self.seen += len(out)
        if self.seen > self.die_after:
            raise Interrupt()
        return out


@pytest.mark.parametrize("method", ["td3-per-asp", "random", "annealing", "cmaes", "map-elites"])
def test_same_seed_same_store_whatever_the_order(tmp_path, method):
    a = campaign(tmp_path, "a", FakePool(2, seed=1), method=method)
    a.start()
    a.run()
    b = campaign(tmp_path, "b", FakePool(3, seed=2), method=method, store=a.store)
    b.start()
    b.run()
    da, db = a.store.content_digest("a"), a.store.content_digest("b")
    assert len(da) == 40 and da == db
    assert [r[0] for r in da] == list(range(40))


def test_error_is_retried_and_counted_once(tmp_path):
    pool = FakePool(2, seed=3, fail_jobs={5, 6})
    c = campaign(tmp_path, "r", pool, total=20)
    c.start()
    c.run()
    rows = {r["job"]: r for r in c.store.rows("r")}
    assert sorted(rows) == list(range(20))
    assert rows[5]["attempts"] == 2 and rows[5]["termination"] == "SUCCESS"
    assert pool.submitted.count(5) == 2
    assert c.status()["retries"] == 2


@pytest.mark.parametrize("method", ["td3-per-asp", "cmaes", "map-elites"])
def test_interrupted_mid_episode_and_resumed_equals_uninterrupted(tmp_path, method):
    ref = campaign(tmp_path, "ref", FakePool(2, seed=4), method=method)
    ref.start()
    ref.run()
    store = ref.store
    first = campaign(tmp_path, "cut", DyingPool(23, workers=2, seed=5), store=store, method=method)
    first.start()
    with pytest.raises(Interrupt):
        first.run()
    stored = store.count("cut")
    assert 0 < stored < 40
    second = campaign(tmp_path, "cut", FakePool(2, seed=6), store=store, method=method)
    second.resume()
    second.run()
    jobs = store.jobs("cut")
    assert jobs == list(range(40))  # every scenario exactly once
    assert store.content_digest("cut") == store.content_digest("ref")


def test_parked_on_one_machine_and_resumed_on_another_equals_uninterrupted(tmp_path):
    """A campaign cut off mid-episode is parked (rows + checkpoint in one file), unparked into an
    empty store in another folder, as a fresh checkout would, and resumed there."""
    ref = campaign(tmp_path, "ref", FakePool(2, seed=4))
    ref.start()
    ref.run()
    here = tmp_path / "here"
    here.mkdir()
    first = campaign(here, "cut", DyingPool(23, workers=2, seed=5))
    first.start()
    with pytest.raises(Interrupt):
        first.run()
    stored = first.store.count("cut")
    parked = str(tmp_path / "parked" / "cut.tar.xz")
    assert park(first.store, "cut", str(here / "cut.ckpt"), parked) == stored
    with open(parked, "rb") as f:
        once = f.read()
    park(first.store, "cut", str(here / "cut.ckpt"), parked)
    with open(parked, "rb") as f:
        assert f.read() == once  # parking the same state twice writes the same bytes
    there = tmp_path / "there"
    there.mkdir()
    store = Store(str(there / "store.sqlite"))
    assert unpark(store, parked, lambda c: str(there / f"{c}.ckpt")) == stored
    assert unpark(store, parked, lambda c: str(there / f"{c}.ckpt")) is None  # already there: left alone
    second = campaign(there, "cut", FakePool(2, seed=6), store=store)
    second.resume()
    second.run()
    assert store.jobs("cut") == list(range(40))
    assert store.content_digest("cut") == ref.store.content_digest("ref")


def test_park_and_unpark_refuse_bad_input_by_name(tmp_path):
    store = Store(str(tmp_path / "store.sqlite"))
    with pytest.raises(StoreError, match="no campaign 'nope'"):
        park(store, "nope", str(tmp_path / "x.ckpt"), str(tmp_path / "p.tar.xz"))
    c = campaign(tmp_path, "c", FakePool(2, seed=1), total=8)
    c.start()
    with pytest.raises(StoreError, match="no checkpoint"):
        park(store, "c", str(tmp_path / "missing.ckpt"), str(tmp_path / "p.tar.xz"))
    junk = tmp_path / "junk.tar.xz"
    junk.write_bytes(b"not a tar file")
    with pytest.raises(StoreError, match="junk.tar.xz: not a parked campaign"):
        unpark(store, str(junk))


def test_readers_of_a_store_that_is_not_there_say_so_and_make_none(tmp_path, capsys):
    from asg_agent.analysis import export, report

    missing = tmp_path / "typo.sqlite"
    with pytest.raises(StoreError, match="typo.sqlite: no such scenario store"):
        Store(str(missing), create=False)
    assert report.main(["campaign", str(missing), "c", str(tmp_path / "out")]) == 2
    assert export.main(["export", str(missing), "c", str(tmp_path / "c.jsonl.gz")]) == 2
    assert "no such scenario store" in capsys.readouterr().err
    assert not missing.exists()  # no empty store left behind for the next reader


def test_resume_with_a_cut_budget_stores_every_job_below_it_once(tmp_path):
    """The soak's ending: a campaign with a large budget is interrupted, then resumed with its
    budget cut to the scenarios begun; it finishes with jobs 0..T-1 stored exactly once."""
    store = Store(str(tmp_path / "store.sqlite"))
    first = campaign(tmp_path, "cut", DyingPool(23, workers=2, seed=5), total=1000, store=store)
    first.start()
    with pytest.raises(Interrupt):
        first.run()
    cut = max(store.jobs("cut")) + 1
    second = campaign(tmp_path, "cut", FakePool(2, seed=6), total=cut, store=store)
    second.resume()
    second.run()
    assert store.jobs("cut") == list(range(cut))
    assert store.campaign("cut")["finished"]


def test_a_finished_campaign_is_extended_by_a_resume_with_a_larger_budget(tmp_path):
    store = Store(str(tmp_path / "store.sqlite"))
    first = campaign(tmp_path, "ext", FakePool(2, seed=1), total=20, store=store)
    first.start()
    first.run()
    assert store.jobs("ext") == list(range(20))
    second = campaign(tmp_path, "ext", FakePool(3, seed=2), total=45, store=store)
    second.resume()
    second.run()
    assert store.jobs("ext") == list(range(45))
    again = campaign(tmp_path, "ext2", FakePool(2, seed=3), total=20, store=store)
    again.start()
    again.run()
    third = campaign(tmp_path, "ext2", FakePool(1, seed=4), total=45, store=store)
    third.resume()
    third.run()
    assert store.content_digest("ext") == store.content_digest("ext2")  # the extension repeats


def test_kill_9_of_the_campaign_process_then_resume(tmp_path):
    env = dict(
        os.environ,
        PYTHONPATH=os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src")
        + os.pathsep
        + os.environ.get("PYTHONPATH", ""),
    )
    cmd = [
        sys.executable,
        "-m",
        "asg_agent.cli.campaign",
        EXP,
        "--fake-workers",
        "2",
        "--scenarios",
        "150",
        "--store",
        str(tmp_path / "k.sqlite"),
        "--name",
        "k",
        "--checkpoint-every",
        "1",
        "--no-progress",
    ]
    store = Store(str(tmp_path / "k.sqlite"))
    for kill_at in (15, 60):  # kill -9 at two moments, resuming in between
        p = subprocess.Popen(
            cmd + (["--resume"] if kill_at != 15 else []), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        deadline = time.time() + 120
        while store.count("k") < kill_at and time.time() < deadline and p.poll() is None:
            time.sleep(0.002)
        p.send_signal(signal.SIGKILL)
        p.wait()
    assert store.integrity_ok()
    p = subprocess.run(cmd + ["--resume"], env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    assert store.jobs("k") == list(range(150))
    assert "proxy >= 3" in p.stdout
    assert store.integrity_ok()


def test_bad_experiment_files_are_named(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nscenario: nowhere.yaml\nepisode_steps: 0\ncolour: red\n")
    with pytest.raises(ExperimentError) as e:
        load_experiment(str(bad))
    assert "colour: unknown key" in str(e.value) and "episode_steps" in str(e.value)
    bad.write_text("name: x\nscenario: nowhere.yaml\n")
    with pytest.raises(ExperimentError, match="nowhere.yaml"):
        load_experiment(str(bad))
    with pytest.raises(ExperimentError, match="cannot read"):
        load_experiment(str(tmp_path / "missing.yaml"))


def test_the_stack_under_test_is_named_by_the_experiment(tmp_path):
    # Issue #39: the depth stack's experiment; a stack the campaign cannot check is refused.
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1-depth.yaml"))
    assert exp.stack == "depth"
    assert load_experiment(os.path.join(REPO, "experiments", "exp1.yaml")).stack == "paper"
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"name: x\nstack: lidar\nscenario: {os.path.join(REPO, 'scenarios', 'exp1.yaml')}\n")
    with pytest.raises(ExperimentError, match=r"stack: 'lidar' is not a registered stack \(depth, gap_nav, paper\)"):
        load_experiment(str(bad))


def test_export_summary_and_report_agree_with_the_store(tmp_path):
    from asg_agent.analysis.export import counts, export, read_export
    from asg_agent.analysis.report import campaign_report

    c = campaign(tmp_path, "rep", FakePool(2, seed=8), total=30, method="random")
    c.start()
    c.run()
    out = str(tmp_path / "rep.jsonl.gz")
    assert export(c.store, "rep", out) == 30
    time.sleep(1.1)  # a gzip header with the time in it would differ now
    assert export(c.store, "rep", str(tmp_path / "again.jsonl.gz")) == 30
    assert open(out, "rb").read() == open(tmp_path / "again.jsonl.gz", "rb").read()  # byte-identical re-export
    head, rows = read_export(out)
    assert all(r["collision_with"] is None for r in rows if r["termination"] != "COLLISION")
    s = c.store.summary("rep")
    k = counts(rows)
    assert head["name"] == "rep"
    assert (k["scenarios"], k["proxy_ge_3"], k["proxy_ge_4"]) == (s["scenarios"], s["proxy_ge_3"], s["proxy_ge_4"])
    assert abs(k["max_proxy"] - s["max_proxy"]) < 1e-12
    page = open(campaign_report(c.store.path, "rep", str(tmp_path / "report"), top=3)).read()
    assert f"<td>{s['scenarios']}</td><td>{s['proxy_ge_3']}</td><td>{s['proxy_ge_4']}</td>" in page
    assert page.count("rosrun asg_agent replay") == 3
    assert os.path.isfile(tmp_path / "report" / "curves.png")


def test_the_collision_reward_adds_its_bonus_to_perception_collisions_only(tmp_path):
    """--reward collision (issue #27): the search learns from the proxy plus the bonus where the
    stack under test collided and the reference stack reached the goal (a perception collision, as
    every count defines it); the stored proxy stays the paper's."""
    from asg_agent.campaign.loop import collision_reward

    assert collision_reward(1.2, "COLLISION", None, 2.0) == 3.2  # no reference: every collision
    assert collision_reward(1.2, "COLLISION", "SUCCESS", 2.0) == 3.2
    assert collision_reward(1.2, "COLLISION", "COLLISION", 2.0) == 1.2  # the stack's, not the perception's
    assert collision_reward(1.2, "SUCCESS", None, 2.0) == 1.2
    assert collision_reward(1.2, "COLLISION", "STUCK_TIMEOUT", 2.0) == 1.2  # the reference did not get through
    exp = load_experiment(EXP)
    store = Store(str(tmp_path / "r.sqlite"))
    c = Campaign(
        "r",
        exp,
        make_method("random", exp, 3, budget=24),
        store,
        FakePool(2, seed=1, collide_jobs={2, 5, 9}),
        24,
        3,
        str(tmp_path / "r.ckpt"),
        slots=4,
        reference=FakePool(2, seed=11, prefix="fake_ref", collide_jobs={9}),
        reward="collision",
        collision_bonus=1.5,
    )
    c.start()
    c.run(poll_timeout=0.0)
    rows = {r["job"]: r for r in store.rows("r")}
    assert len(rows) == 24
    for job, r in rows.items():
        bonus = 1.5 if job in (2, 5) else 0.0  # job 9: the reference collided too
        assert r["termination"] == ("COLLISION" if job in (2, 5, 9) else "SUCCESS")
        assert abs(r["reward"] - (r["proxy"] + bonus)) < 1e-12, job
    from asg_agent.cli.campaign import parse

    assert parse([EXP, "--fake-workers", "2", "--reward", "collision"]).collision_bonus == 2.0
    with pytest.raises(SystemExit):
        parse([EXP, "--fake-workers", "2", "--reward", "collision", "--collision-bonus", "nan"])
    for bad, match in (
        ({"reward": "collisions"}, "must be one of"),
        ({"reward": "collision", "collision_bonus": -1.0}, ">= 0"),
    ):
        with pytest.raises(ValueError, match=match):
            Campaign(
                "x", exp, make_method("random", exp, 3, budget=4), store, FakePool(1), 4, 3, str(tmp_path / "x"), **bad
            )


def test_the_export_names_the_obstacle_a_run_hit_by_its_index_in_positions():
    from asg_agent.analysis.export import collision_index

    req = {"structural": {"layouts": [{"instances": [{}, {}, {}]}, {"instances": [{}, {}]}]}}
    assert collision_index(req, "") is None
    assert collision_index(req, "0:2") == 2
    assert collision_index(req, "1:0") == 3 and collision_index(req, "1:1") == 4
    with pytest.raises(ValueError, match="names no obstacle"):
        collision_index(req, "1:2")
    with pytest.raises(ValueError, match="not 'layout:instance'"):
        collision_index(req, "juniper")


def test_complete_tells_a_finished_export_at_its_budget_and_park_names_bad_input(tmp_path, capsys):
    """What scripts/repro/campaigns.sh asks before running a plan line: `complete` exits 0 only for the
    export of a finished campaign holding at least the budget; `park` and `unpark` exit 2 naming
    what is wrong."""
    from asg_agent.analysis.export import export, main

    c = campaign(tmp_path, "done", FakePool(2, seed=8), total=12, method="random")
    c.start()
    c.run()
    out = str(tmp_path / "done.jsonl.gz")
    export(c.store, "done", out)
    assert main(["complete", out, "12"]) == 0
    assert main(["complete", out, "13"]) == 1  # a larger budget than it ran: not done
    assert main(["complete", str(tmp_path / "none.jsonl.gz"), "12"]) == 1
    cut = campaign(tmp_path, "cut", DyingPool(9, workers=2, seed=5), total=40, store=c.store)
    cut.start()
    with pytest.raises(Interrupt):
        cut.run()
    export(c.store, "cut", str(tmp_path / "cut.jsonl.gz"))
    assert main(["complete", str(tmp_path / "cut.jsonl.gz"), "1"]) == 1  # unfinished
    store = c.store.path
    assert main(["park", "--unfinished-only", store, "done", str(tmp_path / "p.tar.xz")]) == 0
    assert not os.path.exists(tmp_path / "p.tar.xz") and "finished; not parked" in capsys.readouterr().out
    assert main(["park", store, "nope", str(tmp_path / "p.tar.xz")]) == 2
    assert "no campaign 'nope'" in capsys.readouterr().err
    assert main(["unpark", store, str(tmp_path / "done.jsonl.gz")]) == 2
    assert "not a parked campaign" in capsys.readouterr().err


def test_differential_campaign_learns_from_the_difference_and_repeats(tmp_path):
    """--reference-workers: every scenario runs on both stacks (here stand-ins that wiggle 0.8 and
    0.3 m per nearby obstacle); the stored reward is the proxy difference, the reference run is
    kept, and the same seed gives the same store whatever the two pools' speeds."""
    import json as _json

    digests = []
    for name, seed in (("d1", 1), ("d2", 2)):
        store = Store(str(tmp_path / "d.sqlite"))
        exp = load_experiment(EXP)
        c = Campaign(
            name,
            exp,
            make_method("td3-per-asp", exp, 4, budget=40),
            store,
            FakePool(2, seed=seed),
            40,
            4,
            str(tmp_path / f"{name}.ckpt"),
            slots=4,
            reference=FakePool(2, seed=seed + 10, gain=0.3, prefix="fake_ref"),
            reward="differential",
        )
        c.start()
        c.run(poll_timeout=0.0)
        rows = list(store.rows(name))
        assert [r["job"] for r in rows] == list(range(40))
        for r in rows:
            ref = _json.loads(r["reference"])
            assert ref["worker"].startswith("/fake_ref_")
            assert abs(r["reward"] - (r["proxy"] - ref["proxy"])) < 1e-12
        assert any(r["reward"] > 0 for r in rows)  # the wigglier stack scores higher somewhere
        st = c.status()  # the progress bar's differential figures agree with the store
        assert st["diff_ge1"] == sum(r["reward"] >= 1 for r in rows)
        assert abs(st["diff_best"] - max(r["reward"] for r in rows)) < 1e-12
        digests.append([(r["job"], r["proxy"], r["reward"], r["request"]) for r in rows])
    assert digests[0] == digests[1]


def test_attribution_counts_perception_and_stack_findings(tmp_path):
    """--reference-workers with the proxy reward (the default): the search learns from the stack
    under test's proxy, every scenario also runs on the reference stand-in, and the progress
    figures, the store's summary and a resumed campaign all count a finding (proxy >= 3) as the
    perception's when the reference stays below 2 and as the stack's when it reaches 3."""
    import json as _json

    store = Store(str(tmp_path / "a.sqlite"))
    exp = load_experiment(EXP)
    c = Campaign(
        "a",
        exp,
        make_method("random", exp, 3, budget=60),
        store,
        FakePool(2, seed=1, gain=6.0),
        60,
        3,
        str(tmp_path / "a.ckpt"),
        slots=4,
        reference=FakePool(2, seed=11, gain=1.5, prefix="fake_ref"),
    )
    c.start()
    c.run(poll_timeout=0.0)
    rows = list(store.rows("a"))
    assert len(rows) == 60
    ref = {r["job"]: _json.loads(r["reference"])["proxy"] for r in rows}
    for r in rows:
        assert r["reward"] == r["proxy"]  # the paper's objective, not the difference
    perception = sum(r["proxy"] >= 3 and ref[r["job"]] < 2 for r in rows)
    stack = sum(r["proxy"] >= 3 and ref[r["job"]] >= 3 for r in rows)
    assert perception > 0 and stack > 0, (perception, stack)  # the stand-ins give both kinds
    st = c.status()
    assert (st["perception"], st["stack"]) == (perception, stack)
    s = store.summary("a")
    assert (s["attributed"], s["perception_ge3"], s["stack_ge3"]) == (60, perception, stack)
    assert s["differential_ge1"] == sum(r["proxy"] - ref[r["job"]] >= 1 for r in rows)
    # The compact export keeps the reference runs, and its counts are the store's.
    from asg_agent.analysis.export import counts, export, read_export

    export(store, "a", str(tmp_path / "a.jsonl.gz"))
    k = counts(read_export(str(tmp_path / "a.jsonl.gz"))[1])
    assert (k["attributed"], k["perception_ge3"], k["stack_ge3"], k["differential_ge1"]) == (
        60,
        perception,
        stack,
        s["differential_ge1"],
    )
    # Collisions are attributed too (the stand-ins never collide: make some). Jobs 0-4: the stack
    # under test collides, the reference drives through; jobs 5-6: both collide.
    assert (s["perception_collisions"], s["stack_collisions"]) == (0, 0)
    for job in range(7):
        r = next(x for x in rows if x["job"] == job)
        refd = dict(_json.loads(r["reference"]), termination="COLLISION" if job >= 5 else "SUCCESS")
        store.db.execute(
            "UPDATE scenarios SET termination = 'COLLISION', reference = ? WHERE campaign = 'a' AND job = ?",
            (_json.dumps(refd), job),
        )
    store.db.commit()
    s2 = store.summary("a")
    assert (s2["perception_collisions"], s2["stack_collisions"]) == (5, 2)
    export(store, "a", str(tmp_path / "a2.jsonl.gz"))
    k2 = counts(read_export(str(tmp_path / "a2.jsonl.gz"))[1])
    assert (k2["perception_collisions"], k2["stack_collisions"]) == (5, 2)
    # PLR < 0.999 is warned about only where the run reached the goal: a run that ended early is
    # extended by a straight line to the goal, which may pass through what it hit.
    base = s2["plr_below_0999"]
    store.db.execute("UPDATE scenarios SET plr = 0.99 WHERE campaign = 'a' AND job IN (0, 20)")
    store.db.commit()
    assert next(x for x in store.rows("a") if x["job"] == 20)["termination"] == "SUCCESS"
    assert store.summary("a")["plr_below_0999"] == base + 1  # job 20, not the collision of job 0
    # A resumed campaign takes its counts from the store.
    again = Campaign(
        "a",
        exp,
        make_method("random", exp, 3, budget=60),
        store,
        FakePool(2, seed=1, gain=6.0),
        60,
        3,
        str(tmp_path / "a.ckpt"),
        slots=4,
        reference=FakePool(2, seed=11, gain=1.5, prefix="fake_ref"),
    )
    again.resume()
    assert (again.status()["perception"], again.status()["stack"]) == (perception, stack)
    with pytest.raises(ValueError, match="needs a reference stack"):
        Campaign(
            "b",
            exp,
            make_method("random", exp, 3, budget=5),
            store,
            FakePool(1),
            5,
            3,
            str(tmp_path / "b.ckpt"),
            reward="differential",
        )


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
        "t",
        exp,
        make_method("td3-per-asp", exp, 5, budget=60, td3_config=TD3Config(**SMALL)),
        store,
        FakePool(2, seed=2, gain=6.0),
        60,
        5,
        str(tmp_path / "t.ckpt"),
        slots=4,
        reference=FakePool(2, seed=12, gain=1.5, prefix="fake_ref"),
        scalars=log.scenario,
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


def test_replayed_reference_run_is_checked_against_what_attribution_stored(capsys):
    # Issue #25: `replay_ros STORE CAMPAIGN JOB --perception ground_truth` replays an attributed
    # row's reference run; it counts as reproduced only when the termination, the proxy and the
    # kept positions (campaign.kept_xy) equal what attribution stored.
    import argparse
    from asg_agent.campaign.loop import Outcome, kept_xy
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
            method,
            exp,
            m,
            Store(str(tmp_path / f"{method}.sqlite")),
            FakePool(2, seed=1),
            12,
            1,
            str(tmp_path / f"{method}.ckpt"),
            slots=4,
        )
        c.start()
        c.run()
        rows = list(c.store.rows(method))
        fog = [json.loads(r["request"])["textural"]["fog_visibility_m"] for r in rows]
        assert len(rows) == 12 and all(25.0 <= f <= 500.0 for f in fog) and len(set(fog)) > 3
    bad = tmp_path / "bad.yaml"
    text = open(os.path.join(REPO, "experiments", "exp5.yaml")).read()
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
    c = Campaign("t", exp, m, Store(str(tmp_path / "t.sqlite")), FakePool(2, seed=1), 12, 1, str(tmp_path / "t.ckpt"))
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
    env = dict(
        os.environ,
        PYTHONPATH=os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src")
        + os.pathsep
        + os.environ.get("PYTHONPATH", ""),
    )
    cmd = [sys.executable, "-m", "asg_agent.cli.campaign", EXP, "--fake-workers", "2", "--scenarios", "400"]
    cmd += ["--store", str(tmp_path / "s.sqlite"), "--name", "s", "--no-progress"]
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

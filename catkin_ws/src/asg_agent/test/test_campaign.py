"""Campaign loop with the in-process pool: determinism whatever the workers' order, exactly-once
storage, retries, resume after an interruption and after kill -9 of the campaign process, parking."""

import os
import re
import signal
import subprocess
import sys
import time

import pytest

from asg_agent.records.experiment import ExperimentError, load_experiment
import stand_in
from stand_in.fake_pool import FakePool
from asg_agent.records.store import Store, StoreError, park, unpark


from stand_ins import EXP, REPO, DyingPool, Interrupt, campaign


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
    from asg_agent.cli import store as store_cli

    missing = tmp_path / "typo.sqlite"
    with pytest.raises(StoreError, match="typo.sqlite: no such scenario store"):
        Store(str(missing), create=False)
    assert store_cli.main(["export", str(missing), "c", str(tmp_path / "c.jsonl.gz")]) == 2
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
    env = stand_in.environ()  # the stand-in and the agent's sources first on PYTHONPATH
    cmd = [
        sys.executable,
        "-m",
        "stand_in.campaign",
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
        "--method",
        "td3-per-asp",  # the paper's search on its proxy: the learner whose state a kill must not lose
        "--reward",
        "proxy",
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
    # the summary leads with what the campaign searched for (issue #78), the proxy's counts after
    first = p.stdout.strip().splitlines()
    lead = next(i for i, line in enumerate(first) if line.startswith("campaign k: 150 scenarios"))
    assert "findings of the proxy reward" in first[lead] and "distinct at 2 m" in first[lead]
    assert any(line.startswith("the paper's proxy: >= 3 in") for line in first[lead:])
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
    with pytest.raises(
        ExperimentError,
        match=r"stack: 'lidar' is not a registered stack \("
        + re.escape(
            ", ".join(
                sorted(
                    os.path.splitext(n)[0] for n in os.listdir(os.path.join(REPO, "stacks")) if n.endswith(".launch")
                )
            )
        )
        + r"\)",
    ):
        load_experiment(str(bad))

"""Agent death and damaged files (issue #14), with the in-process stand-in workers (no ROS): the
campaign process killed with SIGKILL at random moments (with a checkpoint after every episode,
so kills land during checkpoints and store writes too), resumed each time, must end with exactly
the store an uninterrupted campaign of the same seed writes: no scenario lost, none twice, the
SQLite integrity check passing. Damaged checkpoints, stores and model files get clear errors."""

import os
import random
import signal
import subprocess
import sys
import time

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "test"))  # the stand-in beside its tests
import stand_in  # noqa: E402
from asg_agent.records.store import Store  # noqa: E402

EXP = os.path.join(REPO, "experiments", "exp1.yaml")
ENV = stand_in.environ()  # the stand-in and the agent's sources first on PYTHONPATH
N = 200


def cmd(store, name, *extra):
    return [
        sys.executable,
        "-m",
        "stand_in.campaign",
        EXP,
        "--fake-workers",
        "2",
        "--scenarios",
        str(N),
        "--store",
        store,
        "--name",
        name,
        "--checkpoint-every",
        "1",
        "--no-progress",
        "--seed",
        "5",
        "--method",
        "td3-per-asp",  # the paper's search on its proxy (a learner with a replay buffer to lose)
        "--reward",
        "proxy",
        *extra,
    ]


def test_random_kill_9_of_the_agent_then_resume_equals_an_uninterrupted_campaign(tmp_path):
    ref_path, path = str(tmp_path / "ref.sqlite"), str(tmp_path / "killed.sqlite")
    r = subprocess.run(cmd(ref_path, "c"), env=ENV, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    rng = random.Random(14)
    store = Store(path)
    kills = 0
    # One kill during start-up, then seven when the store reaches random counts, each a few
    # milliseconds later (so they land in store writes, learning and checkpoints alike).
    schedule = [None] + sorted(rng.sample(range(2, N - 5), 7))
    for k, at in enumerate(schedule):
        p = subprocess.Popen(
            cmd(path, "c", *([] if k == 0 else ["--resume"])),
            env=ENV,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        if at is None:
            time.sleep(rng.uniform(0.3, 1.2))
        else:
            deadline = time.time() + 120
            while store.count("c") < at and p.poll() is None and time.time() < deadline:
                time.sleep(0.002)
            time.sleep(rng.uniform(0.0, 0.03))
        if p.poll() is not None:
            continue  # it finished (or had stored past this mark) before the kill
        p.send_signal(signal.SIGKILL)
        p.wait()
        kills += 1
        assert store.integrity_ok()
    r = subprocess.run(cmd(path, "c", "--resume"), env=ENV, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert kills >= 6
    assert store.integrity_ok()
    assert store.jobs("c") == list(range(N))  # none lost, none twice
    ref = Store(ref_path).content_digest("c")
    got = store.content_digest("c")
    assert got == ref, "the killed-and-resumed campaign differs from the uninterrupted one"


def test_truncated_checkpoint_is_named_and_the_previous_state_is_not_lost(tmp_path):
    path = str(tmp_path / "s.sqlite")
    r = subprocess.run(cmd(path, "t", "--scenarios", "30"), env=ENV, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    ckpt = os.path.splitext(path)[0] + ".t.ckpt"
    data = open(ckpt, "rb").read()
    open(ckpt, "wb").write(data[: len(data) // 2])
    r = subprocess.run(
        cmd(path, "t", "--scenarios", "40", "--resume"), env=ENV, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 2
    assert ckpt in r.stderr and "not a readable checkpoint" in r.stderr
    assert Store(path).count("t") == 30  # the stored scenarios are untouched


def test_corrupt_store_is_named(tmp_path):
    path = tmp_path / "bad.sqlite"
    path.write_bytes(b"this is not a database" * 100)
    r = subprocess.run(cmd(str(path), "x"), env=ENV, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert str(path) in r.stderr and "not a usable scenario store" in r.stderr


def test_truncated_model_file_is_named(tmp_path):
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_perception", "src"))
    from asg_perception.train import load_model

    src = os.path.join(REPO, "catkin_ws", "src", "asg_perception", "models", "flawed.pt")
    bad = tmp_path / "flawed.pt"
    bad.write_bytes(open(src, "rb").read()[:5000])
    with pytest.raises(ValueError) as e:
        load_model(str(bad))
    assert str(bad) in str(e.value)


def test_replay_of_an_unknown_job_is_named(tmp_path):
    path = str(tmp_path / "s.sqlite")
    r = subprocess.run(cmd(path, "u", "--scenarios", "10"), env=ENV, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0
    r = subprocess.run(
        [sys.executable, "-m", "asg_agent.ros.replay", path, "u", "999"],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2
    assert "has no job 999" in r.stderr

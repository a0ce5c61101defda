"""Issue #68 item 5: a seeded campaign proposes the same scenes whatever OpenBLAS kernel the CPU
would pick. The agent's arithmetic runs on OpenBLAS, whose kernel follows the CPU; the campaign
pins it (asg_agent/blas.py). Shown with the in-process stand-in pool (no simulator): TD3-PER-ASP,
seed 0, 120 scenarios (its warm-up is 100), with OPENBLAS_CORETYPE set as two CPUs would have it."""

import os
import sqlite3
import subprocess
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "test"))  # the stand-in beside its tests
import stand_in  # noqa: E402


def proposals(tmp_path, name, coretype, native=False):
    store = str(tmp_path / f"{name}.sqlite")
    env = stand_in.environ(dict(os.environ, OPENBLAS_CORETYPE=coretype, OMP_NUM_THREADS="1"))
    env.pop("ASG_AGENT_BLAS", None)
    if native:
        env["ASG_AGENT_BLAS"] = "native"
    cmd = [
        "/usr/bin/python3",
        "-m",
        "stand_in.campaign",
        os.path.join(REPO, "experiments", "exp1.yaml"),
        "--fake-workers",
        "3",
        "--scenarios",
        "120",
        "--method",
        "td3-per-asp",
        "--seed",
        "0",
        "--store",
        store,
        "--no-progress",
        "--no-tensorboard",
    ]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env, cwd=REPO)
    assert r.returncode == 0, r.stderr[-2000:]
    db = sqlite3.connect(store)
    settings = db.execute("select settings from campaigns").fetchone()[0]
    return [row[0] for row in db.execute("select request from scenarios order by job")], settings


def test_a_seeded_campaign_proposes_the_same_scenes_whatever_the_cpus_blas_kernel(tmp_path):
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))
    from asg_agent.blas import _has_avx2

    assert _has_avx2()  # every CPU class of the project has AVX2 (docs/benchmarks.md)
    # Sandy Bridge's and Haswell's kernels run on any of them
    a, settings = proposals(tmp_path, "a", "Sandybridge")
    b, _ = proposals(tmp_path, "b", "Haswell")
    assert len(a) == 120 and a == b
    assert '"agent_blas": "openblas' in settings and "Haswell" in settings
    # what the pin prevents: OpenBLAS's own kernel choice changes the proposals once TD3 learns
    native, settings = proposals(tmp_path, "n", "Sandybridge", native=True)
    first = next(k for k, (x, y) in enumerate(zip(a, native)) if x != y)
    assert 100 <= first < 120 and "Sandybridge" in settings

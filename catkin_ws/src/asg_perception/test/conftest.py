import os
import subprocess

import pytest


def make_dataset(folder, count, seed, meshes="juniper,barberry", extra=()):
    from asg_scenario.binaries import find_binary

    subprocess.run(
        [
            find_binary("asg_sim", "asg_sim_dataset"),
            "--out",
            str(folder),
            "--count",
            str(count),
            "--seed",
            str(seed),
            "--meshes",
            meshes,
            *extra,
        ],
        check=True,
        capture_output=True,
        env=dict(os.environ, LP_NUM_THREADS="1"),
    )
    return str(folder)


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("tiny"), 48, 11)


@pytest.fixture(scope="session")
def test_dataset(tmp_path_factory):
    """Held apart: a seed no shipped model was trained on, both obstacle types; the 600 frames
    of docs/perception.md (about 5 s to render)."""
    return make_dataset(tmp_path_factory.mktemp("test"), 600, 3)

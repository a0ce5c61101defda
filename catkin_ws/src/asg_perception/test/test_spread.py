"""asg_perception.spread: the table of shadow false-obstacle ratios over held-apart sets."""

import json

import pytest

from asg_perception import spread


def write(folder, seed, full, flawed, full_low, flawed_low):
    d = {
        "results": {
            "full": {"shadow_false_obstacle_rate": full, "low_sun": {"shadow_false_obstacle_rate": full_low}},
            "flawed": {"shadow_false_obstacle_rate": flawed, "low_sun": {"shadow_false_obstacle_rate": flawed_low}},
        }
    }
    (folder / f"seed_{seed}.json").write_text(json.dumps(d))


def test_ratios_and_the_table(tmp_path):
    write(tmp_path, 3, 0.02, 0.08, 0.01, 0.10)
    write(tmp_path, 4, 0.03, 0.09, 0.02, 0.12)
    write(tmp_path, 5, 0.01, 0.05, 0.01, 0.08)
    rows = spread.ratios(str(tmp_path))
    assert [r[0] for r in rows] == ["3", "4", "5"]
    assert rows[0][1] == pytest.approx(4.0) and rows[0][2] == pytest.approx(10.0)
    t = spread.table(str(tmp_path))
    assert "| 4 | 0.0300 | 0.0900 | 3.0x | 6.0x |" in t
    assert t.endswith("overall ratio: median 4.0x, min 3.0x, max 5.0x; low sun: median 8.0x, min 6.0x, max 10.0x")


def test_no_measurement_and_a_training_seed_are_named(tmp_path, capsys):
    with pytest.raises(FileNotFoundError, match="no seed_"):
        spread.table(str(tmp_path))
    with pytest.raises(SystemExit):
        spread.main(["--seeds", "1", "--table-only"])
    assert "--seeds 1: a training seed" in capsys.readouterr().err


def test_a_held_apart_set_draws_every_class_of_the_catalogue_in_its_order(tmp_path, monkeypatch):
    """Issue #80: spread.py named the classes ("juniper,barberry"); it asks the catalogue (the one
    source), in the catalogue's order, which is the order the stored sets were drawn in."""
    import subprocess

    from asg_scenario import binaries
    from asg_scenario.catalogue import MESHES

    calls = []
    monkeypatch.setattr(binaries, "find_binary", lambda pkg, name: f"/bin/{name}")
    monkeypatch.setattr(subprocess, "run", lambda cmd, **kw: calls.append(cmd))
    spread.measure(3, "", str(tmp_path))
    dataset = calls[0]
    assert dataset[0] == "/bin/asg_sim_dataset" and dataset[dataset.index("--meshes") + 1] == ",".join(MESHES)
    assert ",".join(MESHES) == "juniper,barberry"  # the stored sets' order (results/perception_spread)

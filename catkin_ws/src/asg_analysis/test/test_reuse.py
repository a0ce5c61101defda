"""asg_analysis.reuse (issue #67): an old export stands for a new protocol's campaign only when a
campaign run on today's code repeats its results."""

import gzip
import json

from asg_analysis import reuse


def _export(path, name, rows):
    with gzip.open(path, "wt", encoding="utf-8") as f:
        f.write(json.dumps({"campaign": {"name": name, "settings": "{}"}}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")


def _rows(flip=None):
    rows = []
    for j in range(6):
        rows.append(
            {
                "job": j,
                "positions": [[1.0 + j, 2.0]],
                "termination": "COLLISION" if j == flip else "SUCCESS",
                "proxy": 1.5,
                "collision_with": None,
                "attribution": "not_candidate",
                "wall_time": 9.0 + j,
                "worker": f"/worker_{j % 2}",
            }
        )
    return rows


def test_an_old_export_is_adopted_only_when_todays_run_repeats_it(tmp_path):
    old, proof, other = tmp_path / "old.jsonl.gz", tmp_path / "proof.jsonl.gz", tmp_path / "other.jsonl.gz"
    _export(old, "flaw-route-random-s10", _rows())
    same = _rows()
    for r in same:  # wall times and workers differ run to run: not results
        r["wall_time"] += 1.0
        r["worker"] = "/worker_9"
    _export(proof, "flaw3-route-random-s10", same)
    _export(other, "flaw3-route-random-s11", _rows(flip=3))
    assert reuse.run(["check", str(proof), str(old), "--budget", "6"]) == 0
    assert reuse.run(["check", str(other), str(old), "--budget", "6"]) == 1
    assert reuse.first_difference(reuse._read(str(other))[1], reuse._read(str(old))[1]) == 3
    assert reuse.first_difference(reuse._read(str(other))[1], reuse._read(str(old))[1], budget=3) is None
    folder = tmp_path / "study"
    folder.mkdir()
    rec = reuse.adopt(str(old), "flaw3-route-random-s12", str(folder), str(other), 6)
    assert rec["adopted"] is None and not (folder / "flaw3-route-random-s12.jsonl.gz").exists()
    rec = reuse.adopt(str(old), "flaw3-route-random-s12", str(folder), str(proof), 6)
    head, rows = reuse._read(str(folder / "flaw3-route-random-s12.jsonl.gz"))
    assert rec["adopted"] == "flaw3-route-random-s12" and head["campaign"]["name"] == "flaw3-route-random-s12"
    assert rows == _rows()
    assert head["campaign"]["adopted"] == {"from": "old.jsonl.gz", "proof": "proof.jsonl.gz", "budget": 6}
    assert [r["adopted"] for r in json.loads((folder / "reuse.json").read_text())] == [None, "flaw3-route-random-s12"]


def test_an_adopted_export_carries_its_own_studys_sharing_of_the_machine(tmp_path):
    # round 5's route-random s13 and s14 ran beside a soak (results/flaw_study/machine.log): adopted
    # into version 3, that deviation must still be listed in their rows
    from asg_analysis import protocol_analysis

    old_study, study = tmp_path / "old", tmp_path / "study"
    old_study.mkdir()
    study.mkdir()
    (old_study / "machine.log").write_text(
        "# flaw-route-random-s13 named in a comment does not count\n"
        "2026-11-28 a soak beside flaw-route-random-s13 and flaw-route-random-s14\n"
        "2026-11-29 a build beside flaw-route-random-s1\n",
        encoding="utf-8",
    )
    _export(old_study / "flaw-route-random-s13.jsonl.gz", "flaw-route-random-s13", _rows())
    _export(old_study / "flaw-route-random-s10.jsonl.gz", "flaw-route-random-s10", _rows())
    _export(tmp_path / "proof.jsonl.gz", "proof", _rows())
    for old, new in (("flaw-route-random-s13", "flaw3-route-random-s13"), ("flaw-route-random-s10", "x-s10")):
        assert reuse.adopt(str(old_study / f"{old}.jsonl.gz"), new, str(study), str(tmp_path / "proof.jsonl.gz"), 6)
    head, _ = reuse._read(str(study / "flaw3-route-random-s13.jsonl.gz"))
    assert head["campaign"]["adopted"]["shared"] == ["old/machine.log line 2"]
    head10, _ = reuse._read(str(study / "x-s10.jsonl.gz"))
    assert "shared" not in head10["campaign"]["adopted"]  # s1 is not s10, and no line names s10
    c = {"name": "flaw3-route-random-s13", "method": "route-random", "seed": 13, "reward": "proxy", "band": None}
    devs = protocol_analysis.deviations(
        {"budget": 6, "experiment": "x", "attribution": "three", "workers": 3}, c, head["campaign"], []
    )
    assert "flaw3-route-random-s13: shared the machine in its older study (old/machine.log line 2)" in devs

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
    assert reuse.main(["check", str(proof), str(old), "--budget", "6"]) == 0
    assert reuse.main(["check", str(other), str(old), "--budget", "6"]) == 1
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

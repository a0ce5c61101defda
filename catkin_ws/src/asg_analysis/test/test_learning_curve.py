"""asg_analysis.learning_curve (issue #67): findings per block of the budget, arm by arm."""

import gzip
import json

import pytest

from asg_analysis import learning_curve as lc


def _export(path, name, classes):
    with gzip.open(path, "wt", encoding="utf-8") as f:
        f.write(json.dumps({"campaign": {"name": name, "settings": "{}"}}) + "\n")
        for job, cls in enumerate(classes):
            f.write(json.dumps({"job": job, "attribution": cls}) + "\n")


def test_findings_are_counted_in_their_block_and_only_below_the_budget():
    rows = [{"job": j, "attribution": "flaw" if j in (0, 2, 3, 7, 9) else "model"} for j in range(10)]
    assert lc.blocks(rows, 10, 3) == [2, 1, 1, 1]  # the last block is short (job 9)
    assert lc.blocks(rows, 8, 4) == [3, 1]  # job 9 is past the budget
    assert lc.blocks(rows, 10, 5, target="model") == [2, 3]
    with pytest.raises(ValueError, match="block 0"):
        lc.blocks(rows, 10, 0)


def test_a_learning_arm_rises_and_a_level_one_does_not(tmp_path, capsys):
    # made-up campaigns: one finds more as it goes, one finds the same throughout
    _export(tmp_path / "a1.jsonl.gz", "a1", ["pass"] * 5 + ["flaw", "pass", "flaw", "flaw", "flaw"])
    _export(tmp_path / "a2.jsonl.gz", "a2", ["pass"] * 4 + ["flaw"] + ["flaw"] * 5)
    _export(tmp_path / "b1.jsonl.gz", "b1", ["flaw", "pass"] * 5)
    res = lc.curves(str(tmp_path), {"learns": ["a1", "a2"], "level": ["b1"]}, 10, 5)
    assert res["curves"] == {"learns": {"a1": [0, 4], "a2": [1, 5]}, "level": {"b1": [3, 2]}}
    md = lc.markdown(res)
    assert "| 0-4 | 0.5 (0, 1) | 3.0 (3) |" in md and "| 5-9 | 4.5 (4, 5) | 2.0 (2) |" in md
    drawn = lc.figure(res, str(tmp_path / "c.png"))
    assert drawn == {"learns": [0.5, 4.5], "level": [3.0, 2.0]} and (tmp_path / "c.png").stat().st_size > 0
    # each refusal names what is wrong (an exit code alone is shared by every error)
    assert lc.run([str(tmp_path), "--arm", "x=a1,nope", "--budget", "10", "--block", "5"]) == 2
    assert f"no export {tmp_path / 'nope.jsonl.gz'}" in capsys.readouterr().err
    assert lc.run([str(tmp_path), "--arm", "no-equals-sign"]) == 2
    assert "--arm 'no-equals-sign' is not NAME=CAMPAIGN" in capsys.readouterr().err

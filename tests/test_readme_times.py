"""Issue #79: the README's first screen is for the engineer who has a stack to test: it fits 40
lines, holds no p-value, round or issue number, and its commands' times are the newest records of
scripts/repro/readme_times.sh (measured, with the CPU named beside each), written into the page by
scripts/ci/readme_times.py."""

import os
import re
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "scripts", "ci"))

import readme_times  # noqa: E402


def first_screen():
    text = open(os.path.join(REPO, "README.md"), encoding="utf-8").read()
    return text.split("\n## Using it", 1)[0]


def test_the_first_screen_fits_40_lines_and_holds_no_study_figure():
    screen = first_screen()
    assert len(screen.splitlines()) <= 40
    assert not re.search(r"\bp [=<]|\bround \d|\bissue #\d|per CPU-hour|per 1,000", screen), screen
    for command in ("bash scripts/demo.sh", "bash scripts/train.sh", "bash scripts/test.sh"):
        assert f"`{command}`" in screen


def test_the_times_block_is_the_newest_records():
    recs = readme_times.records()
    assert readme_times.block(recs) in first_screen(), "run python3 scripts/ci/readme_times.py --doc README.md"
    for name, rec in recs.items():
        assert rec["wall_s"] > 0 and rec["cpu"] and rec["command"] == f"bash scripts/{name}.sh"


def test_each_time_is_measured_since_its_commands_files_last_changed_and_the_first_run_is_among_them():
    """A time is regenerated when the command's files change (the script, what it sources, the
    launch file it runs): bash scripts/repro/readme_times.sh NAME, then the --doc line above."""
    recs = readme_times.records()
    for name in ("demo", "train", "test"):
        assert name in recs, name
        assert readme_times.stale(recs[name]) == [], (name, readme_times.stale(recs[name]))
    # the first run a newcomer meets: train.sh in a fresh clone, installing and building first
    first = [r for r in readme_times.all_records().get("train", []) if not r["built_before"] and r["exit"] == 0]
    assert first, "no train.sh run from a fresh clone is recorded"
    assert "in a fresh clone, installing what is missing and building first" in first_screen()


def test_the_block_names_each_cpu_and_an_older_record_gives_way(tmp_path):
    import json

    for name, date, wall in (("demo", "2026-12-01 10:00 UTC", 50.0), ("demo", "2026-12-02 10:00 UTC", 61.0)):
        rec = {
            "command": f"bash scripts/{name}.sh",
            "wall_s": wall,
            "exit": 0,
            "built_before": True,
            "cpu": "AMD EPYC",
            "cpu_kind": "AVX2-only",
            "cores": 2,
            "commit": "abc1234",
            "date": date,
        }
        (tmp_path / f"{name}-{date[:10]}.json").write_text(json.dumps(rec))
    failed = dict(rec, date="2026-12-03 10:00 UTC", wall_s=5.0, exit=1)
    (tmp_path / "demo-failed.json").write_text(json.dumps(failed))
    text = readme_times.block(readme_times.records(str(tmp_path)), readme_times.passing(str(tmp_path)))
    # the newest run failed: said, with the newest that passed beside it
    assert "`bash scripts/demo.sh`: its newest run exited 1 after 5 s on a 2-core AMD EPYC (AVX2-only)" in text
    assert "the newest that passed: 1 min 01 s on a 2-core AMD EPYC (AVX2-only)" in text


def test_benchmarks_says_the_measured_avx2_train_runs():
    doc = open(os.path.join(REPO, "docs", "benchmarks.md"), encoding="utf-8").read()
    assert readme_times.avx2_train_block() in doc, "run python3 scripts/ci/readme_times.py --doc docs/benchmarks.md"
    assert "not measured" not in doc.split("## Scale-out")[0].split("on an AVX2-only CPU: predicted")[1]

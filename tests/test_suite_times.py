"""docs/testing.md's figures of the suite's time, recomputed from the runs recorded in
results/suite_times/ (issues #56, #69)."""

import json
import os
import re

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
TIMES = os.path.join(REPO, "results", "suite_times")


def record(name):
    with open(os.path.join(TIMES, name), encoding="utf-8") as f:
        return json.load(f)


def prose():
    with open(os.path.join(REPO, "docs", "testing.md"), encoding="utf-8") as f:
        return " ".join(f.read().split())


def wall_s(r):
    """The whole run's seconds: the record's number (issue #79), not its words."""
    return int(round(r["wall_s"]))


def test_every_record_holds_its_wall_seconds_as_a_number_its_words_agree_with():
    for name in sorted(os.listdir(TIMES)):
        r = record(name)
        assert isinstance(r["wall_s"], (int, float)) and r["wall_s"] > 0 and r["wall_s_from"], name
        m = re.search(r"(\d+) m (\d+) s", r.get("wall", ""))
        if m:  # the words typed beside it, where there are any, say the same time
            assert abs(int(m.group(1)) * 60 + int(m.group(2)) - r["wall_s"]) < 1.0, name


def test_the_suite_writes_its_measured_wall_time_into_its_record(tmp_path, monkeypatch):
    import subprocess
    import sys
    import time

    sys.path.insert(0, os.path.join(REPO, "scripts", "ci"))
    import summarize_tests

    monkeypatch.setenv("ASG_SUITE_START", str(time.time() - 12.5))
    summarize_tests.write_times(str(tmp_path), {"tests: tests.test_a": 3.0})
    rec = json.loads((tmp_path / "times.json").read_text())
    assert 12.5 <= rec["wall_s"] < 60.0 and "scripts/test.sh" in rec["wall_s_from"]
    monkeypatch.setenv("ASG_SUITE_START", "yesterday")
    summarize_tests.write_times(str(tmp_path), {"tests: tests.test_a": 3.0})
    assert "wall_s" not in json.loads((tmp_path / "times.json").read_text())
    # scripts/test.sh starts the clock before it installs or builds anything
    text = open(os.path.join(REPO, "scripts", "test.sh"), encoding="utf-8").read()
    assert text.index("ASG_SUITE_START=") < text.index("install_packages")
    assert subprocess.run(["bash", "-n", os.path.join(REPO, "scripts", "test.sh")]).returncode == 0


def test_each_recorded_run_is_as_the_page_gives_it():
    text = prose()
    for name in sorted(os.listdir(TIMES)):
        r = record(name)
        assert r["files"] and r["cores"] == 2 and r["commit"] in name, name
        assert f"`{name}`" in text, name
    r = record("r6-cb08c85-epyc-avx2.json")
    assert f"{len(r['files'])} files, {sum(r['files'].values()) / 60:.1f} min of test files" in text


def test_round_6_against_round_5_on_one_cpu_is_what_the_records_say():
    text = prose()
    a, b = record("r5-6d798f4-xeon-amx.json"), record("r6-a08b21b-xeon-amx.json")
    assert (a["cpu"], a["cpu_class"], a["cores"]) == (b["cpu"], b["cpu_class"], b["cores"])
    for name, r in (("r5-6d798f4-xeon-amx.json", a), ("r6-a08b21b-xeon-amx.json", b)):
        minutes = sum(r["files"].values()) / 60
        assert f"`{name}`: {len(r['files'])} files, {minutes:.1f} min of test files, {wall_s(r):,} s in all" in text
    assert f"That is {wall_s(b) / wall_s(a):.2f}x slower" in text
    assert f"Where the {wall_s(b) - wall_s(a)} s went" in text
    both = [k for k in b["files"] if k in a["files"]]
    assert not [k for k in a["files"] if k not in b["files"]]  # no file of round 5 was dropped
    new = {k: v for k, v in b["files"].items() if k not in a["files"]}
    assert f"**New test files: {sum(new.values()):.0f} s.**" in text
    top = max(new, key=new.get)
    assert top == "tests: tests.test_your_stack_recipe" and f"`test_your_stack_recipe`, at {new[top]:.0f} s" in text
    before, after = sum(a["files"][k] for k in both), sum(b["files"][k] for k in both)
    assert f"**Files that grew: {after - before:.0f} s.**" in text
    assert f"The {len(both)} files in both runs took {before:,.0f} s before and {after:,.0f} s after" in text
    grew = b["files"]["asg_tests/rosunit-registered_stacks.xml"] - a["files"]["asg_tests/rosunit-registered_stacks.xml"]
    assert f"`registered_stacks` grew by {grew:.0f} s" in text


def block():
    text = open(os.path.join(REPO, "docs", "testing.md"), encoding="utf-8").read()
    body = text.split("<!-- suite lanes: begin", 1)[1].split("<!-- suite lanes: end -->", 1)[0]
    return " ".join(body.split("\n", 1)[1].split())


def test_the_suite_side_by_side_against_one_at_a_time_and_round_5_on_one_cpu():
    text = block()
    r5, one, lanes = (
        record(n)
        for n in ("r5-6d798f4-xeon-noamx.json", "r6-ae5392e-xeon-noamx.json", "r6-ae5392e+lanes-xeon-noamx.json")
    )
    assert r5["cpu_class"] == one["cpu_class"] == lanes["cpu_class"] and "no amx" in one["cpu_class"]
    assert set(one["files"]) == set(lanes["files"])  # the same files, one at a time and side by side
    for name, r in (
        ("r5-6d798f4-xeon-noamx.json", r5),
        ("r6-ae5392e-xeon-noamx.json", one),
        ("r6-ae5392e+lanes-xeon-noamx.json", lanes),
    ):
        minutes = sum(r["files"].values()) / 60
        assert (
            f"`{name}`" in text
            and f"{len(r['files'])} files, {minutes:.1f} min of test files, {wall_s(r):,} s in all" in text
        ), name
    assert f"{wall_s(lanes) / wall_s(one):.2f}x the one-at-a-time run" in text
    both = [k for k in one["files"]]
    grew = sum(lanes["files"][k] for k in both) / sum(one["files"][k] for k in both)
    assert f"each file took {grew:.2f}x as long" in text
    assert f"{wall_s(lanes) / wall_s(r5):.2f}x round 5's end" in text
    assert f"{wall_s(one) / wall_s(r5):.2f}x before" in text


def test_round_7_against_round_6s_end_back_to_back_is_what_the_records_say():
    r7, r6 = record("r7-a67df1c-epyc-avx2.json"), record("r6-c6378da-epyc-avx2.json")
    assert r7["cpu_class"] == r6["cpu_class"]
    text = prose()
    assert f"`r7-a67df1c-epyc-avx2.json` took {wall_s(r7):,} s for {len(r7['files'])} files" in text
    assert f"`r6-c6378da-epyc-avx2.json` (round 6's last commit) {wall_s(r6):,} s for {len(r6['files'])} files" in text
    ratio = wall_s(r7) / wall_s(r6)
    assert f"{ratio:.2f}x, **slower by {wall_s(r7) - wall_s(r6)} s" in text and ratio > 1.0
    both = set(r7["files"]) & set(r6["files"])
    new = set(r7["files"]) - set(r6["files"])
    assert (
        f"The {len(both)} files both ran took {sum(r6['files'][k] for k in both):,.0f} s of job time before and "
        f"{sum(r7['files'][k] for k in both):,.0f} s after, the {len(new)} new files {sum(r7['files'][k] for k in new):.0f} s"
    ) in text


def test_the_suite_after_the_speed_ups_is_what_its_record_says():
    r7, r6 = record("r7-9bb0cbc-epyc-avx2.json"), record("r6-c6378da-epyc-avx2.json")
    assert r7["cpu_class"] == r6["cpu_class"]
    both = set(r7["files"]) & set(r6["files"])
    text = prose()
    assert (
        f"{wall_s(r7):,} s for {len(r7['files'])} files, {wall_s(r7) / wall_s(r6):.2f}x round 6's end's "
        f"{wall_s(r6):,} s; the {len(both)} files both ran took {sum(r7['files'][k] for k in both):,.0f} s of job "
        f"time against {sum(r6['files'][k] for k in both):,.0f} s"
    ) in text


def test_ctest_against_run_parallel_is_what_the_records_say():
    c, p = record("r7-1acf8cf+ctest-epyc-avx2.json"), record("r7-9bb0cbc-epyc-avx2.json")
    assert c["cpu_class"] == p["cpu_class"] and c["runner"] == "ctest -j 2"
    text = prose()
    assert f"took {wall_s(c):,} s (`r7-1acf8cf+ctest-epyc-avx2.json`, 866 tests) against" in text
    assert f"run_parallel's {wall_s(p):,} s: {wall_s(c) / wall_s(p):.2f}x" in text


def test_round_7_against_round_6s_end_back_to_back_after_the_speed_ups():
    """Issue #80: the pair run again back to back (round 6's end first), each alone on one machine."""
    r6 = record("r6-c6378da-b-epyc-avx2.json")
    r7 = record("r7-d1a8db5-epyc-avx2.json")
    assert r7["cpu_class"] == r6["cpu_class"]
    both = set(r7["files"]) & set(r6["files"])
    text = prose()
    assert f"`r6-c6378da-b-epyc-avx2.json` took {wall_s(r6):,} s for {len(r6['files'])} files" in text
    assert f"`r7-d1a8db5-epyc-avx2.json` {wall_s(r7):,} s for {len(r7['files'])} files" in text
    assert f"{wall_s(r7) / wall_s(r6):.2f}x" in text
    assert (
        f"the {len(both)} files both ran took {sum(r6['files'][k] for k in both):,.0f} s of job time before and "
        f"{sum(r7['files'][k] for k in both):,.0f} s after"
    ) in text


def test_round_8_against_round_7s_end_back_to_back_is_what_the_records_say():
    """Issue #94: round 8 no slower than round 7's end, back to back on one machine."""
    r7 = record("r7-18c8fe5-epyc-bf16.json")
    r8 = record("r8-39c3f09-epyc-bf16.json")
    assert r8["cpu_class"] == r7["cpu_class"] and r8["cpu"] == r7["cpu"]
    both = set(r8["files"]) & set(r7["files"])
    new = set(r8["files"]) - both
    text = prose()
    assert f"`r7-18c8fe5-epyc-bf16.json` took {wall_s(r7):,} s for {len(r7['files'])} files" in text
    assert f"`r8-39c3f09-epyc-bf16.json` {wall_s(r8):,} s for {len(r8['files'])} files" in text
    assert f"{wall_s(r8) / wall_s(r7):.2f}x, no slower, with {len(new)} more files" in text
    assert wall_s(r8) <= wall_s(r7)
    assert (
        f"the {len(both)} files both ran took {sum(r7['files'][k] for k in both):,.0f} s before and "
        f"{sum(r8['files'][k] for k in both):,.0f} s after, the {len(new)} new files "
        f"{sum(r8['files'][k] for k in new):,.0f} s"
    ) in text
    before = open(os.path.join(REPO, "results", "bench", "r8-one-before-1.digest")).read().split()
    after = open(os.path.join(REPO, "results", "bench", "r8-one-after-1.digest")).read().split()
    assert before == after and f"{after[1][:8]})" in text
    registry = open(os.path.join(REPO, "results", "bench", "r8-registry-after-1.digest")).read().split()
    assert registry == after and "`r8-registry-after-1.digest`" in text

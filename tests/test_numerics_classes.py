"""Issue #53: the default numerics are one stack identity on every CPU class checked. Every line
of results/numerics/cpu_classes.json (written by reference_runs.test with ASG_RECORD_CPU_CLASS=1 on
the CPU it names) must hold the digests of the one stored reference set; at least two classes of
different best ISA; and the fp32 replay rule accepts a run recorded on any of them."""

import json
import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_perception", "src"))

from asg_perception import numerics as n  # noqa: E402


def load(name):
    with open(os.path.join(REPO, name)) as f:
        return json.load(f)


def test_every_cpu_class_replayed_the_one_stored_reference():
    ref = load("tests/reference/exp1_flawed_fp32.json")
    digests = [r["digest"] for r in ref["runs"]]
    classes = load("results/numerics/cpu_classes.json")["classes"]
    for c in classes:
        assert c["reference"] == "tests/reference/exp1_flawed_fp32.json", c["cpu"]
        assert c["digests"] == digests, f"{c['cpu']}: digests differ from the stored reference"
        assert c["numerics"].split()[0] in n.FP32_PORTABLE_BACKENDS, c["cpu"]
    assert len({c["best_isa"] for c in classes}) >= 2, "fewer than two CPU classes checked"
    assert n.DEFAULT_BACKEND in n.FP32_PORTABLE_BACKENDS
    assert [c for c in classes if c["numerics"].split()[0] == n.DEFAULT_BACKEND], "the default never replayed"
    # one reference file for the fp32 backends: no per-backend or per-ISA copies
    assert not [
        f
        for f in os.listdir(os.path.join(REPO, "tests", "reference"))
        if any(f.startswith(f"exp1_flawed_{b}") for b in n.FP32_PORTABLE_BACKENDS + ("fp32",))
        and f != "exp1_flawed_fp32.json"
    ]


def test_fp32_runs_replay_across_the_checked_classes_and_bf16_ones_do_not():
    classes = load("results/numerics/cpu_classes.json")["classes"]
    ids = {c["numerics"] for c in classes}
    for a in ids:
        for b in ids:
            assert n.can_reproduce(a, b) is None, (a, b)
    bf = "bf16 isa=AVX512_CORE_BF16 threads=1 torch=1.13.0a0"
    assert "oneDNN kernels" in n.can_reproduce(bf, bf.replace("AVX512_CORE_BF16", "AVX512_CORE_AMX"))
    # fp32 on an ISA never checked is still refused, with the reason
    assert "oneDNN kernels" in n.can_reproduce(
        "channels_last isa=AVX2 threads=1 torch=1.13.0a0", "channels_last isa=SSE41 threads=1 torch=1.13.0a0"
    )


def test_the_benchmarks_page_lists_every_class_checked():
    text = open(os.path.join(REPO, "docs", "benchmarks.md"), encoding="utf-8").read()
    sec = text[text.index("## CPU classes: the default numerics") :]
    sec = sec[: sec.index("\n## ")]
    rows = [ln for ln in sec.splitlines() if ln.startswith("| ") and not ln.startswith("| CPU ")]
    classes = load("results/numerics/cpu_classes.json")["classes"]
    assert len(rows) == len(classes)
    for ln, c in zip(rows, classes):
        cells = [x.strip() for x in ln.strip("|").split("|")]
        assert cells[0] == c["cpu"] and cells[1] == c["best_isa"]
        assert cells[2] == ("yes" if c["native_bf16"] else "no") and cells[3] == f"`{c['numerics']}`"
        assert cells[4].split() == [d[:8] for d in c["digests"]] and cells[5] == c["date"]


def test_the_defaults_baselines_are_the_channels_last_rows():
    """The 300-layout Exp. 1 baselines of the U-Net stacks, run again on the default (polyphase,
    results/baseline/backend_polyphase/), equal the channels_last rows that docs/baseline.md
    tabulates in every field: layout, ending, path length, proxy, simulated time."""

    def rows(path):
        with open(os.path.join(REPO, path)) as f:
            return {r["layout"]: r for r in map(json.loads, f)}

    for stack in ("flawed", "full"):
        cl = rows(f"results/baseline/exp1/{stack}.jsonl")
        pp = rows(f"results/baseline/backend_polyphase/exp1/{stack}.jsonl")
        assert len(pp) == len(cl) == 300, stack
        assert pp == cl, stack


def test_a_cpu_class_line_holds_the_digests_its_runs_produced(tmp_path, monkeypatch):
    # issue #68: the line is the runs' record, not a copy of the stored file's digests (a copy
    # would make the test above compare the file with itself)
    sys.path.insert(0, os.path.join(REPO, "tests"))
    import stack_util as su

    table = tmp_path / "cpu_classes.json"
    monkeypatch.setattr(su, "CPU_CLASSES", str(table))
    path = os.path.join(REPO, "tests", "reference", "exp1_flawed_fp32.json")
    produced = ["made-up digest %d" % k for k in range(len(load("tests/reference/exp1_flawed_fp32.json")["runs"]))]
    su.record_cpu_class(path, "polyphase isa=AVX2 threads=1 torch=x", produced, "test")
    line = json.loads(table.read_text())["classes"][-1]
    assert line["digests"] == produced and line["reference"] == "tests/reference/exp1_flawed_fp32.json"


def test_a_class_whose_runs_differ_is_recorded_before_the_comparison_fails(tmp_path, monkeypatch):
    """issue #79: record_cpu_class used to run only after check_reference had asserted the digests
    equal, so every recorded line equalled the stored file by construction. Now check_reference
    hands what the runs produced to its recorder before any comparison: a run that differs is
    recorded (and the test above then fails on its line), and the comparison still fails."""
    import types
    import unittest

    sys.path.insert(0, os.path.join(REPO, "tests"))
    import stack_util as su

    ref = load("tests/reference/exp1_flawed_fp32.json")
    stored = os.path.join(REPO, "tests", "reference", "exp1_flawed_fp32.json")
    pose = types.SimpleNamespace(pose=types.SimpleNamespace(position=types.SimpleNamespace(x=1.0, y=2.0)))

    def fake_run(client, request):
        entry = ref["runs"][fake_run.k]
        fake_run.k += 1
        r = types.SimpleNamespace(termination_name=entry["termination"], trajectory=[pose] * entry["samples"], error="")
        r.digest = "a digest of another CPU %d" % fake_run.k
        return su.SUCCEEDED, r

    fake_run.k = 0
    monkeypatch.setattr(su, "run", fake_run)
    monkeypatch.setattr(su, "trajectory_digest", lambda r: r.digest)
    monkeypatch.setattr(su, "wait_for_numerics", lambda worker: ref["numerics"])
    table = tmp_path / "cpu_classes.json"
    monkeypatch.setattr(su, "CPU_CLASSES", str(table))
    seen = []

    def record(here, produced):
        seen.append(list(produced))
        su.record_cpu_class(stored, here, produced, "test")

    case = unittest.TestCase()
    try:
        su.check_reference(case, None, stored, False, on_produced=record)
        raise AssertionError("digests that differ from the stored ones passed the comparison")
    except case.failureException as e:
        assert "trajectory differs" in str(e)
    want = ["a digest of another CPU %d" % (k + 1) for k in range(len(ref["runs"]))]
    assert seen == [want]
    assert json.loads(table.read_text())["classes"][-1]["digests"] == want

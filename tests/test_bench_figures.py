"""docs/benchmarks.md's before/after figures of issue #38's refactor (results/bench/r4-arch-*), of
issue #56's architecture step (results/bench/r5-arch-*, the same bench) and of issue #53's fp32
default (results/bench/r5-numerics-* and, with polyphase, r5-final-*; bf16 beside), recomputed from the committed stage
reports and result digests."""

import glob
import json
import os

import pytest

from asg_analysis.bench import before_after, before_after_sentence
from doc_pages import guide, record

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
BENCH_PAGES = [
    guide("benchmarks.md"),
    record("campaign-throughput"),
    record("bf16-lite-backends"),
    record("three-stack-attribution-cost"),
    record("refactors-before-after"),
    record("fp32-and-polyphase"),
]


@pytest.mark.parametrize("tag", ["r4-arch", "r5-arch", "r5-numerics", "r5-final"])
def test_the_refactor_bench_in_the_docs_is_its_reports(tag):
    TAG = os.path.join(REPO, "results", "bench", tag)
    before = sorted(glob.glob(TAG + "-before-*.json"))
    after = sorted(glob.glob(TAG + "-after-*.json"))
    assert len(before) == len(after) == 3

    def load(paths):
        return [json.load(open(p)) for p in paths]

    sentence = before_after_sentence(before_after(load(before), load(after)))
    assert sentence in " ".join(_bench_doc().split()), sentence
    # every campaign, on either side, found the same 120 results (requests, outcomes, trajectories)
    digests = {open(p[: -len(".json")] + ".digest").read().strip() for p in before + after}
    assert len(digests) == 1 and next(iter(digests)).startswith("120 "), digests


def test_the_avx2_prediction_is_the_arithmetic_and_the_model_holds_on_a_measured_bench():
    # issue #53: the README's campaign on an AVX2-only CPU, predicted from committed benches
    from asg_analysis.bench import predict, predict_sentence

    bench = os.path.join(REPO, "results", "bench")
    non_unet = [
        json.load(open(os.path.join(bench, f"r4-arch-{side}-{k}.json")))
        for side in ("before", "after")
        for k in (1, 2, 3)
    ]
    shape = [json.load(open(os.path.join(bench, f"r4-three-{k}-w3.json"))) for k in (1, 2, 3)]
    assert len(non_unet) == 6 and all(r["machine"]["cpu"] == "AMD EPYC" for r in non_unet)
    doc = " ".join(_bench_doc().split())
    for ms in (62, 24, 22):  # 22: the AVX2 EPYC's 62 ms x polyphase / channels_last pinned to AVX2 (10.00 / 27.99)
        assert predict_sentence(predict(ms, non_unet, shape, 150, 2)) in doc, ms
    # the model against campaigns that ran: each three-stack bench from its own per-process CPU
    said = []
    for r in shape:
        c = r["cpu_per_scenario_s"]
        own = [{"stacks": {"under test": {"cpu_per_run_s": c["scene_worker"] + c["planner"]}}, "cpu_per_scenario_s": c}]
        p = predict(1000 * c["segmenter"] / r["frames_per_scenario"], own, [r], r["scenarios"], 2)
        assert abs(p["minutes"] / (r["wall_s"] / 60) - 1) < 0.05
        said.append((f"{p['minutes']:.2f}", f"{r['wall_s'] / 60:.2f}"))
    text = f"gives {', '.join(s[0] for s in said[:-1])} and {said[-1][0]} minutes for campaigns that took {', '.join(s[1] for s in said[:-1])} and {said[-1][1]}"
    assert text in doc, text


@pytest.mark.parametrize("tag,fast_runs", [("r5-numerics", 2), ("r5-final", 3)])
def test_the_numerics_bench_says_what_its_reports_say(tag, fast_runs):
    # issue #53: the default after the issue against before it (fp32 channels_last before; after:
    # channels_last in r5-numerics, polyphase in r5-final), the 1.3x target, and bf16's fast mode
    # beside them (its results differ: it is another stack)
    import statistics

    TAG = os.path.join(REPO, "results", "bench", tag)

    def load(side, runs):
        paths = sorted(glob.glob(f"{TAG}-{side}-*.json"))
        assert len(paths) == runs, side
        return [json.load(open(p)) for p in paths], paths

    # three a side; bf16 beside them (r5-numerics: twice, its third run was cut for the session's time)
    (before, _), (after, _), (fast, fast_paths) = load("before", 3), load("after", 3), load("fast", fast_runs)
    c = before_after(before, after)
    met = "met" if c["rate_ratio"] >= 1.3 else "missed"
    rate = sorted(r["rate_per_hour"] for r in fast)
    said = (
        f"the 1.3x target is {met}: after / before {c['rate_ratio']:.3f}. bf16 fast mode beside them: "
        f"{statistics.median(rate):,.0f} ({rate[0]:,.0f}-{rate[-1]:,.0f}) scenarios an hour, "
        f"{statistics.median(rate) / c['after']['rate'][0]:.2f}x the default's"
    )
    doc = " ".join(_bench_doc().split())
    assert said in doc, said
    # the fast side's campaigns agree with each other (bf16 is deterministic on one ISA)
    fast_digests = {open(p[: -len(".json")] + ".digest").read().strip() for p in fast_paths}
    assert len(fast_digests) == 1 and next(iter(fast_digests)).startswith("120 "), fast_digests
    if tag != "r5-numerics":
        return  # r5-final: the frame times are the table's, and its section reads them there
    # U-Net ms a frame in the campaigns: bf16 under its AVX512_CORE_BF16 cap against fp32
    ms = sorted(r["inference_ms_per_frame"] for r in before + after)
    bf = sorted(r["inference_ms_per_frame"] for r in fast)
    frames = f"{bf[0]:.0f}-{bf[-1]:.0f} ms in the campaign against {ms[0]:.0f}-{ms[-1]:.0f} ms (median {statistics.median(ms):.0f})"
    assert frames in doc, frames


def test_the_polyphase_bench_and_label_table_in_the_docs_are_their_exports():
    # issue #53: channels_last against polyphase, one tree, one pair before and one after the
    # thread-pool fixes; every campaign found the same 120 results
    bench = os.path.join(REPO, "results", "bench")
    pair = [json.load(open(os.path.join(bench, f"r5-polyphase-{side}-1.json"))) for side in ("before", "after")]
    doc = " ".join(_bench_doc().split())
    c = before_after(pair[:1], pair[1:])
    assert before_after_sentence(c) in doc
    assert c["rate_ratio"] > 1.0 and c["cpu_ratio"] < 1.0  # what the section says: faster, less CPU
    digests = {open(p).read().strip() for p in glob.glob(os.path.join(bench, "r5-polyphase-*.digest"))}
    assert len(glob.glob(os.path.join(bench, "r5-polyphase-*.digest"))) == 4
    assert len(digests) == 1 and next(iter(digests)).startswith("120 "), digests
    table = json.load(open(os.path.join(REPO, "results", "numerics", "polyphase_agreement.json")))
    assert len(table["pairs"]) == 6
    for p in table["pairs"]:
        row = f"| `{p['a']}` | `{p['b']}` | {p['frames_differ']} of {p['frames']:,} | {p['pixels_differ']} of {p['pixels']:,} |"
        assert row in doc, row


# -- issue #68 item 6: sentences of docs/benchmarks.md held to what was measured ------------------


def _bench_doc():
    """The benchmarks guide and the benchmark study records (issue #79 split them)."""
    return "\n\n".join(open(p, encoding="utf-8").read() for p in BENCH_PAGES)


def test_every_stored_reference_file_the_docs_cite_exists():
    # a file that is gone is named without its folder, as what it was then
    import re

    pages = glob.glob(os.path.join(REPO, "docs", "**", "*.md"), recursive=True) + [os.path.join(REPO, "README.md")]
    gone = []
    for page in pages:
        with open(page, encoding="utf-8") as f:
            for cited in re.findall(r"tests/reference/[\w.*-]+\.json", f.read()):
                if not glob.glob(os.path.join(REPO, cited)):
                    gone.append(f"{os.path.relpath(page, REPO)}: {cited}")
    assert not gone, gone


#: what marks a sentence about bf16 as history: bf16 was the default from issue #24 to issue #53
THEN = ("then", "to 2026-11-27", "until 2026-11-27", "before 2026-11-27")


def test_bf16_is_called_shipped_only_in_sentences_marked_as_history():
    import re

    units = []
    for para in re.split(r"\n\s*\n", _bench_doc()):
        rows = [ln for ln in para.splitlines() if ln.startswith("|")]
        text = " ".join(ln for ln in para.splitlines() if not ln.startswith("|"))
        units += rows + re.split(r"(?<=[.!?])\s+", " ".join(text.split()))
    # "shipped" of bf16, not "not shipped" (said of other backends beside it)
    said = [u for u in units if "bf16" in u and re.search(r"(?<![Nn]ot )\bshipped\b", u)]
    unmarked = [u for u in said if not any(re.search(rf"\b{m}\b", u) for m in THEN)]
    assert not unmarked, unmarked


def test_the_fp32_labels_across_kernels_are_the_agreement_export():
    # the five closed-loop runs are the same on AVX2 and AVX-512 kernels; the labels are not always
    with open(os.path.join(REPO, "results", "numerics", "polyphase_agreement.json"), encoding="utf-8") as f:
        pairs = {(p["a"], p["b"]): p for p in json.load(f)["pairs"]}
    cl = pairs[("channels_last:native", "channels_last:AVX2")]
    pp = pairs[("polyphase:native", "polyphase:AVX2")]
    assert cl["frames"] == pp["frames"] and cl["pixels"] == pp["pixels"]
    doc = " ".join(_bench_doc().split())
    said = (
        f"on the {cl['frames']:,} frames of the label table above, {cl['pixels_differ']} pixels of "
        f"{cl['pixels']:,} differ between the two for `channels_last` and {pp['pixels_differ']} for `polyphase`"
    )
    assert said in doc, said
    if cl["pixels_differ"] or pp["pixels_differ"]:
        assert "fp32 convolutions give the same labels" not in doc


def test_the_default_against_bf16_is_said_beside_the_target():
    # issue #53's 1.433 is against the code before it on its fp32 path; bf16 was that code's
    # default, and the bench ran it beside them (the fast side, this tree, the same CPU)
    import statistics

    TAG = os.path.join(REPO, "results", "bench", "r5-final")

    def median_rate(side):
        runs = [json.load(open(p)) for p in sorted(glob.glob(f"{TAG}-{side}-*.json"))]
        assert len(runs) == 3 and {r["machine"]["cpu"] for r in runs} == {"AMD EPYC"}
        return statistics.median(r["rate_per_hour"] for r in runs)

    after, fast = median_rate("after"), median_rate("fast")
    side = [[json.load(open(p)) for p in sorted(glob.glob(f"{TAG}-{s}-*.json"))] for s in ("before", "after")]
    target = before_after(*side)["rate_ratio"]
    said = f"the default runs at {after / fast:.2f}x: {after:,.0f} against {fast:,.0f} scenarios an hour, medians"
    doc = " ".join(_bench_doc().split())
    assert said in doc, said
    assert (
        f"the {target:.3f} is against the code before issue #53 on its fp32 path, which was not its default then" in doc
    )


def test_the_round_6_refactor_found_the_same_results_before_and_after():
    # issue #69: one seeded 120-scenario campaign a side; the page lists each side's digest
    text = _bench_doc()
    block = text.split("<!-- r6-arch digests: begin -->")[1].split("<!-- r6-arch digests: end -->")[0]
    digests = {}
    for side in ("before", "after"):
        n, d = open(os.path.join(REPO, "results", "bench", f"r6-arch-{side}-1.digest")).read().split()
        assert f"r6-arch-{side}-1.digest`, {n} results, {d[:8]}" in block
        digests[side] = (n, d)
    assert digests["before"] == digests["after"] and digests["after"][0] == "120"


def test_round_8s_refactor_found_round_7s_results_on_another_epyc_class():
    # issue #94: round 7's end (18c8fe5) and the refactored tree, one seeded 120-scenario campaign a
    # side on the AVX512-BF16 EPYC: one digest, round 7's on the AVX2-only EPYC
    bench = os.path.join(REPO, "results", "bench")
    seen = {}
    for name in ("r8-one-before-1", "r8-one-after-1", "r7-config-after-1"):
        seen[name] = tuple(open(os.path.join(bench, f"{name}.digest")).read().split())
    assert len(set(seen.values())) == 1 and seen["r8-one-after-1"][0] == "120"
    cpus = {}
    for name in ("r8-one-before-1", "r8-one-after-1", "r7-config-after-1"):
        with open(os.path.join(bench, f"{name}.json"), encoding="utf-8") as f:
            cpus[name] = json.load(f)["machine"]
    assert cpus["r8-one-before-1"] == cpus["r8-one-after-1"]
    text = " ".join(open(record("refactors-before-after"), encoding="utf-8").read().split())
    assert f"the same digest as round 7's on the AVX2-only EPYC ({seen['r8-one-after-1'][1][:8]})" in text


def test_a_seeded_campaign_gives_one_digest_on_the_xeon_and_the_epyc():
    # issue #68 item 5: with the agent's OpenBLAS kernel pinned, the seeded 120-scenario campaign gives
    # on the AMX Xeon the digest it gave on the AVX2-only EPYC; before the pin the Xeon gave another
    text = _bench_doc()
    block = text.split("<!-- r6-xeon digests: begin -->")[1].split("<!-- r6-xeon digests: end -->")[0]
    seen = {}
    for name in ("r6-xeon-before-1", "r6-xeon-after-1", "r6-arch-after-1"):
        n, d = open(os.path.join(REPO, "results", "bench", f"{name}.digest")).read().split()
        assert f"{name}.digest`, {n} results, {d[:8]}" in block
        with open(os.path.join(REPO, "results", "bench", f"{name}.json"), encoding="utf-8") as f:
            seen[name] = (n, d, json.load(f)["machine"]["cpu"])
    assert len({(n, d) for n, d, _ in seen.values()}) == 1 and seen["r6-arch-after-1"][0] == "120"
    assert seen["r6-xeon-after-1"][2].startswith("Intel") and seen["r6-arch-after-1"][2].startswith("AMD")
    old = open(os.path.join(REPO, "results", "bench", "r5-arch-after-1.digest")).read().split()[1]
    assert old != seen["r6-xeon-after-1"][1]
    assert f"Before the pin the Xeon gave {old[:8]} for this campaign" in " ".join(text.split())


def test_the_whole_stacks_seeded_campaign_is_the_same_on_the_xeon_and_the_epyc():
    # issue #68 item 5: flaw3-default-s10 on the AVX2-only EPYC and again on the AMX Xeon: the same
    # results (positions, termination, proxy, obstacle hit, attribution) job by job, recomputed here
    import gzip

    def read(path):
        with gzip.open(os.path.join(REPO, path), "rt", encoding="utf-8") as f:
            camp = json.loads(f.readline())["campaign"]
            rows = {r["job"]: r for r in map(json.loads, f) if "job" in r}
        cpus = {e.get("cpu") for e in json.loads(camp["settings"])["events"] if e.get("cpu")}
        return cpus, rows

    epyc, a = read("results/flaw_study3/flaw3-default-s10.jsonl.gz")
    xeon, b = read("results/flaw_study3/cpu_check/flaw3-xeon-default-s10.jsonl.gz")
    assert epyc == {"AMD EPYC"} and len(xeon) == 1 and next(iter(xeon)).startswith("Intel")
    assert sorted(a) == sorted(b) == list(range(300))
    keys = ("positions", "termination", "collision_with", "attribution", "meshes")
    for j in range(300):
        assert [a[j][k] for k in keys] == [b[j][k] for k in keys], j
        assert abs(a[j]["proxy"] - b[j]["proxy"]) < 1e-9, j
    text = " ".join(_bench_doc().split())
    assert "the same results digest over its 300 jobs, ecc502be" in text


def test_the_round_7_refactor_gives_round_6s_results_with_round_6s_reward():
    # issue #80: the seeded 120-scenario campaign on the merged tree; with reward:=proxy (round 6's
    # auto without attribution) round 6's digest, without it one other digest, the same twice
    text = open(record("refactors-before-after"), encoding="utf-8").read()
    block = text.split("<!-- r7-config digests: begin -->")[1].split("<!-- r7-config digests: end -->")[0]
    d = {}
    for side in ("before", "after", "proxy"):
        n, sha = open(os.path.join(REPO, "results", "bench", f"r7-config-{side}-1.digest")).read().split()
        assert f"r7-config-{side}-1.digest`, {n} results, {sha[:8]}" in block
        d[side] = (n, sha)
    r6 = tuple(open(os.path.join(REPO, "results", "bench", "r6-arch-after-1.digest")).read().split())
    assert d["proxy"] == r6 and d["before"] == d["after"] != r6
    assert "**With `reward:=proxy` the merged tree gives round 6's 120 results bit for bit**" in text

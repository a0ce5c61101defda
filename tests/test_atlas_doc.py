"""Issue #93: the atlases of results/atlas/ as docs/agent.md shows them, and protocol v5's
baseline figure recounted from the exports by a plain loop (no project geometry)."""

import gzip
import json
import math
import os
import re
import subprocess
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def test_the_docs_atlas_block_is_the_show_output_of_every_atlas_file():
    rc = subprocess.run(
        [sys.executable, "-m", "asg_analysis", "coverage", "doc", "--check"], cwd=REPO, capture_output=True, text=True
    )
    assert rc.returncode == 0, "docs/agent.md's atlas block is stale: python3 -m asg_analysis coverage doc"


def _recall(atlas, path, budget=300):
    places = [g for g in atlas["groupings"] if g["radius_m"] == 5.0][0]["places"]
    with gzip.open(path, "rt") as f:
        f.readline()
        rows = sorted((json.loads(line) for line in f), key=lambda r: r["job"])[:budget]
    hits = [
        (r["meshes"][r["collision_with"]], *r["positions"][r["collision_with"]])
        for r in rows
        if r.get("attribution") == "flaw" and r["termination"] == "COLLISION" and r["collision_with"] is not None
    ]
    ends = [
        ("no contact", *r["trajectory_xy"][-1])
        for r in rows
        if r.get("attribution") == "flaw" and not (r["termination"] == "COLLISION" and r["collision_with"] is not None)
    ]
    got = hits + ends
    n = sum(any(c == p["cls"] and math.hypot(x - p["x"], y - p["y"]) < 5.0 for c, x, y in got) for p in places)
    return n / len(places)


def test_protocol_v5s_baseline_sentence_is_the_recount_of_v4s_exports():
    # the atlas as the protocol was written (results/atlas/ holds its newer versions)
    atlas = json.load(open(os.path.join(REPO, "results", "coverage_v5", "exp1-flaw.v1.json")))
    v4 = os.path.join(REPO, "results", "distinct_v4")
    mean = {
        arm: sum(_recall(atlas, os.path.join(v4, f"dist4-{arm}-s{s}.jsonl.gz")) for s in range(30, 35)) / 5
        for arm in ("default", "route-random")
    }
    text = open(os.path.join(REPO, "experiments", "protocol-coverage-v5.yaml")).read()
    want = f"recall {mean['default']:.2f} against\n# {mean['route-random']:.2f} of results/atlas/exp1-flaw.json v{atlas['version']}"
    assert want in text, (want, mean)


def test_the_v5_records_blocks_are_the_analysis_of_the_exports():
    rc = subprocess.run(
        [sys.executable, "-m", "asg_analysis", "coverage", "record", "--check"],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert (
        rc.returncode == 0
    ), "docs/studies/2026-12-06-coverage-v5.md is stale: python3 -m asg_analysis coverage record"


def test_the_readmes_answer_is_the_recount_of_the_default_and_route_random():
    """The README's first screen says how the default compares with route-random on the study's
    endpoint; its per-seed figures are those of a plain recount against the current atlas."""
    import re

    atlas = json.load(open(os.path.join(REPO, "results", "atlas", "exp1-flaw.json")))
    v4 = os.path.join(REPO, "results", "distinct_v4")
    per = {
        arm: [_recall(atlas, os.path.join(v4, f"dist4-{arm}-s{s}.jsonl.gz")) for s in range(30, 35)]
        for arm in ("default", "route-random")
    }
    readme = open(os.path.join(REPO, "README.md"), encoding="utf-8").read()
    answer = readme.split("<!-- answer: begin -->", 1)[1].split("<!-- answer: end -->", 1)[0]
    assert readme.index("<!-- answer: begin -->") < readme.index("## Start here")  # on the first screen
    for arm, text in (
        ("default", "covered {m:.2f} (per seed {p})"),
        ("route-random", "cheapest competitor, {m:.2f} ({p})"),
    ):
        want = text.format(m=sum(per[arm]) / 5, p=", ".join(f"{r:.2f}" for r in per[arm]))
        assert want in answer, (arm, want)
    ratio = float(re.search(r": (\d\.\d\d)x \(95 % interval", answer).group(1))
    assert abs(ratio - sum(per["default"]) / sum(per["route-random"])) < 0.006
    # the verdict is no stronger than the test it reports
    from asg_analysis import stats

    p = stats.mann_whitney(per["default"], per["route-random"])["p"]
    assert ("Not shown" in answer) == (p >= 0.05), p


def test_the_records_atlas_v3_and_v4_sentences_are_the_atlas_files():
    # the record's prose on v3 (kept as results/coverage_v5/exp1-flaw.v3.json), on v2, which the
    # pilot was read against, and on the current atlas
    def at5(path):
        with open(os.path.join(REPO, path), encoding="utf-8") as f:
            a = json.load(f)
        g = [g for g in a["groupings"] if g["radius_m"] == 5.0][0]
        return a["version"], len(g["places"]), g["chao1"]["completeness"], g["chao2"]["completeness"], a, g

    v3, n3, c1_3, c2_3, _, _ = at5("results/coverage_v5/exp1-flaw.v3.json")
    v2, n2, c1_2, c2_2, _, _ = at5("results/coverage_v5/exp1-flaw.v2.json")
    v, n, c1, c2, a, g = at5("results/atlas/exp1-flaw.json")
    assert (v2, v3) == (2, 3)
    page = os.path.join(REPO, "docs", "studies", "2026-12-06-coverage-v5.md")
    text = " ".join(open(page, encoding="utf-8").read().split())
    said = (
        f"version {v3}, {n3} places at 5 m, estimated completeness {c1_3:.2f} by Chao1 and {c2_3:.2f} by Chao2 "
        f"(v2: {c1_2:.2f} and {c2_2:.2f})"
    )
    assert said in text, said
    assert (n3 < n2) == ("One place fewer than v2" in text)
    # the current atlas: its version, places per class, campaigns, scenarios and completeness
    by_class = ", ".join(f"{k} {m}" for k, m in sorted(g["by_class"].items()))
    said = (
        f"Version {v} pools it: {n} places at 5 m ({by_class}) from {len(a['sources'])} campaigns and "
        f"{a['scenarios']:,} scenarios, estimated completeness {c1:.2f} by Chao1 and {c2:.2f} by Chao2"
    )
    assert said in text, said
    assert f"added {['no', 'one', 'two', 'three', 'four', 'five', 'six'][n - n3]} places" in text
    assert (c1 < 0.90) == ("the atlas is not frozen" in text)


def test_the_records_amendment_3_sentence_is_its_blocks():
    # the prose on cov-veto reads the pilot and rates blocks (themselves checked against the exports)
    page = open(os.path.join(REPO, "docs", "studies", "2026-12-06-coverage-v5.md"), encoding="utf-8").read()
    text = " ".join(page.split())
    pilot = page.split("<!-- pilot: begin -->")[1].split("<!-- pilot: end -->")[0]
    rates = page.split("<!-- rates: begin -->")[1].split("<!-- rates: end -->")[0]

    def arm(name):
        m = re.search(rf"^  {re.escape(name)}: (\d\.\d+) \(per seed ([\d., ]+)\)", pilot, re.M)
        return float(m.group(1)), [float(x) for x in m.group(2).split(", ")]

    def rate(name):
        m = re.search(rf"^{re.escape(name)}: .*\(1 in ([\d.]+)\), .*\((\d\.\d\d) of them\)", rates, re.M)
        return m.group(1), m.group(2)

    mean, seeds = arm("pilot cov-veto")
    _, filt = arm("pilot cov-filter")
    ratio = re.search(
        r"pilot cov-veto / route-random: (\d\.\d\dx \(\d\.\d\d-\d\.\d\d\)), exact Mann-Whitney p = (\d\.\d+)", pilot
    )
    (vr, vd), (rr, rd) = rate("pilot cov-veto"), rate("route-random")
    said = (
        f"kept route-random's rate of findings (1 in {vr} scenarios against 1 in {rr}) but not much more of them at "
        f"new places ({vd} of its findings distinct at 5 m against route-random's {rd}): "
        f"{seeds[0]:.2f} and {seeds[1]:.2f}, mean {mean:.3f}, {ratio.group(1)[:-1].replace(' (', ' route-random (interval ')}"
        f", exact p = {ratio.group(2)}), below `cov-filter` on both seeds"
    )
    assert said in text, said
    assert all(v < min(filt) for v in seeds)

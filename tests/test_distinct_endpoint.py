"""Issue #78: protocol v4's endpoint, distinct flaw findings, recomputed from the flaw study v3's
exports twice: by the project's library (asg_analysis.endpoints, scoring/places.py) and by a plain
loop written here apart from it. Both give the issue's table (round 6's default collapsed onto a
few places: 52.7 distinct per 1,000 at 2 m against route-random's 108.0)."""

import glob
import gzip
import json
import math
import os

import pytest

from doc_pages import record

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
V3 = os.path.join(REPO, "results", "flaw_study3")

#: the issue's table: distinct flaw findings per seed (seeds 10-14) at 2 m, and the per-1,000 figures
ISSUE = {
    "default": {"2": [18, 26, 7, 7, 21], "per_1000": {"2": 52.7, "1": 62.0, "5": 34.0}},
    "route-random": {"2": [29, 31, 34, 32, 36], "per_1000": {"2": 108.0, "1": 118.0, "5": 71.3}},
    "map-elites": {"per_1000": {"2": 99.3, "1": 118.7, "5": 61.3}},
}


def _rows(path):
    with gzip.open(path, "rt") as f:
        f.readline()
        return sorted((json.loads(line) for line in f), key=lambda r: r["job"])[:300]


def _plain_place(r):
    """(class, x, y) of a row: the obstacle it hit or, without contact, where it ended."""
    if r["termination"] == "COLLISION" and r.get("collision_with") is not None:
        (x, y) = r["positions"][r["collision_with"]]
        return r["meshes"][r["collision_with"]], x, y
    x, y = r["trajectory_xy"][-1]
    return "none", x, y


def _plain_distinct(rows, radius, finding="flaw"):
    """The definition, read from the issue and written out: each flaw finding's place (or a
    pair's regression's, finding="regression") is the obstacle it hit (class, position) or,
    without contact, where it ended; it is distinct when no earlier distinct one of its class lies
    closer than `radius`."""
    kept = []
    for r in rows:
        if not _is_found(r, finding):
            continue
        cls, x, y = _plain_place(r)
        if all(c != cls or math.hypot(x - a, y - b) >= radius for c, a, b in kept):
            kept.append((cls, x, y))
    return len(kept)


def _is_found(r, finding):
    """A finding of class `finding`, or with None a failed run (not SUCCESS, not ERROR)."""
    return r["termination"] not in ("SUCCESS", "ERROR") if finding is None else r.get("attribution") == finding


def _pooled_modes(paths, budget, finding):
    """The library's failure modes (records/failure_modes.py) of the campaigns' findings pooled:
    a mode found by two seeds counts once (the issue's table counts them so)."""
    from asg_agent.records import failure_modes as fm
    from asg_agent.records.export import read_export
    from asg_analysis.rules import is_finding

    modes = []
    for p in paths:
        camp, rows = read_export(p)
        modes += fm.modes_of(camp, [r for r in rows if r["job"] < budget and is_finding(r, finding)])
    return fm.distinct(modes)


def _repeats(rows, finding):
    """Each finding within 2 m of an earlier distinct one of its class (a repeat), in job order, as
    (row, its class, the job of the first such distinct finding, the distinct ones so far as
    (class, x, y, job))."""
    kept = []
    for r in rows:
        if not _is_found(r, finding):
            continue
        cls, x, y = _plain_place(r)
        first = [j for c, a, b, j in kept if c == cls and math.hypot(x - a, y - b) < 2.0]
        if first:
            yield r, cls, first[0], kept
        else:
            kept.append((cls, x, y, r["job"]))


def _repeat_lags(rows, finding):
    """For each repeat (_repeats): its job minus the job of the first distinct finding it repeats."""
    return [r["job"] - first for r, _, first, _ in _repeats(rows, finding)]


def _late_banned(rows, finding, window=6, known=20):
    """(later repeats, those of them the tabu bans): a repeat that came `window` or more jobs after
    the distinct finding it repeats is *later*; it is one the tabu bans when its layout put an
    obstacle of the repeat's class within 2 m of a distinct place of that class found `known` or
    more jobs before it (long after that verdict was in). novelty-ts proposes such a layout only
    when every candidate of its draw was banned."""
    late = banned = 0
    for r, cls, first, kept in _repeats(rows, finding):
        if r["job"] - first < window:
            continue
        late += 1
        old = [(a, b) for c, a, b, j in kept if c == cls and j <= r["job"] - known]
        mine = [xy for m, xy in zip(r["meshes"], r["positions"]) if m == cls]
        banned += any(math.hypot(u - a, v - b) < 2.0 for u, v in mine for a, b in old)
    return late, banned


@pytest.mark.parametrize("arm", sorted(ISSUE))
def test_the_issue_table_by_a_plain_loop_and_by_the_library(arm):
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints

    paths = sorted(glob.glob(os.path.join(V3, f"flaw3-{arm}-s1[0-4].jsonl.gz")))
    assert len(paths) == 5
    rows = [_rows(p) for p in paths]
    plain = {r: [_plain_distinct(x, float(r)) for x in rows] for r in ("1", "2", "5")}
    lib = [endpoints.campaign(*read_export(p), budget=300) for p in paths]
    for r in ("1", "2", "5"):
        assert [c["distinct"][r] for c in lib] == plain[r]
        assert round(1000.0 * sum(plain[r]) / 1500.0, 1) == ISSUE[arm]["per_1000"][r]
    if "2" in ISSUE[arm]:
        assert plain["2"] == ISSUE[arm]["2"]


def test_every_default_seed_is_below_every_route_random_seed_exact_p_0_0079():
    from asg_analysis import endpoints

    arms = {a: sorted(glob.glob(os.path.join(V3, f"flaw3-{a}-s1[0-4].jsonl.gz"))) for a in ("default", "route-random")}
    res = endpoints.compare(arms, "default", 300)
    rr = [r for r in res["primary"] if r["arm"] == "route-random"][0]
    assert rr["p"] == pytest.approx(2 / 252) and rr["effect"] == -1.0
    assert rr["ratio"] == pytest.approx(52.6667 / 108.0, rel=1e-4)


def test_the_flaw_study_page_says_the_default_collapsed_with_these_figures():
    text = " ".join(open(record("flaw-study-v3"), encoding="utf-8").read().split())
    for arm, said in (
        ("default", "52.7 distinct flaw findings per 1,000 (seeds 18, 26, 7, 7, 21)"),
        ("route-random", "route-random's 108.0 (29, 31, 34, 32, 36)"),
    ):
        assert said in text, said
        per = ISSUE[arm]["2"]
        assert f"{1000 * sum(per) / 1500:.1f}" in said and ", ".join(map(str, per)) in said
    assert "exact p = 0.0079, the wrong way (MAP-Elites 99.3; at 5 m: 34.0, 71.3 and 61.3)" in text
    assert "a search that learns what exposes the flaw" not in text


def test_the_protocol_v4_pilot_block_is_its_exports():
    """docs/experiments.md's pilot table of protocol v4, regenerated from results/distinct_v4's
    pilot exports (python3 -m asg_analysis endpoints --budget 150 --doc docs/studies/2026-12-04-distinct-failures-v4.md
    "distinct v4 pilot" results/distinct_v4/dist4-pilot-*.jsonl.gz), and the figures for scale
    beside it recomputed from the flaw study v3's exports."""
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints

    paths = sorted(glob.glob(os.path.join(REPO, "results", "distinct_v4", "dist4-pilot-*.jsonl.gz")))
    assert len(paths) >= 4
    table = endpoints.markdown([endpoints.campaign(*read_export(p), budget=150) for p in paths])
    page = open(record("distinct-failures-v4"), encoding="utf-8").read()
    block = page.split("<!-- distinct v4 pilot: begin -->\n", 1)[1].split("<!-- distinct v4 pilot: end -->", 1)[0]
    assert block.strip() == table.strip()
    text = " ".join(page.split())

    def first_150(pattern):
        return [_plain_distinct(_rows(p)[:150], 2.0) for p in sorted(glob.glob(os.path.join(V3, pattern)))]

    rr, rw = first_150("flaw3-route-random-s1[0-4].jsonl.gz"), first_150("flaw3-pilot-random-wide-s2[01].jsonl.gz")
    said = (
        f"held {', '.join(map(str, rr[:-1]))} and {rr[-1]} distinct flaw findings at 2 m "
        f"({1000 * sum(rr) / 750:.1f} per 1,000), random in the route-wide space {rw[0]} and {rw[1]} "
        f"({1000 * sum(rw) / 300:.1f})"
    )
    assert said in text, said


def test_per_cpu_hour_ratios_are_taken_within_blocks_and_pooled_by_their_geometric_mean():
    """Protocol v4: a block is one seed of every arm on one machine; the default's distinct
    findings per CPU-hour over the arm's, block by block, pooled by the geometric mean; a block
    with no CPU measure is left out and named."""
    from asg_analysis import endpoints

    def c(seed, per_hour):
        return {"seed": seed, "per_cpu_hour": per_hour}

    per = {
        "default": [c(30, 40.0), c(31, 10.0), c(32, 30.0)],
        "route-random": [c(30, 20.0), c(31, 20.0), c(32, None)],
    }
    got = endpoints.within_blocks(per, "default")["route-random"]
    assert [(b["seed"], b["ratio"]) for b in got["blocks"]] == [(30, 2.0), (31, 0.5)]
    assert got["geomean"] == pytest.approx(1.0) and got["min"] == 0.5 and got["left_out"] == [32]
    # the table: one row an arm, the default's first, the blocks' ratios and their geometric mean
    res = {
        "primary": [
            {
                "arm": "default",
                "seeds": 2,
                "counts": [100.0, 120.0],
                "mean": 110.0,
                "lo": 100.0,
                "hi": 120.0,
                "ratio": None,
            },
            {
                "arm": "route-random",
                "seeds": 2,
                "counts": [50.0, 60.0],
                "mean": 55.0,
                "lo": 50.0,
                "hi": 60.0,
                "ratio": 2.0,
                "ratio_lo": 1.7,
                "ratio_hi": 2.4,
                "p": 0.3333,
            },
        ],
        "per_cpu_hour": endpoints.within_blocks(per, "default"),
    }
    table = endpoints.comparison_markdown(res)
    assert (
        "| route-random | 2 | 50.0, 60.0 | 55.0 (50.0-60.0) | 2.00x (1.70-2.40) | 0.3333 | s30 2.00, s31 0.50 | 1.00x |"
        in table
    )


def test_the_rules_check_prose_is_its_exports_counted_by_a_plain_loop():
    """The v4 record's sentence on the rule checked on fresh samples (amendment 3), recounted here
    from the rule-sampler's and the random-own arm's exports without asg_analysis.rules."""
    from scipy.stats import fisher_exact

    d4 = os.path.join(REPO, "results", "distinct_v4")

    def counts(paths):
        rows = [r for p in paths for r in _rows(p) if r["termination"] != "ERROR"]
        return [r for r in rows if r.get("attribution") == "flaw"], len(rows)

    fresh, n1 = counts([os.path.join(d4, "dist4-rule-top-s40.jsonl.gz")])
    learnt = json.load(open(os.path.join(d4, "rules-ops-wide.json")))["rules"][0]
    barberry = sum(r["meshes"][r["collision_with"]] == "barberry" for r in fresh if r.get("collision_with") is not None)
    text = " ".join(open(record("distinct-failures-v4"), encoding="utf-8").read().split())

    def against(pattern):
        base, n0 = counts(sorted(glob.glob(os.path.join(d4, pattern))))
        p = fisher_exact([[len(fresh), n1 - len(fresh)], [len(base), n0 - len(base)]])[1]
        return len(fresh) / n1 / (len(base) / n0), p

    ratio, p = against("dist4-random-own-s3?.jsonl.gz")  # the five blocks' base runs
    said = (
        f"{100 * len(fresh) / n1:.0f} % of its layouts were flaw findings against {100 * learnt['precision']:.0f} % "
        f"in the campaigns it was learnt from, and {ratio:.2f}x the base rate of the random-own campaigns of the "
        f"five blocks (Fisher p = {p:.3f}; "
    )
    assert said in text, said
    ratio0, p0 = against("dist4-random-own-s30.jsonl.gz")
    assert f"against block 0's alone it was {ratio0:.2f}x, p = {p0:.3f}" in text
    assert ("do not separate the rule from the base rate at 5 %" in text) == (p >= 0.05)
    assert f"{barberry} of the rule's {len(fresh)} fresh findings hit a barberry" in text
    assert learnt["text"] == "barberry d<2m q3 >= 3"


def test_the_v4_answer_is_its_five_blocks_counted_by_a_plain_loop():
    """The v4 record's answer: its table of targets and why the ratio is not 2x, recounted from the
    five blocks' exports by the plain loop (flaw findings, distinct at 2 m and 5 m), with the flaw
    modes from the library and the exact test with ties (asg_analysis.stats)."""
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints
    from asg_analysis.stats import mann_whitney

    d4 = os.path.join(REPO, "results", "distinct_v4")
    got = {}
    for arm in ("default", "route-random"):
        paths = sorted(glob.glob(os.path.join(d4, f"dist4-{arm}-s3?.jsonl.gz")))
        assert len(paths) == 5, paths
        rows = [_rows(p) for p in paths]
        assert all(len(x) == 300 for x in rows)
        got[arm] = {
            "flaw": sum(r.get("attribution") == "flaw" for x in rows for r in x),
            "2": [_plain_distinct(x, 2.0) for x in rows],
            "5": [_plain_distinct(x, 5.0) for x in rows],
            "modes": [endpoints.campaign(*read_export(p), budget=300)["modes"] for p in paths],
        }
    d, r = got["default"], got["route-random"]
    pooled = {
        a: _pooled_modes(sorted(glob.glob(os.path.join(d4, f"dist4-{a}-s3?.jsonl.gz"))), 300, "flaw") for a in got
    }
    text = " ".join(open(record("distinct-failures-v4"), encoding="utf-8").read().split())
    per = {k: {w: 1000 * sum(v[w]) / 1500 for w in ("2", "5")} for k, v in got.items()}
    ratio = per["default"]["2"] / per["route-random"]["2"]
    p2, p5, pm = (mann_whitney(d[k], r[k])["p"] for k in ("2", "5", "modes"))
    rows = [
        f"| >= 2x route-random's distinct flaw findings (2 m) per 1,000 | {per['default']['2']:.1f} against "
        f"{per['route-random']['2']:.1f}: {ratio:.2f}x (",
        f"| exact p < 0.01 over 5 seeds a side | p = {p2:.3f} | {'yes' if p2 < 0.01 else 'no'} |",
        f"| at least as many flaw modes as route-random | {pooled['default']} against {pooled['route-random']} over "
        f"the five seeds pooled; by campaign {sum(d['modes'])} against {sum(r['modes'])} over the five seeds (exact "
        f"p = {pm:.3f}) | {'yes' if pooled['default'] >= pooled['route-random'] else 'no'} |",
        f"| reported beside it: distinct at 5 m per 1,000 | {per['default']['5']:.1f} against "
        f"{per['route-random']['5']:.1f} (exact p = {p5:.3f}) | - |",
    ]
    for said in rows:
        assert said in text, said
    assert ratio < 2.0 and "Every target of the issue is missed on Exp. 1" in text
    assert all(a > b for a, b in zip(d["2"], r["2"])) and "than route-random in every block" in text
    said = (
        f"({sum(d['2'])} of the default's {d['flaw']} flaw findings, {sum(r['2'])} of route-random's {r['flaw']}), "
        f"so the ratio at 2 m is the ratio of how often each finds the flaw at all: {1000 * d['flaw'] / 1500:.1f} "
        f"flaw findings per 1,000 against route-random's {1000 * r['flaw'] / 1500:.1f}."
    )
    assert said in text, said
    assert per["route-random"]["5"] > per["default"]["5"] and sum(r["modes"]) > sum(d["modes"])


def test_the_defaults_repeats_came_while_the_finding_they_repeat_was_in_flight():
    """The v4 record's "the tabu lags": every flaw finding of the default within 2 m of an earlier
    distinct one of its class came within `slots` jobs of it (read from the exports' settings)."""
    d4 = os.path.join(REPO, "results", "distinct_v4")
    gaps, slots = [], set()
    for path in sorted(glob.glob(os.path.join(d4, "dist4-default-s3?.jsonl.gz"))):
        with gzip.open(path, "rt") as f:
            settings = json.loads(f.readline())["campaign"]["settings"]
            slots.add((json.loads(settings) if isinstance(settings, str) else settings)["slots"])
        gaps += _repeat_lags(_rows(path), "flaw")
    assert slots == {6} and gaps and max(gaps) < 6, (slots, gaps)
    text = " ".join(open(record("distinct-failures-v4"), encoding="utf-8").read().split())
    assert f"each of the default's {len(gaps)} repeats" in text and "came within six jobs" in text


def test_late_banned_counts_a_later_repeat_whose_layout_sits_on_an_old_place():
    """_late_banned on hand-made rows: a repeat within six jobs is not later; a later repeat is
    banned only when an obstacle of its class lay within 2 m of a place found 20 or more jobs
    before it; another class's obstacle there does not count."""

    def row(job, hit, positions, meshes=("a", "b")):
        return dict(
            job=job,
            attribution="flaw",
            termination="COLLISION",
            collision_with=hit,
            meshes=list(meshes),
            positions=[list(p) for p in positions],
            trajectory_xy=[[0, 0]],
        )

    rows = [
        row(0, 0, [(10, 10), (50, 50)]),  # distinct: class a at (10, 10)
        row(3, 0, [(10.5, 10), (50, 50)]),  # a repeat 3 jobs later: not later
        row(30, 0, [(11, 10), (80, 80)]),  # later, its a on the place found 30 jobs before: banned
        row(31, 1, [(90, 90), (50, 50)]),  # distinct: class b at (50, 50)
        row(40, 1, [(10, 10.5), (51, 50)]),  # later (9 jobs), but b's place is 9 jobs old: not banned
    ]
    assert _late_banned(rows, "flaw") == (2, 1)
    assert _late_banned(rows, "flaw", known=5) == (2, 2)
    assert _late_banned(rows, "flaw", window=2) == (3, 1)


def test_the_defaults_first_seed_replays_every_flaw_finding():
    """Issue #78 item 6: the record of replay_findings.sh holds every flaw finding of the default's
    first confirmatory seed (read here from the export), each REPRODUCED, and the page's block is
    that record."""
    import re

    from asg_analysis import replays

    d4 = os.path.join(REPO, "results", "distinct_v4")
    records = replays.read(d4)
    assert [r["campaign"] for r in records] == ["dist4-default-s30"]
    flaw = sorted(
        str(r["job"]) for r in _rows(os.path.join(d4, "dist4-default-s30.jsonl.gz")) if r.get("attribution") == "flaw"
    )
    assert sorted(records[0]["jobs"]) == flaw
    assert all(j["verdict"] == "REPRODUCED" for j in records[0]["jobs"].values())
    begin, end = replays.markers(os.path.join("results", "distinct_v4"))
    page = open(record("distinct-failures-v4"), encoding="utf-8").read()
    block = re.search(re.escape(begin) + r"\n(.*?)\n" + re.escape(end), page, re.S)
    assert block and block.group(1) == replays.markdown(records), "regenerate: python3 -m asg_analysis replays"
    assert f"every one of its {len(flaw)} flaw findings" in " ".join(page.split())


def test_round_6s_depth_pair_recounted_at_2_m_collapsed_as_the_record_says():
    """The v4 record's depth transfer section: round 6's depth pair (seeds 49-51, 200 scenarios)
    recounted by the plain loop, regressions distinct at 2 m."""
    folder = os.path.join(REPO, "results", "regression_depth_rc4")
    per, found = {}, {}
    for arm in ("default", "route-random"):
        paths = sorted(glob.glob(os.path.join(folder, f"depth-pair4-{arm}-s[45]?.jsonl.gz")))
        assert len(paths) == 3
        rows = [_rows(p)[:200] for p in paths]
        per[arm] = 1000 * sum(_plain_distinct(x, 2.0, "regression") for x in rows) / 600
        found[arm] = sum(1 for x in rows for r in x if r.get("attribution") == "regression")
    ratio = found["default"] / found["route-random"]
    text = " ".join(open(record("distinct-failures-v4"), encoding="utf-8").read().split())
    said = (
        f"its default found {ratio:.2f}x route-random's regressions and fewer distinct ones, "
        f"{per['default']:.1f} against {per['route-random']:.1f} per 1,000"
    )
    assert said in text and per["default"] < per["route-random"], said


#: the transfer scenes of issue #78 item 5: (the record's name of the scene, the finding class
#: (None: a failed run of the stack under test), what the answer sentence counts)
TRANSFER = {
    "gapnav": ("gap_nav", None, "failures of gap_nav"),
    "exp3": ("Exp. 3", "flaw", "flaw findings"),
    "exp6": ("Exp. 6", "flaw", "flaw findings"),
    "depth": ("The depth pair", "regression", "regressions"),
}


@pytest.mark.parametrize("scene", sorted(TRANSFER))
def test_a_transfer_answer_is_its_three_seeds_counted_by_a_plain_loop(scene):
    """The v4 record answers a transfer scene only when both arms have their three seeds, and then
    with the figures the plain loop counts from the exports: distinct findings at 2 m and 5 m per
    1,000 (200 scenarios a campaign), the ratio of means, the exact test with ties, and the modes
    (the library's), the tabu's lag (repeats within the six jobs in flight), and for a flaw scene
    the range of places 5 m apart a campaign."""
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints
    from asg_analysis.stats import mann_whitney

    label, finding, what = TRANSFER[scene]
    folder = os.path.join(REPO, "results", "distinct_v4_transfer")
    paths = {
        a: sorted(glob.glob(os.path.join(folder, f"dist4{scene}-{a}-s6?.jsonl.gz")))
        for a in ("default", "route-random")
    }
    text = " ".join(open(record("distinct-failures-v4"), encoding="utf-8").read().split())
    head = f"**{label}, answered (3 seeds a side): the target is "
    if min(len(p) for p in paths.values()) < 3:
        assert head not in text, f"{label} has fewer than three seeds an arm: progress, not an answer"
        return
    got = {}
    for arm, ps in paths.items():
        rows = [_rows(p)[:200] for p in ps]
        assert len(ps) == 3 and all(len(x) == 200 for x in rows), ps
        per = {}
        for radius in (2.0, 5.0):
            per[radius] = [_plain_distinct(x, radius, finding) for x in rows]
        modes = sum(endpoints.campaign(*read_export(p), budget=200, target=finding)["modes"] for p in ps)
        got[arm] = (per, modes, _pooled_modes(ps, 200, finding))
    (d, md, mdp), (r, mr, mrp) = got["default"], got["route-random"]
    mean = {k: {w: 1000 * sum(v[w]) / 600 for w in (2.0, 5.0)} for k, v in (("d", d), ("r", r))}
    p = mann_whitney(d[2.0], r[2.0])["p"]
    seeds = {k: ", ".join(f"{1000 * c / 200:.1f}" for c in v[2.0]) for k, v in (("d", d), ("r", r))}
    met = mean["d"][2.0] >= mean["r"][2.0]
    said = [
        head + ("met" if met else "missed"),
        f"found {mean['d'][2.0]:.1f} distinct {what} per 1,000 at 2 m ({seeds['d']} by seed) against "
        f"route-random's {mean['r'][2.0]:.1f} ({seeds['r']}): {mean['d'][2.0] / mean['r'][2.0]:.2f}x",
        f"exact p = {p:.3f}",
        f"At 5 m it found {mean['d'][5.0]:.1f} against {mean['r'][5.0]:.1f} per 1,000",
        f"{mdp} against {mrp} over the three seeds pooled",
        f"by campaign {md} against {mr}",
    ]
    rows = [_rows(path)[:200] for path in paths["default"]]
    gaps = [g for x in rows for g in _repeat_lags(x, finding)]
    said.append(f"{sum(g < 6 for g in gaps)} of the default's {len(gaps)} repeats came within six jobs")
    late = [_late_banned(x, finding) for x in rows]
    if sum(n for n, _ in late) >= 5:  # a pattern the record explains: how many the tabu bans
        said.append(f"{sum(b for _, b in late)} of the {sum(n for n, _ in late)} later ones put")
    if finding is not None:  # the places 5 m apart of each campaign, both arms, as the record gives them
        fives = [c for v in (d, r) for c in v[5.0]]
        said.append(f"fall in {min(fives)} to {max(fives)} places 5 m apart a campaign")
    for s in said:
        assert s in text, s
    status = text[text.index("**Status (") :].split(".**", 1)[0]  # the record's opening status
    assert f"{mean['d'][2.0] / mean['r'][2.0]:.2f}x" in status, f"the status gives {label}'s ratio"
    if finding == "flaw":
        assert f"{mean['d'][5.0] / mean['r'][5.0]:.2f}x at 5 m" in status, f"the status gives {label}'s 5 m ratio"
    guide = " ".join(open(os.path.join(REPO, "docs", "experiments.md"), encoding="utf-8").read().split())
    today = guide[guide.index("## Today's figures") : guide.index("## What a finding is")]
    assert f"{mean['d'][2.0] / mean['r'][2.0]:.2f}x" in today, f"docs/experiments.md gives {label}'s ratio"
    if finding == "flaw":
        assert f"{mean['d'][5.0] / mean['r'][5.0]:.2f}x at 5 m" in today, f"docs/experiments.md: {label} at 5 m"
    if scene == "gapnav":
        guide = " ".join(open(os.path.join(REPO, "docs", "your-stack.md"), encoding="utf-8").read().split())
        s = (
            f"{mean['d'][2.0]:.1f} distinct failures per 1,000 at 2 m against route-random's "
            f"{mean['r'][2.0]:.1f}, {mean['d'][2.0] / mean['r'][2.0]:.2f}x"
        )
        assert s in guide, s

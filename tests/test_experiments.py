"""Issue #11: one command recomputes every table and figure of docs/experiments.md from
results/ (its time is not asserted: a timed test on a shared machine is a flaky one); its counts equal those of the exports (and of the SQLite stores
where they are on this machine), and the tables quoted in the docs are the ones it makes."""

import glob
import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))
from asg_analysis import campaign_metrics  # noqa: E402
from asg_analysis.studies import experiments  # noqa: E402
from asg_agent.records.export import counts, read_export  # noqa: E402
from asg_agent.records.store import Store  # noqa: E402
from doc_pages import record  # noqa: E402

MANIFEST = os.path.join(REPO, "results", "experiments.yaml")


def test_recompute_matches_exports_stores_and_docs(tmp_path):
    summary = experiments.compute(MANIFEST, str(tmp_path))
    assert summary["table2"], "the manifest names no Table 2 campaign"
    for exp, row in summary["table2"].items():
        camp, rows = read_export(os.path.join(REPO, "results", row["export"]))
        c = counts(rows)
        for key in ("scenarios", "proxy_ge_3", "proxy_ge_4", "max_proxy"):
            assert row[key] == c[key], (exp, key)
        assert os.path.getsize(tmp_path / f"top_{exp}.png") > 10000
        # Where the campaign's store is on this machine, the export holds exactly its scenarios.
        for path in glob.glob(os.path.join(REPO, "results", "campaigns", "*.sqlite")):
            s = Store(path)
            if s.campaign(camp["name"]) is not None and s.count(camp["name"]) == c["scenarios"]:
                st = s.summary(camp["name"], top=0)
                assert (st["proxy_ge_3"], st["proxy_ge_4"]) == (c["proxy_ge_3"], c["proxy_ge_4"])
                assert abs(st["max_proxy"] - c["max_proxy"]) < 1e-9
    # Round 3's Table 2: each row's counts and its split by the reference's proxy are the export's.
    assert summary["table2_attributed"], "the manifest names no round-3 Table 2 campaign"
    for exp, row in summary["table2_attributed"].items():
        camp, rows = read_export(os.path.join(REPO, "results", row["export"]))
        c = counts(rows)
        assert (row["scenarios"], row["ge3_split"][0], row["ge4_split"][0]) == (
            c["scenarios"],
            c["proxy_ge_3"],
            c["proxy_ge_4"],
        )
        assert row["ge3_split"][1] == c["perception_ge3"] and row["ge3_split"][2] == c["stack_ge3"], exp
        assert row["ge4_split"][1] + row["ge4_split"][2] <= row["ge4_split"][0] <= row["ge3_split"][0]
        assert row["perception_collisions"] == c["perception_collisions"]
        for r in row["ranks"]:
            assert os.path.getsize(tmp_path / r["figure"]) > 10000
    # Issue #27's paired baselines by condition: every count is the baseline files' own.
    import json
    import yaml

    with open(MANIFEST) as f:
        cond = yaml.safe_load(f)["conditions"]
    for label, spec in cond["rows"].items():
        got = summary["conditions"][label]
        with open(os.path.join(REPO, "results", spec["stack"])) as f:
            test = [r for r in map(json.loads, f) if r["layout"] < cond["layouts"]]
        with open(os.path.join(REPO, "results", spec["ground_truth"])) as f:
            gt = {r["layout"]: r for r in map(json.loads, f) if r["layout"] < cond["layouts"]}
        hit = [r for r in test if r["termination"] == "COLLISION"]
        assert got["layouts"] == len(test) == len(gt) and got["collisions"] == len(hit), label
        assert got["perception_collisions"] == sum(gt[r["layout"]]["termination"] == "SUCCESS" for r in hit)
        assert sum(got["by_obstacle"].values()) == got["perception_collisions"]
    assert os.path.getsize(tmp_path / cond["figure"]) > 10000
    for arm, info in summary["comparison"].items():
        for run in info["runs"]:
            assert run["ge3"] <= run["scenarios"]
        # The per-window counts of an arm's first run add up to its count at the budget.
        windows = summary["dynamics"][arm]
        assert sum(w["ge3"] for w in windows) == info["runs"][0]["ge3"]
        assert all(0.0 <= w["at_edge"] <= 1.0 and w["median_to_route_m"] >= 0.0 for w in windows)
    with open(record("paper-table2")) as f:
        quoted = experiments.docs_block(f.read())
    generated = (tmp_path / "tables.md").read_text().strip("\n")
    assert quoted == generated, "the Table 2 record is stale: run `python3 -m asg_analysis experiments`"
    # The differential campaigns, round 2's and round 3's: every count is the export's.
    diffs = list((summary.get("differentials") or {}).values())
    if "differential" in summary:
        diffs.append(summary["differential"])
    for d in diffs:
        camp, rows = read_export(os.path.join(REPO, "results", d["export"]))
        both = [r for r in rows if r["reward"] is not None and r.get("reference")]
        assert d["both_runs"] == len(both) and d["scenarios"] == len(rows)
        assert d["regressions"]["1"] == sum(r["reward"] >= 1 for r in both)
        assert d["same"] == sum(abs(r["reward"]) < 0.01 for r in both)
        assert sum(d["cross"].values()) == len(both)
        assert sum(w["regressions_1"] for w in d["windows"]) == d["regressions"]["1"]
        assert d["divergence"]["parted"] + d["divergence"]["never"] == len(both)
    # Round 3's flaw or layout: per stack re-run, the class counts are the re-run files' own, and
    # what each class holds is what the campaign's export says of those scenarios.
    from asg_agent.ros.rerun import campaign_class, still_failing

    with open(MANIFEST) as f:
        fol = yaml.safe_load(f).get("flaw_or_layout_attributed") or {}
    if fol:
        _, crows = read_export(os.path.join(REPO, "results", fol["export"]))
        cls = {r["job"]: campaign_class(r) for r in crows}
        folder = os.path.join(REPO, "results", os.path.splitext(fol["file"])[0])
        for s in summary["flaw_or_layout_attributed"]:
            with open(os.path.join(folder, s["file"])) as f:
                reruns = [json.loads(line) for line in f if line.strip()]
            assert s["runs"] == len(reruns) == sum(e["runs"] for e in s["by_class"].values())
            assert all(r["campaign_class"] == cls[r["job"]] for r in reruns)
            for c, e in s["by_class"].items():
                assert e["still"] == sum(still_failing(r) for r in reruns if r["campaign_class"] == c)
            assert sum(e["runs"] for e in s["collisions_by_obstacle"].values()) == s["by_class"]["collision"]["runs"]


def test_differential_counts_on_a_known_export(tmp_path):
    """The differential section's counts, on an export whose reference runs are made up: twelve
    scenarios of a real Exp. 1 campaign, each given a reference proxy at a known offset."""
    import gzip
    import json

    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    rows = sorted(rows, key=lambda r: r["job"])[:12]
    offsets = [0.0, 0.0, 0.0, 0.5, -0.5, 1.0, 1.5, 2.5, 3.5, -1.2, -2.4, None]  # reward = proxy - reference
    for r, off in zip(rows, offsets):
        ref = None if off is None else r["proxy"] - off
        r["reference"] = {
            "proxy": ref,
            "vis": r["vis"],
            "yaw_term": r["yaw_term"],
            "plr": r["plr"],
            "termination": "SUCCESS" if off is None or off < 2 else "COLLISION",
            "sim_time": 10.0,
            "trajectory_xy": r["trajectory_xy"][::2],
        }
        r["reward"] = None if off is None else r["proxy"] - ref
    with gzip.open(tmp_path / "d.jsonl.gz", "wt") as f:
        f.write(json.dumps({"campaign": dict(camp, name="synthetic-diff")}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")
    (tmp_path / "m.yaml").write_text("differential: {export: d.jsonl.gz, under_test: flawed, reference: full}\n")
    d = experiments.compute(str(tmp_path / "m.yaml"), str(tmp_path / "out"))["differential"]
    assert (d["scenarios"], d["both_runs"], d["same"]) == (12, 11, 3)
    assert d["regressions"] == {"1": 4, "2": 2, "3": 1} and d["reverse"] == {"1": 2, "2": 1, "3": 0}
    assert abs(d["max_reward"] - 3.5) < 1e-9 and abs(d["min_reward"] + 2.4) < 1e-9
    assert d["top"][0]["reward"] == d["max_reward"] and len(d["top"]) == 10
    from collections import Counter

    assert d["terminations"] == dict(
        Counter(f"{r['termination']} / {r['reference']['termination']}" for r in rows[5:9])
    )
    assert sum(d["cross"].values()) == 11
    # Made-up reference runs drive every second sample of the real path, so they part from it
    # (except where the vehicle stood still), and the parting pairs are sorted by the sign.
    dv = d["divergence"]
    assert dv["parted"] + dv["never"] == 11 and dv["parted"] >= 1
    assert sum(e["pairs"] for e in dv["by_sign"].values()) == dv["parted"]
    assert os.path.getsize(tmp_path / "out" / "differential_top.png") > 10000
    assert "synthetic-diff" in (tmp_path / "out" / "tables.md").read_text()


def test_shadow_ahead_sees_a_cast_shadow_in_front_not_behind():
    """Exp. 1's sun (35 degrees up, yaw 150) casts a juniper's shadow 6.4 m towards +x, -y: a
    vehicle 10 m before the tree and driving at it has the shadow ahead; driving away, it has not."""
    import numpy as np

    from asg_agent.records import scenes

    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    r = dict(rows[0])
    r["positions"] = [[95.0, 95.0]] * len(r["positions"])
    r["positions"][r["meshes"].index("juniper")] = [50.0, 50.0]
    req = scenes.scenario_of(camp, r)
    towards = np.array([[40.0 + 0.5 * k, 51.0] for k in range(30)])
    away = towards[::-1] - np.array([20.0, 0.0])
    assert scenes.shadow_ahead(req, towards, 0)
    assert not scenes.shadow_ahead(req, away, 0)


def test_distinct_counts_clusters_of_near_copies_once():
    """Three layouts, each with near copies 0.5-1.5 m away and one 3 m away: at 2 m the far copies
    count as layouts of their own, at 5 m only the three; the fast distance equals the Hungarian one."""
    import numpy as np

    rng = np.random.default_rng(4)
    meshes = ["juniper"] * 4 + ["barberry"] * 4
    bases = [rng.uniform(0, 100, (8, 2)) for _ in range(3)]
    rows, proxy = [], 9.0
    for b in bases:
        for shift in (0.0, 0.5, 1.0, 1.5, 3.0):
            # a copy: each obstacle moved by `shift` in a random direction, the order within a type shuffled
            ang = rng.uniform(0, 2 * np.pi, 8)
            p = b + shift * np.c_[np.cos(ang), np.sin(ang)]
            p[:4], p[4:] = p[:4][rng.permutation(4)], p[4:][rng.permutation(4)]
            rows.append({"proxy": proxy, "positions": p.tolist(), "meshes": meshes})
            proxy -= 0.1
    rows.append({"proxy": 1.0, "positions": rng.uniform(0, 100, (8, 2)).tolist(), "meshes": meshes})
    rows.append({"proxy": None, "positions": rows[0]["positions"], "meshes": meshes})
    assert campaign_metrics.distinct(rows, None, 5.0, min_proxy=3.0) == 3
    assert campaign_metrics.distinct(rows, None, 2.0, min_proxy=3.0) == 6
    assert campaign_metrics.distinct(rows, None, 5.0) == 4  # the low-proxy stranger counts without the floor
    assert campaign_metrics.distinct(rows, 5, 2.0) == 2  # the top 5 are the first layout's copies
    for a in rows[:15]:
        fast = campaign_metrics.layout_distances(a["positions"], [r["positions"] for r in rows[:15]], meshes)
        slow = [campaign_metrics.layout_distance(a["positions"], r["positions"], meshes) for r in rows[:15]]
        assert np.allclose(fast, slow)


def test_attributed_comparison_counts_known_findings(tmp_path):
    """Round 3's comparison (issue #25) on a made-up attributed export: twenty scenarios of a real
    Exp. 1 campaign given reference runs and outcomes with known counts. Two perception findings
    (proxy >= 3, reference < 2) of which one is a near copy of the other, a stack finding (both
    >= 3, not the perception's), three differential ones, two perception collisions and one where
    both collided; 25 s per scenario with one 2-hour pause that wall time leaves out."""
    import gzip
    import json

    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    rows = sorted(rows, key=lambda r: r["job"])[:20]
    for k, r in enumerate(rows):
        r.update(proxy=1.2, termination="SUCCESS", finished=1000.0 + 25.0 * k + (7200.0 if k >= 10 else 0.0))
        r["reference"] = {"proxy": 1.1, "termination": "SUCCESS"}
    rows[3].update(proxy=3.4)  # perception finding, differential
    rows[7].update(proxy=3.1, positions=[[x + 0.3, y] for x, y in rows[3]["positions"]])  # its near copy
    rows[9].update(proxy=3.5)
    rows[9]["reference"]["proxy"] = 3.2  # the stack's: not the perception's
    rows[12].update(proxy=2.6)  # differential only (2.6 - 1.1)
    rows[14].update(termination="COLLISION")  # perception collision
    rows[15].update(termination="COLLISION")
    rows[15]["reference"]["termination"] = "COLLISION"  # both collided: the stack's
    rows[18].update(termination="COLLISION")  # perception collision
    with gzip.open(tmp_path / "a.jsonl.gz", "wt") as f:
        f.write(json.dumps({"campaign": dict(camp, name="synthetic-attr")}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")
    (tmp_path / "m.yaml").write_text("attributed: {budget: 20, threshold_m: 5.0, arms: {random: [a.jsonl.gz]}}\n")
    s = experiments.compute(str(tmp_path / "m.yaml"), str(tmp_path / "out"))["attributed"]["random"][0]
    assert (s["scenarios"], s["attributed"]) == (20, 20)
    assert (s["perception"], s["perception_distinct"]) == (2, 1)
    assert (s["differential"], s["differential_distinct"]) == (3, 2)
    assert (s["collisions"], s["collisions_distinct"]) == (2, 2)
    assert abs(s["max_proxy"] - 3.5) < 1e-9 and abs(s["max_difference"] - 2.3) < 1e-9
    assert abs(s["hours"] * 3600 - 20 * 25.0) < 1e-6  # the pause left out
    for measure in ("scenarios", "hours"):
        assert os.path.getsize(tmp_path / "out" / f"attributed_{measure}.png") > 10000


def test_weather_tables_bin_findings_by_attribute(tmp_path):
    """Issue #27: an attributed export whose rows carry their weather, binned by fog visibility:
    the perception collisions and differential findings land in the bins of their rows."""
    import gzip
    import json

    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    rows = sorted(rows, key=lambda r: r["job"])[:8]
    for k, r in enumerate(rows):
        r.update(proxy=1.1, termination="SUCCESS", textural={"fog_visibility_m": 25.0 + 50.0 * k, "cloud_cover": 0.5})
        r["reference"] = {"proxy": 1.0, "termination": "SUCCESS"}
    rows[0].update(termination="COLLISION")  # fog 25 m: a perception collision
    rows[1].update(proxy=2.5)  # fog 75 m: differential
    rows[7].update(termination="COLLISION")
    rows[7]["reference"]["termination"] = "COLLISION"  # 375 m: both collided
    with gzip.open(tmp_path / "w.jsonl.gz", "wt") as f:
        f.write(json.dumps({"campaign": dict(camp, name="synthetic-weather")}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")
    (tmp_path / "m.yaml").write_text("weather: {exports: [w.jsonl.gz], attributes: [fog_visibility_m], bins: 2}\n")
    s = experiments.compute(str(tmp_path / "m.yaml"), str(tmp_path / "out"))["weather"]["fog_visibility_m"]
    assert [b["scenarios"] for b in s] == [4, 4]
    assert [b["collisions"] for b in s] == [1, 0] and [b["differential"] for b in s] == [1, 0]
    assert [b["reference_collisions"] for b in s] == [0, 1]
    assert os.path.getsize(tmp_path / "out" / "weather.png") > 10000


def test_terrain_tables_bin_findings_by_terrain_attribute(tmp_path):
    """Issue #27: rows that carry their terrain, binned by the rolling amplitude and by how far the
    nearest hill of at least 1 m lies from the start-goal line (rows without such a hill: the far end)."""
    import gzip
    import json

    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    rows = sorted(rows, key=lambda r: r["job"])[:6]
    for k, r in enumerate(rows):
        hills = [{"x": 50.0 + 10.0 * k, "y": 50.0 - 10.0 * k, "radius_m": 8.0, "height_m": 2.0}] if k < 4 else []
        r.update(proxy=1.1, termination="SUCCESS", textural={"fog_visibility_m": 0.0, "cloud_cover": 0.0})
        r["terrain"] = {"amplitude_m": 0.3 * k, "wavelength_m": 30.0, "seed": 1, "hills": hills}
        r["reference"] = {"proxy": 1.0, "termination": "SUCCESS"}
    rows[0].update(termination="COLLISION")  # amplitude 0, a hill on the route (rim 8 m inside it)
    rows[0]["collision_with"] = rows[0]["meshes"].index("juniper")
    rows[5].update(termination="COLLISION", collision_with=rows[5]["meshes"].index("barberry"))
    rows[5]["reference"]["termination"] = "COLLISION"  # both collided: not the perception's
    with gzip.open(tmp_path / "t.jsonl.gz", "wt") as f:
        f.write(json.dumps({"campaign": dict(camp, name="synthetic-terrain")}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")
    (tmp_path / "m.yaml").write_text(
        "terrain: {exports: [t.jsonl.gz], attributes: [terrain.amplitude_m, terrain.hill_from_route_m], bins: 2}\n"
    )
    s = experiments.compute(str(tmp_path / "m.yaml"), str(tmp_path / "out"))["terrain"]
    assert [b["scenarios"] for b in s["terrain.amplitude_m"]] == [3, 3]
    assert [b["collisions"] for b in s["terrain.amplitude_m"]] == [1, 0]
    assert s["obstacle_hit"] == {
        "juniper": {"collisions": 1, "perception_collisions": 1},
        "barberry": {"collisions": 1, "perception_collisions": 0},
    }
    # hills at 0, 14.1, 28.3, 42.4 m from the line, minus the 8 m radius; two rows without a hill
    d = s["terrain.hill_from_route_m"]
    assert abs(d[0]["from"] + 8.0) < 1e-6 and [b["scenarios"] for b in d] == [2, 4] and d[0]["collisions"] == 1
    assert os.path.getsize(tmp_path / "out" / "terrain.png") > 10000


def _attributed_export(tmp_path, n=20):
    """An attributed export made from a real Exp. 1 campaign's first n scenarios: every run and
    its reference succeed with proxy 1.2 / 1.1 unless a test changes them."""
    camp, rows = read_export(os.path.join(REPO, "results", "campaigns", "exp1-random-s0.jsonl.gz"))
    rows = sorted(rows, key=lambda r: r["job"])[:n]
    for r in rows:
        r.update(proxy=1.2, termination="SUCCESS")
        r["reference"] = {"proxy": 1.1, "termination": "SUCCESS"}
    return camp, rows


def _write_export(path, camp, rows):
    import gzip
    import json

    with gzip.open(path, "wt") as f:
        f.write(json.dumps({"campaign": camp}) + "\n")
        for r in rows:
            f.write(json.dumps(r) + "\n")


def test_rerun_selects_what_an_attributed_campaign_blamed_on_the_perception(tmp_path):
    """Round 3's flaw or layout (issue #25): `--select perception` takes the perception findings,
    then the differential-only ones, then the perception collisions, and nothing the reference
    stack failed too; a collision on both stacks or an export without reference runs is refused
    or left out, and `summary` counts per class what fails the same way again."""
    import json

    from asg_agent.ros import rerun

    camp, rows = _attributed_export(tmp_path)
    rows[2].update(termination="COLLISION", collision_with=1)  # perception collision (reference succeeded)
    rows[4].update(proxy=2.4)  # differential only
    rows[6].update(proxy=3.3)  # perception finding
    rows[8].update(proxy=3.6)
    rows[8]["reference"]["proxy"] = 3.4  # the stack's finding: not selected
    rows[10].update(termination="COLLISION")
    rows[10]["reference"]["termination"] = "COLLISION"  # both collided: not selected
    _write_export(tmp_path / "a.jsonl.gz", camp, rows)
    _, todo = rerun.top_requests(str(tmp_path / "a.jsonl.gz"), 50, "perception")
    assert [(r["job"], rerun.campaign_class(r)) for r, _ in todo] == [
        (rows[6]["job"], "finding"),
        (rows[4]["job"], "differential"),
        (rows[2]["job"], "collision"),
    ]
    assert [req["scenario_id"] for _, req in todo] == [7000, 7001, 7002]
    assert len(rerun.top_requests(str(tmp_path / "a.jsonl.gz"), 2, "perception")[1]) == 2
    assert len(rerun.top_requests(str(tmp_path / "a.jsonl.gz"), 5, "proxy")[1]) == 5
    for r in rows:
        r.pop("reference")
    _write_export(tmp_path / "b.jsonl.gz", camp, rows)
    try:
        rerun.top_requests(str(tmp_path / "b.jsonl.gz"), 50, "perception")
        raise AssertionError("an export without reference runs was accepted")
    except ValueError as e:
        assert "no reference runs" in str(e)
    # The re-runs on another stack: the finding drops to 2.9, the differential one stays 1 over the
    # campaign's reference, the collision happens again.
    out = [
        {
            "label": "paper/full",
            "campaign_proxy": 3.3,
            "campaign_class": "finding",
            "proxy": 2.9,
            "termination": "SUCCESS",
            "campaign_reference_proxy": 1.1,
        },
        {
            "label": "paper/full",
            "campaign_proxy": 2.4,
            "campaign_class": "differential",
            "proxy": 2.1,
            "termination": "SUCCESS",
            "campaign_reference_proxy": 1.1,
        },
        {
            "label": "paper/full",
            "campaign_proxy": 1.2,
            "campaign_class": "collision",
            "proxy": 0.9,
            "termination": "COLLISION",
            "campaign_reference_proxy": 1.1,
        },
    ]
    for r, (row, _) in zip(out, todo):
        r["job"] = row["job"]
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "paper-full.jsonl").write_text("".join(json.dumps(r) + "\n" for r in out))
    assert rerun.main(["summary", str(tmp_path / "r" / "paper-full.jsonl"), "--json", str(tmp_path / "r.json")]) == 0
    s = json.loads((tmp_path / "r.json").read_text())["summary"][0]
    assert s["by_class"] == {
        "finding": {"runs": 1, "still": 0},
        "differential": {"runs": 1, "still": 1},
        "collision": {"runs": 1, "still": 1},
    }
    # The collision split by the obstacle the campaign's run hit (index 1 of its positions).
    _write_export(tmp_path / "a.jsonl.gz", camp, rows)
    (tmp_path / "m.yaml").write_text(
        "flaw_or_layout_attributed: {file: r.json, campaign: synthetic, export: a.jsonl.gz}\n"
    )
    s = experiments.compute(str(tmp_path / "m.yaml"), str(tmp_path / "out"))["flaw_or_layout_attributed"][0]
    assert s["collisions_by_obstacle"] == {rows[2]["meshes"][1]: {"runs": 1, "still": 1}}
    table = (tmp_path / "out" / "tables.md").read_text()
    assert f"| paper | full | 3 | 0 of 1 | 1 of 1 | 1 of 1 | {rows[2]['meshes'][1]} 1 of 1 | 0 |" in table


def test_round3_seed_tables_are_the_exports_and_the_prose_holds():
    # Issue #37: the intervals and tests of docs/experiments.md "Round 3 over seeds" are generated;
    # the page's block is what the exports give now, and the prose beside it says what they say.
    from asg_analysis import stats
    from asg_analysis.studies import seed_tables
    from asg_agent.records.export import read_export

    assert seed_tables.run(["--check"]) == 0, "round 3's record: run python3 -m asg_analysis seed-tables"

    rows = {
        (a, s): read_export(os.path.join(REPO, "results", "comparison", p.format(s) + ".jsonl.gz"))[1]
        for a, p in seed_tables.ARMS.items()
        for s in range(3)
    }

    def arm(name, score):
        return [stats.per_thousand(rows[(name, s)], score, 1000) for s in range(3)]

    effect = {}
    for score in ("perception", "differential", "collisions"):
        arms = {a: arm(a, score) for a in seed_tables.ARMS}
        for row in stats.compare(arms, "td3-per-asp")[1:]:
            effect[(row["arm"], score)] = row["effect"]
            assert row["p"] >= 0.05  # three seeds cannot reach it
    assert all(effect[("random", s)] == 1.0 for s in ("perception", "differential", "collisions"))
    assert effect[("map-elites", "collisions")] == -1.0
    assert -1.0 < effect[("map-elites", "perception")] < 1.0 and -1.0 < effect[("map-elites", "differential")] < 1.0

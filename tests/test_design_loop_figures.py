"""docs/design-loop.md's hardening tables, recomputed from the committed evaluation files and the
outcomes recorded in the suites (issue #40)."""

import json
import os
import re

from asg_analysis.studies import hardening as ah

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))


def doc_table(tag):
    text = open(os.path.join(REPO, "docs", "design-loop.md")).read()
    m = re.search(rf"<!-- {tag} table -->\n(.+?)\n<!-- end {tag} table -->", text, re.S)
    assert m, tag
    return m.group(1).strip()


def test_the_hardening_table_is_what_the_results_say():
    t = ah.table(os.path.join(REPO, "results", "hardening"))
    assert doc_table("hardening") == ah.markdown(t)
    # every arm on both suites, each suite's scenarios counted once per arm
    for arm in ("flawed", "full") + tuple(f"hardened-{a}-{r}" for a in ("findings", "random") for r in (1, 2)):
        assert t["arms"][arm]["suite-exp1c"]["n"] == 12 and t["arms"][arm]["suite-r4pilot"]["n"] == 12


def test_the_frames_only_table_is_what_its_results_say():
    assert doc_table("frames-only") == ah.markdown(ah.table(os.path.join(REPO, "results", "hardening", "frames-only")))


def test_the_hardened_baseline_table_is_what_the_rows_say():
    import json

    import numpy as np

    lines = doc_table("baseline").splitlines()[2:]
    for line in lines:
        stack, n, coll, ge3, plr = [c.strip() for c in line.strip("|").split("|")]
        with open(os.path.join(REPO, "results", "baseline", "exp1", f"{stack}.jsonl")) as f:
            rows = {r["layout"]: r for r in map(json.loads, f)}
        assert sorted(rows) == list(range(int(n)))  # the same seeded layouts 0..n-1
        assert sum(r["termination"] == "COLLISION" for r in rows.values()) == int(coll)
        assert sum(r["proxy"] is not None and r["proxy"] >= 3 for r in rows.values()) == int(ge3)
        ok = [r["plr"] for r in rows.values() if r["proxy"] is not None]
        assert f"{float(np.percentile(ok, 90)):.3f}" == plr
    assert [line.split("|")[1].strip() for line in lines] == ["flawed", "flawed_hf1", "flawed_hr1"]


# -- section 4: the loop's campaigns (asg_analysis.studies.loop_study) ------------------------------


def test_the_loop_table_is_what_the_exports_say():
    from asg_analysis.studies import loop_study as ls

    s = ls.study()
    assert doc_table("loop") == ls.markdown(s)
    # every campaign of the plan is either counted (all its scenarios) or listed as not complete
    assert len(s["campaigns"]) + len(s["not_complete"]) == 9
    assert all(c["scenarios"] == 500 for c in s["campaigns"].values())
    assert ("compare" in s) == (not s["not_complete"])
    # round 2: its three campaigns, compared only when both rounds are complete
    r2 = s["round2"]
    assert doc_table("round2") == ls.markdown_round2(s)
    assert len(r2["campaigns"]) + len(r2["not_complete"]) == 3
    assert ("compare" in r2) == (not r2["not_complete"] and not s["not_complete"])
    # the committed figures (results/hardening/loop.json, drawn as docs/images/design_loop.png) are these
    import json

    with open(os.path.join(REPO, "results", "hardening", "loop.json")) as f:
        assert json.load(f) == json.loads(json.dumps(s))


def _rows(n, flaw=(), model=(), collide=()):
    return [
        {
            "job": j,
            "attribution": "flaw" if j in flaw else "model" if j in model else None,
            "termination": "COLLISION" if j in collide else "SUCCESS",
        }
        for j in range(n)
    ]


def test_a_campaign_counts_flaw_and_model_findings_of_its_first_budget_scenarios():
    from asg_analysis.studies import loop_study as ls

    c = ls.campaign_figures(_rows(12, flaw={1, 2, 11}, model={3}, collide={1, 11}), budget=10)
    assert (c["scenarios"], c["flaw"], c["model"], c["collisions"]) == (10, 2, 1, 1)
    assert c["per_1000"] == 300.0
    lo, hi = c["per_1000_interval"]
    assert lo < 300.0 < hi


def test_the_target_needs_all_three_parts():
    from asg_analysis.studies import loop_study as ls

    base = {"layouts": 300, "collisions": 5, "proxy_ge_3": 0}
    worse = {"layouts": 300, "collisions": 9, "proxy_ge_3": 0}
    good = {"flawed": [20.0, 22.0, 18.0], "hardened-findings": [4.0, 6.0, 2.0], "hardened-random": [14.0, 16.0, 12.0]}
    bl = {"flawed": base, "hardened-findings": base, "hardened-random": base}
    t = ls.judge(good, bl, 0.5)["target"]
    assert t["ratio_to_flawed"] == 0.2 and t["ratio_met"] and t["below_random"] and t["met"]
    # half of flawed's is the bound, included; more is missed
    assert ls.judge({**good, "hardened-findings": [10.0, 10.0, 10.0]}, bl, 0.5)["target"]["ratio_met"]
    assert not ls.judge({**good, "hardened-findings": [12.0, 10.0, 11.0]}, bl, 0.5)["target"]["met"]
    # intervals overlapping the random arm's
    t = ls.judge({**good, "hardened-random": [5.0, 3.0, 14.0]}, bl, 0.5)["target"]
    assert t["ratio_met"] and not t["below_random"] and not t["met"]
    # a baseline worse than flawed's, or not measured
    assert ls.judge(good, {**bl, "hardened-findings": worse}, 0.5)["target"]["baseline_no_worse"] is False
    t = ls.judge(good, {**bl, "hardened-findings": None}, 0.5)["target"]
    assert t["baseline_no_worse"] is None and not t["met"]


def test_a_short_export_is_not_complete_and_nothing_is_compared(tmp_path):
    import gzip
    import json

    from asg_analysis.studies import loop_study as ls

    (tmp_path / "plan.txt").write_text(
        "# a plan\n"
        + "".join(
            f"loop-{m}-s{s} 4 train method:=td3-per-asp seed:={s} model:={m}\n"
            for m in ("flawed", "hf", "hr")
            for s in (1, 2)
        )
    )
    proto = {
        "seeds": [1, 2],
        "budget": 4,
        "arms": {
            "flawed": {"model": "flawed"},
            "hardened-findings": {"model": "hf"},
            "hardened-random": {"model": "hr"},
        },
        "target": {"ratio_to_flawed": 0.5},
    }
    (tmp_path / "protocol.yaml").write_text(json.dumps(proto))

    def export(name, rows):
        with gzip.open(tmp_path / f"{name}.jsonl.gz", "wt") as f:
            f.write(json.dumps({"campaign": name}) + "\n" + "".join(json.dumps(r) + "\n" for r in rows))

    for m, flaws in (("flawed", {0, 1, 2}), ("hf", set()), ("hr", {0, 1})):
        for s in (1, 2):
            export(f"loop-{m}-s{s}", _rows(4, flaw=flaws))
    export("loop-hr-s2", _rows(3, flaw={0}))  # stopped at 3 of 4
    s = ls.study(str(tmp_path), str(tmp_path / "protocol.yaml"), str(tmp_path))
    assert list(s["not_complete"]) == ["loop-hr-s2"] and "compare" not in s
    assert s["campaigns"]["loop-flawed-s1"]["per_1000"] == 750.0
    assert "1 of 6 campaigns not complete" in ls.markdown(s)
    export("loop-hr-s2", _rows(4, flaw={0, 1}))
    s = ls.study(str(tmp_path), str(tmp_path / "protocol.yaml"), str(tmp_path))
    assert not s["not_complete"] and s["target"]["ratio_met"] and s["target"]["baseline_no_worse"] is None
    assert "Overall: **missed**" in ls.markdown(s)  # no baselines in that folder
    assert "round2" not in s  # no round 2 in that protocol
    # round 2: a plan of two campaigns, one complete, then both
    proto["round2"] = {"models": {"findings": "hf2"}, "campaigns": {"seeds": [3, 4], "budget": 4}}
    (tmp_path / "protocol.yaml").write_text(json.dumps(proto))
    (tmp_path / "plan-round2.txt").write_text(
        "".join(f"loop2-hf2-s{s} 4 train method:=td3-per-asp seed:={s} model:=hf2\n" for s in (3, 4))
    )
    export("loop2-hf2-s3", _rows(4))
    s = ls.study(str(tmp_path), str(tmp_path / "protocol.yaml"), str(tmp_path))
    assert list(s["round2"]["not_complete"]) == ["loop2-hf2-s4"] and "compare" not in s["round2"]
    assert "1 of 2 round-2 campaigns not complete" in ls.markdown_round2(s)
    export("loop2-hf2-s4", _rows(4))
    s = ls.study(str(tmp_path), str(tmp_path / "protocol.yaml"), str(tmp_path))
    assert s["round2"]["reading"] == "saturate"  # 0 against round 1's 0: not below
    assert "Reading (fixed before the data): **saturate**" in ls.markdown_round2(s)


def test_round_two_reads_compound_only_with_its_interval_below_round_one():
    from asg_analysis.studies import loop_study as ls

    r1 = {"flawed": [150.0, 110.0, 130.0], "hardened-findings": [26.0, 30.0, 22.0]}
    got = ls.read_round2(r1, {}, {ls.ROUND2: [8.0, 10.0, 6.0]}, {})
    assert got["reading"] == "compound"
    by = {r["arm"]: r for r in got["compare"]}
    assert got["compare"][0]["arm"] == ls.ROUND2 and by["hardened-findings"]["ratio"] == 8.0 / 26.0
    # lower mean, intervals overlapping: saturate
    assert ls.read_round2(r1, {}, {ls.ROUND2: [20.0, 28.0, 14.0]}, {})["reading"] == "saturate"
    # higher: saturate
    assert ls.read_round2(r1, {}, {ls.ROUND2: [40.0, 44.0, 36.0]}, {})["reading"] == "saturate"
    # anything missing in either round: nothing read
    assert ls.read_round2(r1, {"loop-hr1-s22": {}}, {ls.ROUND2: [8.0, 10.0, 6.0]}, {}) is None
    assert ls.read_round2(r1, {}, {ls.ROUND2: [8.0, 10.0]}, {"loop2-hf2-s25": {}}) is None


def test_every_committed_experiment_and_protocol_file_is_yaml():
    import glob

    import yaml

    files = sorted(glob.glob(os.path.join(REPO, "experiments", "*.yaml")))
    assert any(f.endswith("protocol-design-loop.yaml") for f in files)
    for path in files:
        with open(path, encoding="utf-8") as f:
            assert isinstance(yaml.safe_load(f), dict), path


def test_the_loop_figure_draws_complete_campaigns_and_the_arms_means(tmp_path):
    from asg_analysis.studies import loop_study as ls

    camp = {
        f"loop-{a}-s{s}": dict(arm=a, seed=s, **ls.campaign_figures(_rows(40, flaw=set(range(k + s))), 40))
        for a, k in (("flawed", 8), ("hardened-findings", 2), ("hardened-random", 5))
        for s in (0, 1, 2)
    }
    s = {"budget": 40, "campaigns": camp, "not_complete": {}}
    per_seed = {
        a: [c["per_1000"] for c in camp.values() if c["arm"] == a]
        for a in ("flawed", "hardened-findings", "hardened-random")
    }
    s.update(ls.judge(per_seed, {}, 0.5))
    # round 2's campaigns and mean drawn beside round 1's
    camp2 = {
        f"loop2-hf2-s{s}": dict(arm=ls.ROUND2, seed=s, **ls.campaign_figures(_rows(40, flaw={s}), 40))
        for s in (3, 4, 5)
    }
    s["round2"] = {
        "campaigns": camp2,
        **ls.read_round2(per_seed, {}, {ls.ROUND2: [c["per_1000"] for c in camp2.values()]}, {}),
    }
    ls.figure(s, str(tmp_path / "loop.png"))
    from PIL import Image

    assert Image.open(tmp_path / "loop.png").size == (768, 432)


def test_the_prose_of_round_one_is_what_its_figures_say():
    """docs/design-loop.md section 4's reading of round 1, checked against the committed figures."""
    import json

    from scipy.stats import mannwhitneyu

    with open(os.path.join(REPO, "results", "hardening", "loop.json")) as f:
        s = json.load(f)
    assert not s["not_complete"]  # the reading is of the complete round
    arms = {r["arm"]: r for r in s["compare"]}
    hf, hr, fl = arms["hardened-findings"], arms["hardened-random"], arms["flawed"]
    t = s["target"]
    # missed on one part of three: the ratio and the baseline met, the intervals not apart
    assert t["ratio_met"] and t["baseline_no_worse"] and not t["below_random"] and not t["met"]
    assert hf["hi"] >= hr["lo"]  # the bootstrap intervals overlap
    # lower on every seed (the same search seed against each stack) ...
    assert all(a < b for a, b in zip(hf["counts"], hr["counts"]))
    # ... by less than either arm's spread over its seeds
    gap = hr["mean"] - hf["mean"]
    assert gap < max(hf["counts"]) - min(hf["counts"]) and gap < max(hr["counts"]) - min(hr["counts"])
    # three seeds an arm: even complete separation gives a two-sided Mann-Whitney p of 0.1
    assert mannwhitneyu([1, 2, 3], [4, 5, 6], alternative="two-sided", method="exact").pvalue == 0.1
    assert len(hf["counts"]) == len(hr["counts"]) == 3
    # the random arm, too, has at most half of flawed's findings
    assert hr["mean"] <= 0.5 * fl["mean"]
    # the open question's size: the seeds an arm, from these counts, as the prose quotes them
    from asg_analysis.stats import seeds_per_arm

    need = seeds_per_arm(hf["counts"], hr["counts"])
    assert need == s["open_question"]
    text = " ".join(open(os.path.join(REPO, "docs", "design-loop.md"), encoding="utf-8").read().split())
    assert (
        f"gap of the arms' means seen so far ({need['difference']:.0f} per 1,000) and their per-seed spread "
        f"(pooled SD {need['pooled_sd']:.1f}), a two-sided test at 5 % with 80 % power needs about "
        f"**{need['seeds_per_arm']} seeds an arm**"
    ) in text
    assert "five times the protocol's three" in text and need["seeds_per_arm"] == 5 * 3


def test_the_prose_of_round_two_hardening_is_what_its_figures_say():
    """docs/design-loop.md's reading of round 2's per-pixel and suite figures."""
    import json

    t = ah.table(os.path.join(REPO, "results", "hardening"))["arms"]

    def px(arm, s, k):
        return t[arm][s]["iou_non_traversable" if k == "iou" else "shadow_false_obstacle_rate"]

    for s in ("test", "heldout-findings"):
        # obstacles: the findings arm better again, the random arm less so and below it
        assert px("hardened-findings-2", s, "iou") > px("hardened-findings-1", s, "iou")
        assert (
            px("hardened-random-1", s, "iou") < px("hardened-random-2", s, "iou") < px("hardened-findings-2", s, "iou")
        )
        # shadows: the findings arm's rate falls, still above flawed's; the random arm's rises
        assert (
            px("flawed", s, "shadow") < px("hardened-findings-2", s, "shadow") < px("hardened-findings-1", s, "shadow")
        )
        assert px("hardened-random-2", s, "shadow") > px("hardened-random-1", s, "shadow")
    assert abs(px("hardened-findings-2", "test", "iou") - px("full", "test", "iou")) < 0.02
    assert px("hardened-findings-2", "heldout-findings", "iou") > px("full", "heldout-findings", "iou")
    # suites: 10 of 12 for every hardened model; on the unseen 12, round 2 passes 2-3 more, random one more
    passed = {a: (t[a]["suite-exp1c"]["passed"], t[a]["suite-r4pilot"]["passed"]) for a in t}
    for a in ("hardened-findings-1", "hardened-random-1", "hardened-findings-2", "hardened-random-2"):
        assert passed[a][0] == 10 and t[a]["suite-exp1c"]["n"] == 12 and t[a]["suite-r4pilot"]["n"] == 12
    for arm in ("findings", "random"):
        assert passed[f"hardened-{arm}-2"][1] - passed[f"hardened-{arm}-1"][1] in (2, 3)
    assert passed["hardened-random-2"][1] == passed["hardened-findings-2"][1] + 1
    # round 1's arms, re-evaluated in round 2 on re-made frame sets, agree with their first figures
    for s in ("test", "heldout-findings"):
        with open(os.path.join(REPO, "results", "hardening", f"evaluation-{s}-1.json")) as f:
            first = json.load(f)["results"]
        with open(os.path.join(REPO, "results", "hardening", f"evaluation-{s}-2.json")) as f:
            again = json.load(f)["results"]
        for arm, r in first.items():
            assert abs(r["iou"]["non_traversable"] - again[arm]["iou"]["non_traversable"]) < 1e-5
            assert abs(r["shadow_false_obstacle_rate"] - again[arm]["shadow_false_obstacle_rate"]) < 1e-5


def test_the_prose_of_round_two_campaigns_is_what_its_figures_say():
    """docs/design-loop.md's reading of round 2's campaigns, checked against the committed figures."""
    import json

    with open(os.path.join(REPO, "results", "hardening", "loop.json")) as f:
        s = json.load(f)
    r2 = s["round2"]
    assert not r2["not_complete"] and r2["reading"] == "saturate"
    arms = {r["arm"]: r for r in r2["compare"]}
    two, one, fl = arms["hardened-findings-2"], arms["hardened-findings"], arms["flawed"]
    assert two["lo"] <= one["hi"] and one["lo"] <= two["hi"]  # the intervals overlap
    assert two["mean"] <= 0.5 * fl["mean"] and one["mean"] <= 0.5 * fl["mean"]
    # `model` findings are most of what remains in both rounds
    model = sum(c["model"] for c in r2["campaigns"].values())
    flaw = sum(c["flaw"] for c in r2["campaigns"].values())
    assert model > flaw
    model1 = sum(c["model"] for k, c in s["campaigns"].items() if "hf1" in k)
    flaw1 = sum(c["flaw"] for k, c in s["campaigns"].items() if "hf1" in k)
    assert model1 > flaw1


def test_the_corrected_sentences_of_issue_57_are_what_the_figures_say():
    """docs/design-loop.md after issue #57: round 1's pooled comparison, the classes `flawed`'s flaw
    findings hit, round 2's random-arm IoU sentence, and job 126's caption."""
    import gzip
    import json
    import math

    import numpy as np
    from scipy.stats import fisher_exact

    doc = open(os.path.join(REPO, "docs", "design-loop.md"), encoding="utf-8").read()
    with open(os.path.join(REPO, "results", "hardening", "loop.json")) as f:
        s = json.load(f)
    arms = {r["arm"]: r for r in s["compare"]}
    per = {a: [round(c * 500 / 1000) for c in arms[a]["counts"]] for a in ("hardened-findings", "hardened-random")}
    x, y, n = sum(per["hardened-findings"]), sum(per["hardened-random"]), 1500
    rr = x / y
    se = math.sqrt(1 / x - 1 / n + 1 / y - 1 / n)
    p = fisher_exact([[x, n - x], [y, n - y]]).pvalue
    said = (
        f"findings arm has {x} flaw + model findings in 1,500 scenarios and the random arm {y}: rate ratio\n"
        f"  {rr:.2f} (95 % {math.exp(math.log(rr) - 1.96 * se):.2f}-{math.exp(math.log(rr) + 1.96 * se):.2f}), "
        f"Fisher's exact p = {p:.2f}"
    )
    assert said in doc
    # the classes flawed's flaw findings collided with, seeds 20-22
    hit = {"barberry": 0, "juniper": 0}
    for seed in (20, 21, 22):
        with gzip.open(os.path.join(REPO, "results", "hardening", f"loop-flawed-s{seed}.jsonl.gz"), "rt") as f:
            rows = [json.loads(ln) for ln in f][1:]
        for r in rows:
            if r.get("attribution") == "flaw" and r.get("collision_with") is not None:
                hit[r["meshes"][r["collision_with"]]] += 1
    total = sum(hit.values())
    flat = " ".join(doc.split())
    assert (
        f"Of its {total} flaw findings over seeds 20-22, {hit['barberry']} end against a barberry and "
        f"{hit['juniper']} against a juniper" in flat
    )
    # round 2: the random arm's IoU rises less than the findings arm's on the test set, more on the held-apart findings
    t = ah.table(os.path.join(REPO, "results", "hardening"))["arms"]

    def rise(arm, st):
        return t[f"{arm}-2"][st]["iou_non_traversable"] - t[f"{arm}-1"][st]["iou_non_traversable"]

    assert rise("hardened-random", "test") < rise("hardened-findings", "test")
    assert rise("hardened-random", "heldout-findings") > rise("hardened-findings", "heldout-findings")
    assert "by less than the findings arm's on the test set,\n  by more on the held-apart findings" in doc
    # job 126's caption: the obstacle nearest where each stack's run ended
    from asg_scenario import load_scenario

    scen = load_scenario(
        os.path.join(
            REPO, "results", "hardening", "suite-r4pilot", "scenarios", "002-round4-pilot-reward-proxy-s0-job126.yaml"
        )
    )
    obs = [(lay["mesh_name"], i["x"], i["y"]) for lay in scen["structural"]["layouts"] for i in lay["instances"]]
    ended = {}
    for arm in ("flawed-cl", "hardened-findings-1", "hardened-random-1"):
        with open(os.path.join(REPO, "results", "hardening", "paths", f"{arm}.json")) as f:
            run = next(r for r in json.load(f) if "job126" in r["file"])
        end = np.asarray(run["trajectory_xy"][-1])
        near = min(obs, key=lambda o: math.dist(o[1:], end))
        ended[arm] = (run["termination"], near[0])
    assert ended["flawed-cl"] == ("COLLISION", "juniper")
    assert ended["hardened-findings-1"] == ("COLLISION", "barberry")
    assert ended["hardened-random-1"][0] == "SUCCESS"
    assert "job 126: flawed hits a juniper, hardened-findings a barberry, hardened-random drives round both" in doc


def test_the_rebuilt_held_apart_sets_share_no_scene_with_any_training_source():
    """Section 3's held-apart sets since issue #57: the per-pixel frame set (its sources in
    results/hardening/heldout-findings.json) and suite-r4pilot share no scene with the training
    sources of either round's arms as the same layout (`overlap.SAME_M`, the tolerance they were
    built at; their near twins at the augmentation's radius: tests/test_held_apart.py); what was
    left out is what the old sets shared."""
    from asg_agent.campaign import overlap

    training = [
        os.path.join(REPO, "results", *p)
        for p in (
            ("attribution", "exp1c-td3-per-asp-s0.jsonl.gz"),
            ("comparison", "exp1b-random-s1.jsonl.gz"),
            ("hardening", "loop-hf1-s20.jsonl.gz"),
            ("comparison", "exp1b-random-s2.jsonl.gz"),
        )
    ]
    with open(os.path.join(REPO, "results", "hardening", "heldout-findings.json"), encoding="utf-8") as f:
        held = json.load(f)
    jobs = {int(s["job"]) for s in held["sources"]}
    pilot = overlap.scenes_of(os.path.join(REPO, "results", "round4", "round4-pilot-reward-proxy-s0.jsonl.gz"))
    scenes = [s for s in pilot if int(s[0].rsplit(" ", 1)[1]) in jobs]
    suite = overlap.scenes_of(os.path.join(REPO, "results", "hardening", "suite-r4pilot"))
    assert len(scenes) == len(jobs) == 47 and len(suite) == 12
    for src in training:
        t = overlap.scenes_of(src)
        assert overlap.shared(scenes, t, overlap.SAME_M) == [] and overlap.shared(suite, t, overlap.SAME_M) == [], src
    dropped = sorted(int(d.split(" = ")[0].rsplit(" ", 1)[1]) for d in held["made_from"]["dropped_shared"])
    assert dropped == [24, 27, 40, 65, 94, 110]
    doc = " ".join(open(os.path.join(REPO, "docs", "design-loop.md"), encoding="utf-8").read().split())
    assert f"{len(jobs)} of the 53 findings" in doc and "jobs 24, 27, 40, 65, 94 and 110" in doc
    # the suite: the first one's 14 findings less the 4 shared, and two the export chose in their place
    first = {24, 27, 94, 110, 114, 126, 128, 180, 201, 209, 214, 276, 335, 365}  # the first suite (git history)
    now = {int(s[0].rsplit(" job ", 1)[1].rstrip(")")) for s in suite}
    assert len(now & first) == 10 and sorted(now - first) == [116, 482]
    assert "10 of the first suite's 14, and jobs 116 and 482" in doc and "4 of the first `suite-r4pilot`'s 14" in doc

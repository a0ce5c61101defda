"""Issue #57: the mechanism section of docs/design-loop.md (what `flawed` labels before its flaw
findings' contacts) is generated from the exports and frames: the findings recounted by class
from the exports with code of this test's own, the table regenerated from mechanism.json, the
figures quoted in the prose checked, the counting checked on a frame built by hand, and the
dataset tool's obstacle index image checked on a real finding's scene."""

import collections
import gzip
import json
import os
import re
import subprocess

import numpy as np
import pytest

from asg_analysis.studies import mechanism
from doc_pages import record

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
RESULT = os.path.join(REPO, "results", "hardening", "mechanism", "mechanism.json")
DOC = os.path.join(REPO, "docs", "design-loop.md")


def load():
    with open(RESULT, encoding="utf-8") as f:
        return json.load(f)


def doc_text():
    with open(DOC, encoding="utf-8") as f:
        return f.read()


def recount(paths):
    """Flaw findings ended in a collision, by the class of the obstacle hit: the export's lines
    read here directly (first line the campaign, then one row a scenario)."""
    out = collections.Counter()
    for path in paths:
        with gzip.open(path, "rt", encoding="utf-8") as f:
            lines = [json.loads(line) for line in f if line.strip()]
        for row in lines[1:]:
            if row.get("attribution") == "flaw" and row.get("termination") == "COLLISION":
                hit = row.get("collision_with")
                if hit not in (None, ""):
                    out[row["meshes"][int(hit)]] += 1
    return out


def test_the_findings_are_every_flaw_contact_of_the_exports():
    result = load()
    paths = [os.path.join(REPO, "results", "hardening", name) for name in result["exports"]]
    want = recount(paths)
    got = collections.Counter(f["hit_class"] for f in result["findings"])
    assert got == want
    assert sum(want.values()) == 89 and want["barberry"] == 74 and want["juniper"] == 15
    for f in result["findings"]:  # every finding has its frames, at most one per time before contact
        assert 1 <= len(f["frames"]) <= len(result["seconds_before"])


def test_the_docs_table_is_generated_from_the_json():
    m = re.search(r"<!-- mechanism:begin[^>]*-->\n(.*?)\n<!-- mechanism:end -->", doc_text(), re.S)
    assert m, "docs/design-loop.md has no mechanism block"
    assert m.group(1) == mechanism.markdown(load()), "regenerate it: python3 -m asg_analysis mechanism ... --doc"


def test_the_prose_quotes_the_measured_shares():
    s = mechanism.summary(load())
    text = " ".join(doc_text().split())

    def pct(cls, name, model):
        acc = s[cls]["sets"][name]
        return f"{100.0 * acc[model] / acc['px']:.1f} %"

    b, j = s["barberry"], s["juniper"]
    assert f"Of its {b['findings'] + j['findings']} flaw findings over seeds 20-22, {b['findings']} end" in text
    assert f"{j['findings']} against a juniper" in text
    assert (
        f"({pct('barberry', 'hit', 'flawed')} of its pixels non-traversable against {pct('barberry', 'hit', 'full')})"
        in text
    )
    juniper = f"the junipers in view ({pct('barberry', 'other juniper', 'flawed')} of their pixels against {pct('barberry', 'other juniper', 'full')})"
    assert juniper in text
    assert (
        f"({pct('barberry', 'shadow', 'flawed')} of shadowed ground called an obstacle against {pct('barberry', 'shadow', 'full')})"
        in text
    )
    assert f"sees {pct('juniper', 'hit', 'flawed')} of the juniper (`full` {pct('juniper', 'hit', 'full')})" in text


def test_frame_counts_on_a_frame_built_by_hand():
    gt = np.zeros((4, 4), np.uint8)
    gt[0, :] = 1  # obstacles on the top row: index 0 (juniper) at columns 0-1, index 2 (barberry) at 2-3
    inst = np.zeros((4, 4), np.uint16)
    inst[0, :2], inst[0, 2:] = 1, 3
    lit = np.full((4, 4), 255, np.uint8)
    lit[3, :] = 0  # the bottom row is in shadow
    flawed = np.zeros((4, 4), np.uint8)
    flawed[0, 2:] = 1  # sees the barberry, not the juniper
    flawed[3, 0] = 1  # one shadow pixel called an obstacle
    out = mechanism.frame_counts(gt, lit, inst, {"flawed": flawed}, hit=2, classes=["juniper", "juniper", "barberry"])
    assert out["hit"] == {"px": 2, "gt": 2, "flawed": 2}
    assert out["other juniper"] == {"px": 2, "gt": 2, "flawed": 0}
    assert out["other barberry"] == {"px": 0, "gt": 0, "flawed": 0}
    assert out["shadow"] == {"px": 4, "gt": 0, "flawed": 1}
    assert out["lit"] == {"px": 8, "gt": 0, "flawed": 0}


def test_the_dataset_tool_writes_the_obstacle_index_of_a_findings_scene(tmp_path):
    cv2 = pytest.importorskip("cv2")
    from asg_agent.campaign.hardening import dataset_tool

    found = mechanism.findings([os.path.join(REPO, "results", "hardening", "loop-flawed-s20.jsonl.gz")])
    f = max(found[:10], key=lambda f: len(f["xy"]))
    f = dict(f, xy=f["xy"][: len(f["xy"]) - 10])  # 1 s before the contact: the obstacle ahead
    keys = mechanism.write_poses([f], str(tmp_path))
    assert keys and all(k == 0 for k, _ in keys)
    subprocess.run(
        [dataset_tool(), "--out", str(tmp_path / "frames"), "--poses", str(tmp_path / "poses.csv"), "--instances", "1"],
        check=True,
        capture_output=True,
    )
    stem = str(tmp_path / "frames" / "images" / f"{len(keys) - 1:06d}")
    inst = cv2.imread(stem + "_instances.png", cv2.IMREAD_UNCHANGED)
    gt = cv2.imread(stem + "_labels.png", cv2.IMREAD_UNCHANGED)
    assert inst.dtype == np.uint16 and inst.shape == gt.shape
    assert (inst == f["hit"] + 1).sum() >= mechanism.MIN_HIT_PX, "the obstacle hit is in view just before it"
    assert inst.max() <= len(f["classes"])
    assert (gt[inst > 0] == mechanism.NON_TRAVERSABLE).mean() > 0.9  # obstacle pixels are obstacles


def test_the_pages_say_the_barberry_contacts_are_not_explained_by_juniper_blindness():
    """Issue #68 (the mechanism): most flaw findings of the design loop's campaigns hit barberries,
    which `flawed` labels about as `full` does before the contact; no page may say or imply that
    its blindness to junipers explains them, and the pages that discuss it say it is not yet
    explained, with the figures (recounted here from the exports)."""
    result = load()
    c = recount([os.path.join(REPO, "results", "hardening", name) for name in result["exports"]])
    b, j = c["barberry"], c["juniper"]
    assert (b, j) == (74, 15)
    acc = mechanism.summary(result)["barberry"]["sets"]["hit"]
    fl, fu = (f"{100.0 * acc[m] / acc['px']:.1f} %" for m in ("flawed", "full"))
    assert (fl, fu) == ("75.0 %", "72.5 %")

    def page(*p):
        with open(os.path.join(REPO, *p), encoding="utf-8") as f:
            return " ".join(f.read().split())

    loop, exp = (
        page("docs", "design-loop.md"),
        page("docs", "studies", os.path.basename(record("round3-search-comparison"))),
    )
    said = (
        f"Of its {b + j} flaw findings over seeds 20-22, {b} end against a barberry and {j} against a juniper: "
        "most hit the class `flawed` was trained on, not the one it is blind to."
    )
    assert said in loop
    assert f"({fl} of its pixels non-traversable against {fu}): the barberry is not missed" in loop
    assert (
        "How missing the junipers (or the false shadow obstacles) leads `flawed` into a barberry both models see "
        "is **not yet explained**: the plans, votes and swerves before those contacts were not measured" in loop
    )
    assert "how its blindness to junipers leads it into a barberry was not measured" in loop
    # `flawed` was trained on barberries only (its data set: --meshes barberry)
    with open(os.path.join(REPO, "scripts", "repro", "make_models.sh"), encoding="utf-8") as f:
        assert "--count 4000 --seed 2 --meshes barberry" in f.read()
    # round 3's record (docs/studies/), the lite stack: the flawed campaign's collisions by class, from its export
    with gzip.open(os.path.join(REPO, "results", "comparison", "exp1b-td3-per-asp-s0.jsonl.gz"), "rt") as f:
        rows = [json.loads(line) for line in f][1:]
    hits = collections.Counter(r["meshes"][int(r["collision_with"])] for r in rows if r["termination"] == "COLLISION")
    n = sum(r["termination"] == "COLLISION" for r in rows)
    assert n == sum(hits.values()) and max(r["proxy"] or 0 for r in rows) == pytest.approx(5.48, abs=0.005)
    assert f"{hits['barberry']} of `flawed`'s {n} collisions in this campaign are barberries" in exp
    assert f"`full` ({fl} of its pixels against {fu}; docs/design-loop.md" in exp
    assert "How missing junipers leads to hitting barberries is not yet explained" in exp
    assert "| `flawed` (bf16) | 4 | 4 | 4 | 138 |" in exp  # the row the sentence is about
    old = (
        "contacts happen on routes laid among unseen junipers",  # design-loop.md, section 4
        "those 15 are the missing class itself",  # design-loop.md, "Before the contacts"
        "a missed juniper, not a phantom shadow obstacle, is what ends in a collision",  # round 3's record
        "it misses fewer junipers",  # round 3's record: only pooled obstacle pixels were measured
    )
    studies = [os.path.join("studies", n) for n in sorted(os.listdir(os.path.join(REPO, "docs", "studies")))]
    for name in ["design-loop.md", "experiments.md", "perception.md", "agent.md"] + studies:
        text = page("docs", name)
        assert not [o for o in old if o in text], name
    assert not [o for o in old if o in page("README.md")]

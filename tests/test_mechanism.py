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

from asg_analysis import mechanism

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
    assert m.group(1) == mechanism.markdown(load()), "regenerate it: python3 -m asg_analysis.mechanism ... --doc"


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
    from asg_agent.campaign.hardening import DATASET_TOOL

    found = mechanism.findings([os.path.join(REPO, "results", "hardening", "loop-flawed-s20.jsonl.gz")])
    f = max(found[:10], key=lambda f: len(f["xy"]))
    f = dict(f, xy=f["xy"][: len(f["xy"]) - 10])  # 1 s before the contact: the obstacle ahead
    keys = mechanism.write_poses([f], str(tmp_path))
    assert keys and all(k == 0 for k, _ in keys)
    subprocess.run(
        [DATASET_TOOL, "--out", str(tmp_path / "frames"), "--poses", str(tmp_path / "poses.csv"), "--instances", "1"],
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

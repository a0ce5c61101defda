"""docs/design-loop.md's hardening tables, recomputed from the committed evaluation files and the
outcomes recorded in the suites (issue #40)."""

import os
import re

from asg_agent.analysis import hardening as ah

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
    for arm in ("flawed", "hardened-findings-1", "hardened-random-1", "full"):
        assert t["arms"][arm]["suite-exp1c"]["n"] == 12 and t["arms"][arm]["suite-r4pilot"]["n"] == 14


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

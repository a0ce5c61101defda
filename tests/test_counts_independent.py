"""Issue #37: the counts of the committed exports checked by a second implementation written apart
from the project's (it imports none of scoring/attribution.py, records/store.py's rules or
records/export.py's counts; only the file reader), so that a wrong rule in the project's code
fails here instead of being checked against itself.

The rules, restated from docs/agent.md: a run fails when it ends in a collision, a timeout, a flip
or out of bounds, or reaches the goal with proxy >= 3. Three-stack classes: flaw (fails; `full` and
ground truth both reach the goal below 2), model (fails; `full` fails, ground truth does not),
stack (fails; ground truth fails), unclear, reverse, pass, error. Round 3's single-reference
counts: a perception finding has proxy >= 3 with the ground-truth run below 2; a perception
collision, a collision where the ground-truth run reached the goal."""

import glob
import gzip
import json
import os
import sys

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))
from asg_agent.records.export import counts  # noqa: E402  (the implementation under test)
from doc_pages import record  # noqa: E402

BAD_ENDS = {"COLLISION", "FLIPPED", "SIM_TIMEOUT", "IDLING_TIMEOUT", "STUCK_TIMEOUT", "OUT_OF_BOUNDS"}


def rows_of(path):
    with gzip.open(path, "rt") as f:
        f.readline()
        return [json.loads(line) for line in f]


def broken(run):
    if run["termination"] in BAD_ENDS:
        return True
    return run["termination"] == "SUCCESS" and run["proxy"] is not None and run["proxy"] >= 3.0


def clean(run):
    return run["termination"] == "SUCCESS" and run["proxy"] is not None and run["proxy"] < 2.0


def my_class(row):
    runs = row["reference_runs"]
    everyone = [row, runs["full"], runs["ground_truth"]]
    if any(r["termination"] == "ERROR" or r["proxy"] is None for r in everyone):
        return "error"
    full, truth = runs["full"], runs["ground_truth"]
    if not broken(row):
        return "reverse" if broken(full) or broken(truth) else "pass"
    if broken(truth):
        return "stack"
    if broken(full):
        return "model"
    if clean(full) and clean(truth):
        return "flaw"
    return "unclear"


THREE_STACK = sorted(
    glob.glob(os.path.join(REPO, "results", "attribution", "*.jsonl.gz"))
    # issue #79: the flaw study v3's and protocol v4's headline counts, recounted from the runs
    + glob.glob(os.path.join(REPO, "results", "flaw_study3", "flaw3-*-s1[0-4].jsonl.gz"))
    + glob.glob(os.path.join(REPO, "results", "distinct_v4", "*.jsonl.gz"))
)
ROUND3 = sorted(glob.glob(os.path.join(REPO, "results", "comparison", "exp1b-*-s*.jsonl.gz")))


@pytest.mark.parametrize("path", THREE_STACK, ids=[os.path.basename(p) for p in THREE_STACK])
def test_three_stack_classes_recounted(path):
    rows = rows_of(path)
    mine = {}
    for r in rows:
        if r.get("reference_runs"):
            want = my_class(r)
            assert r["attribution"] == want, (r["job"], r["attribution"], want)
        else:
            # not re-run: neither a failure nor near one (proxy < 2), and so labelled
            assert not broken(r) and (r["proxy"] is None or r["proxy"] < 2.0), r["job"]
            assert r["attribution"] == "not_candidate", r["job"]
            want = "not_candidate"
        mine[want] = mine.get(want, 0) + 1
    theirs = {k: v for k, v in counts(rows)["classes"].items() if v}
    assert theirs == mine


def test_three_stack_exports_are_committed():
    assert THREE_STACK, "no three-stack export under results/attribution/"


@pytest.mark.parametrize("path", ROUND3, ids=[os.path.basename(p) for p in ROUND3])
def test_round3_single_reference_counts_recounted(path):
    rows = rows_of(path)
    refd = [r for r in rows if r.get("reference")]
    perception = sum(
        1
        for r in refd
        if r["proxy"] is not None
        and r["reference"].get("proxy") is not None
        and r["proxy"] >= 3.0
        and r["reference"]["proxy"] < 2.0
    )
    collisions = sum(1 for r in refd if r["termination"] == "COLLISION" and r["reference"]["termination"] == "SUCCESS")
    c = counts(rows)
    assert (c["perception_ge3"], c["perception_collisions"]) == (perception, collisions)


def test_the_three_stack_campaign_prose_is_its_export():
    # docs/experiments.md "Round 4 groundwork": its table row is the independent recount.
    path = os.path.join(REPO, "results", "attribution", "exp1c-td3-per-asp-s0.jsonl.gz")
    rows = rows_of(path)
    mine = {}
    for r in rows:
        c = my_class(r) if r.get("reference_runs") else "not_candidate"
        mine[c] = mine.get(c, 0) + 1
    ge3 = sum(1 for r in rows if r["proxy"] is not None and r["proxy"] >= 3.0)
    row = (
        f"| {len(rows)} | {len(rows) - mine['not_candidate']} | {mine.get('flaw', 0)} | {mine.get('model', 0)} | "
        f"{mine.get('stack', 0)} | {mine.get('unclear', 0)} | {mine.get('reverse', 0)} | {mine.get('pass', 0)} | {ge3} |"
    )
    assert row in open(record("first-three-stack-campaign")).read(), row
    # and the prose beside it
    text = open(record("first-three-stack-campaign")).read()

    def hits(cls, mesh):
        return sum(
            1
            for r in rows
            if r.get("reference_runs")
            and my_class(r) == cls
            and r["collision_with"] is not None
            and r["meshes"][r["collision_with"]] == mesh
        )

    found = mine["flaw"] + mine["model"] + mine["stack"]
    assert (
        f"Of the {found} findings" in text
        and f"{mine['flaw']} are the flaw's ({round(100 * mine['flaw'] / found)} %)" in text
    )
    assert (
        f"{hits('flaw', 'barberry')} of the flaw findings hit a barberry and {hits('flaw', 'juniper')} a juniper"
        in text
    )
    assert (
        f"{hits('model', 'barberry')} of\n  the model findings a barberry and {hits('model', 'juniper')} a juniper"
        in text
    )
    single = sum(
        1
        for r in rows
        if r["termination"] == "COLLISION" and (r.get("reference") or {}).get("termination") == "SUCCESS"
    )
    assert f"called {single} of these collisions" in text
    per200 = [
        sum(1 for r in rows if lo <= r["job"] < lo + 200 and r.get("attribution") == "flaw")
        for lo in range(0, 1000, 200)
    ]
    assert f"{min(per200)}-{max(per200)} flaw findings in every 200 scenarios" in text
    # the rate quoted beside the table, from the export's finish times
    t = sorted(r["finished"] for r in rows)
    hours = (t[-1] - t[0]) / 3600
    assert f"{round(hours * 60)}\nminutes, {round((len(t) - 1) / hours):,} scenarios an hour" in text


def test_what_the_candidate_rule_missed_is_the_reruns():
    # docs/experiments.md: the first 300 scenarios re-run on both references, classed here apart
    # from the project's rule; the page's counts are these.
    folder = os.path.join(REPO, "results", "attribution", "first300")
    full = {json.loads(x)["job"]: json.loads(x) for x in open(os.path.join(folder, "paper-full.jsonl"))}
    truth = {json.loads(x)["job"]: json.loads(x) for x in open(os.path.join(folder, "paper-ground_truth.jsonl"))}
    rows = {r["job"]: r for r in rows_of(os.path.join(REPO, "results", "attribution", "exp1c-td3-per-asp-s0.jsonl.gz"))}
    assert sorted(full) == sorted(truth) == list(range(300))
    same = missed = 0
    reverse = []
    for j in range(300):
        r = dict(rows[j], reference_runs={"full": full[j], "ground_truth": truth[j]})
        c = my_class(r)
        if rows[j].get("reference_runs"):
            same += c == rows[j]["attribution"]
        else:
            missed += c in ("flaw", "model", "stack")
            reverse += [j] if c == "reverse" else []
    cands = sum(1 for j in range(300) if rows[j].get("reference_runs"))
    text = open(record("first-three-stack-campaign")).read()
    assert same == cands and missed == 0
    assert (
        f"The {cands} candidates among them get, from the re-runs, the class the campaign stored,\n  all {same}" in text
    )
    assert f"{len(reverse)} are reverse cases the rule does not count" in text

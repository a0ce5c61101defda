"""Issue #54: docs/experiments.md's flaw-study table is what the exports say. `protocol status
--check` finds the block in step; and, apart from the project's counting code, this test reads
each export (gzip JSON lines) itself and checks every listed campaign's scenarios and flaw,
model and stack counts."""

import gzip
import json
import os
import re
import subprocess

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
FOLDER = os.path.join(REPO, "results", "flaw_study")
DOC = os.path.join(REPO, "docs", "experiments.md")


def budgets():
    """{campaign: budget} from the committed plans (NAME SCENARIOS train ...)."""
    out = {}
    for plan in ("pilot.txt", "plan.txt"):
        path = os.path.join(FOLDER, plan)
        if os.path.isfile(path):
            for line in open(path):
                w = line.split("#", 1)[0].split()
                if len(w) >= 3:
                    out[w[0]] = int(w[1])
    return out


def test_the_doc_block_is_in_step_with_the_exports():
    r = subprocess.run(
        [
            "/usr/bin/python3",
            "-m",
            "asg_analysis.protocol",
            "status",
            os.path.join(REPO, "experiments", "protocol-flaw-study.yaml"),
            FOLDER,
            "--doc",
            DOC,
            "--check",
        ],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, (
        "docs/experiments.md's flaw-study block is stale: rerun `protocol status ... --doc`" + r.stderr
    )


def test_every_row_counts_what_its_export_holds():
    text = open(DOC, encoding="utf-8").read()
    block = text[text.index("<!-- flaw study status: begin") : text.index("<!-- flaw study status: end")]
    plan = budgets()
    rows = [ln for ln in block.splitlines() if ln.startswith("| flaw-")]
    assert [ln.split("|")[1].strip() for ln in rows] == list(plan)  # every planned campaign, in order
    for ln in rows:
        cells = [c.strip() for c in ln.strip("|").split("|")]
        name, scenarios = cells[0], cells[3]
        path = os.path.join(FOLDER, name + ".jsonl.gz")
        if not os.path.isfile(path):
            assert scenarios == f"0 of {plan[name]}"
            continue
        with gzip.open(path, "rt") as f:
            lines = [json.loads(x) for x in f]
        jobs = [x for x in lines[1:] if "job" in x and x["job"] < plan[name]]
        assert int(re.match(r"\d+", scenarios).group()) == len(jobs), name
        got = [sum(1 for x in jobs if x.get("attribution") == k) for k in ("flaw", "model", "stack")]
        assert [int(cells[5]), int(cells[6]), int(cells[7])] == got, name
        assert abs(float(cells[4].split()[0]) - 1000.0 * got[0] / len(jobs)) < 0.051, name


def test_the_replays_block_is_what_the_replay_records_say():
    # scripts/repro/replay_findings.sh's records: each names every flaw finding of its campaign's
    # export (read here apart from the project's code) and its verdict; the doc's block is generated
    from asg_analysis import replays

    records = replays.read(FOLDER)
    assert records, "no replay record in results/flaw_study/replays/"
    text = open(DOC, encoding="utf-8").read()
    block = re.search(re.escape(replays.BEGIN) + r"\n(.*?)\n" + re.escape(replays.END), text, re.S)
    assert block and block.group(1) == replays.markdown(records), "regenerate: python3 -m asg_analysis.replays"
    for r in records:
        with gzip.open(os.path.join(FOLDER, f"{r['campaign']}.jsonl.gz"), "rt") as f:
            rows = [json.loads(line) for line in f][1:]
        flaw = sorted(str(row["job"]) for row in rows if row.get("attribution") == r["class"])
        assert sorted(r["jobs"]) == flaw, f"{r['campaign']}: the replays are not every {r['class']} finding"
    first = next(r for r in records if r["campaign"] == "flaw-default-s10")
    assert first["reproduced"] == first["findings"]  # the docs say every one replayed exactly
    # the walked-through finding, as the page tells it: job 3, a juniper, a collision after 11.2 s
    with gzip.open(os.path.join(FOLDER, "flaw-default-s10.jsonl.gz"), "rt") as f:
        job3 = next(row for row in map(json.loads, f) if row.get("job") == 3)
    assert job3["attribution"] == "flaw" and job3["termination"] == "COLLISION"
    assert job3["meshes"][job3["collision_with"]] == "juniper" and f"{job3['sim_time']:.1f}" == "11.2"
    assert "job 3, in rviz" in text and "a collision after 11.2 s of simulated time" in " ".join(text.split())

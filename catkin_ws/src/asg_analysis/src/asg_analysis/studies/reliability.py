"""docs/reliability.md's soak table, generated from the soak's report (results/reliability/soak.json,
written by asg_agent.cli.soak through asg_agent.campaign.soak_check; no ROS):

    python3 -m asg_analysis reliability results/reliability/soak.json --doc docs/reliability.md [--check]

One row: scenarios run, kills (SIGKILL) by node type, agent restarts, re-queues, lost, duplicates,
stored as ERROR, SQLite integrity, and for three-stack attribution the classes and the candidates
left pending; then the re-queues by what the pool saw."""

import argparse
import json
import sys

PROG = "python3 -m asg_analysis reliability"

BEGIN, END = "<!-- soak: begin (generated) -->", "<!-- soak: end -->"
KINDS = (("planner", "planners"), ("scene_worker", "scene workers"), ("segmenter", "segmenters"))


def markdown(res: dict) -> str:
    kills = dict(res["kills"])
    agent = kills.pop("agent", 0) + kills.pop("agent-final", 0)
    parts = [f"{kills.pop(k, 0)} {words}" for k, words in KINDS]
    parts += [f"{n} {k}" for k, n in sorted(kills.items())]  # a kind this table does not know yet
    parts.append(f"{agent} agents ({agent - res['kills'].get('agent-final', 0)} + the final one)")
    n = res["scenarios_expected"]
    run = f"{res['scenarios_stored']:,} (0..{n - 1}, campaign {'finished' if res['finished'] else 'NOT finished'})"
    attribution = res.get("attribution")
    header = "| scenarios run | kills (SIGKILL) | agent restarts | re-queues | lost | duplicates | stored as ERROR | SQLite integrity |"
    row = (
        f"| {run} | **{res['kills_total']}**: {', '.join(parts)} | {res['agent_restarts']} | "
        f"{res['retries_logged']} ({res['retried_scenarios_in_store']} scenarios) | **{res['lost']}** | "
        f"**{res['duplicates']}** | {res['stored_as_error']} | {'ok' if res['integrity_ok'] else 'FAILED'} |"
    )
    lines = [BEGIN, header, "|---|---|---|---|---|---|---|---|", row, ""]
    if attribution:
        classes = ", ".join(f"{k} {v}" for k, v in attribution.items() if v)
        lines += [
            f"Three-stack attribution under the kills: {classes}; candidates left pending: "
            f"**{res['candidates_pending']}**.",
            "",
        ]
    reasons = sorted(res["retries_by_reason"].items(), key=lambda kv: (-kv[1], kv[0]))
    lines.append(
        "Re-queues by what the pool saw: " + ("; ".join(f"{k} {v}" for k, v in reasons) if reasons else "none") + "."
    )
    lines.append(END)
    return "\n".join(lines)


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("report", help="the soak's JSON report")
    ap.add_argument("--doc", default="", help="rewrite the page's soak block")
    ap.add_argument("--check", action="store_true", help="with --doc: only say whether the block is stale (exit 1)")
    a = ap.parse_args(argv)
    try:
        with open(a.report, encoding="utf-8") as f:
            res = json.load(f)
        block = markdown(res)
    except (OSError, ValueError, KeyError) as e:
        print(f"reliability: {a.report}: {e}", file=sys.stderr)
        return 2
    if not a.doc:
        print(block)
        return 0
    from asg_analysis.docblocks import rewrite_between as rewrite_block

    return rewrite_block(a.doc, BEGIN, END, block, a.check, "reliability")

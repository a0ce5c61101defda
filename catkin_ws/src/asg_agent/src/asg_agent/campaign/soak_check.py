"""The soak's accounting (issue #14; asg_agent.cli.soak writes it), written to a JSON file and
printed: every scenario 0..N-1 stored exactly once, the kills by kind, the agent's restarts, the
retries (from the store and, by reason, from the agent's log), SQLite integrity. No ROS.
    python3 -m asg_agent.campaign.soak_check STORE NAME N KILLS_LOG AGENT_LOG START END OUT.json"""

import collections
import json
import re
import sys

from asg_agent.records.store import Store
from asg_agent.scoring.attribution import FINDING

REASONS = [
    ("scene worker died", r"scene worker died"),
    # since issue #68 the worker names a stack node whose process changed before what its protocol saw
    ("planner restarted", r"planner: restarted or gone"),
    ("segmenter restarted", r"segmenter: restarted or gone"),
    ("planner silent", r"planner: no command"),
    ("segmenter silent", r"segmenter: no labels"),
    ("goal lost", r"goal ended LOST"),
    ("no answer in time", r"did not answer"),
    ("never acknowledged", r"never acknowledged"),
]


def reason(line: str) -> str:
    """What the pool saw, for one "retrying elsewhere" line of the agent's log: the first of REASONS
    whose pattern it holds, else "other"."""
    return next((k for k, pat in REASONS if re.search(pat, line)), "other")


def report(store_path: str, name: str, n: int, kills_path: str, log_path: str, start: float, end: float) -> dict:
    s = Store(store_path, create=False)
    rows = list(s.rows(name))
    jobs = [r["job"] for r in rows]
    with open(kills_path) as f:
        kills = collections.Counter(line.split()[1].split("/")[-1] for line in f if line.strip())
    with open(log_path, errors="replace") as f:
        log = f.read().splitlines()
    retries = [line for line in log if "retrying elsewhere" in line]
    by_reason = collections.Counter()
    for line in retries:
        by_reason[reason(line)] += 1
    camp = s.campaign(name)
    res = {
        "campaign": name,
        "scenarios_expected": n,
        "scenarios_stored": len(rows),
        "lost": len(set(range(n)) - set(jobs)),
        "duplicates": len(jobs) - len(set(jobs)),
        "beyond_budget": sum(j >= n for j in jobs),
        "integrity_ok": s.integrity_ok(),
        "finished": bool(camp and camp["finished"]),
        "hours": round((end - start) / 3600, 2),
        "kills": dict(kills),
        "kills_total": sum(kills.values()),
        "agent_restarts": sum("restarting with --resume" in line for line in log),
        "retries_logged": len(retries),
        "retries_by_reason": dict(by_reason),
        "retried_scenarios_in_store": sum(1 for r in rows if r["attempts"] > 1),
        "stored_as_error": sum(1 for r in rows if r["termination"] == "ERROR"),
        # issue #36: three-stack attribution under kills: every candidate attributed once, none left pending
        "attribution": s.classes(name) if any(r["attribution"] for r in rows) else None,
        "candidates_pending": sum(1 for r in rows if r["attribution"] == "pending"),
        "proxy_ge_3": sum((r["proxy"] or 0) >= FINDING for r in rows),
    }
    return res


def passed(res: dict) -> bool:
    """Nothing lost or doubled, the store sound, the campaign finished, no candidate left pending."""
    ok = res["lost"] == 0 and res["duplicates"] == 0 and res["integrity_ok"] and res["finished"]
    return ok and res["candidates_pending"] == 0


def main(argv):
    store_path, name, n, kills_path, log_path, start, end, out = argv
    res = report(store_path, name, int(n), kills_path, log_path, float(start), float(end))
    with open(out, "w") as f:
        json.dump(res, f, indent=1)
    print(json.dumps(res, indent=1))
    return 0 if passed(res) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

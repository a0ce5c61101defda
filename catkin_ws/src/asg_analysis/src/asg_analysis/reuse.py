"""Whether an older study's export may stand for a campaign of a newer protocol (issue #67; no ROS):
"old exports count only if a seeded campaign on today's code gives the same digest as on theirs".

The results digest of an export is the SHA-256 of, job by job in job order, its obstacle
positions, termination, proxy (to 1e-9), the obstacle hit and its attribution class: what the
protocol counts and what the search saw, not the wall times, the workers or the campaign's name.

    python3 -m asg_analysis reuse check NEW.jsonl.gz OLD.jsonl.gz [--budget 300]
    python3 -m asg_analysis reuse adopt OLD.jsonl.gz NEW_NAME FOLDER --proof NEW.jsonl.gz [--budget 300]

`check` says whether two exports have the same results over the first `budget` jobs, and where
they first differ. `adopt` copies an old export into FOLDER as NEW_NAME.jsonl.gz (its campaign
renamed and its origin recorded as `campaign.adopted`, with the lines of the old study's machine.log
that list it as sharing the machine, every row as it was) only when the proof (a campaign of the same method and seed run on
today's code) has the same digest as the old export of that seed, and records the adoption in
FOLDER/reuse.json.
"""

import argparse
import gzip
import hashlib
import json
import os
import sys
from typing import List, Optional, Tuple

PROG = "python3 -m asg_analysis reuse"


def _read(path: str) -> Tuple[dict, List[dict]]:
    with gzip.open(path, "rt", encoding="utf-8") as f:
        head = json.loads(f.readline())
        rows = [json.loads(line) for line in f]
    return head, [r for r in rows if "job" in r]


def _key(r: dict) -> list:
    proxy = r.get("proxy")
    return [
        r["job"],
        [[round(float(v), 3) for v in p] for p in r.get("positions") or []],
        r.get("termination"),
        None if proxy is None else round(float(proxy), 9),
        r.get("collision_with"),
        r.get("attribution"),
    ]


def digest(rows: List[dict], budget: Optional[int] = None) -> str:
    keep = sorted((r for r in rows if budget is None or r["job"] < budget), key=lambda r: r["job"])
    h = hashlib.sha256()
    for r in keep:
        h.update(json.dumps(_key(r), separators=(",", ":")).encode())
    return h.hexdigest()


def first_difference(a: List[dict], b: List[dict], budget: Optional[int] = None) -> Optional[int]:
    """The first job whose results differ (or that one export lacks), None when equal."""
    ka = {r["job"]: _key(r) for r in a if budget is None or r["job"] < budget}
    kb = {r["job"]: _key(r) for r in b if budget is None or r["job"] < budget}
    for job in sorted(set(ka) | set(kb)):
        if ka.get(job) != kb.get(job):
            return job
    return None


def _shared_in_its_study(old: str, name: str) -> List[str]:
    """The lines of the old export's own study log (machine.log beside it) that list its campaign as
    sharing the machine, each as 'FOLDER/machine.log line K' (FOLDER relative to the repository)."""
    from asg_agent.paths import REPO
    from asg_analysis.protocol_analysis import log_lines

    folder = os.path.dirname(os.path.abspath(old))
    rel = os.path.relpath(folder, REPO)
    where = os.path.basename(folder) if rel.startswith("..") else rel
    return [f"{where}/machine.log line {k}" for k in log_lines(folder, name)]


def adopt(old: str, new_name: str, folder: str, proof: str, budget: int) -> dict:
    """Copies `old` into `folder` as `new_name` if `proof` repeats its results; the record."""
    (oh, orows), (_, prows) = _read(old), _read(proof)
    same = digest(orows, budget) == digest(prows, budget)
    record = {
        "adopted": new_name if same else None,
        "old": os.path.basename(old),
        "proof": os.path.basename(proof),
        "budget": budget,
        "digest_old": digest(orows, budget),
        "digest_proof": digest(prows, budget),
        "first_difference": first_difference(orows, prows, budget),
    }
    if same:
        # where it came from, for the study's deviations (protocol.deviations)
        adopted = {"from": record["old"], "proof": record["proof"], "budget": budget}
        shared = _shared_in_its_study(old, oh["campaign"]["name"])
        if shared:  # a deviation of the old run that the adoption carries with it (protocol.deviations)
            adopted["shared"] = shared
        camp = dict(oh["campaign"], name=new_name, adopted=adopted)
        out = os.path.join(folder, new_name + ".jsonl.gz")
        with gzip.open(old, "rt", encoding="utf-8") as f:
            lines = f.read().splitlines()[1:]
        with gzip.GzipFile(out, "wb", mtime=0) as gz:
            gz.write((json.dumps(dict(oh, campaign=camp)) + "\n").encode())
            gz.write(("\n".join(lines) + "\n").encode())
    path = os.path.join(folder, "reuse.json")
    log = json.load(open(path)) if os.path.isfile(path) else []
    log.append(record)
    with open(path, "w") as f:
        json.dump(log, f, indent=1, sort_keys=True)
        f.write("\n")
    return record


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("check")
    c.add_argument("new")
    c.add_argument("old")
    c.add_argument("--budget", type=int, default=300)
    d = sub.add_parser("adopt")
    d.add_argument("old")
    d.add_argument("new_name")
    d.add_argument("folder")
    d.add_argument("--proof", required=True)
    d.add_argument("--budget", type=int, default=300)
    a = ap.parse_args(argv)
    try:
        if a.cmd == "check":
            (_, na), (_, oa) = _read(a.new), _read(a.old)
            diff = first_difference(na, oa, a.budget)
            print(
                f"{digest(na, a.budget)[:8]} {digest(oa, a.budget)[:8]}: "
                + ("same" if diff is None else f"differ from job {diff}")
            )
            return 0 if diff is None else 1
        r = adopt(a.old, a.new_name, a.folder, a.proof, a.budget)
    except (OSError, ValueError, KeyError) as e:
        print(f"reuse: {e}", file=sys.stderr)
        return 2
    print(
        ("adopted as " + r["adopted"])
        if r["adopted"]
        else f"not adopted: results differ from job {r['first_difference']}"
    )
    return 0 if r["adopted"] else 1

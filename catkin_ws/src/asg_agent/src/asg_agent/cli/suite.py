"""suite: findings as a regression suite (issue #40; docs/design-loop.md).

    suite export EXPORT.jsonl.gz [...] --out SUITE [--classes flaw,model] [--limit N] [--label L]
    suite run SUITE [--workers 2] [--against LABEL] [--record LABEL] [--junit OUT.xml] [--json OUT.json]

`export` writes a suite folder (suite.yaml and scenarios/) from campaign exports: one finding per
failure mode of the classes named. `run` sends every scenario to running scene workers (any stack:
launch worker.launch with it), prints pass or fail per scenario with the reason, compares with the
outcomes recorded under --against (a regression: passed there, fails now; changed: the same
verdict but another trajectory), writes JUnit XML and JSON, and exits 1 on a regression, a change,
or (without --against) any failing scenario. `--record LABEL` stores this run's outcomes in the
suite under LABEL (and, without --against, exits 0: its failures are what it records). The tests
run it on their in-process stand-in, handing main() its workers instead of RosWorkers.
"""

import argparse
import json
import os
import sys

from asg_agent.campaign.suite import SuiteError, compare, export_suite, junit, load_suite, record, run_suite


class RosWorkers:
    """The suite's workers: scene workers of the running ROS master, named by --workers. Another
    `workers` of main() has the same three methods."""

    def options(self, r):
        """Options of `run` of the workers' own (none: --workers is the command's)."""

    def pool(self, a):
        """The pool of the workers (RuntimeError or ValueError: none to run on)."""
        from asg_agent.campaign.policy import worker_names
        from asg_agent.ros.node import init_node
        from asg_agent.ros.pool import WorkerPool

        init_node("suite", anonymous=True, disable_signals=True)
        return WorkerPool(worker_names(a.workers))

    def numerics(self, a) -> str:
        """The numerics the segmenter runs on the first worker (none for a ground-truth stack)."""
        import rospy

        from asg_agent.campaign.policy import worker_names
        from asg_agent.ros.stack_identity import segmenter_numerics

        first = worker_names(a.workers)[0]
        return segmenter_numerics(first, timeout=60.0) if rospy.has_param(f"{first}/segmenter/model") else ""


def main(argv=None, workers=None) -> int:
    """`workers`: what runs the suite's scenarios (default RosWorkers(); the tests pass their
    in-process stand-in's)."""
    workers = workers or RosWorkers()
    p = argparse.ArgumentParser(prog="suite", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export")
    e.add_argument("exports", nargs="+")
    e.add_argument("--out", required=True)
    e.add_argument("--classes", default="flaw", help="attribution classes, comma-separated (default flaw)")
    e.add_argument("--limit", type=int, default=0)
    e.add_argument("--label", default="", help="the stack under test's label in the outcomes (default MODEL-BACKEND)")
    e.add_argument(
        "--apart-from",
        default="",
        help="training sources (exports, suites, frame sets), comma-separated, whose scenes the suite must not hold",
    )
    e.add_argument("--drop-shared", action="store_true", help="leave shared findings out instead of refusing")
    r = sub.add_parser("run")
    r.add_argument("suite")
    r.add_argument("--workers", default="1", help="worker count N (/worker_0..) or namespaces, comma-separated")
    workers.options(r)
    r.add_argument("--against", default="", help="compare with the outcomes recorded under this label")
    r.add_argument("--record", default="", help="store this run's outcomes under this label")
    r.add_argument("--junit", default="")
    r.add_argument("--json", default="")
    a = p.parse_args([x for x in sys.argv[1:] if ":=" not in x] if argv is None else argv)
    try:
        if a.cmd == "export":
            s = export_suite(
                a.exports,
                a.out,
                tuple(c.strip() for c in a.classes.split(",") if c.strip()),
                a.limit,
                a.label,
                [x for x in a.apart_from.split(",") if x],
                a.drop_shared,
            )
            print(f"suite {a.out}: {len(s['scenarios'])} scenarios ({', '.join(s['classes'])}, one per failure mode)")
            for d in s.get("dropped_shared", []):
                print(f"  left out, in a training source: {d}")
            return 0
        suite = load_suite(a.suite)
    except (SuiteError, OSError, ValueError) as err:  # OverlapError is a ValueError
        print(f"suite: {err}", file=sys.stderr)
        return 2
    try:
        pool = workers.pool(a)
    except (RuntimeError, ValueError) as err:
        print(f"suite: {err}", file=sys.stderr)
        return 2
    numerics = workers.numerics(a)
    results = compare(suite, run_suite(suite, pool), a.against, numerics)
    name = os.path.basename(os.path.abspath(a.suite))
    for res in results:
        word = "FAIL" if res["fails"] else "pass"
        note = f" ({res['note']})" if res.get("note") else ""
        print(f"{word}  {os.path.basename(res['file'])}: {res['reason']} [{res['change']}]{note}")
    bad = sum(r["change"] in ("regression", "changed") or (r["change"] == "new" and r["fails"]) for r in results)
    if a.junit:
        junit(results, name, a.junit)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1, default=str)
    if a.record:
        record(suite, results, a.record, numerics)
        print(f"recorded as {a.record!r} in {os.path.join(a.suite, 'suite.yaml')}")
    n = len(results)
    print(f"suite {name}: {n - sum(r['fails'] for r in results)} of {n} pass; {bad} regressions or changes")
    if a.record and not a.against:
        return 0  # a recording run: its failures are what it records
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

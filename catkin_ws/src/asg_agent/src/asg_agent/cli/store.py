"""store: a campaign store's exports and parking (no ROS).

    python3 -m asg_agent.cli.store export STORE CAMPAIGN OUT.jsonl.gz
    python3 -m asg_agent.cli.store summary EXPORT.jsonl.gz [...]
    python3 -m asg_agent.cli.store show STORE CAMPAIGN        # the campaign's last screen, again
    python3 -m asg_agent.cli.store park STORE CAMPAIGN OUT.tar.xz [--unfinished-only]
    python3 -m asg_agent.cli.store unpark STORE PARKED.tar.xz
    python3 -m asg_agent.cli.store complete EXPORT.jsonl.gz SCENARIOS   # exit 0: finished, that many

`park` packs an unfinished campaign (its rows and its checkpoint) into one file to carry to
another machine or checkout; `unpark` puts it back into a store, and `--resume` goes on from it.
"""

import argparse
import json
import os
import sys

from asg_agent.records.export import counts, export, read_export
from asg_agent.records.store import Store, StoreError, checkpoint_path, park, unpark


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="asg_agent.cli.store", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export", help="compact gzip JSON-lines export of a campaign")
    e.add_argument("store")
    e.add_argument("campaign")
    e.add_argument("out")
    sm = sub.add_parser("summary", help="counts of exported campaigns")
    sm.add_argument("exports", nargs="+")
    sh = sub.add_parser("show", help="a campaign's last screen again: its findings with their replay commands")
    sh.add_argument("store")
    sh.add_argument("campaign")
    pk = sub.add_parser("park", help="pack an unfinished campaign (rows and checkpoint) into one tar.xz")
    pk.add_argument("store")
    pk.add_argument("campaign")
    pk.add_argument("out")
    pk.add_argument(
        "--unfinished-only",
        action="store_true",
        help="do nothing (exit 0) for a campaign the store lacks or that has finished",
    )
    cp = sub.add_parser("complete", help="exit 0 when an export is of a finished campaign of >= SCENARIOS")
    cp.add_argument("export")
    cp.add_argument("scenarios", type=int)
    up = sub.add_parser("unpark", help="put a parked campaign back into a store (left alone if it holds it)")
    up.add_argument("store")
    up.add_argument("parked")
    return p


def park_or_unpark(args) -> int:
    try:
        if args.cmd == "park":
            store = Store(args.store)
            c = store.campaign(args.campaign)
            if args.unfinished_only and (c is None or c["finished"]):
                print(f"{args.campaign}: " + ("not in the store" if c is None else "finished") + "; not parked")
                return 0
            n = park(store, args.campaign, checkpoint_path(args.store, args.campaign), args.out)
            print(f"{args.out}: campaign {args.campaign}, {n} scenarios and its checkpoint")
        else:
            n = unpark(Store(args.store), args.parked)
            held = "the store already holds this campaign; left alone"
            print(
                f"{args.parked}: "
                + (held if n is None else f"{n} scenarios and the checkpoint restored into {args.store}")
            )
    except StoreError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    if args.cmd in ("park", "unpark"):
        return park_or_unpark(args)
    if args.cmd in ("export", "show"):
        try:
            store = Store(args.store, create=False)
        except StoreError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
    if args.cmd == "export":
        n = export(store, args.campaign, args.out)
        print(f"{args.out}: {n} scenarios")
        return 0
    if args.cmd == "show":
        if store.campaign(args.campaign) is None:
            names = ", ".join(store.campaign_names()) or "none"
            print(f"error: {args.store} holds no campaign {args.campaign!r} (it holds: {names})", file=sys.stderr)
            return 2
        from asg_agent.cli.campaign import print_summary

        print_summary(store, args.campaign, out=sys.stdout)  # the stdout of now, not of import
        return 0
    if args.cmd == "complete":  # exit 1 (not complete) says why
        if not os.path.isfile(args.export):
            print(f"{args.export}: not complete: no such export", file=sys.stderr)
            return 1
        c, rows = read_export(args.export)
        if not c["finished"]:
            print(f"{args.export}: not complete: campaign {c['name']} is unfinished", file=sys.stderr)
            return 1
        if len(rows) < args.scenarios:
            print(f"{args.export}: not complete: {len(rows)} of {args.scenarios} scenarios", file=sys.stderr)
            return 1
        return 0
    for path in args.exports:  # summary
        c, rows = read_export(path)
        print(json.dumps({"campaign": c["name"], **counts(rows)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Issue #53's race, repeated: sound_runs' early-cancel check (test_5) run ROUNDS times in a row on
a running worker, with the cancel as the test makes it (stack_util.cancel_acknowledged) and, with
--naive, as it was made before (cancel_goal at once, which actionlib can answer LOST).

    python3 tests/early_cancel_loop.py [--rounds 20] [--naive] [--worker worker_0]

Prints one line a round (the three delays' states) and the counts; exits 1 if any state was not
the test's (PREEMPTED, or RECALLED at delay 0). scripts/repro/early_cancel.sh brings up the worker."""

import argparse
import collections
import os
import sys
import time

import rospy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stack_util as su  # noqa: E402

NAMES = {
    su.PREEMPTED: "PREEMPTED",
    su.RECALLED: "RECALLED",
    su.SUCCEEDED: "SUCCEEDED",
    su.ABORTED: "ABORTED",
    9: "LOST",
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--naive", action="store_true", help="cancel at once, as before the fix")
    ap.add_argument("--worker", default="worker_0")
    a = ap.parse_args()
    rospy.init_node("early_cancel_loop", anonymous=True)
    c = su.client(a.worker)
    if rospy.has_param(f"/{a.worker}/segmenter/model"):
        su.wait_for_segmenter(a.worker)
    scene = su.random_exp1(1, 101)
    counts, bad = collections.Counter(), 0
    for k in range(a.rounds):
        got = []
        for delay, ok in ((0.0, (su.PREEMPTED, su.RECALLED)), (0.02, (su.PREEMPTED,)), (0.2, (su.PREEMPTED,))):
            c.send_goal(su.to_goal_msg(scene))
            time.sleep(delay)
            c.cancel_goal() if a.naive else su.cancel_acknowledged(c)
            if not c.wait_for_result(rospy.Duration(60)):
                got.append(f"{delay:g} s: no result")
                bad += 1
                continue
            st = c.get_state()
            counts[(delay, NAMES.get(st, str(st)))] += 1
            bad += st not in ok
            got.append(f"{delay:g} s: {NAMES.get(st, st)}")
        print(f"round {k + 1:2d}: " + ", ".join(got), flush=True)
    mode = "cancel at once (before the fix)" if a.naive else "cancel once acknowledged (the fix)"
    print(f"{mode}: {a.rounds} rounds, " + ", ".join(f"delay {d:g} s {s} {n}" for (d, s), n in sorted(counts.items())))
    print(f"all {a.rounds} rounds as the test wants" if not bad else f"{bad} states the test refuses")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

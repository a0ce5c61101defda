#!/usr/bin/python3
"""rostest (issue #24): the stored reference runs of the backend worker_0 runs (reference_runs.test
starts it on channels_last) repeat bit for bit. ASG_WRITE_REFERENCE=1 records them instead. Under
ONEDNN_MAX_CPU_ISA=ALL (reference_runs_uncapped.test, issue #36) they repeat, or are refused before
any run where this CPU's kernels are not the recorded ones."""

import os
import unittest

import rospy
import rostest

import stack_util as su


class ReferenceRuns(unittest.TestCase):
    def test_stored_reference_bit_for_bit(self):
        rospy.init_node("reference_runs_test")
        from asg_perception.numerics import BF16_BACKENDS, native_bf16

        if rospy.get_param("/worker_0/segmenter/backend", "") in BF16_BACKENDS and not native_bf16():
            # issue #53: bf16 is refused at start where the CPU would emulate it, with the reason
            why = su.wait_for_param("/worker_0/segmenter/refused")
            self.assertIn("no native bf16", why)
            print(f"refused, as it must be on this CPU: {why}")
            return
        path = su.reference_path("worker_0", os.environ.get("ASG_WRITE_REFERENCE") == "1")
        write = os.environ.get("ASG_WRITE_REFERENCE") == "1"
        self.assertTrue(write or os.path.isfile(path), f"no reference runs for this backend: {path}")
        su.wait_for_segmenter("worker_0")
        if os.environ.get("ONEDNN_MAX_CPU_ISA", "").upper() == "ALL":
            # reference_runs_uncapped.test: repeat them, or refuse them with the reason, before any run.
            import json

            from asg_perception.numerics import can_reproduce

            with open(path) as f:
                recorded = json.load(f).get("numerics", "")
            here = su.wait_for_numerics("/worker_0")
            why = can_reproduce(recorded, here)
            if why:
                self.assertIn("oneDNN kernels", why)
                print(f"refused, as it must be: recorded {recorded!r}, here {here!r}: {why}")
                return
        record = None
        if os.environ.get("ASG_RECORD_CPU_CLASS") == "1":
            # what the runs produced is recorded before any comparison (issue #79): a class whose
            # runs differ gets its line too, and tests/test_numerics_classes.py fails on it
            def record(here, produced):
                su.record_cpu_class(path, here, produced, os.environ.get("ASG_CPU_CLASS_NOTE", ""))

        su.check_reference(self, su.client("worker_0"), path, write, on_produced=record)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "reference_runs", ReferenceRuns)

#!/usr/bin/python3
"""rostest (issue #9): a stack node that cannot serve a run ends it at once, naming itself;
free-running mode drives and can be cancelled; scenes beyond the budget are refused at once."""

import math
import time
import unittest

import rospy
import rostest
from asg_msgs.msg import RunScenarioResult

import stack_util as su


class StackFaults(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("stack_faults_test")
        cls.w2, cls.w3 = su.client("worker_2"), su.client("worker_3")

    def test_1_segmenter_of_another_frame_size_is_named_at_once(self):
        s = su.exp1(201, sim_timeout=4.0)
        # The first goal may wait for the segmenter to load its model; time the second.
        su.run(self.w2, s)
        s["scenario_id"] = 202
        t0 = time.time()
        state, r = su.run(self.w2, s)
        waited = time.time() - t0
        self.assertEqual(state, su.ABORTED)
        self.assertEqual(r.termination, RunScenarioResult.ERROR)
        self.assertTrue(r.error.startswith("segmenter:"), r.error)
        self.assertIn("256x256", r.error)
        self.assertLess(waited, 2.0)
        # Restarted with the right size, the same worker serves the next goal.
        rospy.set_param("/worker_2/segmenter/width", 256)
        rospy.set_param("/worker_2/segmenter/height", 256)
        # The respawned process announces itself by setting ~numerics once its model is loaded
        # (segmenter_node.py); the goal goes out after that, as a user's would after a restart.
        rospy.delete_param("/worker_2/segmenter/numerics")
        old = su.kill9("/worker_2/segmenter")
        su.wait_respawned("/worker_2/segmenter", old, "/worker_2/segmenter/numerics")
        s["scenario_id"] = 203
        state, r = su.run(self.w2, s)
        self.assertEqual(state, su.SUCCEEDED, f"termination {r.termination}: {r.error}")
        self.assertEqual(r.termination, RunScenarioResult.SIM_TIMEOUT)
        self.assertEqual(len(r.trajectory), 241)

    def test_2_free_running_drives_to_the_goal(self):
        s = su.exp1(204, sim_timeout=40.0)
        s["structural"]["layouts"] = []
        t0 = time.time()
        state, r = su.run(self.w3, s)
        wall = time.time() - t0
        self.assertEqual(state, su.SUCCEEDED, r.error)
        self.assertEqual(r.termination, RunScenarioResult.SUCCESS, r.error)
        self.assertGreater(r.num_control_msgs, 100)
        # Real-time factor 4: simulated time runs at most 4x wall time.
        self.assertGreater(wall, r.sim_time / 4.0 - 0.1)
        end = r.trajectory[-1].pose.position
        self.assertLessEqual(math.dist((end.x, end.y), (80, 80)), 11.0)

    def test_3_free_running_can_be_cancelled(self):
        s = su.exp1(205, sim_timeout=40.0)
        self.w3.send_goal(su.to_goal_msg(s))
        time.sleep(1.0)
        t0 = time.time()
        self.w3.cancel_goal()
        self.assertTrue(self.w3.wait_for_result(rospy.Duration(10)))
        self.assertLess(time.time() - t0, 1.0)
        self.assertEqual(self.w3.get_state(), su.PREEMPTED)

    def test_4_scenes_beyond_the_budget_are_refused_at_once(self):
        huge = su.to_goal_msg(su.exp1(206))
        huge.scene.structural.landscape.subdivisions = 4096
        huge.scene.structural.landscape.border = 600.0
        wide = su.to_goal_msg(su.exp1(207))
        wide.scene.structural.landscape.size = 10000.0
        endless = su.to_goal_msg(su.exp1(208))
        endless.scene.operational.sim_timeout = -1.0
        for goal, field in (
            (huge, "structural.landscape.subdivisions"),
            (wide, "structural.landscape.size"),
            (endless, "operational.sim_timeout"),
        ):
            t0 = time.time()
            self.w3.send_goal(goal)
            self.assertTrue(self.w3.wait_for_result(rospy.Duration(30)))
            self.assertLess(time.time() - t0, 1.0)
            self.assertEqual(self.w3.get_state(), su.ABORTED)
            self.assertIn(field, self.w3.get_result().error)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "stack_faults", StackFaults)

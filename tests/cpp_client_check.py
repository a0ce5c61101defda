#!/usr/bin/python3
"""rostest (issue #39): the C++ lockstep client makes a roscpp stack of standard messages
reproducible: two runs of a scenario, one under CPU load, are identical; the stack drives."""

import unittest

import rospy
import rostest

import stack_util as su


class CppClient(unittest.TestCase):
    def test_runs_repeat_bit_for_bit_and_the_stack_drives(self):
        rospy.init_node("cpp_client_test")
        c = su.client("worker_0")
        for seed in (3, 4):
            scenario = su.random_exp1(seed, scenario_id=10 + seed, sim_timeout=20.0)
            _, first = su.run(c, scenario)
            self.assertNotEqual(first.termination_name, "ERROR", first.error)
            hogs = su.busy_cores(2)  # the same run while two processes compete for the cores
            try:
                _, second = su.run(c, scenario)
            finally:
                for h in hogs:
                    h.kill()
                    h.wait()
            self.assertEqual(su.trajectory_key(first), su.trajectory_key(second), f"seed {seed}")
            # Twists answered the control ticks, and the vehicle moved towards the goal.
            self.assertGreater(first.num_control_msgs, 10)
            start, end = first.trajectory[0].pose.position, first.trajectory[-1].pose.position
            goal = scenario["operational"]
            before = ((goal["goal_x"] - start.x) ** 2 + (goal["goal_y"] - start.y) ** 2) ** 0.5
            after = ((goal["goal_x"] - end.x) ** 2 + (goal["goal_y"] - end.y) ** 2) ** 0.5
            self.assertLess(after, before - 10.0)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "cpp_client", CppClient)

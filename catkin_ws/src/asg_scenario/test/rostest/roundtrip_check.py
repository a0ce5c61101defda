#!/usr/bin/python3
"""rostest: a RunScenario goal built from a scenario file round-trips through an action server."""

import math
import os
import unittest

import rospy
import rostest
from asg_msgs.msg import RunScenarioAction, RunScenarioResult

from asg_scenario import load_scenario
from asg_scenario.convert import from_scene_msg, to_goal_msg
from asg_scenario.ros_node import GoalClient

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", ".."))


class RoundTrip(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("roundtrip_test")
        cls.client = GoalClient("run_scenario", RunScenarioAction)
        assert cls.client.wait_for_server(rospy.Duration(30.0)), "no action server"

    def run_goal(self, goal):
        self.client.send_goal(goal)
        self.assertTrue(self.client.wait_for_result(rospy.Duration(120.0)))
        return self.client.get_result()

    def test_good_goal(self):
        s = load_scenario(os.path.join(REPO, "scenarios", "exp3.yaml"))
        goal = to_goal_msg(s)
        self.assertEqual(from_scene_msg(goal.scene, s["scenario_id"], s["name"])["structural"], s["structural"])
        r = self.run_goal(goal)
        self.assertEqual(r.termination, RunScenarioResult.SUCCESS, r.error)
        self.assertEqual(r.scenario_id, 3)
        self.assertEqual(len(r.obstacle_visibility), 32)
        self.assertAlmostEqual(r.trajectory[0].pose.position.x, 50.0)
        self.assertAlmostEqual(r.trajectory[-1].pose.position.y, 150.0)

    def test_bad_goal_then_good_goal(self):
        s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
        goal = to_goal_msg(s)
        goal.scene.operational.start_x = math.nan
        r = self.run_goal(goal)
        self.assertEqual(r.termination, RunScenarioResult.ERROR)
        self.assertIn("operational.start_x", r.error)
        r = self.run_goal(to_goal_msg(s))
        self.assertEqual(r.termination, RunScenarioResult.SUCCESS, r.error)


if __name__ == "__main__":
    rostest.rosrun("asg_scenario", "roundtrip", RoundTrip)

#!/usr/bin/python3
"""rostest: the scene worker and the planner in closed loop on ground-truth labels."""

import math
import os
import unittest

import rospy
import rostest
from asg_msgs.msg import PlannerState, RunScenarioAction, RunScenarioResult

from asg_scenario import load_scenario
from asg_scenario.convert import to_goal_msg
from asg_scenario.ros_node import GoalClient

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))


def exp1(scenario_id, layouts):
    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    s["scenario_id"] = scenario_id
    s["structural"]["layouts"] = layouts
    s["operational"]["sim_timeout"] = 60.0
    return s


def bush_row():
    # Five bushes 2.5 m apart across the start-goal diagonal at its middle (50, 50).
    d = 2.5 / math.sqrt(2)
    return [
        {
            "mesh_name": "barberry",
            "instances": [
                {"visible": True, "cast_shadow": True, "x": 50 + k * d, "y": 50 - k * d, "yaw": 0.0, "scale": 1.0}
                for k in range(-2, 3)
            ],
        }
    ]


def path_length(traj):
    pts = [(s.pose.position.x, s.pose.position.y) for s in traj]
    return sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))


class ClosedLoop(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("closed_loop_test")
        cls.clients = {}
        for ns in ("worker_0", "worker_1"):
            cls.clients[ns] = GoalClient(f"/{ns}/run_scenario", RunScenarioAction)
            assert cls.clients[ns].wait_for_server(rospy.Duration(60.0)), ns
        cls.states = []
        rospy.Subscriber("/worker_1/planner/state", PlannerState, cls.states.append, queue_size=2000)
        rospy.sleep(1.0)

    def run_scenario(self, s, ns="worker_0"):
        client = self.clients[ns]
        client.send_goal(to_goal_msg(s))
        self.assertTrue(client.wait_for_result(rospy.Duration(180.0)))
        return client.get_result()

    def test_1_empty_scene_straight_to_goal(self):
        r = self.run_scenario(exp1(21, []))
        self.assertEqual(r.termination, RunScenarioResult.SUCCESS, r.termination_name + r.error)
        optimal = math.dist((20, 20), (80, 80)) - 11.0  # to the goal circle
        plr = path_length(r.trajectory) / optimal
        rospy.loginfo("empty scene: PLR %.4f in %.1f s", plr, r.sim_time)
        self.assertLess(plr, 1.05)

    def test_2_row_of_bushes_is_avoided(self):
        # With the paper's 5 m grids a fully voted vertex only adds alpha * 50 = 100 % to nearby
        # edges, and A* drives through this row (see docs/planner.md); the finer grids avoid it.
        del self.states[:]
        r = self.run_scenario(exp1(22, bush_row()), "worker_1")
        self.assertEqual(r.termination, RunScenarioResult.SUCCESS, r.termination_name + r.error)
        self.assertEqual(r.collision_with, "")
        # The planner saw the bushes and planned around them.
        voted = [s.voted_vertices for s in self.states if s.scenario_id == 22]
        self.assertGreater(max(voted), 0)
        closest = min(math.dist((s.pose.position.x, s.pose.position.y), (50, 50)) for s in r.trajectory)
        rospy.loginfo("bush row: closest approach to the row centre %.2f m", closest)
        self.assertGreater(closest, 2.0)

    def test_3_same_scenario_same_trajectory(self):
        a = self.run_scenario(exp1(23, bush_row()), "worker_1")
        b = self.run_scenario(exp1(24, bush_row()), "worker_1")
        self.assertEqual(len(a.trajectory), len(b.trajectory))
        self.assertEqual(a.num_control_msgs, b.num_control_msgs)
        for sa, sb in zip(a.trajectory, b.trajectory):
            self.assertEqual(sa.pose, sb.pose)

    def test_4_paper_defaults_replay_exactly_too(self):
        s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
        s["operational"]["sim_timeout"] = 20.0
        s["scenario_id"] = 25
        a = self.run_scenario(s)
        s["scenario_id"] = 26
        b = self.run_scenario(s)
        self.assertEqual([x.pose for x in a.trajectory], [x.pose for x in b.trajectory])
        self.assertEqual(a.termination, b.termination)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "closed_loop", ClosedLoop)

#!/usr/bin/python3
"""rostest: RunScenario goals through actionlib against real scene workers."""

import copy
import math
import os
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from asg_msgs.msg import RunScenarioAction, RunScenarioResult, ScenarioInfo, Tick
from sensor_msgs.msg import Image

from asg_scenario import load_scenario
from asg_scenario.convert import to_goal_msg
from asg_scenario.ros_node import GoalClient

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", ".."))


def short_exp1(scenario_id, sim_timeout=3.0):
    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    s["scenario_id"] = scenario_id
    s["operational"]["sim_timeout"] = sim_timeout
    return s


class SceneWorkerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("scene_worker_test")
        cls.clients = {}
        for ns in ("worker_0", "worker_1", "worker_2"):
            c = GoalClient(f"/{ns}/run_scenario", RunScenarioAction)
            assert c.wait_for_server(rospy.Duration(60.0)), f"no action server in {ns}"
            cls.clients[ns] = c
        cls.images, cls.ticks, cls.infos = [], [], []
        rospy.Subscriber("/worker_0/camera/image_raw", Image, lambda m: cls.images.append(m), queue_size=100)
        rospy.Subscriber("/worker_0/tick", Tick, lambda m: cls.ticks.append(m), queue_size=1000)
        rospy.Subscriber("/worker_0/scenario", ScenarioInfo, lambda m: cls.infos.append(m), queue_size=10)
        rospy.sleep(1.0)

    def run_goal(self, ns, goal, timeout=120.0):
        c = self.clients[ns]
        c.send_goal(goal)
        self.assertTrue(c.wait_for_result(rospy.Duration(timeout)), "no result")
        return c.get_state(), c.get_result()

    def test_1_trajectory_and_sensors(self):
        self.images[:], self.ticks[:] = [], []
        goal = to_goal_msg(short_exp1(11))
        goal.top_down_px = 64
        state, r = self.run_goal("worker_0", goal)
        self.assertEqual(state, GoalStatus.SUCCEEDED, r.error)
        self.assertEqual(r.termination, RunScenarioResult.SIM_TIMEOUT, r.error)
        self.assertAlmostEqual(r.sim_time, 3.0, places=6)
        self.assertEqual(len(r.trajectory), 181)  # 60 Hz, t = 0 .. 3 s
        self.assertEqual(r.num_control_msgs, 60)  # 20 Hz
        first, last = r.trajectory[0].pose.position, r.trajectory[-1].pose.position
        self.assertAlmostEqual(first.x, 20.0, places=1)
        moved = math.hypot(last.x - first.x, last.y - first.y)
        self.assertGreater(moved, 3.0)  # it drove under the scripted throttle
        self.assertEqual(len(r.obstacle_visibility), 8)
        self.assertEqual((r.top_down.width, r.top_down.height, r.top_down.encoding), (64, 64, "rgb8"))
        rospy.sleep(0.5)
        # The worker's own count of camera frames, told with every control tick (small messages,
        # none lost): 15 Hz over [0, 2.95] s, the last control tick's time.
        ticks = [t for t in self.ticks if t.scenario_id == 11]
        self.assertEqual(len(ticks), 60)
        self.assertEqual(max(t.camera_frames for t in ticks), 45)
        # Stamps are the run's base (a multiple of the run window) + simulated time on the 15 Hz
        # grid. (A subscriber slower than a 30x-real-time run may miss images: the publisher
        # keeps 4 per subscriber; the lockstep stack never does, it answers each frame first.)
        base = [i for i in self.infos if i.scenario_id == 11][-1].base_stamp
        self.assertEqual((base.secs % ScenarioInfo.RUN_WINDOW, base.nsecs), (0, 0))
        stamps = sorted(m.header.stamp for m in self.images)
        self.assertGreater(len(stamps), 0)
        self.assertEqual(len(set(stamps)), len(stamps))
        for t in stamps:
            k = (t - base).to_sec() * 15.0
            self.assertAlmostEqual(k, round(k), places=4)
            self.assertTrue(0 <= round(k) < 45)

    def test_2_same_goal_same_trajectory(self):
        goal = to_goal_msg(short_exp1(12, sim_timeout=2.0))
        _, a = self.run_goal("worker_0", goal)
        goal.scenario_id = 13
        _, b = self.run_goal("worker_0", goal)
        self.assertEqual(len(a.trajectory), len(b.trajectory))
        for sa, sb in zip(a.trajectory, b.trajectory):
            self.assertEqual(sa.pose, sb.pose)
            self.assertEqual(sa.twist, sb.twist)

    def test_3_bad_goal_then_good_goal(self):
        goal = to_goal_msg(short_exp1(14, sim_timeout=1.0))
        bad = copy.deepcopy(goal)
        bad.scene.operational.start_x = float("nan")
        bad.scene.structural.layouts[0].mesh_name = "oak"
        state, r = self.run_goal("worker_0", bad)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertEqual(r.termination, RunScenarioResult.ERROR)
        self.assertIn("operational.start_x", r.error)
        self.assertIn("unknown mesh", r.error)
        state, r = self.run_goal("worker_0", goal)
        self.assertEqual(state, GoalStatus.SUCCEEDED, r.error)
        self.assertEqual(r.termination, RunScenarioResult.SIM_TIMEOUT)

    def test_4_silent_stack_is_an_error_not_a_hang(self):
        state, r = self.run_goal("worker_1", to_goal_msg(short_exp1(15)), timeout=60.0)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertEqual(r.termination, RunScenarioResult.ERROR)
        self.assertIn("driver: no command for control tick t = 0.000 s", r.error)

    def test_5_missing_stack_node_is_named(self):
        state, r = self.run_goal("worker_2", to_goal_msg(short_exp1(16)), timeout=60.0)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn("planner", r.error)


if __name__ == "__main__":
    rostest.rosrun("asg_sim", "scene_worker", SceneWorkerTest)

#!/usr/bin/python3
"""rostest (issue #55): stacks from their registration files alone. gap_nav, an ordinary ROS 1
stack that imports nothing of this project, runs free on simulated time (its nodes hear
/worker_0/clock as /clock) through a 20-scenario campaign; the paper and depth stacks run short
campaigns through their files. On the way: the worker's clock advances with the simulation,
tf resolves map -> odom -> base_link (REP 105), and the camera speaks image_pipeline's names in an
`_optical` frame."""

import json
import os
import subprocess
import tempfile
import unittest

import rospy
import rostest
import tf2_ros
import yaml
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image

from asg_agent.records.store import Store

import stack_util as su

SCENARIOS = 20  # gap_nav's campaign (the size)
SHORT = 4  # the paper and depth stacks': that their files bring them up and they run
PAIR = 6  # the depth pair's campaign, run twice (issue #67)


def campaign(store, experiment, worker, name, scenarios, timeout, extra=()):
    cmd = [
        "/usr/bin/python3",
        "-m",
        "asg_agent.cli.campaign",
        os.path.join(su.REPO, "experiments", experiment),
        "--workers",
        worker,
        "--scenarios",
        str(scenarios),
        "--method",
        "random",
        "--seed",
        "0",
        "--store",
        store,
        "--name",
        name,
        "--no-progress",
        *extra,
    ]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=su.REPO)


class RegisteredStacks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("registered_stacks_test")
        for ns in ("worker_0", "worker_1", "worker_2", "worker_3", "worker_4"):
            su.client(ns, timeout=180.0)
        cls.dir = tempfile.mkdtemp()
        cls.store = os.path.join(cls.dir, "store.sqlite")

    def test_0_gap_nav_campaign_on_simulated_time(self):
        clocks, images, infos = [], [], []
        rospy.Subscriber("/worker_0/clock", Clock, lambda m: clocks.append(m.clock.to_sec()), queue_size=1000)
        rospy.Subscriber("/worker_0/camera/image_raw", Image, lambda m: images.append(m.header), queue_size=10)
        rospy.Subscriber("/worker_0/camera/depth/camera_info", CameraInfo, lambda m: infos.append(m), queue_size=10)
        tf = tf2_ros.Buffer(rospy.Duration(30.0))
        tf2_ros.TransformListener(tf)  # /tf and /tf_static: worker_0's (the test's remaps)
        p = campaign(self.store, "exp1-gap-nav.yaml", "worker_0,worker_3", "gap-nav", SCENARIOS, 1000)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        store = Store(self.store)
        settings = json.loads(store.campaign("gap-nav")["settings"])
        self.assertEqual((settings["stack"], settings["command_interface"]), ("gap_nav", "twist"))
        self.assertEqual(settings["registration"]["sim_time"], True)
        self.assertEqual(
            sorted(settings["identity"]), ["gap_drive/half_width", "gap_drive/speed", "gap_drive/step_height"]
        )
        rows = list(store.rows("gap-nav"))
        self.assertEqual(len(rows), SCENARIOS)
        for r in rows:
            self.assertNotEqual(r["termination"], "ERROR", r["error"])
            self.assertGreater(r["samples"], 10)
        # It drives: a run that never moves ends idle (IDLING_TIMEOUT); most do not.
        self.assertGreaterEqual(
            sum(r["termination"] != "IDLING_TIMEOUT" for r in rows), SCENARIOS // 2, [r["termination"] for r in rows]
        )
        self.assertEqual({r["worker"] for r in rows}, {"/worker_0", "/worker_3"})  # both gap_nav workers ran
        # The worker's clock advanced with the simulation, over several runs' windows.
        self.assertGreater(len(clocks), 100)
        self.assertGreater(max(clocks) - min(clocks), 4096.0)
        # REP 105 and REP 103: map -> odom -> base_link, the camera's optical frame by name.
        tree = yaml.safe_load(tf.all_frames_as_yaml())
        self.assertEqual(tree["base_link"]["parent"], "odom")
        self.assertEqual(tree["odom"]["parent"], "map")
        self.assertEqual(tree["camera_optical"]["parent"], "base_link")
        tf.lookup_transform("map", "base_link", rospy.Time(0), rospy.Duration(5.0))
        self.assertTrue(images and all(h.frame_id == "camera_optical" for h in images))
        self.assertTrue(infos and infos[-1].K[0] > 0)

    def test_1_the_paper_and_depth_stacks_through_their_files(self):
        for exp, worker, name in (("exp1.yaml", "worker_1", "paper"), ("exp1-depth.yaml", "worker_2", "depth")):
            # exp1.yaml runs the U-Net; this worker's paper stack runs ground truth: refused, named
            p = campaign(self.store, exp, worker, name, SHORT, 600)
            if name == "paper":
                self.assertNotEqual(p.returncode, 0)
                self.assertIn("the campaign ran the U-Net, /worker_1 has no segmenter", p.stdout + p.stderr)
                p = campaign(self.store, "exp1-gt.yaml", worker, name, SHORT, 600)
            self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
            rows = list(Store(self.store).rows(name))
            self.assertEqual(len(rows), SHORT)
            self.assertTrue(all(r["termination"] != "ERROR" for r in rows), [r["error"] for r in rows])

    def test_2_a_stack_pair_in_lockstep_gives_the_same_verdicts_twice(self):
        # issue #67: depth_rc (worker_4) under test, its registration's reference `depth` (worker_2)
        # re-running every scenario; two campaigns of the same seed give the same runs and verdicts
        extra = ("--reference", "release=worker_2", "--candidates", "all")
        for name in ("pair-a", "pair-b"):
            p = campaign(self.store, "exp1-depth-rc.yaml", "worker_4", name, PAIR, 600, extra)
            self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
            self.assertIn("stack-pair attribution against depth", p.stdout)
        store = Store(self.store)
        settings = json.loads(store.campaign("pair-a")["settings"])
        self.assertEqual((settings["stack"], settings["references"]["release"]["stack"]), ("depth_rc", "depth"))
        a, b = list(store.rows("pair-a")), list(store.rows("pair-b"))
        self.assertEqual(len(a), PAIR)
        classes = ("regression", "shared", "unclear", "reverse", "pass")
        self.assertTrue(all(r["attribution"] in classes for r in a), [r["attribution"] for r in a])
        for x, y in zip(a, b):
            self.assertEqual(x["attribution"], y["attribution"])
            self.assertEqual(x["trajectory"], y["trajectory"])  # the stack under test's runs, bit for bit
            rx, ry = json.loads(x["reference_runs"])["release"], json.loads(y["reference_runs"])["release"]
            self.assertEqual(
                (rx["termination"], rx["proxy"], rx["trajectory_xy"]),
                (ry["termination"], ry["proxy"], ry["trajectory_xy"]),
            )


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "registered_stacks", RegisteredStacks)

#!/usr/bin/python3
"""rostest (issue #10): `campaign` against two real workers fills the store, and a second
campaign with the same seed stores the same scenarios, proxies and trajectories."""

import os
import subprocess
import tempfile
import unittest

import rospy
import rostest

from asg_agent.records.store import Store, unpack_trajectory

import stack_util as su
from asg_perception.numerics import DEFAULT_BACKEND

SCENARIOS = 20
# The U-Net backend the workers run (scripts/test.sh: the shipped default, fp32 channels_last since
# issue #53), the experiment that names it, and one that names another backend (refused).
# exp1.yaml names no backend (the shipped default); exp1-bf16.yaml names the bf16 fast mode.
BACKEND = os.environ.get("ASG_TEST_UNET_BACKEND") or DEFAULT_BACKEND
EXPERIMENT, OTHER, OTHER_BACKEND = (
    ("exp1.yaml", "exp1-bf16.yaml", "bf16")
    if BACKEND == DEFAULT_BACKEND
    else ("exp1-bf16.yaml", "exp1.yaml", DEFAULT_BACKEND)
)


class CampaignEndToEnd(unittest.TestCase):
    def run_campaign(self, store, name):
        cmd = [
            "/usr/bin/python3",
            "-m",
            "asg_agent.cli.campaign",
            os.path.join(su.REPO, "experiments", EXPERIMENT),
            "--workers",
            "2",
            "--scenarios",
            str(SCENARIOS),
            "--seed",
            "3",
            "--store",
            store,
            "--name",
            name,
            "--no-progress",
        ]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=500)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        return p.stdout

    def test_campaign_fills_the_store_and_repeats(self):
        rospy.init_node("campaign_test")
        su.client("worker_0")
        su.client("worker_1")
        # Issue #24: an experiment whose backend is not what the workers run stores nothing.
        path = os.path.join(tempfile.mkdtemp(), "store.sqlite")
        p = subprocess.run(
            [
                "/usr/bin/python3",
                "-m",
                "asg_agent.cli.campaign",
                os.path.join(su.REPO, "experiments", OTHER),
                "--workers",
                "2",
                "--scenarios",
                "2",
                "--store",
                path,
                "--no-progress",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        self.assertEqual(p.returncode, 2, p.stdout[-2000:] + p.stderr[-2000:])
        self.assertIn(
            f"the campaign's stack runs the {OTHER_BACKEND!r} inference backend, /worker_0 runs {BACKEND!r}", p.stderr
        )
        other_name = OTHER.replace(".yaml", "") + "-td3-per-asp-s0"
        self.assertFalse(os.path.exists(path) and Store(path).campaign(other_name))
        out = self.run_campaign(path, "first")
        self.assertIn("campaign first: 20 scenarios", out)
        # Issue #36: the campaign stores the numerics its segmenters ran (what replay compares).
        import json

        numerics = json.loads(Store(path).campaign("first")["settings"])["numerics"]
        self.assertEqual(numerics, rospy.get_param("/worker_0/segmenter/numerics"))
        self.assertRegex(numerics, rf"^{BACKEND} isa=\S+ threads=1 torch=\S+$")
        self.run_campaign(path, "second")
        store = Store(path)
        a, b = store.content_digest("first"), store.content_digest("second")
        self.assertEqual(len(a), SCENARIOS)
        self.assertEqual([r[0] for r in a], list(range(SCENARIOS)))
        for ra, rb in zip(a, b):
            self.assertEqual(ra, rb, f"job {ra[0]} differs between the two campaigns")
        rows = list(store.rows("first"))
        self.assertEqual({r["worker"] for r in rows}, {"/worker_0", "/worker_1"})
        for r in rows:
            self.assertEqual(r["termination"] != "ERROR", r["proxy"] is not None)
            traj = unpack_trajectory(r["trajectory"])
            self.assertEqual(len(traj), r["samples"])
            self.assertGreater(r["samples"], 60)
        self.assertTrue(store.integrity_ok())
        bag, row = self.check_replay(path, store)
        self.check_pictures(path, bag, row)

    def check_replay(self, path, store):
        """The top scenario replays exactly, and the bag of the replay holds the run's topics."""
        top = store.summary("first", top=1)["top"][0]
        bag = os.path.join(os.path.dirname(path), "replay.bag")
        p = subprocess.run(
            [
                "/usr/bin/python3",
                "-m",
                "asg_agent.ros.replay",
                path,
                "first",
                str(top["job"]),
                "--worker",
                "/worker_0",
                "--bag",
                bag,
            ],
            capture_output=True,
            text=True,
            timeout=300,
        )
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr[-2000:])
        self.assertIn("REPRODUCED", p.stdout)
        self.assertIn("largest position difference to the stored run: 0.000000 m", p.stdout)
        import rosbag

        with rosbag.Bag(bag) as b:
            counts = {t: i.message_count for t, i in b.get_type_and_topic_info().topics.items()}
        row = next(r for r in store.rows("first") if r["job"] == top["job"])
        frames = int(row["sim_time"] * 15) + 1  # 15 Hz from t = 0
        for topic in ("camera/image_raw", "labels", "camera/depth/image_raw"):
            self.assertGreaterEqual(counts.get("/worker_0/" + topic, 0), frames - 1, topic)
        # odom at the ticks a stack reads (camera every 4th, control every 3rd of the 60 Hz ticks),
        # and the final state (the worker's default odom_every_tick: false).
        ticks = row["samples"] - 1
        self.assertEqual(counts.get("/worker_0/odom", 0), sum(1 for k in range(ticks) if k % 4 == 0 or k % 3 == 0) + 1)
        self.assertEqual(counts.get("/worker_0/planner/state", 0), row["num_control_msgs"])
        self.assertGreater(counts.get("/worker_0/planner/path", 0), 0)
        self.assertGreater(counts.get("/worker_0/planner/votes", 0), 0)
        for topic in ("replay/scene", "replay/optimal_path", "replay/trajectory"):
            self.assertEqual(counts.get("/worker_0/" + topic, 0), 1, topic)
        self.assertEqual(counts.get("/worker_0/replay/labels_rgb", 0), counts["/worker_0/labels"])
        return bag, row

    def check_pictures(self, path, bag, row):
        """rviz with rviz/replay.rviz on the replay's bag, under Xvfb: the vote grid, the plan and
        the driven path are drawn (a blank view or an error panel has none of their colours); a
        planner snapshot from the bag and the campaign's HTML report."""
        from asg_agent.ros.replay_view import screenshot

        shot = os.path.join(os.path.dirname(path), "replay.png")
        px = screenshot(bag, shot, at=0.7)  # the namespace found in the bag (worker_0)
        self.assertGreater(px["votes"], 300, px)
        self.assertGreater(px["plan"], 50, px)
        self.assertGreater(px["trajectory"], 100, px)
        from asg_analysis.report import campaign_report
        from asg_agent.ros.bag_figures import snapshot

        snap = os.path.join(os.path.dirname(path), "snapshot.png")
        snapshot(bag, snap, row["sim_time"] / 2)
        self.assertGreater(os.path.getsize(snap), 10000)
        page = open(campaign_report(path, "first", os.path.join(os.path.dirname(path), "report"), top=3)).read()
        self.assertIn(f"<td>{SCENARIOS}</td>", page)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "campaign", CampaignEndToEnd)

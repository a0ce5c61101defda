#!/usr/bin/python3
"""rostest: `campaign` with its defaults (what train.sh runs, without the reference stacks)
against two real workers fills the store, a second campaign with the same seed stores the same
scenarios, proxies and trajectories, and every command of docs/replay.md runs as written on it
(its store, campaign and job swapped in)."""

import ast
import os
import re
import shlex
import subprocess
import tempfile
import unittest

import rospy
import rostest

from asg_agent.defaults import DEFAULTS
from asg_agent.records.store import Store, unpack_trajectory

import stack_util as su
from asg_perception.numerics import DEFAULT_BACKEND

SCENARIOS = 20
# The U-Net backend the workers run (scripts/test.sh: the shipped default, fp32 channels_last since
# issue #53), the experiment that names it, and one that names another backend (refused).
# The default experiment names no backend (the shipped default); exp1-bf16.yaml names the bf16
# fast mode.
BACKEND = os.environ.get("ASG_TEST_UNET_BACKEND") or DEFAULT_BACKEND
EXPERIMENT, OTHER, OTHER_BACKEND = (
    (os.path.basename(DEFAULTS["experiment"].value), "exp1-bf16.yaml", "bf16")
    if BACKEND == DEFAULT_BACKEND
    else ("exp1-bf16.yaml", "exp1.yaml", DEFAULT_BACKEND)
)
METHOD = DEFAULTS["method"].value
# what train.sh's campaign is named in docs/replay.md, and this test's own
DOC_STORE, DOC_CAMPAIGN = "results/train.sqlite", f"exp1-route-wide-{METHOD}-s0"
FIRST = f"{EXPERIMENT[: -len('.yaml')]}-{METHOD}-s0"


class CampaignEndToEnd(unittest.TestCase):
    def run_campaign(self, store, name=None):
        """A campaign of the CLI's defaults (the experiment only where the backend asks for another),
        named by default (EXPERIMENT-METHOD-s0) or `name`."""
        cmd = ["/usr/bin/python3", "-m", "asg_agent.cli.campaign"]
        if EXPERIMENT != os.path.basename(DEFAULTS["experiment"].value):
            cmd.append(os.path.join(su.REPO, "experiments", EXPERIMENT))
        cmd += ["--workers", "2", "--scenarios", str(SCENARIOS), "--store", store, "--no-progress"]
        cmd += ["--name", name] if name else []
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
        other_name = OTHER.replace(".yaml", "") + f"-{METHOD}-s0"
        self.assertFalse(os.path.exists(path) and Store(path).campaign(other_name))
        out = self.run_campaign(path)
        self.assertIn(f"campaign {FIRST}: 20 scenarios", out)
        # Issue #36: the campaign stores the numerics its segmenters ran (what replay compares).
        import json

        numerics = json.loads(Store(path).campaign(FIRST)["settings"])["numerics"]
        self.assertEqual(numerics, rospy.get_param("/worker_0/segmenter/numerics"))
        self.assertRegex(numerics, rf"^{BACKEND} isa=\S+ threads=1 torch=\S+$")
        self.run_campaign(path, "second")
        store = Store(path)
        a, b = store.content_digest(FIRST), store.content_digest("second")
        self.assertEqual(len(a), SCENARIOS)
        self.assertEqual([r[0] for r in a], list(range(SCENARIOS)))
        for ra, rb in zip(a, b):
            self.assertEqual(ra, rb, f"job {ra[0]} differs between the two campaigns")
        rows = list(store.rows(FIRST))
        self.assertEqual({r["worker"] for r in rows}, {"/worker_0", "/worker_1"})
        for r in rows:
            self.assertEqual(r["termination"] != "ERROR", r["proxy"] is not None)
            traj = unpack_trajectory(r["trajectory"])
            self.assertEqual(len(traj), r["samples"])
            self.assertGreater(r["samples"], 60)
        self.assertTrue(store.integrity_ok())
        top = store.summary(FIRST, top=1)["top"][0]
        outputs = self.run_replay_guide(path, top["job"])
        bag = os.path.join(os.path.dirname(path), "job.bag")
        row = self.check_replay(bag, store, top["job"], outputs)
        self.check_pictures(path, bag, row, outputs)

    def run_replay_guide(self, path, job):
        """Every command of docs/replay.md's bash blocks, as written, with this test's store,
        campaign and job for train.sh's; `roslaunch` (an interactive rviz) is the one left out,
        and replay_view runs its picture headless instead. Returns {command's first words: stdout}."""
        text = open(os.path.join(su.REPO, "docs", "replay.md"), encoding="utf-8").read()
        blocks = re.findall(r"```bash\n(.*?)```", text, re.S)
        commands = [line.split("  #")[0].strip() for b in blocks for line in b.splitlines() if line.strip()]
        self.assertGreaterEqual(len(commands), 6, commands)
        work = os.path.dirname(path)
        outputs = {}
        for command in commands:
            if command.startswith("roslaunch "):
                self.assertIn("launch/replay.launch bag:=job.bag", command)
                continue
            argv = shlex.split(command.replace(DOC_STORE, path).replace(DOC_CAMPAIGN, FIRST).replace("JOB", str(job)))
            if argv[0] == "python3":
                argv[0] = "/usr/bin/python3"
            p = subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=400)
            self.assertEqual(p.returncode, 0, f"docs/replay.md: {command}\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
            outputs[" ".join(argv[:4])] = p.stdout
        return outputs

    def check_replay(self, bag, store, job, outputs):
        """The guide's replay reproduced the run exactly, and its bag holds the run's topics."""
        out = next(v for k, v in outputs.items() if k.startswith("rosrun asg_agent replay"))
        self.assertIn("REPRODUCED", out)
        self.assertIn("largest position difference to the stored run: 0.000000 m", out)
        show = next(v for k, v in outputs.items() if "cli.store show" in k)
        self.assertIn(f"campaign {FIRST}: 20 scenarios", show)
        import rosbag

        with rosbag.Bag(bag) as b:
            counts = {t: i.message_count for t, i in b.get_type_and_topic_info().topics.items()}
        row = next(r for r in store.rows(FIRST) if r["job"] == job)
        ns = "/replay_worker/"  # the worker replay brought up
        frames = int(row["sim_time"] * 15) + 1  # 15 Hz from t = 0
        for topic in ("camera/image_raw", "labels", "camera/depth/image_raw"):
            self.assertGreaterEqual(counts.get(ns + topic, 0), frames - 1, topic)
        # odom at every tick and the final state: the worker replay brings up runs odom_every_tick
        # (a campaign's worker, by default, only at the ticks a stack reads)
        ticks = row["samples"] - 1
        self.assertEqual(counts.get(ns + "odom", 0), ticks + 1)
        self.assertEqual(counts.get(ns + "planner/state", 0), row["num_control_msgs"])
        self.assertGreater(counts.get(ns + "planner/path", 0), 0)
        self.assertGreater(counts.get(ns + "planner/votes", 0), 0)
        for topic in ("replay/scene", "replay/optimal_path", "replay/trajectory"):
            self.assertEqual(counts.get(ns + topic, 0), 1, topic)
        self.assertEqual(counts.get(ns + "replay/labels_rgb", 0), counts[ns + "labels"])
        return row

    def check_pictures(self, path, bag, row, outputs):
        """rviz with rviz/replay.rviz on the replay's bag, under Xvfb: the vote grid, the plan and
        the driven path are drawn (a blank view or an error panel has none of their colours); a
        planner snapshot from the bag and the campaign's HTML report."""
        view = next(v for k, v in outputs.items() if "replay_view" in k)
        px = ast.literal_eval(view.strip().split(": ", 1)[1])  # replay_view prints its pixel counts
        self.assertGreater(px["votes"], 300, px)
        self.assertGreater(px["plan"], 50, px)
        self.assertGreater(px["trajectory"], 100, px)
        work = os.path.dirname(path)
        self.assertGreater(os.path.getsize(os.path.join(work, "snapshot.png")), 10000)
        self.assertTrue(any(f.startswith(FIRST) for f in os.listdir(os.path.join(work, "figures"))))
        page = open(os.path.join(work, "report", "index.html")).read()
        self.assertIn(f"<td>{SCENARIOS}</td>", page)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "campaign", CampaignEndToEnd)

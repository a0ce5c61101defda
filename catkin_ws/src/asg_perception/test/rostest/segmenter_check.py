#!/usr/bin/python3
"""rostest: the segmenter turns published images into label images with the same stamps."""

import os
import unittest

import numpy as np
import rospy
import rostest
from asg_msgs.msg import ScenarioInfo, StackAck, StackError
from PIL import Image as PILImage
from sensor_msgs.msg import Image

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", ".."))


class SegmenterTest(unittest.TestCase):
    def test_labels_keep_stamps_and_order(self):
        rospy.init_node("segmenter_test")
        got, acks, errors = [], [], []
        rospy.Subscriber("/worker_0/labels", Image, got.append, queue_size=10)
        rospy.Subscriber("/worker_0/stack_error", StackError, errors.append, queue_size=10)
        rospy.Subscriber("/worker_0/stack_ack", StackAck, acks.append, queue_size=10)
        pub = rospy.Publisher("/worker_0/camera/image_raw", Image, queue_size=10)
        ann = rospy.Publisher("/worker_0/scenario", ScenarioInfo, queue_size=1, latch=True)
        deadline = rospy.Time.now() + rospy.Duration(60)
        base = rospy.Time(3 * ScenarioInfo.RUN_WINDOW)
        while not acks and rospy.Time.now() < deadline:
            # Announce as the worker does: again every 0.5 s until acknowledged (an ack sent
            # before our subscription was connected is lost). The model is loaded by then.
            ann.publish(ScenarioInfo(scenario_id=7, run=3, base_stamp=base, camera_width=256, camera_height=256))
            rospy.sleep(0.5)
        self.assertTrue(acks, "no acknowledgement from the segmenter")
        self.assertEqual((acks[0].node, acks[0].scenario_id, acks[0].run), ("segmenter", 7, 3))
        while pub.get_num_connections() == 0:
            rospy.sleep(0.05)
        # A rendered camera frame (left third of the docs panel): sky on top, ground below.
        rgb = np.asarray(PILImage.open(os.path.join(REPO, "docs", "images", "shadows_panel.png")).convert("RGB"))[
            :256, :256
        ].copy()
        stamps = [base + rospy.Duration(k / 15.0) for k in range(3)]
        stale = rospy.Time(2 * ScenarioInfo.RUN_WINDOW + 1)  # a late frame of the run before
        for st in [stale] + stamps:
            msg = Image(height=256, width=256, encoding="rgb8", step=768, data=rgb.tobytes())
            msg.header.stamp, msg.header.frame_id = st, "camera"
            pub.publish(msg)
        while len(got) < 3 and rospy.Time.now() < deadline:
            rospy.sleep(0.05)
        rospy.sleep(0.5)
        self.assertEqual([m.header.stamp for m in got], stamps)  # the stale frame is not labelled
        self.assertEqual(errors, [])
        bad = Image(height=2, width=2, encoding="bgr8", step=6, data=bytes(12))
        bad.header.stamp = base + rospy.Duration(1.0)
        pub.publish(bad)  # ends the run with a StackError naming the segmenter; the node stays up
        while not errors and rospy.Time.now() < deadline:
            rospy.sleep(0.05)
        self.assertEqual((errors[0].node, errors[0].scenario_id, errors[0].run), ("segmenter", 7, 3))
        self.assertIn("bgr8", errors[0].reason)
        for m in got:
            self.assertEqual((m.encoding, m.width, m.height, m.header.frame_id), ("mono8", 256, 256, "camera"))
            labels = np.frombuffer(m.data, np.uint8).reshape(256, 256)
            self.assertTrue(set(np.unique(labels)) <= {0, 1, 2})
            self.assertGreater((labels[:64] == 2).mean(), 0.95)  # sky
            self.assertGreater((labels[200:] == 0).mean(), 0.7)  # near ground


if __name__ == "__main__":
    rostest.rosrun("asg_perception", "segmenter", SegmenterTest)

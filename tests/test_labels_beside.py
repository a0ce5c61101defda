"""Issue #54: a replay bag gets another U-Net's labels of the same camera frames beside the stack's
(`replay --labels-beside full`), for rviz/replay.rviz's third image panel: each camera frame of
the bag labelled by the named model, with the frame's stamp, in the palette of the stack's own."""

import os

import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import Image

from asg_agent.ros.bag_scene import PALETTE, labels_beside, labels_rgb

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))


def frame(seed, stamp):
    rgb = np.random.default_rng(seed).integers(0, 255, (256, 256, 3), dtype=np.uint8)
    msg = Image(height=256, width=256, encoding="rgb8", step=256 * 3, data=rgb.tobytes())
    msg.header.stamp, msg.header.frame_id = rospy.Time(stamp), "camera_optical"
    return rgb, msg


def test_every_camera_frame_is_labelled_again_by_the_named_model(tmp_path):
    from asg_perception.inference import Segmenter

    path = str(tmp_path / "run.bag")
    frames = [frame(k, 4096 + k) for k in range(3)]
    with rosbag.Bag(path, "w") as bag:
        for rgb, msg in frames:
            bag.write("/w/camera/image_raw", msg, msg.header.stamp)
        bag.write("/w/odom_other", msg, msg.header.stamp)  # not a camera frame: left alone
    with rosbag.Bag(path) as bag:
        out = labels_beside(bag, "/w", "full")
    assert [topic for _, topic, _ in out] == ["/w/replay/labels_beside_rgb"] * 3
    seg = Segmenter(os.path.join(REPO, "catkin_ws", "src", "asg_perception", "models", "full.pt"))
    for (rgb, msg), (t, _, img) in zip(frames, out):
        assert t == msg.header.stamp and img.header.stamp == msg.header.stamp and img.encoding == "rgb8"
        want = np.array(PALETTE, np.uint8)[seg(rgb)]
        assert np.array_equal(np.frombuffer(img.data, np.uint8).reshape(256, 256, 3), want)


def test_the_stacks_own_labels_take_the_same_palette():
    lab = np.array([[0, 1], [2, 3]], np.uint8)
    msg = Image(height=2, width=2, encoding="mono8", step=2, data=lab.tobytes())
    img = labels_rgb(msg)
    assert (img.encoding, img.step) == ("rgb8", 6)
    assert np.frombuffer(img.data, np.uint8).reshape(4, 3).tolist() == [list(c) for c in PALETTE]

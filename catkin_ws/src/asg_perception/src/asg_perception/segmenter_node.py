"""segmenter: the rospy adapter of the U-Net (docs/perception.md).

Subscribes `camera/image` (rgb8) and publishes `labels` (mono8, same header): one output per
input, in order. Acknowledges scenario announcements so that the worker starts only once the
model is loaded.
"""
import os

import numpy as np
import rospy
from asg_msgs.msg import ScenarioInfo, StackAck
from sensor_msgs.msg import Image

from .inference import BACKENDS, Segmenter

MODELS = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "models"))


def resolve_model(name: str) -> str:
    """A shipped model's name ('full', 'flawed') or a path."""
    if os.sep not in name and not name.endswith(".pt"):
        path = os.path.join(MODELS, name + ".pt")
        if not os.path.isfile(path):
            import rospkg
            path = os.path.join(rospkg.RosPack().get_path("asg_perception"), "models", name + ".pt")
        return path
    return name


class SegmenterNode:
    def __init__(self):
        model = rospy.get_param("~model", "flawed")
        backend = rospy.get_param("~backend", "channels_last")
        threads = int(rospy.get_param("~threads", 1))
        width = int(rospy.get_param("~width", 256))
        height = int(rospy.get_param("~height", 256))
        self.ack_name = rospy.get_param("~ack_name", "segmenter")
        if backend not in BACKENDS:
            raise ValueError(f"~backend = {backend!r}: one of {', '.join(BACKENDS)}")
        if not 1 <= threads <= 64:
            raise ValueError(f"~threads = {threads}: must be 1..64")
        path = resolve_model(model)
        self.segmenter = Segmenter(path, backend, threads, height, width)
        rospy.loginfo("segmenter: %s (%s backend, %d thread(s))", path, backend, threads)
        self.pub = rospy.Publisher("labels", Image, queue_size=32, tcp_nodelay=True)
        self.ack_pub = rospy.Publisher("stack_ack", StackAck, queue_size=4)
        rospy.Subscriber("scenario", ScenarioInfo, self.on_scenario, queue_size=4)
        rospy.Subscriber("camera/image", Image, self.on_image, queue_size=64, tcp_nodelay=True,
                         buff_size=2 ** 24)

    def on_scenario(self, info):
        self.ack_pub.publish(StackAck(node=self.ack_name, scenario_id=info.scenario_id, run=info.run))

    def on_image(self, msg):
        if msg.encoding != "rgb8" or msg.step != msg.width * 3 or len(msg.data) != msg.step * msg.height:
            rospy.logerr_throttle(5.0, f"segmenter: image at t = {msg.header.stamp.to_sec():.3f} s "
                                       f"skipped: encoding {msg.encoding!r}, {msg.width}x{msg.height}, "
                                       f"step {msg.step} (expected packed rgb8)")
            return
        rgb = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
        try:
            labels = self.segmenter(rgb)
        except ValueError as e:
            rospy.logerr_throttle(5.0, f"segmenter: image at t = {msg.header.stamp.to_sec():.3f} s skipped: {e}")
            return
        out = Image(header=msg.header, height=msg.height, width=msg.width, encoding="mono8",
                    is_bigendian=0, step=msg.width, data=labels.tobytes())
        self.pub.publish(out)


def main():
    rospy.init_node("segmenter")
    try:
        SegmenterNode()
    except ValueError as e:
        rospy.logfatal(f"segmenter: {e}")
        raise SystemExit(2)
    rospy.spin()

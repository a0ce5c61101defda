"""segmenter: the rospy adapter of the U-Net (docs/perception.md).

Subscribes `camera/image_raw` (rgb8) and publishes `labels` (mono8, same header): one output per
input, in order. Acknowledges scenario announcements so that the worker starts only once the
model is loaded. Images stamped outside the current run's window (ScenarioInfo.RUN_WINDOW) are
dropped before inference and counted; a camera size it was not made for, or a frame it cannot
label, ends the run at once with a StackError naming this node.
"""

import os
import threading

import numpy as np
import rospy
from asg_lockstep import StackProtocol, params
from asg_lockstep.stack_protocol import Run
from asg_msgs.msg import ScenarioInfo, StackAck, StackError, StageTimes
from sensor_msgs.msg import Image

from . import numerics
from .inference import Segmenter
from .node_params import SEGMENTER
from .numerics import resolve_backend
from .stage_clock import StageClock

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
        # every parameter through the node's table (node_params.SEGMENTER): a bad one is named
        p = params.read(SEGMENTER, lambda name, default: rospy.get_param("~" + name, default))
        model, threads, width, height = p["model"], p["threads"], p["width"], p["height"]
        backend = resolve_backend(p["backend"])  # empty: the shipped default (numerics, its one home)
        self.ack_name = p["ack_name"]
        rospy.set_param("~backend", backend)  # the one it runs, for whoever reads the parameter
        refused = numerics.refuse_emulated(backend)
        if refused:  # bf16 is a fast mode for CPUs that run it natively (issue #53)
            rospy.set_param("~refused", refused)  # for whoever waits for ~numerics
            raise ValueError(refused)
        path = resolve_model(model)
        self.segmenter = Segmenter(path, backend, threads, height, width)
        # What decides the labels' numerics on this CPU (numerics.py): the campaign stores it,
        # replay compares it before it runs.
        self.numerics = numerics.identity(backend, threads)
        rospy.set_param("~numerics", self.numerics)
        rospy.loginfo("segmenter: %s (%s)", path, self.numerics)
        self.width, self.height = width, height
        self.lock = threading.Lock()
        # Which run is current and which images belong to it: the protocol core (asg_lockstep).
        self.protocol = StackProtocol(int(round(ScenarioInfo.RUN_WINDOW * 1e9)))
        self.failed = None  # the StackError sent for the current run, if any
        self.pub = rospy.Publisher("labels", Image, queue_size=32, tcp_nodelay=True)
        self.ack_pub = rospy.Publisher("stack_ack", StackAck, queue_size=4)
        self.error_pub = rospy.Publisher("stack_error", StackError, queue_size=4)
        # Where the time goes (docs/benchmarks.md): decode the image, infer, publish the labels.
        self.clock = StageClock(["decode", "inference", "publish"])
        self.stage_pub = rospy.Publisher("stage_times", StageTimes, queue_size=1, latch=True)
        self._last_reading = None
        self.publish_stage_times()
        rospy.Timer(rospy.Duration(1.0), lambda _: self.publish_stage_times())
        rospy.Subscriber("scenario", ScenarioInfo, self.on_scenario, queue_size=4)
        self.image_sub = rospy.Subscriber(
            "camera/image_raw", Image, self.on_image, queue_size=64, tcp_nodelay=True, buff_size=2**24
        )

    def on_scenario(self, info):
        with self.lock:
            run = Run(info.scenario_id, info.run, info.base_stamp.to_nsec(), info.camera_width, info.camera_height)
            if self.protocol.announce(run):
                self.failed = None
                if (info.camera_width, info.camera_height) != (self.width, self.height):
                    self.fail(
                        f"camera frames are {info.camera_width}x{info.camera_height}, this "
                        f"segmenter was made for {self.width}x{self.height} (~width, ~height)"
                    )
            if self.failed:  # say it again: the first one may have gone out before the worker listened
                self.error_pub.publish(self.failed)
            elif not self.connected():
                return  # the worker announces again in 0.5 s
            else:
                self.ack_pub.publish(StackAck(node=self.ack_name, scenario_id=info.scenario_id, run=info.run))

    def connected(self):
        """Whether to acknowledge now: once the camera and the labels' listener are connected (a
        segmenter that has just (re)started subscribes and advertises before the TCP links
        exist, and a frame or labels sent before then are lost), or when the protocol's rule
        says to stop waiting (StackProtocol.acknowledge: a stack without a labels listener
        still runs)."""
        linked = self.image_sub.get_num_connections() > 0 and self.pub.get_num_connections() > 0
        return self.protocol.acknowledge(linked)

    def publish_stage_times(self):
        stages, seconds, calls, cpu = self.clock.read()
        key = (self.protocol.runs, sum(calls))
        if key == self._last_reading:
            return
        self._last_reading = key
        self.stage_pub.publish(
            StageTimes(
                stamp=rospy.Time.now(),
                node=self.ack_name,
                runs=self.protocol.runs,
                cpu_seconds=cpu,
                stages=stages,
                seconds=seconds,
                calls=calls,
            )
        )

    def fail(self, reason):
        """Ends the current run (the caller holds the lock)."""
        run = self.protocol.fail(reason)
        rospy.logerr(f"segmenter: scenario {run.scenario_id}: {reason}")
        self.failed = StackError(node=self.ack_name, scenario_id=run.scenario_id, run=run.run, reason=reason)
        self.error_pub.publish(self.failed)

    def on_image(self, msg):
        with self.lock:
            stamp = msg.header.stamp.to_nsec()
            if not self.protocol.accept(stamp):
                if not self.protocol.current(stamp):
                    # Normal after a run ends early (late frames of the last run): counted, not a warning.
                    rospy.logdebug_throttle(
                        5.0,
                        f"segmenter: image stamped {msg.header.stamp.to_sec():.3f} s "
                        f"is not of the current run: dropped ({self.protocol.stale} so far)",
                    )
                return
            t = self.protocol.seconds(stamp)
            with self.clock.time("decode"):
                ok = msg.encoding == "rgb8" and msg.step == msg.width * 3 and len(msg.data) == msg.step * msg.height
                if ok:
                    rgb = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
            if not ok:
                return self.fail(
                    f"cannot label the image at t = {t:.3f} s: encoding {msg.encoding!r}, "
                    f"{msg.width}x{msg.height}, step {msg.step} (expected packed rgb8)"
                )
            try:
                with self.clock.time("inference"):
                    labels = self.segmenter(rgb)
            except (ValueError, RuntimeError) as e:
                return self.fail(f"cannot label the image at t = {t:.3f} s: {e}")
        with self.clock.time("publish"):
            out = Image(
                header=msg.header,
                height=msg.height,
                width=msg.width,
                encoding="mono8",
                is_bigendian=0,
                step=msg.width,
                data=labels.tobytes(),
            )
            self.pub.publish(out)


def main():
    rospy.init_node("segmenter")
    try:
        SegmenterNode()
    except ValueError as e:
        rospy.logfatal(f"segmenter: {e}")
        raise SystemExit(2)
    rospy.spin()

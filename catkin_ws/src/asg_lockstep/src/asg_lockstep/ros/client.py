"""LockstepClient: what a stack written against standard messages adds to become reproducible
in a scene worker's lockstep (docs/your-stack.md). The stack keeps its logic; it creates its
input subscribers and its `cmd_vel` publisher through the client instead of rospy:

    lock = LockstepClient("my_stack", on_run=my_stack.reset)
    lock.Subscriber("odom", Odometry, my_stack.on_odom)
    lock.Subscriber("camera/depth/points", PointCloud2, my_stack.on_points)
    lock.Subscriber("goal", PoseStamped, my_stack.on_goal)
    cmd = lock.Publisher("cmd_vel", Twist, queue_size=1)

In lockstep (the node's `~lockstep` parameter; without it, its stack registration's `stack/mode`,
lockstep by default), the client acknowledges each run,
holds the inputs back and, at each control tick, hands them to the stack's callbacks in stamp order
on one thread (asg_lockstep.gate), then answers the tick with the stack's latest `cmd_vel`, as a
geometry_msgs/TwistStamped on `cmd_vel_stamped` stamped with the tick. With `~lockstep` false the
subscribers and the publisher are rospy's own and the stack runs free (not reproducible); the
client still acknowledges runs, so the worker starts them.

The worker's node parameters must name the client in `stack_nodes` and set `command_interface:
twist`. Only this module of the stack's process imports this project's messages."""

import threading
import traceback
from typing import Callable, List, Optional

import rospy
from asg_msgs.msg import ScenarioInfo, StackAck, StackError, Tick
from geometry_msgs.msg import Twist, TwistStamped

from asg_lockstep.gate import TickGate, kind_of
from asg_lockstep.params import CLIENT, read, registered_lockstep
from asg_lockstep.stack_protocol import Run, StackProtocol

WAIT_REPORT_S = 5.0  #: [s, wall] a tick still waiting for an input after this is reported


class _Publisher:
    """rospy.Publisher, remembering the last Twist published (the answer to the next tick)."""

    def __init__(self, client: "LockstepClient", pub: rospy.Publisher, answers: bool):
        self._client, self._pub, self._answers = client, pub, answers

    def publish(self, msg) -> None:
        self._pub.publish(msg)
        if self._answers:
            self._client._latest = msg

    def __getattr__(self, name):
        return getattr(self._pub, name)


class LockstepClient:
    def __init__(self, node: Optional[str] = None, on_run: Optional[Callable[[], None]] = None, lockstep=None):
        """`node`: the name the worker's `stack_nodes` lists (default: this node's name);
        `on_run`: called at every new run before it is acknowledged (reset the stack there);
        `lockstep`: default the private parameter `~lockstep` (true)."""
        self.node = node or rospy.get_name().rsplit("/", 1)[-1]
        if lockstep is None:  # the node's own parameter (params.CLIENT), else its stack's registration
            registered = registered_lockstep(rospy.get_param("stack/mode", None))
            default = CLIENT[0].default if registered is None else registered
            lockstep = read(CLIENT, lambda name, _: rospy.get_param("~" + name, default))["lockstep"]
        self.lockstep = bool(lockstep)
        self._on_run = on_run
        self._on_tick: List[Callable[[float], None]] = []
        self._protocol = StackProtocol(ScenarioInfo.RUN_WINDOW * 10**9)
        self._gate = TickGate(ScenarioInfo.RUN_WINDOW * 10**9)
        self._callbacks = {}
        self._cv = threading.Condition()
        self._latest = Twist()  # a stop until the stack says otherwise
        self._answer_pub = rospy.Publisher("cmd_vel_stamped", TwistStamped, queue_size=4, tcp_nodelay=True)
        self._ack_pub = rospy.Publisher("stack_ack", StackAck, queue_size=4)
        self._error_pub = rospy.Publisher("stack_error", StackError, queue_size=4)
        self._subs = [rospy.Subscriber("scenario", ScenarioInfo, self._on_scenario, queue_size=4)]
        if self.lockstep:
            self._subs.append(rospy.Subscriber("tick", Tick, self._on_tick_msg, queue_size=4, tcp_nodelay=True))

    # --- what the stack calls -------------------------------------------------------------------
    def Subscriber(self, topic: str, msg_class, callback, kind: Optional[str] = None, **kwargs):
        """rospy.Subscriber's place: in lockstep the callback gets the messages at the ticks, in
        stamp order. `kind` ('run', 'state', 'camera': asg_lockstep.gate) is needed only for a
        message type the gate does not know."""
        if not self.lockstep:
            return rospy.Subscriber(topic, msg_class, callback, **kwargs)
        name = rospy.resolve_name(topic)
        self._gate.add(name, kind_of(msg_class._type, kind))
        self._callbacks[name] = callback
        kwargs.setdefault("queue_size", 64)  # held by the gate, never dropped by rospy
        kwargs.setdefault("tcp_nodelay", True)
        return rospy.Subscriber(topic, msg_class, self._offer, callback_args=name, **kwargs)

    def Publisher(self, topic: str, msg_class, **kwargs):
        """rospy.Publisher's place; a Twist publisher's last message answers each tick."""
        return _Publisher(self, rospy.Publisher(topic, msg_class, **kwargs), msg_class is Twist)

    def on_tick(self, callback: Callable[[float], None]) -> None:
        """For a stack whose control runs on a timer: in lockstep, `callback(t)` [s of simulated
        time] runs at every control tick after its inputs, before the answer (instead of the
        timer; free-running, it is never called)."""
        self._on_tick.append(callback)

    # --- the protocol ---------------------------------------------------------------------------
    def _on_scenario(self, info: ScenarioInfo) -> None:
        run = Run(info.scenario_id, info.run, info.base_stamp.to_nsec(), info.camera_width, info.camera_height)
        with self._cv:
            new = self._protocol.announce(run)
            if new:
                self._gate.begin(run.base)
                self._latest = Twist()
                self._cv.notify_all()
        if new and self._on_run is not None:
            try:
                self._on_run()
            except Exception as e:  # the run cannot be served: say so, stay up
                self._fail(f"on_run failed: {e!r}")
                return
        self._ack_pub.publish(StackAck(node=self.node, scenario_id=info.scenario_id, run=info.run))

    def _offer(self, msg, topic: str) -> None:
        with self._cv:
            if self._gate.offer(topic, msg.header.stamp.to_nsec(), msg):
                self._cv.notify_all()

    def _on_tick_msg(self, tick: Tick) -> None:
        stamp = tick.header.stamp.to_nsec()
        with self._cv:
            if not self._protocol.tick(tick.scenario_id, stamp):
                return
            run = self._protocol.run.run
            if not self._gate.tick(stamp, tick.last_camera_stamp.to_nsec(), tick.camera_frames):
                return
            waited = 0.0
            while self._gate.missing():
                if rospy.is_shutdown() or self._protocol.run.run != run:
                    return
                self._cv.wait(0.05)
                waited += 0.05
                if waited >= WAIT_REPORT_S:
                    rospy.logwarn_throttle(
                        WAIT_REPORT_S,
                        f"{self.node}: control tick t = {self._protocol.seconds(stamp):.3f} s still waits for "
                        f"{', '.join(self._gate.missing())} (is the worker publishing it? "
                        "camera/depth/points needs the worker's ~publish_points)",
                    )
            batch = self._gate.release()
        try:
            for topic, msg in batch:
                self._callbacks[topic](msg)
            for fn in self._on_tick:
                fn(self._protocol.seconds(stamp))
        except Exception as e:
            rospy.logerr(f"{self.node}: {traceback.format_exc()}")
            self._fail(f"{type(e).__name__}: {e}")
            return
        answer = TwistStamped()
        answer.header.stamp = tick.header.stamp
        answer.header.frame_id = "base_link"
        answer.twist = self._latest
        self._answer_pub.publish(answer)

    def _fail(self, reason: str) -> None:
        with self._cv:
            run = self._protocol.fail(reason)
        if run is not None:
            self._error_pub.publish(StackError(node=self.node, scenario_id=run.scenario_id, run=run.run, reason=reason))

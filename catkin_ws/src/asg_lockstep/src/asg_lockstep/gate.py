"""The input gate of a foreign stack in lockstep (no rospy): a stack written against standard
messages reads odometry, camera data and a goal from topics, each on its own callback thread, and
publishes `cmd_vel` whenever its code decides to. That is not reproducible: which messages a
command saw depends on thread timing. The gate makes it so without touching the stack's logic:
its input messages are held back and handed over, tick by tick, in stamp order on one thread,
and only once every message the worker published up to the tick is here.

What the worker publishes, and so what the gate waits for at a control tick stamped t:

- ``run``: once per run at simulated time 0 (the goal): a message of the current run;
- ``state``: at every control tick and camera frame (odometry): a message stamped t;
- ``camera``: at every camera frame (images, camera_info, points): a message stamped the tick's
  `last_camera_stamp`, once the run has any camera frame.

Stamps are integer nanoseconds; the ROS adapter (asg_lockstep.ros_client) converts."""

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

KINDS = ("run", "state", "camera")
#: The kind of the standard message types a stack reads, by ROS type name.
KIND_OF_TYPE = {
    "geometry_msgs/PoseStamped": "run",
    "nav_msgs/Odometry": "state",
    "sensor_msgs/Image": "camera",
    "sensor_msgs/CameraInfo": "camera",
    "sensor_msgs/PointCloud2": "camera",
}


def kind_of(type_name: str, kind: Optional[str] = None) -> str:
    """The gate kind of a topic of `type_name`, or `kind` when given; a clear error otherwise."""
    if kind is not None:
        if kind not in KINDS:
            raise ValueError(f"lockstep input kind {kind!r}: must be one of {', '.join(KINDS)}")
        return kind
    if type_name not in KIND_OF_TYPE:
        raise ValueError(
            f"lockstep input of type {type_name}: the gate does not know when the worker publishes it; "
            f"pass kind= one of {', '.join(KINDS)}"
        )
    return KIND_OF_TYPE[type_name]


@dataclass
class Pending:
    stamp: int  #: [ns] the control tick
    last_camera: int  #: [ns] newest camera frame published before it (0: none yet)
    camera_frames: int


@dataclass
class TickGate:
    window: int  #: [ns] width of a run's stamp window (ScenarioInfo.RUN_WINDOW)
    topics: Dict[str, str] = field(default_factory=dict)  #: topic -> kind, in delivery order
    base: Optional[int] = None  #: [ns] the current run's stamp of t = 0
    stale: int = 0  #: messages dropped as not of the current run

    def __post_init__(self):
        self._held: List[Tuple[int, int, int, str, Any]] = []
        self._newest: Dict[str, int] = {}
        self._seq = 0
        self.pending: Optional[Pending] = None

    def add(self, topic: str, kind: str) -> None:
        if kind not in KINDS:
            raise ValueError(f"lockstep input {topic}: kind {kind!r} is not one of {', '.join(KINDS)}")
        self.topics[topic] = kind

    def begin(self, base: int) -> None:
        """A new run whose stamps start at `base` [ns]: what was held of other runs is dropped;
        what arrived of this one before its announcement (the goal, published first) is kept."""
        self.base = int(base)
        keep = [m for m in self._held if self._current(m[0])]
        self.stale += len(self._held) - len(keep)
        self._held = keep
        self._newest = {}
        for stamp, _, _, topic, _ in keep:
            self._newest[topic] = max(stamp, self._newest.get(topic, stamp))
        self.pending = None

    def _current(self, stamp: int) -> bool:
        return self.base is not None and self.base <= stamp < self.base + self.window

    def offer(self, topic: str, stamp: int, msg: Any) -> bool:
        """A message arrived on an input topic: held for delivery if of the current run or of a
        later one (announced after its first messages went out); dropped if of an earlier run."""
        if topic not in self.topics:
            raise KeyError(f"{topic} is not a lockstep input of this stack")
        if self.base is not None and stamp < self.base:
            self.stale += 1
            return False
        if not self._current(stamp):  # of a run not announced yet: held, not counted as newest
            order = list(self.topics).index(topic)
            self._held.append((stamp, order, self._seq, topic, msg))
            self._seq += 1
            return True
        order = list(self.topics).index(topic)
        self._held.append((stamp, order, self._seq, topic, msg))
        self._seq += 1
        self._newest[topic] = max(stamp, self._newest.get(topic, stamp))
        return True

    def tick(self, stamp: int, last_camera: int, camera_frames: int) -> bool:
        """The worker waits for the answer to the tick at `stamp`; False for a tick of another run."""
        if not self._current(stamp):
            self.stale += 1
            return False
        self.pending = Pending(int(stamp), int(last_camera), int(camera_frames))
        return True

    def missing(self) -> List[str]:
        """The input topics the pending tick still waits for (empty: ready)."""
        p = self.pending
        if p is None:
            return []
        out = []
        for topic, kind in self.topics.items():
            newest = self._newest.get(topic)
            if kind == "run":
                ok = newest is not None
            elif kind == "state":
                ok = newest is not None and newest >= p.stamp
            else:
                ok = p.camera_frames == 0 or (newest is not None and newest >= p.last_camera)
            if not ok:
                out.append(topic)
        return out

    def release(self) -> List[Tuple[str, Any]]:
        """The held messages stamped up to the pending tick, in (stamp, topic order, arrival)
        order; later ones stay held. Call when `missing()` is empty."""
        if self.pending is None:
            return []
        self._held.sort(key=lambda m: m[:3])
        out = [(m[3], m[4]) for m in self._held if self._current(m[0]) and m[0] <= self.pending.stamp]
        self._held = [m for m in self._held if not (self._current(m[0]) and m[0] <= self.pending.stamp)]
        return out

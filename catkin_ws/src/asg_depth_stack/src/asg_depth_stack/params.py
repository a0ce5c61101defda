"""The depth_stack node's parameters (asg_lockstep.params; docs/your-stack.md quotes this table,
config/depth_stack.yaml holds the defaults; its `lockstep` is the lockstep client's, CLIENT)."""

from asg_lockstep.params import Param

from asg_depth_stack.arcs import ArcParams
from asg_depth_stack.grid import GridParams

_G, _A = GridParams(), ArcParams()
_NOT_EMPTY = dict(rule=lambda v: v != "", rule_text="not empty")

DEPTH_STACK = [
    Param("use_lockstep_client", bool, True, "-", "false: plain rospy subscribers and publisher (free-running only)"),
    Param(
        "ack_name",
        str,
        "depth_stack",
        "-",
        "the name it acknowledges runs with (the worker's `stack_nodes`)",
        **_NOT_EMPTY,
    ),
    Param(
        "camera_frame",
        str,
        "camera_optical",
        "-",
        "frame of `camera/depth/points` (tf `base_link` <- `camera_optical`, looked up once)",
        **_NOT_EMPTY,
    ),
    Param("base_frame", str, "base_link", "-", "the vehicle's frame", **_NOT_EMPTY),
    Param(
        "publish_markers",
        bool,
        True,
        "-",
        "publish `depth_stack/arc` (`nav_msgs/Path`, map frame: the arc it chose) and `depth_stack/obstacles` "
        "(`visualization_msgs/Marker`: the grid's obstacle cells) for rviz and replay bags; worker.launch sets it "
        "from `markers` (off in campaigns)",
    ),
    Param("grid/cell", float, _G.cell, "m", "cell side", lo=0.05, hi=10.0),
    Param("grid/size", float, _G.size, "m", "side of the map, centred on the run's first pose", lo=1.0, hi=2000.0),
    Param(
        "grid/step_height",
        float,
        _G.step_height,
        "m",
        "height span in a cell that makes it an obstacle",
        lo=0.01,
        hi=10.0,
    ),
    Param(
        "grid/min_points", int, _G.min_points, "-", "points a cell needs before it can be an obstacle", lo=1, hi=10000
    ),
    Param("grid/max_range", float, _G.max_range, "m", "planar range of the points used", lo=0.1, hi=1000.0),
    Param(
        "grid/max_height", float, _G.max_height, "m", "points this far above the camera are ignored", lo=0.0, hi=100.0
    ),
    Param("arcs/speed", float, _A.speed, "m/s", "cruise speed (Exp. 1's tracking speed)", lo=0.1, hi=30.0),
    Param(
        "arcs/min_speed",
        float,
        _A.min_speed,
        "m/s",
        "speed at the least clearance that still passes (at most `speed`)",
        lo=0.0,
        hi=30.0,
    ),
    Param(
        "arcs/max_curvature",
        float,
        _A.max_curvature,
        "1/m",
        "sharpest arc (the vehicle's is tan(0.6 rad) / 2.3 m = 0.30)",
        lo=0.001,
        hi=10.0,
    ),
    Param(
        "arcs/arcs",
        int,
        _A.arcs,
        "-",
        "arcs in the lattice (odd: one is straight)",
        lo=1,
        hi=1001,
        rule=lambda v: v % 2 == 1,
        rule_text="odd",
    ),
    Param("arcs/horizon", float, _A.horizon, "m", "arc length", lo=0.1, hi=1000.0),
    Param("arcs/step", float, _A.step, "m", "sample spacing along an arc", lo=0.01, hi=100.0),
    Param(
        "arcs/clearance",
        float,
        _A.clearance,
        "m",
        "least distance from the centre line to an obstacle cell",
        lo=0.01,
        hi=100.0,
    ),
    Param(
        "arcs/slow_clearance",
        float,
        _A.slow_clearance,
        "m",
        "below this the speed falls towards `min_speed`",
        lo=0.0,
        hi=100.0,
    ),
    Param("arcs/turn_weight", float, _A.turn_weight, "m per 1/m", "cost of curvature", lo=0.0, hi=1e6),
    Param("arcs/change_weight", float, _A.change_weight, "m per 1/m", "cost of changing arc", lo=0.0, hi=1e6),
]

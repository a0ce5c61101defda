"""Adds what a replay bag needs for rviz beyond the worker's own topics (rospy messages, no node):
the obstacles by type, start and goal circles, the optimal path, the driven trajectory and the
planner's earlier plans fading, all in the map frame under `<ns>/replay/...`."""

import math

from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Path
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from asg_scenario.catalogue import MESHES
from asg_scenario.terrain import scenario_terrain


def _colour(mesh: str):
    """RGB of a mesh in rviz: the catalogue's (grey for a mesh it lacks)."""
    from asg_scenario.catalogue import MESHES

    info = MESHES.get(mesh)
    return info.colour if info else (0.3, 0.3, 0.3)


def _path(points, stamp, z=0.15, ground=None):
    """A nav_msgs/Path z [m] above the ground (the terrain's, or the plane z = 0)."""
    p = Path()
    p.header.frame_id, p.header.stamp = "map", stamp
    for x, y in points:
        ps = PoseStamped()
        ps.header = p.header
        ps.pose.position.x, ps.pose.position.y = x, y
        ps.pose.position.z = z + (ground.height(x, y) if ground is not None else 0.0)
        ps.pose.orientation.w = 1.0
        p.poses.append(ps)
    return p


def _circle(mid, ns, x, y, r, rgb, stamp, ground):
    m = Marker(ns=ns, id=mid, type=Marker.LINE_STRIP, action=Marker.ADD)
    m.header.frame_id, m.header.stamp = "map", stamp
    m.pose.orientation.w = 1.0
    m.scale.x = 0.3
    m.color = ColorRGBA(*rgb, 1.0)
    for a in range(65):
        px, py = x + r * math.cos(a * math.pi / 32), y + r * math.sin(a * math.pi / 32)
        m.points.append(Point(px, py, 0.1 + ground.height(px, py)))
    return m


def _ground(terrain, size, stamp, step=2.5):
    """The terrain over the landscape as a shaded triangle list (only when it is not flat)."""
    m = Marker(ns="terrain", id=0, type=Marker.TRIANGLE_LIST, action=Marker.ADD)
    m.header.frame_id, m.header.stamp = "map", stamp
    m.pose.orientation.w = 1.0
    m.scale.x = m.scale.y = m.scale.z = 1.0
    n = max(1, int(round(size / step)))
    g = [i * size / n for i in range(n + 1)]
    h = [[terrain.height(x, y) for x in g] for y in g]
    lo, hi = min(map(min, h)), max(map(max, h))

    def vertex(i, j):
        m.points.append(Point(g[j], g[i], h[i][j]))
        t = (h[i][j] - lo) / (hi - lo) if hi > lo else 0.5
        m.colors.append(ColorRGBA(0.35 + 0.4 * t, 0.45 + 0.25 * t, 0.25, 0.6))  # low: green, high: tan

    for i in range(n):
        for j in range(n):
            for a, b in ((i, j), (i, j + 1), (i + 1, j + 1), (i, j), (i + 1, j + 1), (i + 1, j)):
                vertex(a, b)
    return m


def scene_messages(request, removed, optimal_points, trajectory_xy, stamp):
    """(topic suffix, message) pairs describing the scene of a run."""
    arr = MarkerArray()
    ground = scenario_terrain(request)
    if not ground.flat:
        arr.markers.append(_ground(ground, request["structural"]["landscape"]["size"], stamp))
    k = 0
    for li, layout in enumerate(request["structural"]["layouts"]):
        mesh = MESHES[layout["mesh_name"]]
        for ii, inst in enumerate(layout["instances"]):
            if not inst["visible"]:
                continue
            m = Marker(ns="obstacles", id=k, type=Marker.CYLINDER, action=Marker.ADD)
            k += 1
            m.header.frame_id, m.header.stamp = "map", stamp
            h = mesh.height * inst["scale"]
            z = ground.height(inst["x"], inst["y"]) + h / 2  # stands on the ground, as in the simulator
            m.pose.position.x, m.pose.position.y, m.pose.position.z = inst["x"], inst["y"], z
            m.pose.orientation.w = 1.0
            m.scale.x = m.scale.y = 2 * mesh.collision_radius * inst["scale"]
            m.scale.z = h
            gone = (li, ii) in removed
            m.color = ColorRGBA(*((0.6, 0.6, 0.6) if gone else _colour(layout["mesh_name"])), 0.35 if gone else 0.9)
            arr.markers.append(m)
    op = request["operational"]
    arr.markers.append(
        _circle(0, "start", op["start_x"], op["start_y"], op["safety_radius"], (0.1, 0.4, 1.0), stamp, ground)
    )
    arr.markers.append(
        _circle(0, "goal", op["goal_x"], op["goal_y"], op["goal_radius"], (1.0, 0.6, 0.0), stamp, ground)
    )
    return [
        ("replay/scene", arr),
        ("replay/optimal_path", _path(optimal_points, stamp, 0.2, ground)),
        ("replay/trajectory", _path(trajectory_xy, stamp, 0.25, ground)),
    ]


def plans_fading(plans, max_kept=8):
    """For each (stamp, path points) replan, a MarkerArray of the earlier plans, older ones fainter."""
    out = []
    for n, (stamp, _) in enumerate(plans):
        arr = MarkerArray()
        earlier = plans[max(0, n - max_kept) : n]
        for j, (_, pts) in enumerate(earlier):
            m = Marker(ns="earlier_plans", id=j, type=Marker.LINE_STRIP, action=Marker.ADD)
            m.header.frame_id, m.header.stamp = "map", stamp
            m.pose.orientation.w = 1.0
            m.scale.x = 0.25
            age = len(earlier) - j
            m.color = ColorRGBA(0.2, 0.8, 1.0, max(0.1, 0.7 - 0.08 * age))
            m.points = [Point(x, y, 0.12) for x, y in pts]
            arr.markers.append(m)
        for j in range(len(earlier), max_kept):
            arr.markers.append(Marker(ns="earlier_plans", id=j, action=Marker.DELETE))
        out.append((stamp, arr))
    return out


#: Labels in colour for rviz's image panel: ground tan, obstacle red, sky blue, void grey.
PALETTE = ((170, 150, 110), (220, 40, 40), (110, 160, 230), (128, 128, 128))


def labels_rgb(msg, labels=None):
    """An rgb8 sensor_msgs/Image of `labels` (H x W, 0..3; default the mono8 `msg`'s own), with
    `msg`'s header and size."""
    import numpy as np

    lab = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width) if labels is None else labels
    palette = np.array(PALETTE, np.uint8)
    return type(msg)(
        header=msg.header,
        height=msg.height,
        width=msg.width,
        encoding="rgb8",
        is_bigendian=0,
        step=msg.width * 3,
        data=palette[np.minimum(lab, 3)].tobytes(),
    )


def labels_beside(bag, worker: str, model: str):
    """[(bag time, topic, message)]: every camera frame of the bag labelled again by another U-Net
    `model` (a shipped name, e.g. 'full', or a path) on the default numerics, in colour on
    `<worker>/replay/labels_beside_rgb`: what the unflawed model would have seen beside what the
    stack under test saw (issue #54). `bag` is an open rosbag.Bag."""
    import numpy as np

    from asg_perception.inference import Segmenter
    from asg_perception.segmenter_node import resolve_model

    seg = None
    out = []
    for _, msg, t in bag.read_messages(topics=[f"{worker}/camera/image_raw"]):
        if seg is None:
            seg = Segmenter(resolve_model(model), height=msg.height, width=msg.width)
        rgb = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
        out.append((t, f"{worker}/replay/labels_beside_rgb", labels_rgb(msg, seg(rgb))))
    return out

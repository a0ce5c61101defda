"""The depth stack's ROS node (rospy): odometry, a point cloud and a goal in, `cmd_vel` out.
Standard messages only; the lockstep client is the one thing of this project it uses
(docs/your-stack.md). Parameters: config/depth_stack.yaml."""

import math

import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2

from asg_depth_stack.arcs import ArcParams, ArcPlanner, rollout
from asg_depth_stack.grid import ElevationGrid, GridParams
from asg_depth_stack.params import DEPTH_STACK

#: A jump of the vehicle this large between two odometry messages is a new run (free-running
#: without the lockstep client: the stack sees the teleport to the next start).
NEW_RUN_JUMP_M = 5.0  # [m]


def quaternion_matrix(q):
    x, y, z, w = q.x, q.y, q.z, q.w
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def cloud_xyz(msg: PointCloud2) -> np.ndarray:
    """N x 3 float points of a PointCloud2 with float32 fields x, y, z (any layout)."""
    offsets = {f.name: f.offset for f in msg.fields if f.datatype == 7}  # FLOAT32
    missing = [c for c in "xyz" if c not in offsets]
    if missing:
        raise ValueError(f"point cloud without float32 field(s) {', '.join(missing)}")
    n = msg.width * msg.height
    raw = np.frombuffer(msg.data, np.uint8)[: n * msg.point_step].reshape(n, msg.point_step)
    cols = [raw[:, offsets[c] : offsets[c] + 4].copy().view("<f4" if not msg.is_bigendian else ">f4") for c in "xyz"]
    return np.hstack(cols).astype(np.float64)


class DepthStack:
    def __init__(
        self, grid: GridParams, arcs: ArcParams, camera_frame: str = "camera_optical", base_frame: str = "base_link"
    ):
        self.grid_params, self.planner = grid, ArcPlanner(arcs)
        self.camera_frame, self.base_frame = camera_frame, base_frame
        self.cmd = None  # set by main(): the cmd_vel publisher
        self.show = None  # set by main() with ~publish_markers: show(stamp, arc_xy, obstacles_xy)
        self.mount = None  # 4 x 4 base_link <- camera, from tf
        self.reset()

    def reset(self):
        self.grid = None
        self.pose = None  # (x, y, z, yaw, R)
        self.cloud = None  # the newest point cloud not yet in the grid
        self.goal = None
        self.planner.reset()

    # --- inputs ---------------------------------------------------------------------------------
    def on_goal(self, msg: PoseStamped):
        self.goal = (msg.pose.position.x, msg.pose.position.y)

    def on_odom(self, msg: Odometry):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        if self.pose is not None and math.hypot(p.x - self.pose[0], p.y - self.pose[1]) > NEW_RUN_JUMP_M:
            goal = self.goal
            self.reset()
            self.goal = goal
        R = quaternion_matrix(q)
        self.pose = (p.x, p.y, p.z, math.atan2(R[1, 0], R[0, 0]), R)
        if self.grid is None:
            self.grid = ElevationGrid(self.grid_params, (p.x, p.y))
        # The worker sends odometry at every camera frame's stamp: a cloud goes into the grid
        # with the pose of its own instant (or the newest before it, running free).
        if self.cloud is not None and self.cloud.header.stamp <= msg.header.stamp:
            self.insert(self.cloud)
            self.cloud = None
        self.control(msg.header.stamp)

    def on_points(self, msg: PointCloud2):
        self.cloud = msg

    def insert(self, msg: PointCloud2):
        if self.pose is None or self.mount is None:
            return
        pts = cloud_xyz(msg)
        x, y, z, _, R = self.pose
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, (x, y, z)
        T = T @ self.mount
        world = pts @ T[:3, :3].T + T[:3, 3]
        self.grid.insert(world, T[:3, 3])

    # --- output ---------------------------------------------------------------------------------
    def control(self, stamp=None):
        if self.goal is None or self.pose is None:
            return
        x, y, _, yaw, _ = self.pose
        obs = self.grid.centres(self.grid.obstacles()) if self.grid is not None else None
        c = self.planner.choose(x, y, yaw, self.goal, obs)
        t = Twist()
        t.linear.x, t.angular.z = c.speed, c.yaw_rate
        if self.cmd is not None:
            self.cmd.publish(t)
        if self.show is not None:  # what it decided on, for rviz and replay bags (not an input)
            arc = (
                np.zeros((0, 2))
                if c.blocked
                else rollout(x, y, yaw, c.curvature, self.planner.p.horizon, self.planner.p.step)
            )
            self.show(stamp, np.vstack([[x, y], arc]), np.zeros((0, 2)) if obs is None else obs)


class Markers:
    """The chosen arc (nav_msgs/Path `depth_stack/arc`) and the obstacle cells of the grid
    (visualization_msgs/Marker `depth_stack/obstacles`), in the map frame, for rviz."""

    def __init__(self):
        from nav_msgs.msg import Path
        from visualization_msgs.msg import Marker

        self.Path, self.Marker = Path, Marker
        self.arc = rospy.Publisher("depth_stack/arc", Path, queue_size=4)
        self.obstacles = rospy.Publisher("depth_stack/obstacles", Marker, queue_size=4)

    def __call__(self, stamp, arc_xy, obstacles_xy):
        from geometry_msgs.msg import Point

        path = self.Path()
        path.header.frame_id = "map"
        path.header.stamp = stamp or rospy.Time()
        for px, py in arc_xy:
            p = PoseStamped()
            p.header = path.header
            p.pose.position.x, p.pose.position.y, p.pose.position.z = px, py, 0.2
            p.pose.orientation.w = 1.0
            path.poses.append(p)
        self.arc.publish(path)
        m = self.Marker()
        m.header = path.header
        m.ns, m.type = "depth_stack_obstacles", self.Marker.CUBE_LIST
        m.action = self.Marker.ADD if len(obstacles_xy) else self.Marker.DELETE
        m.pose.orientation.w = 1.0
        m.scale.x = m.scale.y = m.scale.z = 0.4
        m.color.r, m.color.g, m.color.b, m.color.a = 1.0, 0.4, 0.0, 0.8
        m.points = [Point(float(px), float(py), 0.2) for px, py in obstacles_xy]
        self.obstacles.publish(m)


def read_params():
    """Every parameter through the node's table (params.DEPTH_STACK): a bad one is named."""
    from asg_lockstep.params import read

    p = read(DEPTH_STACK, lambda name, default: rospy.get_param("~" + name, default))
    g, a = GridParams(), ArcParams()
    for obj, prefix in ((g, "grid"), (a, "arcs")):
        for name in vars(obj):
            setattr(obj, name, p[f"{prefix}/{name}"])
    return p, g.check(), a.check()


def main():
    rospy.init_node("depth_stack")
    try:
        p, grid, arcs = read_params()
    except (ValueError, TypeError) as e:
        rospy.logfatal(f"depth_stack: bad parameter: {e}")
        raise SystemExit(2)
    stack = DepthStack(grid, arcs, p["camera_frame"], p["base_frame"])
    tf_buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(tf_buffer)

    def camera_mount():
        try:
            t = tf_buffer.lookup_transform(stack.base_frame, stack.camera_frame, rospy.Time(0), rospy.Duration(10.0))
        except tf2_ros.TransformException as e:
            rospy.logerr(f"depth_stack: no transform {stack.base_frame} <- {stack.camera_frame}: {e}")
            return None
        T = np.eye(4)
        T[:3, :3] = quaternion_matrix(t.transform.rotation)
        tr = t.transform.translation
        T[:3, 3] = (tr.x, tr.y, tr.z)
        return T

    def on_points(msg):
        if stack.mount is None:
            stack.mount = camera_mount()  # fixed on the vehicle: looked up once
        stack.on_points(msg)

    if p["use_lockstep_client"]:
        from asg_lockstep.ros import LockstepClient  # asg_lockstep: the one package of this project it uses

        lock = LockstepClient(p["ack_name"], on_run=stack.reset)  # reads ~lockstep (its table)
        sub, pub = lock.Subscriber, lock.Publisher
    else:
        sub, pub = rospy.Subscriber, rospy.Publisher
    stack.cmd = pub("cmd_vel", Twist, queue_size=1)
    # In lockstep, messages of one stamp reach the callbacks in this order: the cloud is held
    # until the odometry of its instant places it.
    if p["publish_markers"]:
        stack.show = Markers()
    sub("goal", PoseStamped, stack.on_goal)
    sub("camera/depth/points", PointCloud2, on_points)
    sub("odom", Odometry, stack.on_odom)
    rospy.spin()

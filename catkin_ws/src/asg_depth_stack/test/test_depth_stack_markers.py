"""The depth stack shows what it decided on (the chosen arc, the obstacle cells) without changing
what it decides: the command is the same with and without markers."""

import numpy as np
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry

from asg_depth_stack.arcs import ArcParams
from asg_depth_stack.grid import GridParams
from asg_depth_stack.node import DepthStack


class Sent:
    def __init__(self):
        self.msgs = []

    def publish(self, m):
        self.msgs.append((m.linear.x, m.angular.z))


def drive(show):
    s = DepthStack(GridParams(), ArcParams())
    s.cmd, s.show = Sent(), show
    g = PoseStamped()
    g.pose.position.x, g.pose.position.y = 80.0, 20.0
    s.on_goal(g)
    # A bush's cells in the grid ahead of the vehicle, then odometry at (20, 20) heading +x.
    s.on_odom(odom(20.0, 20.0))
    bush = np.array([[26.1 + dx, 20.1 + dy, h] for dx in (0, 0.2) for dy in (0, 0.2) for h in (0.1, 1.5, 2.0)])
    s.grid.insert(bush, (20.0, 20.0, 1.4))
    s.on_odom(odom(20.0, 20.0))
    return s.cmd.msgs


def odom(x, y):
    m = Odometry()
    m.pose.pose.position.x, m.pose.pose.position.y = x, y
    m.pose.pose.orientation.w = 1.0
    return m


def test_the_arc_and_cells_are_shown_and_the_commands_do_not_change():
    shown = []
    with_markers = drive(lambda stamp, arc, obs: shown.append((arc, obs)))
    assert with_markers == drive(None)
    arc, obs = shown[-1]
    assert np.allclose(arc[0], (20.0, 20.0))  # from the vehicle
    assert np.hypot(*(arc[-1] - arc[0])) > 10.0  # along the horizon (12 m)
    assert len(obs) >= 1 and np.all(np.hypot(obs[:, 0] - 26.25, obs[:, 1] - 20.25) < 0.6)
    assert np.min(np.hypot(arc[:, 0] - 26.25, arc[:, 1] - 20.25)) >= ArcParams().clearance - 1e-9

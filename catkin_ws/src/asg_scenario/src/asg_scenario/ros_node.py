"""Starting a rospy node of a command-line tool, simulated time included (issue #68): every tool
that talks to a worker (run_scenario here; replay, rerun, suites, baseline and campaigns in
asg_agent) starts its node with `init_node`, so that its ROS-time deadlines hold under
/use_sim_time. rospy is imported inside the functions: importing this module needs no ROS."""

import time


def wait_for_time(timeout=30.0):
    """Returns once this node's clock reads a time. Under /use_sim_time rospy reads 0 until the
    first /clock message arrives, and every ROS-time deadline computed before then is already
    past once it does (actionlib's wait_for_server returns False at once): wait for it on the wall
    clock. Raises RuntimeError naming what is missing when nothing publishes /clock."""
    import rospy

    if not rospy.get_param("/use_sim_time", False):
        return
    deadline = time.time() + timeout
    while rospy.get_rostime().is_zero():
        if rospy.is_shutdown():
            raise RuntimeError("ROS shut down while waiting for /clock")
        if time.time() > deadline:
            raise RuntimeError(
                f"/use_sim_time is true but nothing published /clock within {timeout:.0f} s "
                "(launch/sim_time.launch starts asg_sim/wall_clock for the master's /clock)"
            )
        time.sleep(0.05)


def init_node(name, timeout=30.0, **kwargs):
    """rospy.init_node, then wait_for_time: ready for ROS-time timeouts on either clock."""
    import rospy

    rospy.init_node(name, **kwargs)
    wait_for_time(timeout)

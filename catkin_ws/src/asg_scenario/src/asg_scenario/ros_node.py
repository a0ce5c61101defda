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


class GoalClient:
    """A client of one action server with SimpleActionClient's calls (send_goal, wait_for_result,
    get_state, get_result, cancel_goal, wait_for_server), on actionlib's plain ActionClient.

    SimpleActionClient attaches its goal handle only once `send_goal` returns; a server that
    answers before then (a scene worker refusing a bad scene at once does) is logged as "Got a
    transition callback on a goal handle that we're not tracking" and the result is lost, so
    `wait_for_result` waits out its timeout (issue #68). Here every goal's callbacks are tied to
    its own handle when the goal is made, before it is sent, so an answer is never lost.
    `wait_for_result`'s timeout is wall-clock time (under /use_sim_time too). The last goal sent
    is the one tracked, as in SimpleActionClient."""

    def __init__(self, name, action_type):
        import actionlib

        self.client = actionlib.ActionClient(name, action_type)
        self.gh = None
        self._done = None

    def wait_for_server(self, timeout=None):
        import rospy

        return self.client.wait_for_server(timeout if timeout is not None else rospy.Duration())

    def send_goal(self, goal, feedback_cb=None):
        import threading

        from actionlib.action_client import CommState

        done = threading.Event()

        def transition(gh):
            if gh.get_comm_state() == CommState.DONE:
                done.set()

        def feedback(gh, fb):
            if feedback_cb is not None:
                feedback_cb(fb)

        self._done = done
        self.gh = self.client.send_goal(goal, transition_cb=transition, feedback_cb=feedback)

    def wait_for_result(self, timeout=None):
        """True once the last goal is done; False after `timeout` (rospy.Duration or seconds;
        none or zero: no limit) of wall-clock time, or at shutdown."""
        import time

        import rospy

        if self._done is None:
            return False
        limit = timeout.to_sec() if hasattr(timeout, "to_sec") else float(timeout or 0.0)
        end = time.monotonic() + limit if limit > 0 else None
        while not self._done.wait(0.05):
            if rospy.is_shutdown() or (end is not None and time.monotonic() > end):
                return False
        return True

    def get_state(self):
        """The last goal's status (actionlib_msgs/GoalStatus), as SimpleActionClient reports it."""
        from actionlib_msgs.msg import GoalStatus

        if self.gh is None:
            return GoalStatus.LOST
        s = self.gh.get_goal_status()
        return {GoalStatus.RECALLING: GoalStatus.PENDING, GoalStatus.PREEMPTING: GoalStatus.ACTIVE}.get(s, s)

    def get_result(self):
        return None if self.gh is None else self.gh.get_result()

    def get_goal_status_text(self):
        return "" if self.gh is None else self.gh.get_goal_status_text()

    def cancel_goal(self):
        if self.gh is not None:
            self.gh.cancel()

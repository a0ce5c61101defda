"""Starting a rospy node of the agent's tools, simulated time included: the one definition is
asg_scenario.ros_node's (run_scenario uses it too)."""

from asg_scenario.ros_node import init_node, wait_for_time

__all__ = ["init_node", "wait_for_time"]

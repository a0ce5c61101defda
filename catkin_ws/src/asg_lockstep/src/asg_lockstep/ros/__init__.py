"""The lockstep client for a stack of standard ROS messages (rospy): docs/your-stack.md."""

from asg_lockstep.ros.client import LockstepClient

__all__ = ["LockstepClient"]

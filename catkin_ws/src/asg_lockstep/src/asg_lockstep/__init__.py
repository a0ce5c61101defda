"""The lockstep protocol's core in Python (no rospy): the stack node's side, the twin of the C++
library's (include/asg_lockstep). docs/architecture.md describes the protocol."""

from .stack_protocol import StackProtocol

__all__ = ["StackProtocol"]

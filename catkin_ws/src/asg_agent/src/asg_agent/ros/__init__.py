"""The ROS layer of the agent: worker pool, replay, re-runs, stage timers, bag scenes (rospy)."""

"""The search methods behind one interface, TD3, and the prioritized replay buffer (no ROS)."""

"""Adversarial scene generator: search methods, proxy, optimal path, store, campaigns (no rospy)."""

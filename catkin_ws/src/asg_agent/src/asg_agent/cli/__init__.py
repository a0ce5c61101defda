"""Commands: campaign (the search against running workers) and baseline (rospy)."""

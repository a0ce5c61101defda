"""The paper's difficulty proxy and the optimal path it is measured against (no ROS)."""

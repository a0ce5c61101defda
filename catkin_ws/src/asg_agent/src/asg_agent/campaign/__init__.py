"""Experiments, the campaign loop, its store, the in-process pool and TensorBoard files (no ROS)."""

"""Traversability perception of the stack under test: U-Net, datasets, training, evaluation and
fast inference (no rospy outside segmenter_node)."""

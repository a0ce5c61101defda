"""A second stack under test, written apart from the paper's (issue #39): depth points to an
elevation grid, a lattice of arcs, a velocity command. No U-Net, no vote grid, no message of this
project: it reads nav_msgs/Odometry, sensor_msgs/PointCloud2 and geometry_msgs/PoseStamped and
publishes geometry_msgs/Twist. The cores (grid, arcs) use no ROS."""

"""Adversarial scene generator. Subpackages say what they hold and whether they need ROS:

- search/: the search methods (TD3-PER-ASP and ablations, random, annealing, CMA-ES, MAP-Elites),
  TD3, the prioritized replay buffer (per_buffer) - no ROS;
- scoring/: the paper's difficulty proxy and the optimal path - no ROS;
- campaign/: experiment files, the campaign loop, the SQLite store, the in-process pool,
  TensorBoard files - no ROS;
- analysis/: exports, the docs' tables and figures, reports, benchmark tables - no rospy (report
  reads bags with rosbag);
- ros/: the worker pool, replay, re-runs, stage timers, bag scenes, rviz screenshots - rospy;
- cli/: the `campaign` and `baseline` commands - rospy.
"""

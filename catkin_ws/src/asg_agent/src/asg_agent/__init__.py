"""Adversarial scene generator, built in floors; each imports only from those below it
(tests/test_architecture.py; docs/agent.md):

- cli/: the commands (campaign, baseline, suite, harden, plan, store, soak) - rospy;
- ros/: the worker pool, the campaign's pools and checks, replay, re-runs, stage timers, bag
  scenes, rviz screenshots - rospy;
- campaign/: the campaign loop and its policy, suites, hardening, overlap checks, the soak's
  accounting, the in-process pool, TensorBoard files - no ROS;
- search/: the search methods (TD3-PER-ASP and ablations, random, annealing, CMA-ES, MAP-Elites),
  TD3, the prioritized replay buffer - no ROS;
- records/: experiment files, registered stacks, the SQLite store, exports, failure modes, the
  scene of a row, stage costs - no ROS;
- scoring/: the paper's difficulty proxy, the optimal path, attribution, rewards - no ROS.

paths.py is the ground. The analysis of what campaigns wrote is the asg_analysis package, which
this one never imports.
"""

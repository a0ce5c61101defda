"""What the documents say, recomputed from campaign stores and exports (no rospy): the tables
and figures of docs/, campaign reports, benchmark tables, the study protocols and their
statistics. It reads what asg_agent writes (asg_agent.records); asg_agent never imports it.

A library and one runner (issue #80): the study primitives here (exports, endpoints, stats, rules,
campaign_metrics, learning_curve, figures, files, replays, report, bench, blocks, reuse, protocol)
and `asg_analysis.study`, which regenerates a study record's blocks from its protocol file
(`python3 -m asg_analysis study experiments/protocol-NAME.yaml`); the logic of one study or page
of docs/ each is in asg_analysis.studies.

    python3 -m asg_analysis --help          # every command (asg_analysis.commands)
"""

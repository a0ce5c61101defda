"""What the documents say, recomputed from campaign stores and exports (no rospy): the tables
and figures of docs/, campaign reports, benchmark tables, the study protocols and their
statistics. It reads what asg_agent writes (asg_agent.records); asg_agent never imports it.

    python3 -m asg_analysis figure|asp-effect ...   # asg_analysis.figures
"""

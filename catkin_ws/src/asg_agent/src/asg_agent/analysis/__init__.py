"""Exports, the tables and figures of docs/, reports and benchmark tables (no rospy).

python3 -m asg_agent.analysis ...   # the export tool (analysis/export.py)
"""

#!/usr/bin/python3
"""A minimal RunScenario action server for the round-trip test: it validates the goal with the
scenario validator and answers with a two-sample straight-line trajectory from start to goal."""

import math

import actionlib
import rospy
from asg_msgs.msg import RunScenarioAction, RunScenarioResult, TrajectorySample

from asg_scenario import ScenarioError, validate_scenario
from asg_scenario.convert import from_scene_msg


def execute(goal):
    result = RunScenarioResult(scenario_id=goal.scenario_id)
    try:
        s = validate_scenario(from_scene_msg(goal.scene, goal.scenario_id), "goal")
    except ScenarioError as e:
        result.termination, result.termination_name, result.error = (RunScenarioResult.ERROR, "ERROR", str(e))
        server.set_succeeded(result)
        return
    op = s["operational"]
    for t, (x, y) in ((0.0, (op["start_x"], op["start_y"])), (1.0, (op["goal_x"], op["goal_y"]))):
        sample = TrajectorySample(t=t)
        sample.pose.position.x, sample.pose.position.y = x, y
        sample.pose.orientation.z = math.sin(op["start_yaw"] / 2)
        sample.pose.orientation.w = math.cos(op["start_yaw"] / 2)
        result.trajectory.append(sample)
    result.termination, result.termination_name, result.sim_time = (RunScenarioResult.SUCCESS, "SUCCESS", 1.0)
    result.obstacle_visibility = [-1.0] * sum(len(l.instances) for l in goal.scene.structural.layouts)
    server.set_succeeded(result)


rospy.init_node("echo_worker")
server = actionlib.SimpleActionServer("run_scenario", RunScenarioAction, execute, auto_start=False)
server.start()
rospy.spin()

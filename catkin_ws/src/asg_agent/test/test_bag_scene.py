"""The replay's scene markers (asg_agent.ros.bag_scene) stand on the scenario's ground (issue #27)."""

import os

import rospy

from asg_agent.ros.bag_scene import scene_messages
from asg_scenario import load_scenario
from asg_scenario.catalogue import MESHES
from asg_scenario.terrain import scenario_terrain

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def markers(name):
    s = load_scenario(os.path.join(REPO, "scenarios", name))
    msgs = dict(scene_messages(s, set(), [(20.0, 20.0), (80.0, 80.0)], [(20.0, 20.0), (50.0, 52.0)], rospy.Time(1)))
    return s, msgs


def test_on_terrain_obstacles_and_paths_stand_on_the_ground():
    s, msgs = markers("exp6.yaml")
    t = scenario_terrain(s)
    arr = msgs["replay/scene"].markers
    ground = [m for m in arr if m.ns == "terrain"]
    assert len(ground) == 1 and len(ground[0].points) == 6 * 40 * 40 == len(ground[0].colors)
    obstacles = [m for m in arr if m.ns == "obstacles"]
    insts = [(l["mesh_name"], i) for l in s["structural"]["layouts"] for i in l["instances"]]
    assert len(obstacles) == len(insts) == 8
    for m, (mesh, i) in zip(obstacles, insts):
        assert abs(m.pose.position.z - (t.height(i["x"], i["y"]) + MESHES[mesh].height * i["scale"] / 2)) < 1e-9
    p = msgs["replay/trajectory"].poses[1].pose.position
    assert abs(p.z - (t.height(50.0, 52.0) + 0.25)) < 1e-9 and abs(t.height(50.0, 52.0)) > 0.3  # in the ditch


def test_on_flat_ground_no_terrain_marker():
    s, msgs = markers("exp1.yaml")
    arr = msgs["replay/scene"].markers
    assert not [m for m in arr if m.ns == "terrain"]
    juniper = next(m for m in arr if m.ns == "obstacles")
    assert juniper.pose.position.z == MESHES["juniper"].height / 2
    assert msgs["replay/optimal_path"].poses[0].pose.position.z == 0.2

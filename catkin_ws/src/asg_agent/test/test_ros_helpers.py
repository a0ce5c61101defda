"""ROS helpers of the agent without a running master: the replay's scene markers stand on the scenario's ground, and the campaign's planner check (issue #27)."""

import os

import pytest

import rospy

from asg_agent.ros import stack_identity
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


def test_planner_mismatch_names_what_a_worker_runs_against_the_experiment(monkeypatch):
    # Issue #27: the campaign refuses workers whose planner runs another configuration than the
    # experiment's (exp6 with the flat planner.yaml, say), naming the parameter.
    import yaml

    cfg = os.path.join(REPO, "catkin_ws", "src", "asg_planner", "config")
    params = {}

    def load(worker, name):
        def flat(d, p=""):
            for k, v in d.items():
                if isinstance(v, dict):
                    flat(v, f"{p}{k}/")
                else:
                    params[f"{worker}/planner/{p}{k}"] = v

        flat(yaml.safe_load(open(os.path.join(cfg, name))))

    load("/worker_0", "planner.yaml")
    load("/worker_1", "planner.yaml")  # worker.launch: the base, then the variant over it
    load("/worker_1", "planner_terrain.yaml")
    params["/worker_1/planner/publish_markers"] = False  # set by worker.launch: not the stack's identity
    monkeypatch.setattr(rospy, "has_param", lambda n: n in params)
    monkeypatch.setattr(rospy, "get_param", lambda n: params[n])
    assert stack_identity.planner_mismatch("/worker_1", os.path.join(cfg, "planner_terrain.yaml")) == []
    assert stack_identity.planner_mismatch("/worker_0", os.path.join(cfg, "planner.yaml")) == []
    wrong = stack_identity.planner_mismatch("/worker_0", os.path.join(cfg, "planner_terrain.yaml"))
    assert len(wrong) == 1 and "projection/height_above_ground = False" in wrong[0], wrong
    # A variant is an overlay: what it leaves to planner.yaml is checked too.
    params["/worker_1/planner/follower/kp"] = 343.7747
    assert "follower/kp = 343.7747, planner_terrain.yaml says 10.0" in " ".join(
        stack_identity.planner_mismatch("/worker_1", os.path.join(cfg, "planner_terrain.yaml"))
    )
    params["/worker_1/planner/follower/kp"] = 10.0
    del params["/worker_1/planner/projection/ground_cell"]
    assert (
        "has no parameter projection/ground_cell"
        in stack_identity.planner_mismatch("/worker_1", os.path.join(cfg, "planner_terrain.yaml"))[0]
    )


def test_a_replay_bag_names_its_worker_namespace():
    # rviz/replay.rviz names topics relative; replay_view runs rviz in the bag's namespace
    from asg_agent.ros.replay_view import bag_namespace

    assert bag_namespace(["/replay_worker/planner/votes", "/replay_worker/odom", "/rosout"]) == "replay_worker"
    assert bag_namespace({"/worker_3/camera/image_raw": None, "/worker_3/scenario": None}) == "worker_3"
    with pytest.raises(ValueError, match="not a replay bag"):
        bag_namespace(["/rosout", "/chatter"])


def test_the_rviz_configs_name_topics_relative_and_the_launch_files_set_the_namespace():
    import re

    repo = os.path.join(os.path.dirname(__file__), "..", "..", "..", "..")
    for cfg in ("worker.rviz", "replay.rviz", "replay_depth.rviz"):
        text = open(os.path.join(repo, "rviz", cfg)).read()
        topics = re.findall(r"^\s*(?:\w+ )?Topic: (\S+)$", text, flags=re.M)
        assert topics and all(not t.startswith("/") for t in topics), (cfg, topics)
    for launch in ("rviz.launch", "replay.launch"):
        assert 'ns="$(arg ns)"' in open(os.path.join(repo, "launch", launch)).read(), launch


def test_what_replay_adds_to_a_bag_keeps_it_in_time_order(tmp_path):
    # A depth-stack replay bag had its scene appended in a last chunk at the start time; rosbag
    # took that chunk's time as the end, and `rosbag info` read 0 s for a 27 s run.
    import rosbag
    import rospy
    from asg_agent.ros.replay import merge_into_bag
    from std_msgs.msg import String

    path = str(tmp_path / "run.bag")
    latched = {"topic": "/w/scenario", "type": "std_msgs/String", "md5sum": String._md5sum}
    latched.update(message_definition=String._full_text, callerid="/rec", latching="1")
    with rosbag.Bag(path, "w") as bag:
        for k in range(1, 4):
            bag.write("/w/odom", String(data=f"odom {k}"), rospy.Time(k))
        bag.write("/w/scenario", String(data="scenario"), rospy.Time(1), connection_header=latched)
    merge_into_bag(
        path,
        [
            (rospy.Time(2.5), "/w/replay/late", String(data="late")),
            (rospy.Time(1), "/w/replay/scene", String(data="scene")),
        ],
    )
    with rosbag.Bag(path) as bag:
        assert (bag.get_start_time(), bag.get_end_time()) == (1.0, 3.0)
        got = [(t.to_sec(), topic, m.data) for topic, m, t in bag.read_messages()]
        headers = {c.topic: c.header for c in bag._get_connections()}
    assert [g[2] for g in got] == ["odom 1", "scenario", "scene", "odom 2", "late", "odom 3"]
    assert [g[0] for g in got] == sorted(g[0] for g in got)
    assert headers["/w/scenario"].get("latching") in ("1", b"1")
    assert not os.path.exists(path + ".sorting")

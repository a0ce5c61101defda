"""Issue #69 item 3: a wrongly typed parameter is refused by name, on a master, by every C++ node.
NodeHandle::param kept the default silently when a value had another type (a string for
follower/kp ran with the default gain); every C++ node now reads its table through asg_lockstep's
helper (param_table.hpp, ros/param_reader.hpp), by kind, and refuses to start, naming the
parameter: the planner (shown in full below), the scene worker (its table, and a registration's
stack/ keys), wall_clock and the example twist_driver."""

import os
import subprocess
import time

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
PLANNER = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_planner", "planner")
PORT = 11473


def _env():
    return dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{PORT}", ROS_HOSTNAME="127.0.0.1", ROS_IP="127.0.0.1")


def _master(env):
    core = subprocess.Popen(["roscore", "-p", str(PORT)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(120):
        if subprocess.run(["rosparam", "get", "/run_id"], env=env, capture_output=True).returncode == 0:
            break
        time.sleep(0.5)
    return core


def test_the_planner_refuses_a_parameter_of_the_wrong_type_by_name(tmp_path):
    assert os.access(PLANNER, os.X_OK), f"{PLANNER}: not built"
    env = dict(_env(), ROS_LOG_DIR=str(tmp_path))
    core = _master(env)
    try:
        for value, want in (
            ("fast", "~follower/kp = 'fast': must be a number"),
            ("true", "~follower/kp = true: must be a number"),
        ):
            subprocess.run(["rosparam", "set", "/planner/follower/kp", value], env=env, check=True)
            r = subprocess.run([PLANNER, "__name:=planner"], env=env, capture_output=True, text=True, timeout=60)
            assert r.returncode == 1 and want in r.stdout + r.stderr, (value, r.stdout[-500:], r.stderr[-500:])
        # an integer where a boolean is wanted, and a real where an integer is
        subprocess.run(["rosparam", "set", "/planner/follower/kp", "1.5"], env=env, check=True)
        subprocess.run(["rosparam", "set", "/planner/publish_markers", "1"], env=env, check=True)
        r = subprocess.run([PLANNER, "__name:=planner"], env=env, capture_output=True, text=True, timeout=60)
        assert r.returncode == 1 and "~publish_markers = 1: must be true or false" in r.stdout + r.stderr
        # the right types start it (it spins until stopped)
        subprocess.run(["rosparam", "set", "/planner/publish_markers", "false"], env=env, check=True)
        p = subprocess.Popen([PLANNER, "__name:=planner"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        time.sleep(3.0)
        alive = p.poll() is None
        p.terminate()
        p.wait(timeout=10)
        assert alive, p.stdout.read().decode()[-500:]
    finally:
        core.terminate()
        core.wait(timeout=20)


NODES = [  # (package, executable, parameter, wrongly typed value, what the refusal says)
    ("asg_sim", "scene_worker", "camera/width", "wide", "~camera/width = 'wide': must be a whole number"),
    ("asg_sim", "wall_clock", "rate", "fast", "~rate = 'fast': must be a number"),
    ("asg_lockstep", "twist_driver", "speed", "true", "~speed = true: must be a number"),
]


def test_every_other_cpp_node_refuses_a_wrongly_typed_parameter_by_name(tmp_path):
    env = dict(_env(), ROS_LOG_DIR=str(tmp_path))
    core = _master(env)
    try:
        for package, exe, name, value, want in NODES:
            binary = os.path.join(REPO, "catkin_ws", "devel", "lib", package, exe)
            assert os.access(binary, os.X_OK), f"{binary}: not built"
            subprocess.run(["rosparam", "set", f"/{exe}_t/{name}", value], env=env, check=True)
            r = subprocess.run([binary, f"__name:={exe}_t"], env=env, capture_output=True, text=True, timeout=60)
            assert r.returncode != 0 and want in r.stdout + r.stderr, (exe, r.stdout[-500:], r.stderr[-500:])
    finally:
        core.terminate()
        core.wait(timeout=20)


def test_the_scene_worker_refuses_a_wrongly_typed_registration_key_by_name(tmp_path):
    """A stack registration's own keys (stack/mode, command, sim_time, acks, nodes) are read by
    kind too: a string for sim_time was taken as false, an integer for acks as true."""
    binary = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_sim", "scene_worker")
    assert os.access(binary, os.X_OK), f"{binary}: not built"
    env = dict(_env(), ROS_LOG_DIR=str(tmp_path))
    core = _master(env)
    try:
        for key, value in (
            ("name", "mine"),
            ("nodes", "[planner]"),
            ("mode", "free"),
            ("sim_time", "sometimes"),
            ("acks", "1"),
        ):
            subprocess.run(["rosparam", "set", f"/reg/stack/{key}", value], env=env, check=True)
        r = subprocess.run(
            [binary, "__ns:=/reg", "__name:=scene_worker"], env=env, capture_output=True, text=True, timeout=60
        )
        out = r.stdout + r.stderr
        assert r.returncode != 0, out[-500:]
        assert "stack/sim_time = 'sometimes': must be true or false" in out, out[-800:]
        assert "stack/acks = 1: must be true or false" in out, out[-800:]
        subprocess.run(["rosparam", "set", "/reg/stack/nodes", "planner"], env=env, check=True)
        r = subprocess.run(
            [binary, "__ns:=/reg", "__name:=scene_worker"], env=env, capture_output=True, text=True, timeout=60
        )
        assert "stack/nodes = 'planner': must be a list of node names" in r.stdout + r.stderr, (r.stdout + r.stderr)[
            -800:
        ]
    finally:
        core.terminate()
        core.wait(timeout=20)

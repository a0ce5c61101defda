"""Helpers shared by the end-to-end checks (rospy; not a test themselves)."""

import math
import re
import os
import signal
import subprocess
import time
import xmlrpc.client

import rosgraph
import rospy
from actionlib_msgs.msg import GoalStatus
from asg_msgs.msg import RunScenarioAction

from asg_scenario import load_scenario
from asg_scenario.convert import to_goal_msg
from asg_scenario.layout import random_scene
from asg_scenario.ros_node import GoalClient

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))


def exp1(scenario_id, sim_timeout=30.0):
    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    s["scenario_id"] = scenario_id
    s["operational"]["sim_timeout"] = sim_timeout
    return s


def random_exp1(seed, scenario_id, sim_timeout=30.0):
    """A seeded random Exp. 1 layout (4 junipers, 4 barberries anywhere on the landscape)."""
    return random_scene(exp1(scenario_id, sim_timeout), seed)


def client(ns, timeout=90.0):
    from asg_agent.ros.node import wait_for_time

    wait_for_time()  # under /use_sim_time, ROS-time timeouts mean nothing before the first /clock
    c = GoalClient(f"/{ns}/run_scenario", RunScenarioAction)  # no lost answers (SimpleActionClient's race)
    assert c.wait_for_server(rospy.Duration(timeout)), f"no action server in /{ns}"
    return c


def wait_for_segmenter(ns, timeout=180.0):
    """Until /ns/segmenter has loaded its model and subscribed to the camera (torch and the
    model's warm-up take a while on a loaded machine)."""
    import time

    master, deadline = rosgraph.Master("/stack_util"), time.time() + timeout
    while time.time() < deadline:
        _, subs, _ = master.getSystemState()
        if any(t == f"/{ns}/camera/image_raw" and f"/{ns}/segmenter" in nodes for t, nodes in subs):
            return
        time.sleep(0.5)
    raise AssertionError(f"/{ns}/segmenter did not subscribe to /{ns}/camera/image_raw within {timeout:.0f} s")


def run(c, scenario, timeout=300.0):
    """Sends a scenario, waits; (goal state, result)."""
    c.send_goal(to_goal_msg(scenario))
    assert c.wait_for_result(rospy.Duration(timeout)), f"no result for scenario {scenario['scenario_id']}"
    return c.get_state(), c.get_result()


def trajectory_key(result):
    """Everything a run produced that must repeat bit for bit."""
    return (
        result.termination,
        result.num_control_msgs,
        tuple(
            (
                s.t,
                s.pose.position.x,
                s.pose.position.y,
                s.pose.position.z,
                s.pose.orientation.x,
                s.pose.orientation.y,
                s.pose.orientation.z,
                s.pose.orientation.w,
                s.twist.linear.x,
                s.twist.angular.z,
            )
            for s in result.trajectory
        ),
    )


def trajectory_digest(result):
    """sha256 of trajectory_key: the stored form of a reference run (tests/reference/)."""
    import hashlib

    return hashlib.sha256(repr(trajectory_key(result)).encode()).hexdigest()


REFERENCE_DIR = os.path.join(os.path.dirname(os.path.realpath(__file__)), "reference")


def reference_path(worker_ns, write=False):
    """The stored reference runs for the U-Net backend `worker_ns` runs: tests/reference/
    exp1_flawed_BACKEND.json (issue #24: one file per backend, recorded once). The fp32 backends
    that replay each other bit for bit (numerics.FP32_PORTABLE_BACKENDS: channels_last and the
    default, polyphase) share one, exp1_flawed_fp32.json, on every CPU (issue #53: their runs are
    bit-identical across the CPU classes of docs/benchmarks.md); for bf16, where the segmenter's
    kernels here are not the ones that file was recorded with (another CPU: issue #36),
    exp1_flawed_BACKEND.ISA.json recorded on such a CPU, when there is one (or when writing)."""
    import json

    from asg_perception.numerics import BF16_BACKENDS, FP32_PORTABLE_BACKENDS

    backend = rospy.get_param(f"/{worker_ns}/segmenter/backend")
    if backend in FP32_PORTABLE_BACKENDS:
        backend = "fp32"
    base = os.path.join(REFERENCE_DIR, f"exp1_flawed_{backend}.json")
    here = wait_for_numerics(f"/{worker_ns}")
    if backend not in BF16_BACKENDS:
        return base
    isa = dict(kv.split("=", 1) for kv in here.split()[1:] if "=" in kv).get("isa", "unknown")
    if os.path.isfile(base):
        with open(base) as f:
            recorded = json.load(f).get("numerics", "")
        if not recorded or f"isa={isa} " in recorded + " ":
            return base
    other = os.path.join(REFERENCE_DIR, f"exp1_flawed_{backend}.{isa.lower()}.json")
    return other if write or os.path.isfile(other) else base


def cancel_acknowledged(client, timeout=5.0):
    """Cancels the client's (GoalClient's) goal once the server has acknowledged it (issue #53's race).
    actionlib's client leaves WAITING_FOR_GOAL_ACK when it cancels; a status array the server
    published before it received the goal then lacks the goal, and the client marks it LOST
    (actionlib's CommStateMachine.update_status) although the server goes on to recall or preempt
    it. Waiting for the acknowledgement (the goal in a status array) closes that window."""
    from actionlib.action_client import CommState

    deadline = time.time() + timeout
    while client.gh is not None and time.time() < deadline:
        if client.gh.get_comm_state() != CommState.WAITING_FOR_GOAL_ACK:
            break
        time.sleep(0.0005)
    client.cancel_goal()


def wait_for_param(name, timeout=120.0):
    """The value of parameter `name` once it is set and not empty."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        got = rospy.get_param(name, "")
        if got:
            return got
        time.sleep(0.2)
    raise AssertionError(f"{name} was not set within {timeout:.0f} s")


def wait_for_numerics(worker, timeout=120.0):
    """The segmenter's numerics identity (asg_perception.numerics), set once its model is loaded."""
    return wait_for_param(f"{worker}/segmenter/numerics", timeout)


def check_reference(test, c, path, write=False, worker="/worker_0", on_produced=None):
    """Runs every stored request of `path` on client `c`; each run must repeat its stored
    termination, length and trajectory digest. write=True (ASG_WRITE_REFERENCE=1) stores what
    the runs did instead. `on_produced(here, produced)` is called with what every run produced
    before any comparison (issue #79: a CPU-class record holds the runs' digests, equal or not).
    Returns (the segmenter's numerics here, the digests the runs produced)."""
    import json

    # A new CPU's file is written with the requests of the backend's first one.
    source = path if os.path.isfile(path) or not write else re.sub(r"\.[a-z0-9_]+\.json$", ".json", path)
    with open(source) as f:
        ref = json.load(f)
    # Issue #36: before any run, whether this machine can repeat them (the segmenter's numerics:
    # oneDNN kernels, threads, torch) or why not.
    here = wait_for_numerics(worker)
    if write:
        ref["numerics"] = here
    else:
        from asg_perception.numerics import can_reproduce

        why = can_reproduce(ref.get("numerics", ""), here)
        test.assertIsNone(
            why,
            f"{os.path.basename(path)} was recorded where the segmenter ran {ref.get('numerics')!r}; this "
            f"machine cannot repeat it bit for bit: {why}",
        )
    produced, gots = [], []
    for entry in ref["runs"]:
        state, r = run(c, entry["request"])
        test.assertEqual(state, SUCCEEDED, r.error)
        got = {
            "termination": r.termination_name,
            "samples": len(r.trajectory),
            "digest": trajectory_digest(r),
            "final_xy": [r.trajectory[-1].pose.position.x, r.trajectory[-1].pose.position.y],
        }
        produced.append(got["digest"])
        gots.append(got)
    if on_produced is not None and not write:
        on_produced(here, list(produced))
    for k, (entry, got) in enumerate(zip(ref["runs"], gots)):
        if write:
            entry.update(got)
            continue
        test.assertEqual(
            (got["termination"], got["samples"]),
            (entry["termination"], entry["samples"]),
            f"reference run {k} ({entry['source']})",
        )
        test.assertEqual(
            got["digest"],
            entry["digest"],
            f"reference run {k} ({entry['source']}) of {os.path.basename(path)}: trajectory differs "
            f"from the stored one (final position {got['final_xy']} vs {entry['final_xy']})",
        )
    if write:
        with open(path, "w") as f:
            json.dump(ref, f, indent=1)
            f.write("\n")
    return here, produced


CPU_CLASSES = os.path.join(REPO, "results", "numerics", "cpu_classes.json")


def record_cpu_class(path, here, produced, note=""):
    """Adds (or renews) this CPU's line for these numerics in results/numerics/cpu_classes.json
    (issue #53): the CPU's model name, its best ISA, the segmenter's numerics here (backend and
    effective ISA: one CPU may have a line for each), and the digests its runs produced
    (`produced`, check_reference's: issue #68, the runs' own, not the stored file's, so that
    tests/test_numerics_classes.py compares two records)."""
    import datetime
    import json

    from asg_agent.records.store import provenance
    from asg_perception.numerics import best_isa, cpu_flags, native_bf16

    model = provenance()["cpu"]
    flags = cpu_flags()
    entry = {
        "cpu": model,
        "best_isa": best_isa(flags),
        "native_bf16": native_bf16(flags),
        "numerics": here,
        "reference": os.path.relpath(path, REPO),
        "digests": list(produced),
        "date": datetime.date.today().isoformat(),
        "note": note,
    }
    table = []
    if os.path.isfile(CPU_CLASSES):
        with open(CPU_CLASSES) as f:
            table = json.load(f)["classes"]
    key = ("cpu", "best_isa", "numerics")
    table = [e for e in table if [e[k] for k in key] != [entry[k] for k in key]] + [entry]
    os.makedirs(os.path.dirname(CPU_CLASSES), exist_ok=True)
    with open(CPU_CLASSES, "w") as f:
        json.dump({"about": CPU_CLASSES_ABOUT, "classes": table}, f, indent=1)
        f.write("\n")


CPU_CLASSES_ABOUT = (
    "CPU classes on which the fp32 numerics' stored reference runs (tests/reference/exp1_flawed_fp32.json, of "
    "channels_last and of the default, polyphase) replayed bit for bit (issue #53). Each line is written by "
    "`ASG_RECORD_CPU_CLASS=1 rostest asg_tests reference_runs.test [unet_backend:=B]` after its check passed, "
    "one a CPU and numerics; tests/test_numerics_classes.py checks every line's digests "
    "against the stored reference; docs/benchmarks.md lists them."
)


def largest_difference(a, b):
    """[m] largest position difference between two trajectories (inf if lengths differ)."""
    if len(a.trajectory) != len(b.trajectory):
        return math.inf
    return max(
        (
            math.dist((p.pose.position.x, p.pose.position.y), (q.pose.position.x, q.pose.position.y))
            for p, q in zip(a.trajectory, b.trajectory)
        ),
        default=0.0,
    )


def node_pid(name):
    """pid of a running ROS node, through its XML-RPC API; None while it is not registered or its
    registration is stale (a killed node's URI stays with the master until the respawned process
    registers again, and connecting to it is refused)."""
    try:
        uri = rosgraph.Master("/asg_tests").lookupNode(name)
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/asg_tests")
    except (rosgraph.MasterError, OSError, xmlrpc.client.Error):
        return None
    return pid if code == 1 else None


def kill9(name):
    pid = node_pid(name)
    assert pid, f"node {name} is not running"
    os.kill(pid, signal.SIGKILL)
    return pid


def wait_respawned(name, old_pid, ready_param, timeout=90.0):
    """Waits until roslaunch has respawned node `name` (a pid other than old_pid answers) and the
    new process has set its parameter `ready_param` (which the caller deleted before the kill):
    a goal sent before then meets a stale registration and a half-started node. Returns the
    seconds waited."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        pid = node_pid(name)
        if pid and pid != old_pid and rospy.has_param(ready_param):
            return time.time() - t0
        time.sleep(0.2)
    raise AssertionError(f"node {name} was not back within {timeout:.0f} s of its kill")


def busy_cores(n=2):
    """n processes spinning on the CPU (the caller terminates them)."""
    return [subprocess.Popen(["/usr/bin/python3", "-c", "while True: pass"]) for _ in range(n)]


SUCCEEDED, ABORTED, PREEMPTED, ACTIVE, RECALLED = (
    GoalStatus.SUCCEEDED,
    GoalStatus.ABORTED,
    GoalStatus.PREEMPTED,
    GoalStatus.ACTIVE,
    GoalStatus.RECALLED,
)

"""replay: run a stored scenario again on a scene worker and check it reproduces the stored run.

    replay STORE CAMPAIGN JOB [--bag OUT.bag] [--figure OUT.png]       (brings up its own worker)
    replay STORE CAMPAIGN JOB --worker /worker_0 [...]                  (uses a running worker)
    replay --scenario FILE.yaml [--perception unet --model flawed] [...]

Sends the stored request (the exact scenario JSON) to a worker, prints the largest position
difference between the replayed and the stored trajectory and the proxy recomputed beside the
stored one, and exits 0 only if they match (difference under 1 cm, proxy equal to 1e-6). The
worker must run the stack the campaign ran (perception, model, planner config: stored with
the campaign). Without --worker, replay brings one up itself with the stored stack
configuration (roslaunch launch/worker.launch on a private ROS master on loopback: the first
free port from 11390 on, or --port, refused when in use) and shuts it down afterwards; with --worker it uses a running one, compares what it
can read from the parameter server and refuses a mismatch. --bag records the worker's topics
during the run with rosbag.
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np

from asg_scenario import ScenarioError, load_scenario

from asg_agent.campaign.dispatch import Outcome
from asg_agent.records.store import kept_xy
from asg_agent.records.experiment import LEGACY_UNET_BACKEND
from asg_agent.scoring.proxy import run_terms
from asg_agent.records.store import Store, unpack_trajectory
from asg_agent.ros.stack_identity import stack_mismatch

BAG_TOPICS = [
    "camera/image_raw",
    "camera/labels_gt",
    "labels",
    "camera/depth/image_raw",
    "camera/camera_info",
    "odom",
    "tf",
    "tf_static",
    "clock",
    "tick",
    "cmd",
    "planner/state",
    "planner/path",
    "planner/votes",
    "planner/lookahead",
    "planner/vehicle_grid",
    "scenario",
    # a stack of standard messages (docs/your-stack.md): its goal, commands and what it shows
    "goal",
    "cmd_vel",
    "cmd_vel_stamped",
    "depth_stack/arc",
    "depth_stack/obstacles",
]


def compare(stored: np.ndarray, replayed: np.ndarray) -> float:
    """[m] largest position difference (inf when the lengths differ)."""
    if len(stored) != len(replayed):
        return float("inf")
    return float(np.max(np.hypot(stored[:, 1] - replayed[:, 1], stored[:, 2] - replayed[:, 2]))) if len(stored) else 0.0


def add_scene_to_bag(path, worker, request, o: Outcome, beside: str = ""):
    """Adds the scene, optimal path, driven trajectory, fading earlier plans and coloured labels
    to the bag (and, with `beside`, another U-Net's labels of the same frames). The bag is written
    anew in time order (not appended to): rosbag takes a bag's end time from its last chunk, so a
    chunk appended at the start time made `rosbag info` read 0 s and tools that use the duration
    misjudge the run."""
    import rosbag
    import rospy
    from asg_agent.ros.bag_scene import labels_beside, labels_rgb, plans_fading, scene_messages
    from asg_agent.scoring.proxy import optimal_path, placed_mask

    removed = {(l, i) for l, i, _ in o.removed}
    opt = optimal_path(request, placed_mask(request, o.removed))
    extra = []  # (bag time, topic, message)
    with rosbag.Bag(path) as bag:
        start = bag.get_start_time()
        plans, first_stamp, times = [], None, {}
        for _, msg, t in bag.read_messages(topics=[f"{worker}/planner/path"]):
            if msg.poses:
                plans.append((msg.header.stamp, [(p.pose.position.x, p.pose.position.y) for p in msg.poses]))
                times[msg.header.stamp] = t
        for _, msg, t in bag.read_messages(topics=[f"{worker}/scenario"]):
            first_stamp = msg.base_stamp
        when = rospy.Time.from_sec(start)
        for suffix, msg in scene_messages(
            request, removed, opt.points, o.trajectory[::6, 1:3].tolist(), first_stamp or rospy.Time()
        ):
            extra.append((when, f"{worker}/{suffix}", msg))
        # Labels in colour (bag_scene.PALETTE) for the image panel, and another model's beside them.
        for _, msg, t in bag.read_messages(topics=[f"{worker}/labels", f"{worker}/camera/labels_gt"]):
            extra.append((t, f"{worker}/replay/labels_rgb", labels_rgb(msg)))
        if beside:
            extra += labels_beside(bag, worker, beside)
        # Earlier plans: written at the bag time of the plan they accompany.
        for stamp, arr in plans_fading(plans):
            extra.append((times.get(stamp, when), f"{worker}/replay/earlier_plans", arr))
    merge_into_bag(path, extra)


def merge_into_bag(path: str, extra) -> None:
    """Writes the bag at `path` again with the messages `extra` ((bag time, topic, message)) in
    it, every chunk in time order, each recorded connection's header (latching) kept; the
    recorded messages come first among equal times. Replaces the file only once it is whole."""
    import heapq

    import rosbag

    extra = sorted(extra, key=lambda e: e[0])  # stable: equal times keep their order
    tmp = path + ".sorting"
    with rosbag.Bag(path) as bag, rosbag.Bag(tmp, "w", compression=rosbag.Compression.LZ4) as out:
        recorded = (
            (t, topic, msg, header)
            for topic, msg, t, header in bag.read_messages(raw=True, return_connection_header=True)
        )
        added = ((t, topic, msg, None) for t, topic, msg in extra)
        for t, topic, msg, header in heapq.merge(recorded, added, key=lambda e: e[0]):
            if header is None:
                out.write(topic, msg, t)
            else:
                out.write(topic, msg, t, raw=True, connection_header=header)
    os.replace(tmp, path)


def replayed_proxy(request, o: Outcome):
    """The difficulty proxy of a replayed run (None for a run that ended in ERROR), computed as the
    campaign computed it."""
    terms = run_terms(request, o)[1]
    return terms.proxy if terms else None


def report_match(what: str, diff: float, samples: str, proxy, stored_proxy, bag, ns: str = "") -> bool:
    """Prints the position and proxy comparison of a replay with a stored run; True if the proxies agree."""
    print(f"largest position difference to the stored {what}: {diff:.6f} m ({samples})")
    print(
        f"proxy: replayed {proxy if proxy is None else round(proxy, 6)}, stored "
        f"{stored_proxy if stored_proxy is None else round(stored_proxy, 6)}"
    )
    if bag:
        print(f"bag: {os.path.abspath(bag)}")
        print(f"view it: roslaunch asg_bringup replay.launch bag:={os.path.abspath(bag)} ns:={ns.strip('/')}")
    return (proxy is None and stored_proxy is None) or (
        proxy is not None and stored_proxy is not None and abs(proxy - stored_proxy) <= 1e-6
    )


def check_reference_run(a, request, ref: dict, o: Outcome) -> int:
    """The replay of a row's reference run against what attribution stored of it: termination,
    proxy, and the positions it keeps (every 6th sample, to 1 cm)."""
    proxy = replayed_proxy(request, o)
    kept = np.asarray(kept_xy(o.trajectory), float).reshape(-1, 2)
    stored = np.asarray(ref.get("trajectory_xy") or [], float).reshape(-1, 2)
    diff = float(np.abs(kept - stored).max()) if kept.shape == stored.shape and len(stored) else float("inf")
    samples = f"{len(kept)} vs {len(stored)} kept samples"
    same_proxy = report_match("reference run", diff, samples, proxy, ref.get("proxy"), a.bag, getattr(a, "worker", ""))
    ok = diff <= 0.011 and same_proxy and o.termination == ref.get("termination")
    print("REPRODUCED (the reference run)" if ok else "NOT REPRODUCED (the reference run)")
    return 0 if ok else 1


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="replay", description=__doc__.split("\n\n")[0])
    p.add_argument("store", nargs="?")
    p.add_argument("campaign", nargs="?")
    p.add_argument("job", nargs="?", type=int)
    p.add_argument("--scenario", help="a scenario YAML file instead of a stored scenario")
    p.add_argument("--worker", default="", help="a running worker's namespace (default: bring one up)")
    p.add_argument(
        "--perception",
        default="",
        help="unet or ground_truth (with --scenario, default unet); for a stored "
        "scenario of an attributed campaign, ground_truth replays its reference run and checks it",
    )
    p.add_argument("--model", default="", help="with --scenario: the U-Net model (default flawed)")
    p.add_argument(
        "--port",
        type=int,
        default=0,
        help="ROS master port of the worker replay brings up (default: the first free one from "
        f"{FIRST_PORT} on; a port in use is refused: the master would not be private)",
    )
    p.add_argument("--bag", default="", help="record the run's topics into this bag")
    p.add_argument(
        "--labels-beside",
        default="",
        metavar="MODEL",
        help="with --bag: label the bag's camera frames again with this U-Net (e.g. full, the unflawed "
        "model) and add them beside the stack's labels (replay/labels_beside_rgb, shown by rviz/replay.rviz)",
    )
    p.add_argument(
        "--record",
        action="append",
        default=[],
        metavar="TOPIC",
        help="with --bag: one more topic of the stack to record, relative to the worker's namespace "
        "(repeatable; e.g. gap_nav/points, the cloud rviz/replay_depth.rviz shows)",
    )
    p.add_argument("--figure", default="", help="write a top-down PNG of the replayed run")
    p.add_argument("--force", action="store_true", help="replay even if the worker's stack differs")
    p.add_argument(
        "--default-numerics",
        action="store_true",
        help="rerun a stored bf16 run on the default fp32 numerics (a new run, not a bit-for-bit replay)",
    )
    return p


def main(argv=None):
    p = parser()
    a = p.parse_args([x for x in (sys.argv[1:] if argv is None else argv) if ":=" not in x])
    if a.labels_beside and not a.bag:
        p.error("--labels-beside adds to a bag: give --bag too")
    row, settings = None, {}
    if a.scenario:
        try:
            request = load_scenario(a.scenario)
        except ScenarioError as e:
            print(f"replay: {e}", file=sys.stderr)
            return 2
    else:
        if a.store is None or a.campaign is None or a.job is None:
            p.error("give STORE CAMPAIGN JOB, or --scenario FILE")
        if not os.path.isfile(a.store):
            print(f"replay: {a.store}: no such store", file=sys.stderr)
            return 2
        store = Store(a.store)
        c = store.campaign(a.campaign)
        if c is None:
            print(f"replay: no campaign {a.campaign!r} in {a.store}", file=sys.stderr)
            return 2
        settings = json.loads(c["settings"])
        why = bf16_refusal(settings)
        if why and not a.default_numerics and not a.worker:
            print(
                f"replay: {why}\nrerun it on the default numerics (a new run, compared but not expected to match):\n"
                f"  rosrun asg_agent replay {a.store} {a.campaign} {a.job} --default-numerics",
                file=sys.stderr,
            )
            return 2
        row = next((r for r in store.rows(a.campaign, a.job - 1) if r["job"] == a.job), None)
        if row is None:
            print(f"replay: campaign {a.campaign!r} has no job {a.job}", file=sys.stderr)
            return 2
        request = json.loads(row["request"])
    if a.default_numerics:
        from asg_perception.numerics import DEFAULT_BACKEND

        settings = dict(settings, unet_backend=DEFAULT_BACKEND, numerics="")
    # An attributed row replayed on the ground-truth stack is checked against its reference run.
    a.against_reference = bool(
        row is not None
        and row["reference"]
        and a.perception == "ground_truth"
        and settings.get("perception") != "ground_truth"
    )
    launched = None
    if not a.worker:
        # --perception replays a run of the paper's stack (the reference run of an attribution)
        under_test = "paper" if a.perception else settings.get("stack", "paper")
        stack = {
            "stack": under_test,
            # a stack registered by a file outside this project: its file (repository-relative
            # when it is one of the repository's), and whether it runs on simulated time
            "stack_file": settings.get("stack_file", "") if under_test != "paper" else "",
            "sim_time": bool((settings.get("registration") or {}).get("sim_time")) and under_test != "paper",
            "perception": a.perception
            or (settings.get("perception", "unet") if under_test == "paper" else "ground_truth"),
            "model": a.model or settings.get("model", "flawed"),
            "unet_backend": settings.get("unet_backend", LEGACY_UNET_BACKEND),
            "planner_config": settings.get("planner_config", "planner.yaml"),
        }
        try:
            port = private_port(a.port)
        except ValueError as e:
            print(f"replay: {e}", file=sys.stderr)
            return 2
        launched = bring_up_worker(stack, port)
        a.force = True  # the worker is the stored stack by construction: no identity check
        a.worker = "/replay_worker"
    try:
        return run_replay(a, request, row, settings)
    finally:
        if launched is not None:
            os.killpg(os.getpgid(launched.pid), signal.SIGINT)
            try:
                launched.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(os.getpgid(launched.pid), signal.SIGKILL)


def bf16_refusal(settings: dict) -> str:
    """Why a stored run of the bf16 fast mode cannot replay bit for bit on this CPU ("" if it
    can): its findings repeat only where oneDNN runs the ISA they were recorded with (issue #53)."""
    from asg_perception import numerics as nm

    recorded = settings.get("numerics", "")
    if not recorded or recorded.split()[0] not in nm.BF16_BACKENDS:
        return ""
    isa = dict(kv.split("=", 1) for kv in recorded.split()[1:] if "=" in kv).get("isa", "")
    flags = nm.cpu_flags()
    here = nm.effective_isa(flags) if nm.native_bf16(flags) else ""
    if here == isa:
        return ""
    where = f"oneDNN runs {here} here" if here else "this CPU has no native bf16"
    return f"the campaign ran the bf16 fast mode on oneDNN {isa}; its runs replay bit for bit only there ({where})"


def registration_arg(stack: dict) -> str:
    """worker.launch's stack:= for a stored stack: its registration file (a relative path is the
    repository's), or the name of a registered stack of this project where none was stored."""
    path = stack.get("stack_file", "")
    if not path:
        return stack.get("stack", "paper")
    return path if os.path.isabs(path) else os.path.join(_repo(), path)


def _repo() -> str:
    return os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), *[".."] * 6))


def free_running(settings) -> bool:
    """Whether the campaign's stack ran free (its registration's `mode: free`, no lockstep client)."""
    return ((settings or {}).get("registration") or {}).get("mode") == "free"


#: the first port a replay's private master tries (docs/reliability.md: each script's port)
FIRST_PORT = 11390


def _free(port: int) -> bool:
    """Whether nothing listens on loopback port `port` (a bind succeeds)."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def private_port(port: int = 0, tries: int = 64) -> int:
    """The port of the replay's own master: `port` if given and free, else the first free one
    from FIRST_PORT on. Another process's master on it (a second replay, a sim-time stack's)
    would not be private: its /use_sim_time and workers are not this replay's. ValueError naming
    the port when a given one is in use, or when none of `tries` ports is free."""
    if port:
        if not _free(port):
            raise ValueError(f"--port {port} is in use (another ROS master?): give a free one, or leave --port out")
        return port
    for p in range(FIRST_PORT, FIRST_PORT + tries):
        if _free(p):
            return p
    raise ValueError(f"no free port in {FIRST_PORT}-{FIRST_PORT + tries - 1} for the replay's own master")


def bring_up_worker(stack: dict, port: int):
    """roslaunch asg_bringup's worker.launch with the stack of the stored run, on a private master."""
    import rospkg

    packages = rospkg.RosPack()
    worker_launch = os.path.join(packages.get_path("asg_bringup"), "launch", "worker.launch")
    planner = stack["planner_config"]
    if os.sep not in planner:
        planner = os.path.join(packages.get_path("asg_planner"), "config", planner)
    os.environ["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
    os.environ.setdefault("ROS_HOSTNAME", "127.0.0.1")
    cmd = [
        "roslaunch",
        "-p",
        str(port),
        worker_launch,
        "ns:=replay_worker",
        f"stack:={registration_arg(stack)}",
        f"sim_time:={str(stack.get('sim_time', False)).lower()}",
        f"perception:={stack['perception']}",
        f"model:={stack['model']}",
        f"unet_backend:={stack.get('unet_backend', LEGACY_UNET_BACKEND)}",
        f"planner_config:={planner}",
        "odom_every_tick:=true",
        "markers:=true",
    ]  # a replay is for looking at: every tick's pose and the stack's markers in the bag
    print(f"replay: bringing up a worker: {' '.join(cmd[3:])}", file=sys.stderr)
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, preexec_fn=os.setsid)


def _runs_campaigns_stack(worker: str, settings: dict) -> bool:
    """Whether `worker` runs the campaign's stack, saying why not. Read once its server answers: a
    worker launched just before the replay (replay_findings.sh) has not set its parameters until then."""
    problems = stack_mismatch(worker, settings)
    if problems:
        print(
            "replay: the worker's stack is not the campaign's: "
            + "; ".join(problems)
            + " (launch worker.launch with the campaign's perception and model, or --force)",
            file=sys.stderr,
        )
    return not problems


def run_replay(a, request, row, settings) -> int:
    import rospy
    from asg_msgs.msg import RunScenarioAction
    from asg_scenario.convert import to_goal_msg
    from asg_scenario.ros_node import GoalClient
    from asg_scenario.run_scenario_node import run_goal
    from asg_agent.ros.pool import result_to_outcome

    from asg_agent.ros.node import init_node

    init_node("replay", anonymous=True, disable_signals=True)
    worker = "/" + a.worker.strip("/")
    client = GoalClient(worker + "/run_scenario", RunScenarioAction)
    if not client.wait_for_server(rospy.Duration(90)):
        print(f"replay: no scene worker at {worker}/run_scenario", file=sys.stderr)
        return 2
    if settings and not a.force and not _runs_campaigns_stack(worker, settings):
        return 2
    bag = None
    if a.bag:
        topics = [f"{worker}/{t.strip('/')}" for t in BAG_TOPICS + list(getattr(a, "record", []) or [])]
        bag = subprocess.Popen(
            ["rosbag", "record", "-O", a.bag, "--lz4"] + topics,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=os.setsid,
        )
        # The run starts only once the recorder subscribes to the worker's topics.
        import rosgraph

        master, deadline = rosgraph.Master("/replay"), time.time() + 60
        while time.time() < deadline:
            subs = dict(master.getSystemState()[1])
            if all(
                any(n.startswith("/record") for n in subs.get(f"{worker}/{t}", []))
                for t in ("odom", "camera/image_raw", "planner/state")
            ):
                break
            time.sleep(0.2)
        time.sleep(0.5)
    t0 = time.time()
    result = run_goal(client, to_goal_msg(request))
    if bag:
        time.sleep(1.0)
        os.killpg(os.getpgid(bag.pid), signal.SIGINT)
        bag.wait(timeout=30)
        # The recorder (a child of the `rosbag` wrapper) may still be closing the file: wait for
        # it to leave FILE.active and write the index.
        deadline = time.time() + 60
        while time.time() < deadline and (
            os.path.exists(a.bag + ".active") or not os.path.exists(a.bag) or os.path.getsize(a.bag) == 0
        ):
            time.sleep(0.2)
        time.sleep(0.5)
    if result is None:
        print("replay: the worker returned no result", file=sys.stderr)
        return 1
    o: Outcome = result_to_outcome(0, worker, result, time.time() - t0)
    if a.bag:
        add_scene_to_bag(a.bag, worker, request, o, a.labels_beside)
    print(
        f"replayed {request.get('name', '')} on {worker}: {o.termination} after {o.sim_time:.2f} s "
        f"({o.wall_time:.1f} s wall){': ' + o.error if o.error else ''}"
    )
    if a.figure:
        from asg_scenario.report import plot_run

        plot_run(a.figure, request, o.trajectory[:, 1:3].tolist(), title=f"replay of {request.get('name', '')}")
    if row is None:
        return 0 if o.termination != "ERROR" else 1
    if getattr(a, "against_reference", False):
        return check_reference_run(a, request, json.loads(row["reference"]), o)
    stored = unpack_trajectory(row["trajectory"])
    diff = compare(stored, o.trajectory)
    samples = f"{len(o.trajectory)} vs {len(stored)} samples"
    same_proxy = report_match(
        "run", diff, samples, replayed_proxy(request, o), row["proxy"], a.bag, getattr(a, "worker", "")
    )
    ok = diff < 0.01 and same_proxy and o.termination == row["termination"]
    if getattr(a, "default_numerics", False):  # a rerun on other numerics: reported, not judged
        print(f"RERUN on the default numerics: {o.termination} (stored on bf16: {row['termination']})")
        return 0 if o.termination != "ERROR" else 1
    if free_running(settings) and not ok:  # no client gates it: its runs differ from run to run
        print(
            f"RERUN of a free-running stack ({settings.get('stack', '?')}): its runs are not reproducible bit "
            f"for bit, so this is a run of the scenario, not a check of the stored one; {o.termination} "
            f"({'as' if o.termination == row['termination'] else 'unlike'} the stored {row['termination']}). "
            "How often a verdict repeats: asg_agent.ros.rerun and asg_analysis.studies.run_spread (docs/your-stack.md)"
        )
        return 0 if o.termination != "ERROR" else 1
    print("REPRODUCED" if ok else "NOT REPRODUCED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

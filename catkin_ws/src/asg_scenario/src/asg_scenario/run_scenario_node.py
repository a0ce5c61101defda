"""run_scenario: send one scenario file to a scene worker and write what came back.

The ROS adapter of the scenario tools (this module and ros_node.py are the only ones here that import rospy).
"""

import argparse
import os
import sys

from .convert import to_goal_msg
from .report import TERMINATION_NAMES, path_length, plot_run, write_result_yaml, write_trajectory_csv, yaw_of
from .schema import ScenarioError, dump_scenario, load_scenario
from .votes import phantom_votes, shadow_votes


def _samples(result):
    out = []
    for s in result.trajectory:
        p, q, v, w = s.pose.position, s.pose.orientation, s.twist.linear, s.twist.angular
        out.append(
            dict(
                t=s.t,
                x=p.x,
                y=p.y,
                z=p.z,
                yaw=yaw_of(q.x, q.y, q.z, q.w),
                vx=v.x,
                vy=v.y,
                vz=v.z,
                wx=w.x,
                wy=w.y,
                wz=w.z,
            )
        )
    return out


def removed_set(result):
    return {(int(r.layout_index), int(r.instance_index)) for r in result.removed_obstacles}


def run_goal(client, goal, timeout_s=None, feedback_cb=None):
    """Sends `goal` on `client` (ros_node.GoalClient of a worker's run_scenario) and waits for its
    result: the result, or None after `timeout_s` [s, wall] (the goal is then cancelled) or at
    shutdown. GoalClient ties the goal's callbacks to its handle before sending it, so a worker
    that answers at once (before send_goal returns) is never lost."""
    client.send_goal(goal, feedback_cb=feedback_cb)
    if not client.wait_for_result(timeout_s or 0.0):
        client.cancel_goal()
        return None
    return client.get_result()


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="run_scenario",
        description="Run a scenario YAML file on a scene worker and write the outcome "
        "(result.yaml, trajectory.csv, run.png) to an output folder.",
    )
    parser.add_argument("scenario", help="scenario YAML file (docs/scenario-format.md)")
    parser.add_argument("--worker", default="/worker_0", help="worker namespace [/worker_0]")
    parser.add_argument("--out", default="runs/latest", help="output folder [runs/latest]")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-clock limit for the whole run [s] (600)")
    parser.add_argument("--scenario-id", type=int, default=None, help="override the file's scenario_id")
    parser.add_argument(
        "--votes",
        action="store_true",
        help="also record the planner's final vote grid (WORKER/planner/votes) "
        "into result.yaml and draw it in run.png",
    )
    parser.add_argument(
        "--top-down", type=int, default=768, help="size of the rendered top-down picture [px] (768; 0: none)"
    )
    return parser


def _write_outputs(args, scenario: dict, result, votes: dict, wall: float) -> int:
    """result.yaml, trajectory.csv, scenario.yaml and run.png of a run in args.out; the summary
    line; 0, or 1 for a run that ended in ERROR."""
    samples = _samples(result)
    xy = [(s["x"], s["y"]) for s in samples]
    os.makedirs(args.out, exist_ok=True)
    name = (
        TERMINATION_NAMES[result.termination]
        if result.termination < len(TERMINATION_NAMES)
        else str(result.termination)
    )
    summary = {
        "scenario_id": int(result.scenario_id),
        "termination": name,
        "error": result.error,
        "sim_time": float(result.sim_time),
        "wall_time": wall,
        "num_control_msgs": int(result.num_control_msgs),
        "path_length": path_length(xy),
        "trajectory_samples": len(samples),
        "obstacle_visibility": [float(v) for v in result.obstacle_visibility],
        "removed_obstacles": [
            {"layout": int(r.layout_index), "instance": int(r.instance_index), "reason": r.reason}
            for r in result.removed_obstacles
        ],
        "collision_with": result.collision_with,
    }
    removed = removed_set(result)
    cell = votes.get("size", 0) / 0.6 if votes else 0  # the marker side is 0.6 x the vote spacing
    if args.votes:
        # Marker alpha is 0.3 + 0.7 votes / max_votes (planner.yaml max_votes: 50).
        summary["votes"] = [{"x": x, "y": y, "weight": round((a - 0.3) / 0.7, 3)} for x, y, a in votes.get("cells", [])]
        summary["phantom_vote_vertices"] = phantom_votes(scenario, summary["votes"], cell, removed)
        summary["shadow_vote_vertices"] = shadow_votes(scenario, summary["votes"], cell, removed)
        print(
            f"votes: {len(summary['votes'])} vertices, {summary['phantom_vote_vertices']} with no "
            f"obstacle near, {summary['shadow_vote_vertices']} of those in a cast shadow"
        )
    write_result_yaml(os.path.join(args.out, "result.yaml"), summary)
    write_trajectory_csv(os.path.join(args.out, "trajectory.csv"), samples)
    with open(os.path.join(args.out, "scenario.yaml"), "w") as f:
        f.write(dump_scenario(scenario))
    background = None
    if result.top_down.width > 0 and result.top_down.encoding == "rgb8":
        import numpy as np

        background = np.frombuffer(bytes(result.top_down.data), dtype=np.uint8).reshape(
            result.top_down.height, result.top_down.width, 3
        )
    plot_run(
        os.path.join(args.out, "run.png"),
        scenario,
        xy,
        f"{scenario['name']}: {name} after {result.sim_time:.1f} s",
        removed,
        background,
        votes=summary.get("votes"),
        vote_cell=cell,
    )
    print(
        f"outcome: {name}  sim_time {result.sim_time:.2f} s  wall {wall:.2f} s "
        f"({result.sim_time / max(wall, 1e-9):.1f}x real time)  path {summary['path_length']:.1f} m"
        f"  control msgs {result.num_control_msgs}" + (f"  error: {result.error}" if result.error else "")
    )
    print(f"wrote {args.out}/result.yaml, trajectory.csv, scenario.yaml, run.png")
    return 0 if name != "ERROR" else 1


def main(argv=None):
    args = _parser().parse_args(argv)

    try:
        scenario = load_scenario(args.scenario)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.scenario_id is not None:
        scenario["scenario_id"] = args.scenario_id

    import rospy
    from asg_msgs.msg import RunScenarioAction

    from .ros_node import GoalClient, init_node

    try:  # under /use_sim_time: waits for /clock, or the deadline below is past before it starts
        init_node("run_scenario", anonymous=True, disable_signals=True)
    except RuntimeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    name = args.worker.rstrip("/") + "/run_scenario"
    client = GoalClient(name, RunScenarioAction)
    print(f"waiting for worker action server {name} ...", flush=True)
    if not client.wait_for_server(rospy.Duration(60.0)):
        print(f"error: no action server at {name} after 60 s (is the worker launched?)", file=sys.stderr)
        return 3
    last = [-1.0]
    votes = {}
    if args.votes:
        from visualization_msgs.msg import MarkerArray

        def on_votes(msg):
            for m in msg.markers:
                if m.ns == "votes":
                    votes["cells"] = [(p.x, p.y, c.a) for p, c in zip(m.points, m.colors)]
                    votes["size"] = m.scale.x

        rospy.Subscriber(args.worker.rstrip("/") + "/planner/votes", MarkerArray, on_votes)

    def feedback(fb):
        if fb.sim_time - last[0] >= 1.0:
            last[0] = fb.sim_time
            print(f"  t = {fb.sim_time:6.1f} s   distance to goal {fb.distance_to_goal:7.2f} m", flush=True)

    print(f"running scenario {scenario['scenario_id']} ({scenario['name'] or args.scenario})", flush=True)
    goal = to_goal_msg(scenario)
    goal.top_down_px = max(0, args.top_down)
    import time

    wall0 = time.monotonic()
    result = run_goal(client, goal, args.timeout, feedback)
    if result is None:
        print(f"error: no result within {args.timeout:g} s", file=sys.stderr)
        return 4
    wall = time.monotonic() - wall0
    if args.votes:
        rospy.sleep(0.5)  # the last replan's markers
    return _write_outputs(args, scenario, result, votes, wall)

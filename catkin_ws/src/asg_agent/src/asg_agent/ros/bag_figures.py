"""Figures from bags of replays (rosbag; ROS is needed for the replays themselves): what the
planner believed at a simulated time, and a stored scenario replayed on the campaign's stack and on
the ground-truth reference side by side (the paper's Figures 9-10). Moved out of
asg_analysis.report (issue #38: analysis/ reads stores and exports only).

    python3 -m asg_agent.ros.bag_figures snapshot RUN.bag OUT.png --time 6.0 [--ns worker_0]
    python3 -m asg_agent.ros.bag_figures perception STORE CAMPAIGN JOB OUT.png [--work DIR]

`snapshot` draws the vote grid (yellow to red by votes), the plan in force, earlier plans, the
vehicle and its look-ahead point, the obstacles, start and goal. `perception` replays a stored
scenario on the campaign's stack and on the ground-truth reference stack (asg_agent.ros.replay
brings up the workers) and draws both side by side.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

from asg_scenario.report import yaw_of


def _bag_base(bag, w):
    for _, msg, _ in bag.read_messages(topics=[f"{w}/scenario"]):
        return msg.base_stamp.to_sec()
    return None


def draw_snapshot(ax, bag_path: str, t: float, ns: str = "worker_0", legend: bool = True) -> str:
    """Draws on `ax` what the planner of `ns` believed at simulated time `t` of a replay bag;
    returns a one-line description (frames voted, voted vertices, plans)."""
    import rosbag
    from matplotlib.patches import Circle, Rectangle

    w = "/" + ns.strip("/")
    votes, plans, state, odom, scene = None, [], None, None, None
    with rosbag.Bag(bag_path) as bag:
        base = _bag_base(bag, w)
        if base is None:
            raise ValueError(f"{bag_path}: no {w}/scenario message (not a replay bag of {w}?)")
        until = base + t
        for topic, msg, _ in bag.read_messages(
            topics=[f"{w}/planner/votes", f"{w}/planner/path", f"{w}/planner/state", f"{w}/odom", f"{w}/replay/scene"]
        ):
            stamp = (
                msg.header.stamp.to_sec()
                if hasattr(msg, "header")
                else (msg.markers[0].header.stamp.to_sec() if msg.markers else 0.0)
            )
            if topic.endswith("replay/scene"):
                scene = msg
            elif stamp > until + 1e-9:
                continue
            elif topic.endswith("votes"):
                votes = msg
            elif topic.endswith("path") and msg.poses:
                plans.append([(p.pose.position.x, p.pose.position.y) for p in msg.poses])
            elif topic.endswith("state"):
                state = msg
            elif topic.endswith("odom"):
                odom = msg
    if votes:
        for m in votes.markers:
            side = m.scale.x
            for p, c in zip(m.points, m.colors):
                ax.add_patch(
                    Rectangle(
                        (p.x - side / 2, p.y - side / 2), side, side, color=(c.r, c.g, c.b), alpha=max(0.2, c.a), lw=0
                    )
                )
    if scene:
        for m in scene.markers:
            if m.ns == "obstacles":
                ax.add_patch(
                    Circle(
                        (m.pose.position.x, m.pose.position.y),
                        m.scale.x / 2,
                        color=(m.color.r, m.color.g, m.color.b),
                        alpha=m.color.a,
                    )
                )
            else:
                ax.plot([p.x for p in m.points], [p.y for p in m.points], ":", color=(m.color.r, m.color.g, m.color.b))
    for k, pts in enumerate(plans[:-1][-6:]):
        ax.plot(*zip(*pts), "-", color="tab:cyan", alpha=0.25 + 0.1 * k, lw=1)
    if plans:
        ax.plot(*zip(*plans[-1]), "-", color="tab:green", lw=2, label="plan in force")
    if odom:
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        yaw = yaw_of(q.x, q.y, q.z, q.w)
        ax.arrow(p.x, p.y, 3 * math.cos(yaw), 3 * math.sin(yaw), width=0.6, color="magenta", label="vehicle")
    if state:
        ax.plot([state.lookahead.x], [state.lookahead.y], "o", color="purple", label="look-ahead")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if legend:
        ax.legend(loc="upper left", fontsize=7)
    if state:
        return f"{state.frames} frames voted, {state.voted_vertices} voted vertices, {state.plan_count} plans"
    return ""


def snapshot(bag_path: str, out: str, t: float, ns: str = ""):
    """The planner at simulated time `t` [s] of a replay bag, in worker namespace `ns` (empty: the
    bag's own, as replay_view finds it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not ns:
        import rosbag

        from asg_agent.ros.replay_view import bag_namespace

        with rosbag.Bag(bag_path) as b:
            ns = bag_namespace(b.get_type_and_topic_info().topics)
    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    what = draw_snapshot(ax, bag_path, t, ns)
    ax.set_title(f"planner at t = {t:.2f} s" + (f": {what}" if what else ""), fontsize=9)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


#: topics renamed by issue #55 (image_pipeline's names): the old name each one had in older bags
OLD_TOPICS = {"camera/image_raw": ("camera/image",), "camera/depth/image_raw": ("camera/depth",)}


def bag_image(bag_path: str, topic: str, t: float, ns: str) -> "np.ndarray":
    """The last image of `ns`/`topic` stamped at or before simulated time `t` (H x W x 3)."""
    import rosbag

    w = "/" + ns.strip("/")
    img = None
    with rosbag.Bag(bag_path) as bag:
        base = _bag_base(bag, w)
        # bags recorded before issue #55's image_pipeline names hold camera/image
        names = [f"{w}/{topic}"] + [f"{w}/{old}" for old in OLD_TOPICS.get(topic, ())]
        for _, msg, _ in bag.read_messages(topics=names):
            if msg.header.stamp.to_sec() <= base + t + 1e-9:
                img = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, -1)[..., :3]
    if img is None:
        raise ValueError(f"{bag_path}: no {w}/{topic} image before t = {t:.2f} s")
    return img


def bag_end(bag_path: str, ns: str):
    """([s] simulated time of the last odometry of `ns` after the run's start, its (x, y) [m])."""
    import rosbag

    w = "/" + ns.strip("/")
    last = None
    with rosbag.Bag(bag_path) as bag:
        base = _bag_base(bag, w)
        for _, msg, _ in bag.read_messages(topics=[f"{w}/odom"]):
            last = msg
    if base is None or last is None:
        raise ValueError(f"{bag_path}: no {w}/scenario or {w}/odom")
    return last.header.stamp.to_sec() - base, (last.pose.pose.position.x, last.pose.pose.position.y)


def pair_figure(rows, times, out: str, title: str, ns: str = "replay_worker", centre=None, half: float = 25.0):
    """The paper's Figures 9-10 for two stacks on one scene: per row (label, bag), the planner at
    each of `times` (votes, plans, look-ahead, vehicle), then the camera frame and the labels the
    planner voted from at the last time. Top-down panels show `half` metres around `centre`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(times) + 2
    fig, axes = plt.subplots(len(rows), n, figsize=(3.3 * n, 3.8 * len(rows)), squeeze=False)
    for i, (label, bag) in enumerate(rows):
        for j, t in enumerate(times):
            what = draw_snapshot(axes[i][j], bag, t, ns, legend=(i == 0 and j == 0))
            axes[i][j].set_title(f"{label}, t = {t:.1f} s\n{what}", fontsize=7)
            if centre is not None:
                axes[i][j].set_xlim(centre[0] - half, centre[0] + half)
                axes[i][j].set_ylim(centre[1] - half, centre[1] + half)
        for j, (topic, name) in enumerate((("camera/image_raw", "camera"), ("replay/labels_rgb", "labels voted from"))):
            ax = axes[i][len(times) + j]
            ax.imshow(bag_image(bag, topic, times[-1], ns))
            ax.set_title(f"{label}: {name}, t = {times[-1]:.1f} s", fontsize=7)
            ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)


def perception_replay(store: str, campaign: str, job: int, out: str, work: str = "", port: int = 11391) -> dict:
    """Replays a stored scenario on the campaign's stack and on the ground-truth reference stack
    (asg_agent.ros.replay, each on a worker of its own, recording a bag), and draws pair_figure
    at 5, 2.5 and 0.5 s before the end of the run under test (its collision, for a collision)."""
    import subprocess
    import tempfile

    work = work or tempfile.mkdtemp(prefix="perception_replay_")
    os.makedirs(work, exist_ok=True)
    bags = {}
    for kind, extra in (("test", []), ("reference", ["--perception", "ground_truth"])):
        bags[kind] = os.path.join(work, f"{campaign}-{job}-{kind}.bag")
        cmd = [
            sys.executable,
            "-m",
            "asg_agent.ros.replay",
            store,
            campaign,
            str(job),
            "--bag",
            bags[kind],
            "--port",
            str(port),
        ] + extra
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        if not os.path.isfile(bags[kind]):
            raise ValueError(
                f"replay of {campaign} job {job} ({kind}) wrote no bag: {p.stdout[-800:]} {p.stderr[-800:]}"
            )
        print(p.stdout.strip(), file=sys.stderr)
    end, where = bag_end(bags["test"], "replay_worker")
    times = [max(0.5, end - d) for d in (5.0, 2.5, 0.5)]
    from asg_agent.records.store import Store

    row = next(r for r in Store(store, create=False).rows(campaign, job - 1) if r["job"] == job)
    ref = json.loads(row["reference"]) if row["reference"] else {}
    title = (
        f"{campaign} job {job}: under test {row['termination']} (proxy {row['proxy']:.2f}"
        + (f", with {row['collision_with']}" if row["collision_with"] else "")
        + ")"
        + (
            f"; ground-truth reference {ref.get('termination')} (proxy {ref['proxy']:.2f})"
            if ref.get("proxy") is not None
            else ""
        )
    )
    pair_figure([("under test", bags["test"]), ("ground truth", bags["reference"])], times, out, title, centre=where)
    return {"bags": bags, "times": times, "out": out}


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_agent.ros.bag_figures", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("snapshot")
    a.add_argument("bag")
    a.add_argument("out")
    a.add_argument("--time", type=float, required=True, help="[s] simulated time of the snapshot")
    a.add_argument("--ns", default="", help="the worker namespace in the bag (default: found in it)")
    c = sub.add_parser("perception")
    c.add_argument("store")
    c.add_argument("campaign")
    c.add_argument("job", type=int)
    c.add_argument("out")
    c.add_argument("--work", default="", help="folder for the two bags (default: a new temporary one)")
    args = p.parse_args(argv)
    try:
        if args.cmd == "snapshot":
            snapshot(args.bag, args.out, args.time, args.ns)
            print(args.out)
        else:
            r = perception_replay(args.store, args.campaign, args.job, args.out, args.work)
            print(f"{args.out} (bags: {', '.join(r['bags'].values())})")
    except (ValueError, OSError) as e:
        print(f"bag_figures: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

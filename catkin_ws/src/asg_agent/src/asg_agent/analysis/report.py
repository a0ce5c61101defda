"""Figures and a report from campaigns and bags, without a display (no rospy node).

    python3 -m asg_agent.analysis.report snapshot RUN.bag OUT.png --time 6.0 [--ns worker_0]
    python3 -m asg_agent.analysis.report campaign STORE CAMPAIGN OUT_DIR [--top 10]
    python3 -m asg_agent.analysis.report perception STORE CAMPAIGN JOB OUT.png [--work DIR]

`snapshot` draws what the planner believed at a simulated time: the vote grid (yellow to red by
votes), the plan in force, earlier plans, the vehicle and its look-ahead point, the obstacles,
start and goal. `campaign` writes OUT_DIR/index.html (open it from disk, no server): the
Table-2-style counts, the proxy over scenarios with its running best and the counts >= 3 as the
campaign went on, terminations, and the top-k table with each scenario's top-down figure and
its replay command. `perception` replays a stored scenario on the campaign's stack and on the
ground-truth reference stack and draws both side by side, as the paper's Figures 9-10 (ROS is
needed for the replays: asg_agent.ros.replay brings up the workers).
"""

import argparse
import html
import json
import math
import os
import sys

import numpy as np
from asg_agent.scoring.attribution import FINDING, FINDING_STRONG

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


def snapshot(bag_path: str, out: str, t: float, ns: str = "worker_0"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    what = draw_snapshot(ax, bag_path, t, ns)
    ax.set_title(f"planner at t = {t:.2f} s" + (f": {what}" if what else ""), fontsize=9)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def bag_image(bag_path: str, topic: str, t: float, ns: str) -> "np.ndarray":
    """The last image of `ns`/`topic` stamped at or before simulated time `t` (H x W x 3)."""
    import rosbag

    w = "/" + ns.strip("/")
    img = None
    with rosbag.Bag(bag_path) as bag:
        base = _bag_base(bag, w)
        for _, msg, _ in bag.read_messages(topics=[f"{w}/{topic}"]):
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
        for j, (topic, name) in enumerate((("camera/image", "camera"), ("replay/labels_rgb", "labels voted from"))):
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
    from asg_agent.campaign.store import Store

    row = next(r for r in Store(store).rows(campaign, job - 1) if r["job"] == job)
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


def _baseline_html(experiment: str) -> str:
    """The baseline of the campaign's experiment (results/baseline/<exp>.json), if measured."""
    from asg_agent.cli.baseline import REPO

    path = os.path.join(REPO, "results", "baseline", f"{experiment}.json")
    if not os.path.isfile(path):
        return (
            f"<h2>Baseline</h2><p>No baseline of {html.escape(experiment)} yet: "
            f"<code>bash scripts/repro/baseline.sh {html.escape(experiment)}</code> measures it.</p>"
        )
    with open(path) as f:
        b = json.load(f)
    rows = "".join(
        f"<tr><td>{html.escape(k)}</td><td>{g['runs']}</td><td>{100 * g['share_ge3']:.1f} %</td>"
        f"<td>{g['median_yaw_term']:.3f} / {g['p90_yaw_term']:.3f}</td><td>{g['median_plr']:.3f} / {g['p90_plr']:.3f}</td>"
        f"<td>{g['collisions']}</td></tr>"
        for k, g in b["stacks"].items()
    )
    return (
        f"<h2>Baseline: the stacks on seeded random layouts of {html.escape(experiment)}</h2>"
        "<table><tr><th>stack</th><th>runs</th><th>proxy &gt;= 3</th><th>yaw term median / p90</th>"
        f"<th>PLR median / p90</th><th>collisions</th></tr>{rows}</table>"
    )


def _three_stack_html(store, store_path: str, campaign: str, s: dict, out_dir: str, top: int) -> str:
    """The three-stack attribution section (issue #36): the classes, and the findings of the
    stack under test (flaw first) with the three paths on the scene and the replay command."""
    from asg_agent.analysis.export import top_down
    from asg_agent.scoring import attribution as attr

    cl = s["classes"]
    if not sum(cl.values()):
        return ""
    rerun = sum(v for k, v in cl.items() if k != attr.NOT_CANDIDATE)
    head = "".join(f"<th>{k}</th>" for k in attr.CLASSES + (attr.NOT_CANDIDATE, attr.PENDING))
    cells = "".join(f"<td>{cl[k]}</td>" for k in attr.CLASSES + (attr.NOT_CANDIDATE, attr.PENDING))
    order = {k: i for i, k in enumerate(attr.FINDINGS)}
    from asg_agent.analysis import failure_modes as fm

    found = [
        dict(r)
        for r in store.db.execute(
            "SELECT job, proxy, termination, reference_runs, attribution, request, trajectory, collision_with "
            "FROM scenarios WHERE campaign = ? AND attribution IN (" + ",".join("?" * len(attr.FINDINGS)) + ")",
            (campaign, *attr.FINDINGS),
        )
    ]
    for r in found:
        r["mode"] = fm.mode_of_stored(r)
    # grouped by failure mode (analysis/failure_modes.py), flaw findings first
    found = sorted(found, key=lambda r: (order[r["attribution"]], r["mode"], r["job"]))[:top]
    items = []
    for r in found:
        png = f"three_job{r['job']}.png"
        top_down(store, campaign, r["job"], os.path.join(out_dir, png))
        runs = json.loads(r["reference_runs"] or "{}")
        refs = "; ".join(
            f"{k} {v['termination']} ({'n/a' if v.get('proxy') is None else format(v['proxy'], '.2f')})"
            for k, v in sorted(runs.items())
        )
        cmd = f"rosrun asg_agent replay {store_path} {campaign} {r['job']}"
        proxy = "n/a" if r["proxy"] is None else f"{r['proxy']:.2f}"
        items.append(
            f"<tr><td>{html.escape(r['attribution'])}</td><td>{html.escape(fm.label(r['mode']))}</td>"
            f"<td>{r['job']}</td><td>{html.escape(r['termination'])} "
            f"({proxy})</td><td>{html.escape(refs)}</td><td><a href='{png}'><img src='{png}' width='220'></a></td>"
            f"<td><code>{html.escape(cmd)}</code></td></tr>"
        )
    return (
        f"<h2>Three-stack attribution</h2><p>{rerun} of {s['scenarios']} scenarios were candidates (a failure, "
        f"or proxy &gt;= {attr.CANDIDATE:g}) and ran again on the reference stacks; {cl[attr.NOT_CANDIDATE]} were "
        f"not re-run. <b>flaw</b>: only the stack under test fails; <b>model</b>: the unflawed U-Net fails too; "
        f"<b>stack</b>: ground truth fails too (docs/agent.md).</p><table><tr>{head}</tr><tr>{cells}</tr></table>"
        + (
            "<table><tr><th>class</th><th>failure mode</th><th>job</th><th>under test</th><th>references</th>"
            "<th>the three paths</th>"
            f"<th>replay</th></tr>{''.join(items)}</table>"
            if items
            else ""
        )
    )


def _stack_words(settings: dict) -> str:
    """The stack under test as the report names it: the paper's (perception / model) or another."""
    stack = settings.get("stack", "paper")
    if stack != "paper":
        return f"{stack} (command interface {settings.get('command_interface', 'vehicle_command')})"
    return f"{settings.get('perception')} / {settings.get('model')}"


def campaign_report(store_path: str, campaign: str, out_dir: str, top: int = 10) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from asg_agent.analysis.export import top_down
    from asg_agent.campaign.store import Store

    store = Store(store_path)
    c = store.campaign(campaign)
    if c is None:
        raise ValueError(f"no campaign {campaign!r} in {store_path}")
    s = store.summary(campaign, top=top)
    rows = list(
        store.db.execute("SELECT job, proxy, termination FROM scenarios WHERE campaign = ? ORDER BY job", (campaign,))
    )
    os.makedirs(out_dir, exist_ok=True)
    proxy = np.array([r[1] if r[1] is not None else np.nan for r in rows])
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.4))
    axes[0].plot(proxy, ".", ms=3, color="0.4", label="proxy")
    axes[0].plot(np.fmax.accumulate(np.nan_to_num(proxy, nan=-np.inf)), "-", color="tab:red", label="best so far")
    window = 50
    if len(proxy) >= window:
        axes[0].plot(
            np.arange(window - 1, len(proxy)),
            np.convolve(np.nan_to_num(proxy), np.ones(window) / window, "valid"),
            color="tab:blue",
            label=f"mean of {window}",
        )
    axes[0].axhline(3, color="0.7", ls=":")
    axes[0].set_xlabel("scenario (job)")
    axes[0].set_ylabel("proxy")
    axes[0].legend(fontsize=8)
    axes[1].plot(np.cumsum(np.nan_to_num(proxy) >= FINDING), label=f">= {FINDING:g}")
    axes[1].plot(np.cumsum(np.nan_to_num(proxy) >= FINDING_STRONG), label=f">= {FINDING_STRONG:g}")
    axes[1].set_xlabel("scenarios spent")
    axes[1].set_ylabel("count found")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "curves.png"), dpi=100)
    plt.close(fig)
    n = max(1, s["scenarios"])
    items = []
    for r in s["top"]:
        png = f"job{r['job']}.png"
        top_down(store, campaign, r["job"], os.path.join(out_dir, png))
        cmd = f"rosrun asg_agent replay {store_path} {campaign} {r['job']}"
        items.append(
            f"<tr><td>{r['job']}</td><td>{r['id']}</td><td>{r['episode']}.{r['step']}</td>"
            f"<td><b>{r['proxy']:.3f}</b></td><td>{r['vis']:+.2f}</td><td>{r['yaw_term']:.3f}</td>"
            f"<td>{r['plr']:.3f}</td><td>{html.escape(r['termination'])}</td>"
            f"<td><a href='{png}'><img src='{png}' width='220'></a></td><td><code>{html.escape(cmd)}</code></td></tr>"
        )
    terms = "".join(f"<tr><td>{html.escape(k)}</td><td>{v}</td></tr>" for k, v in sorted(s["terminations"].items()))
    settings = json.loads(c["settings"])
    best = "n/a" if s["max_proxy"] is None else f"{s['max_proxy']:.3f}"
    attribution = ""
    if s["attributed"]:
        attribution = (
            f"<h2>Attribution</h2><p>{s['attributed']} scenarios also ran on the reference stack "
            f"(ground-truth labels, the same planner and follower). Of the {s['proxy_ge_3']} with proxy "
            f"&gt;= 3, <b>{s['perception_ge3']}</b> are the perception's (reference proxy &lt; 2) and "
            f"<b>{s['stack_ge3']}</b> the stack's own (reference &gt;= 3); proxy &minus; reference "
            f"&gt;= 1 on {s['differential_ge1']}. Reward: {html.escape(str(settings.get('reward', 'proxy')))}. "
            f"Collisions (the paper's proxy does not score them): <b>{s['perception_collisions']}</b> "
            f"the perception's (the reference stack drove through the same scene), "
            f"<b>{s['stack_collisions']}</b> the stack's (the reference collided too).</p>"
        )
    attribution += _three_stack_html(store, store_path, campaign, s, out_dir, top)
    baseline = _baseline_html(c["experiment"])
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(campaign)}</title>
<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;
padding:4px 8px;text-align:right}}code{{font-size:85%}}</style></head><body>
<h1>Campaign {html.escape(campaign)}</h1>
<p>method <b>{html.escape(c['method'])}</b>, experiment <b>{html.escape(c['experiment'])}</b>, seed {c['seed']},
stack: {html.escape(_stack_words(settings))},
workers {html.escape(', '.join(settings.get('workers', [])))}; store <code>{html.escape(store_path)}</code></p>
<h2>Counts (as in the paper's Table 2)</h2>
<table><tr><th>scenarios</th><th>proxy &gt;= 3</th><th>proxy &gt;= 4</th><th>per 1,000: &gt;= 3 / &gt;= 4</th><th>largest proxy</th></tr>
<tr><td>{s['scenarios']}</td><td>{s['proxy_ge_3']}</td><td>{s['proxy_ge_4']}</td>
<td>{1000 * s['proxy_ge_3'] / n:.0f} / {1000 * s['proxy_ge_4'] / n:.0f}</td><td>{best}</td></tr></table>
{attribution}{baseline}
<h2>Proxy over the campaign</h2><img src="curves.png" width="900">
<h2>Terminations</h2><table>{terms}</table>
<h2>Top {len(items)}</h2>
<table><tr><th>job</th><th>store id</th><th>episode.step</th><th>proxy</th><th>vis</th><th>yaw term</th><th>PLR</th>
<th>termination</th><th>top-down</th><th>replay</th></tr>{''.join(items)}</table>
</body></html>"""
    path = os.path.join(out_dir, "index.html")
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    return path


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_agent.analysis.report", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("snapshot")
    a.add_argument("bag")
    a.add_argument("out")
    a.add_argument("--time", type=float, required=True, help="[s] simulated time of the snapshot")
    a.add_argument("--ns", default="worker_0")
    b = sub.add_parser("campaign")
    b.add_argument("store")
    b.add_argument("campaign")
    b.add_argument("out_dir")
    b.add_argument("--top", type=int, default=10)
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
        elif args.cmd == "perception":
            r = perception_replay(args.store, args.campaign, args.job, args.out, args.work)
            print(f"{args.out} (bags: {', '.join(r['bags'].values())})")
        else:
            print(campaign_report(args.store, args.campaign, args.out_dir, args.top))
    except (ValueError, OSError) as e:
        print(f"report: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

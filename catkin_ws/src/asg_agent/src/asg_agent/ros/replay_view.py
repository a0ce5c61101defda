"""Screenshot of a replay bag in rviz without a display (Xvfb), and the pixel check the tests use.

    python3 -m asg_agent.ros.replay_view RUN.bag OUT.png [--ns NS] [--at 0.8]

Plays the bag into rviz with rviz/replay.rviz on a virtual display and grabs the screen when
the given fraction of the bag has played (default: the end). Needs a ROS master (roscore).
"""

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np


def rviz_config() -> str:
    """asg_bringup's rviz/replay.rviz (the repository's rviz/ folder, or its installed copy)."""
    import rospkg

    return os.path.join(rospkg.RosPack().get_path("asg_bringup"), "rviz", "replay.rviz")


def colour_counts(png: str) -> dict:
    """Pixels of the replay's colours: votes (yellow to red), current plan (green), driven
    trajectory (magenta), obstacles (dark green, dark red)."""
    from PIL import Image

    a = np.asarray(Image.open(png).convert("RGB")).astype(int)
    r, g, b = a[..., 0], a[..., 1], a[..., 2]
    return {
        "votes": int(((r > 180) & (b < 80) & (g > 40) & (r - g > 20)).sum() + ((r > 200) & (g > 200) & (b < 60)).sum()),
        "plan": int(((g > 200) & (r < 120) & (b < 100)).sum()),
        "trajectory": int(((r > 200) & (b > 200) & (g < 130)).sum()),
        "size": a.shape[0] * a.shape[1],
    }


def bag_namespace(topics) -> str:
    """The worker namespace of a replay bag: the first name of its planner's or worker's topics
    (/replay_worker/odom -> replay_worker). ValueError when the bag has none of them."""
    for t in sorted(topics):
        parts = t.strip("/").split("/")
        if len(parts) >= 2 and parts[1] in ("odom", "scenario", "camera"):
            return parts[0]
    raise ValueError("no worker topics (NS/odom, NS/scenario, NS/camera/...) in the bag: not a replay bag")


def screenshot(
    bag: str, out: str, ns: str = "", at: float = 1.0, display: str = ":71", size=(1280, 860), config: str = ""
) -> dict:
    """rviz on `bag` in the worker namespace `ns` (empty: the bag's own, bag_namespace), with the
    display configuration `config` (default rviz/replay.rviz)."""
    import rosbag
    from PIL import ImageGrab

    with rosbag.Bag(bag) as b:
        duration = b.get_end_time() - b.get_start_time()
        ns = ns or bag_namespace(b.get_type_and_topic_info().topics)
    xvfb = subprocess.Popen(
        ["Xvfb", display, "-screen", "0", f"{size[0]}x{size[1]}x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    procs = [xvfb]
    try:
        time.sleep(1.5)
        env = dict(os.environ, DISPLAY=display, LIBGL_ALWAYS_SOFTWARE="1")
        rviz = subprocess.Popen(
            # rviz/replay.rviz names its topics relative: rviz in the worker's namespace shows them
            [
                "rosrun",
                "rviz",
                "rviz",
                "-d",
                config or rviz_config(),
                f"/tf:=/{ns}/tf",
                f"/tf_static:=/{ns}/tf_static",
                "__name:=replay_view_rviz",
                f"__ns:=/{ns}",
            ],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=os.setsid,
        )
        procs.append(rviz)
        time.sleep(8.0)  # rviz up and subscribed
        # -d: wait after advertising, so that rviz is connected before the first messages (the
        # scene and the driven trajectory are published once, at the bag's start).
        delay = 3.0
        play = subprocess.Popen(
            ["rosbag", "play", "-d", str(delay), bag],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=os.setsid,
        )
        procs.append(play)
        if at >= 1.0:
            play.wait(timeout=duration * 3 + 60)
            time.sleep(2.0)
        else:
            time.sleep(delay + duration * at + 0.5)
            os.killpg(os.getpgid(play.pid), signal.SIGSTOP)  # hold the view at that moment
            time.sleep(2.0)
        ImageGrab.grab(xdisplay=display).save(out)
    finally:
        for p in reversed(procs):
            try:
                os.killpg(os.getpgid(p.pid), signal.SIGKILL) if p is not xvfb else p.kill()
            except (ProcessLookupError, PermissionError):
                pass
            p.wait()
    return colour_counts(out)


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_agent.ros.replay_view", description=__doc__.split("\n\n")[0])
    p.add_argument("bag")
    p.add_argument("out")
    p.add_argument("--ns", default="", help="the worker namespace in the bag (default: found in it)")
    p.add_argument("--at", type=float, default=1.0, help="fraction of the bag played when the picture is taken")
    p.add_argument(
        "--config",
        default="",
        help="rviz display configuration (default rviz/replay.rviz; rviz/replay_depth.rviz for a depth stack)",
    )
    a = p.parse_args(argv)
    if a.config and not os.path.isfile(a.config):
        print(f"replay_view: no rviz configuration {a.config}", file=sys.stderr)
        return 2
    if shutil.which("Xvfb") is None:
        print("replay_view: Xvfb is not installed (Debian package xvfb)", file=sys.stderr)
        return 2
    try:
        counts = screenshot(a.bag, a.out, a.ns, a.at, config=a.config)
    except ValueError as e:
        print(f"replay_view: {a.bag}: {e}", file=sys.stderr)
        return 2
    print(f"{a.out}: {counts}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

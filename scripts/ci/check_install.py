#!/usr/bin/python3
"""Test case: `catkin_make install` of the workspace succeeds and installs what users run.

Installs into WS/build/install_check (a throw-away prefix) and writes a JUnit XML file with one
test case, failed with the tail of the build log if the install fails or a file is missing."""

import os
import subprocess
import sys
import time
from xml.sax.saxutils import escape

EXPECTED = [
    "lib/asg_sim/scene_worker",
    "lib/asg_planner/planner",
    "lib/asg_perception/segmenter",
    "lib/asg_scenario/run_scenario",
    "share/asg_perception/models/flawed.pt",
    "share/asg_sim/config/scene_worker.yaml",
    "share/asg_planner/config/planner.yaml",
    "share/asg_msgs/msg/ScenarioInfo.msg",
    "lib/asg_agent/campaign",
    "share/asg_bringup/launch/train.launch",
    "share/asg_bringup/launch/worker.launch",
    "share/asg_bringup/rviz/replay.rviz",
    "share/asg_bringup/experiments/exp1.yaml",
    "share/asg_bringup/scenarios/exp1.yaml",
]


def main(ws, out):
    prefix = os.path.join(ws, "build", "install_check")
    t0 = time.time()
    # -C: catkin_make takes its base path from $PWD, not from the process's working directory.
    cmd = [
        "catkin_make",
        "-C",
        ws,
        "install",
        f"-DCMAKE_INSTALL_PREFIX={prefix}",
        "-DPYTHON_EXECUTABLE=/usr/bin/python3",
        "-j2",
    ]
    proc = subprocess.run(cmd, cwd=ws, capture_output=True, text=True)
    problem = ""
    if proc.returncode != 0:
        problem = f"catkin_make install exited {proc.returncode}:\n" + (proc.stdout + proc.stderr)[-4000:]
    else:
        missing = [p for p in EXPECTED if not os.path.exists(os.path.join(prefix, p))]
        if missing:
            problem = "not installed: " + ", ".join(missing)
    # Back to the devel-space install prefix, so later builds do not install here.
    subprocess.run(
        ["catkin_make", "-C", ws, "-DCMAKE_INSTALL_PREFIX=" + os.path.join(ws, "install"), "-j2"],
        cwd=ws,
        capture_output=True,
    )
    body = f'<failure message="install failed">{escape(problem)}</failure>' if problem else ""
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        f.write(
            f'<?xml version="1.0"?>\n<testsuite name="install" tests="1" failures="{int(bool(problem))}">'
            f'<testcase classname="install" name="catkin_make_install" time="{time.time() - t0:.1f}">'
            f"{body}</testcase></testsuite>\n"
        )
    print("install: " + ("FAILED " + problem.splitlines()[0] if problem else "ok"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))

"""Issue #26: an installed workspace runs a campaign and replays its top scenario, with nothing
from the source tree. Uses the install prefix that scripts/ci/check_install.py made
(catkin_ws/build/install_check; made here if missing), sources only its setup.bash in a clean
environment, works in an empty folder: `roslaunch asg_bringup train.launch` brings up two
workers with the flawed U-Net (no attribution, to save time), the campaign runs 20 scenarios
with the command line the launch file gives it, and `asg_agent.ros.replay` replays the top one on
a worker it brings up itself through asg_bringup's worker.launch."""

import os
import sqlite3
import subprocess
import textwrap

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
WS = os.path.join(REPO, "catkin_ws")
PREFIX = os.path.join(WS, "build", "install_check")


def test_an_installed_workspace_runs_a_campaign_and_replays_its_top_scenario(tmp_path):
    if not os.path.isfile(os.path.join(PREFIX, "setup.bash")):
        subprocess.run(
            [
                "/usr/bin/python3",
                os.path.join(REPO, "scripts", "ci", "check_install.py"),
                WS,
                str(tmp_path / "install.xml"),
            ],
            check=True,
            timeout=1800,
        )
    store = tmp_path / "campaign.sqlite"
    # The U-Net backend the end-to-end tests run on this CPU (scripts/test.sh), and its experiment.
    from asg_perception.numerics import DEFAULT_BACKEND

    backend = os.environ.get("ASG_TEST_UNET_BACKEND") or DEFAULT_BACKEND
    experiment = "exp1.yaml" if backend == DEFAULT_BACKEND else "exp1-channels-last.yaml"
    stack = f"unet_backend:={backend} experiment:={PREFIX}/share/asg_bringup/experiments/{experiment}"
    script = textwrap.dedent(f"""\
        set -e
        source {PREFIX}/setup.bash
        export ROS_MASTER_URI=http://127.0.0.1:11431 ROS_HOSTNAME=127.0.0.1 LP_NUM_THREADS=1 ROS_LOG_DIR={tmp_path}/log
        echo "bringup: $(rospack find asg_bringup)"
        echo "agent: $(/usr/bin/python3 -c 'import asg_agent, os; print(os.path.dirname(asg_agent.__file__))')"
        roslaunch -p 11431 asg_bringup train.launch campaign:=false attribution:=false {stack} > {tmp_path}/launch.log 2>&1 &
        LAUNCH=$!
        trap 'kill -INT $LAUNCH; wait $LAUNCH' EXIT
        read -ra CMD < <(roslaunch --args /campaign asg_bringup train.launch scenarios:=20 attribution:=false {stack} \\
            store:={store} name:=installed seed:=2 extra:=--no-progress)
        for _ in $(seq 60); do rosparam get /run_id > /dev/null 2>&1 && break; sleep 0.5; done
        "${{CMD[@]}}"
        """)
    env = {"HOME": os.environ.get("HOME", "/root"), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"}
    p = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert f"bringup: {PREFIX}/share/asg_bringup" in p.stdout
    assert f"agent: {PREFIX}/lib/python3/dist-packages/asg_agent" in p.stdout
    assert "campaign installed: 20 scenarios" in p.stdout
    db = sqlite3.connect(str(store))
    job, settings = db.execute(
        "SELECT s.job, c.settings FROM scenarios s JOIN campaigns c ON c.name = s.campaign "
        "WHERE s.proxy IS NOT NULL ORDER BY s.proxy DESC LIMIT 1"
    ).fetchone()
    assert f"{PREFIX}/share/asg_bringup/experiments/{experiment}" in settings
    replay = textwrap.dedent(f"""\
        source {PREFIX}/setup.bash
        export ROS_HOSTNAME=127.0.0.1 LP_NUM_THREADS=1 ROS_LOG_DIR={tmp_path}/log
        /usr/bin/python3 -m asg_agent.ros.replay {store} installed {job} --port 11432
        """)
    p = subprocess.run(["bash", "-c", replay], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert "REPRODUCED" in p.stdout and "0.000000 m" in p.stdout

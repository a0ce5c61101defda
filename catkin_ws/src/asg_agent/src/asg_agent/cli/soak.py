"""Soak (issue #14): a long campaign while scene workers, stack nodes and the agent itself are
killed with SIGKILL at random moments (scripts/repro/soak.sh is its wrapper).

Two workers with the flawed U-Net run the campaign; `--reference 2` adds two ground-truth
reference workers (every scenario attributed), `--reference three` the three-stack attribution of
issue #36 (worker_2 the unflawed `full` U-Net, worker_3 ground truth, candidates re-run on both).
Leg 1 lasts HOURS: a killer sends SIGKILL every MIN_GAP..MAX_GAP seconds to one victim drawn at
random (a scene worker, a planner, a segmenter on a worker that has one, or the agent);
worker.launch respawns the nodes and the agent is restarted with --resume whenever it dies. When
the time is up the killer stops and the agent is killed a last time. Leg 2 resumes it with its
budget cut to the scenarios it has begun, so the campaign drains and finishes. Then every scenario
0..N-1 must be stored exactly once (asg_agent.campaign.soak_check).

    python3 -m asg_agent.cli.soak [--hours 2] [--gaps 60 240] [--method random] [--seed 1]
        [--experiment exp1] [--reference 0|N|three] [--extra "--bc-weight 1.0"]
"""

import argparse
import os
import random
import shlex
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from typing import Callable, List, Optional

from asg_agent.paths import REPO

BIG = 1_000_000  # the budget while the kills go on: the clock, not the count, ends leg 1
KINDS = ("scene_worker", "planner", "segmenter")


@dataclass(frozen=True)
class Victims:
    workers: int  # worker_0 .. worker_{workers-1}
    segmented: int  # the workers below this index run a segmenter

    def draw(self, rng: random.Random) -> str:
        """One victim: a node's name, or "agent". Each kind a quarter of the draws; a segmenter
        drawn on a worker without one becomes its scene worker or planner."""
        w = rng.randrange(self.workers)
        kind = rng.randrange(4)
        if kind == 3:
            return "agent"
        if kind == 2 and w >= self.segmented:
            kind = rng.randrange(2)
        return f"/worker_{w}/{KINDS[kind]}"


def node_pid(node: str) -> Optional[int]:
    """The PID of a ROS node, from the master's record of it (None when it is not up)."""
    import xmlrpc.client

    import rosgraph

    try:
        uri = rosgraph.Master("/soak").lookupNode(node)
        return int(xmlrpc.client.ServerProxy(uri).getPid("/soak")[2])
    except Exception:  # not registered, or gone between the lookup and the call
        return None


class Killer(threading.Thread):
    """Every gap (drawn in [lo, hi] seconds) one victim gets SIGKILL; each kill is a log line
    `UNIX_TIME VICTIM PID`."""

    def __init__(
        self,
        victims: Victims,
        gaps,
        agent_pid: Callable[[], Optional[int]],
        log_path: str,
        seed: Optional[int] = None,
        lookup: Callable[[str], Optional[int]] = node_pid,
        kill: Callable[[int, int], None] = os.kill,
    ):
        super().__init__(daemon=True)
        self.victims, self.gaps, self.agent_pid, self.log_path = victims, gaps, agent_pid, log_path
        self.rng, self.lookup, self.kill = random.Random(seed), lookup, kill
        self.stopped = threading.Event()

    def stop(self):
        self.stopped.set()

    def run(self):
        lo, hi = self.gaps
        while not self.stopped.wait(self.rng.uniform(lo, hi)):
            victim = self.victims.draw(self.rng)
            pid = self.agent_pid() if victim == "agent" else self.lookup(victim)
            if pid is None:
                continue
            try:
                self.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                continue
            with open(self.log_path, "a", encoding="utf-8") as f:
                f.write(f"{int(time.time())} {victim} {pid}\n")


class Agent:
    """The campaign process of the soak: started, watched and killed by its Popen, not by name."""

    def __init__(self, command: Callable[[int, bool], List[str]], log_path: str):
        self.command, self.log_path, self.proc = command, log_path, None

    def start(self, budget: int, resume: bool) -> subprocess.Popen:
        with open(self.log_path, "a", encoding="utf-8") as log:
            self.proc = subprocess.Popen(self.command(budget, resume), stdout=log, stderr=subprocess.STDOUT)
        return self.proc

    def pid(self) -> Optional[int]:
        return self.proc.pid if self.proc is not None and self.proc.poll() is None else None

    def note(self, line: str):
        with open(self.log_path, "a", encoding="utf-8") as f:
            f.write(f"{int(time.time())} {line}\n")


def leg_one(agent: Agent, killer: Killer, deadline: float, resume: bool, kills_log: str, poll_s: float = 2.0):
    """Kills until the deadline; the agent restarted with --resume whenever it dies. At the
    deadline the killer stops and the agent is killed a last time."""
    killer.start()
    while time.time() < deadline:
        p = agent.start(BIG, resume)
        while p.poll() is None and time.time() < deadline:
            time.sleep(poll_s)
        if p.poll() is None:
            killer.stop()
            p.kill()
            with open(kills_log, "a", encoding="utf-8") as f:
                f.write(f"{int(time.time())} agent-final {p.pid}\n")
        p.wait()
        agent.note("agent exited: restarting with --resume")
        resume = True
    killer.stop()
    killer.join()


def leg_two(agent: Agent, budget: int, retry_s: float = 1.0):
    """No more kills: the budget cut to the scenarios begun, resumed until the campaign finishes."""
    agent.note(f"draining: budget cut to {budget} scenarios")
    while agent.start(budget, True).wait() != 0:
        time.sleep(retry_s)


def main(argv=None) -> int:
    from asg_agent.campaign import soak_check
    from asg_agent.records.store import Store

    p = argparse.ArgumentParser(prog="asg_agent.cli.soak", description=__doc__.split("\n\n")[0])
    p.add_argument("--hours", type=float, default=2.0, help="[h] length of leg 1 (the kills)")
    p.add_argument("--gaps", type=float, nargs=2, default=(60.0, 240.0), help="[s] least and most time between kills")
    p.add_argument("--method", default="random")
    p.add_argument("--seed", type=int, default=1, help="the campaign's seed (the killer's is the clock's)")
    p.add_argument("--experiment", default="exp1", help="a file of experiments/ without .yaml")
    p.add_argument("--reference", default="0", help="0, a count of ground-truth reference workers, or three")
    p.add_argument("--extra", default="", help="more campaign options, one string")
    p.add_argument("--store", default=os.path.join(REPO, "results", "reliability", "soak.sqlite"))
    p.add_argument("--port", type=int, default=11395, help="the soak's own ROS master port")
    a = p.parse_args(argv)
    if not a.gaps[0] <= a.gaps[1]:
        p.error(f"--gaps {a.gaps[0]:g} {a.gaps[1]:g}: the least gap exceeds the most")
    if a.reference != "three" and not a.reference.isdigit():
        p.error(f"--reference {a.reference}: must be 0, a count of workers, or three")
    runs = os.path.join(REPO, "runs", "soak")
    out = os.path.join(REPO, "results", "reliability")
    os.makedirs(os.path.join(runs, "logs"), exist_ok=True)
    os.makedirs(out, exist_ok=True)
    os.environ.update(
        ROS_MASTER_URI=f"http://127.0.0.1:{a.port}",
        ROS_HOSTNAME="127.0.0.1",
        ROS_IP="127.0.0.1",
        LP_NUM_THREADS="1",
        ROS_LOG_DIR=os.path.join(runs, "logs"),
    )
    name = f"soak-{a.experiment}-{a.method}-s{a.seed}"
    kills_log, agent_log = os.path.join(runs, "kills.log"), os.path.join(runs, "agent.log")
    for path in (kills_log, agent_log):
        open(path, "w").close()
    launch = os.path.join(REPO, "launch", "worker.launch")
    stacks = [["perception:=unet"], ["perception:=unet"]]
    ref_args, segmented = [], 2
    if a.reference == "three":
        stacks += [["perception:=unet", "model:=full"], ["perception:=ground_truth"]]
        ref_args, segmented = ["--reference", "full=1", "--reference", "ground_truth=1"], 3
    elif int(a.reference) > 0:
        stacks += [["perception:=ground_truth"]] * int(a.reference)
        ref_args = ["--reference-workers", a.reference]
    procs = [subprocess.Popen(["roscore", "-p", str(a.port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        time.sleep(3)
        for w, args in enumerate(stacks):
            cmd = ["roslaunch", launch, f"ns:=worker_{w}", "markers:=false", *args]
            procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))

        def command(budget: int, resume: bool) -> List[str]:
            cmd = [
                sys.executable,
                "-m",
                "asg_agent.cli.campaign",
                os.path.join(REPO, "experiments", a.experiment + ".yaml"),
            ]
            cmd += ["--workers", "2", "--method", a.method, "--seed", str(a.seed), "--scenarios", str(budget)]
            cmd += ["--store", a.store, "--name", name, "--no-progress", *ref_args, *shlex.split(a.extra)]
            return cmd + (["--resume"] if resume else [])

        agent = Agent(command, agent_log)
        killer = Killer(Victims(len(stacks), segmented), a.gaps, agent.pid, kills_log)
        resume = os.path.isfile(a.store) and Store(a.store).campaign(name) is not None
        start = time.time()
        leg_one(agent, killer, start + a.hours * 3600.0, resume, kills_log)
        budget = max(Store(a.store).jobs(name)) + 1
        leg_two(agent, budget)
        res = soak_check.report(a.store, name, budget, kills_log, agent_log, start, time.time())
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
    import json

    with open(os.path.join(out, "soak.json"), "w", encoding="utf-8") as f:
        json.dump(res, f, indent=1)
    print(json.dumps(res, indent=1))
    return 0 if soak_check.passed(res) else 1


if __name__ == "__main__":
    sys.exit(main())

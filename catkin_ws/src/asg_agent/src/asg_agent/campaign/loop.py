"""The campaign loop (no ROS imports): proposals to free workers, results back in any order,
applied in proposal order, every scenario stored as it finishes, checkpoints, resume.

W = `slots` episodes run side by side (one per slot). Job j belongs to slot j mod W at first;
after a job's result is applied, its slot's next proposal becomes the next job. Results are
applied strictly in job order (a result that arrives early waits), so the method sees the same
sequence whatever the workers' speeds: a campaign is a function of its experiment, method and
seed. With W larger than the number of workers a free worker always finds a proposal waiting.

Resume: a checkpoint (written atomically at episode ends) holds the method (networks,
optimisers, replay buffer, generators), the slots and the proposals not yet applied. `resume`
loads it and applies, in job order, the results already in the store after it (the same
computation the interrupted run did), then submits what is missing. No scenario is run for
nothing twice and none is stored twice (the store's (campaign, job) key).
"""

import json
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional

import numpy as np


from asg_agent.campaign.experiment import Experiment
from asg_agent.scoring.proxy import ProxyConfig, run_terms
from asg_agent.search.methods import SearchMethod
from asg_agent.campaign.store import Store, attribute, pack_trajectory, unpack_trajectory
from asg_agent.search.td3 import load_checked, save_atomic


#: what a search can maximise (Campaign's `reward`, the campaign's --reward)
REWARDS = ("proxy", "differential", "collision")


def collision_reward(proxy: float, termination: str, reference_termination: Optional[str], bonus: float) -> float:
    """The "collision" reward: the proxy, plus `bonus` [-] when the stack under test collided and
    the reference stack (where there is one) reached the goal on the same scene: a perception
    collision as every count of the project defines it, which the proxy alone scores like any
    run that ended early."""
    collided = termination == "COLLISION" and reference_termination in (None, "SUCCESS")
    return proxy + (bonus if collided else 0.0)


class Stages:
    """Wall seconds and calls per stage of the campaign loop (docs/benchmarks.md: `bench`)."""

    NAMES = ("propose", "update", "proxy", "store", "checkpoint", "dispatch", "wait")

    def __init__(self):
        self.seconds = {n: 0.0 for n in self.NAMES}
        self.calls = {n: 0 for n in self.NAMES}

    def add(self, name: str, t0: float):
        self.seconds[name] += time.perf_counter() - t0
        self.calls[name] += 1


def kept_xy(trajectory) -> list:
    """The positions attribution stores of a reference run: every 6th sample (10 Hz), to 1 cm."""
    return np.round(np.asarray(trajectory, np.float32).reshape(-1, 5)[::6, 1:3], 2).tolist()


@dataclass
class Outcome:
    """What a pool returns for a job: the result as plain values."""

    job: int
    worker: str
    termination: str
    error: str = ""
    sim_time: float = 0.0
    num_control_msgs: int = 0
    trajectory: np.ndarray = field(default_factory=lambda: np.zeros((0, 5), np.float32))  # t, x, y, yaw, yaw rate
    visibility: List[float] = field(default_factory=list)
    removed: List[list] = field(default_factory=list)  # [layout, instance, reason]
    collision_with: str = ""
    wall_time: float = 0.0


class Pool:
    """Workers that run scenario requests (the ROS adapter is pool_ros.WorkerPool)."""

    def free(self) -> List[str]:
        raise NotImplementedError

    def submit(self, worker: str, job: int, request: dict):
        raise NotImplementedError

    def poll(self, timeout: float) -> List[Outcome]:
        raise NotImplementedError


@dataclass
class Job:
    job: int
    slot: int
    episode: int
    step: int
    state: np.ndarray
    action: np.ndarray
    request: dict
    attempts: int = 0
    avoid: str = ""  # the worker that failed it last
    ref_attempts: int = 0  # differential campaigns: the same on the reference stack
    ref_avoid: str = ""


class Campaign:
    def __init__(
        self,
        name: str,
        experiment: Experiment,
        method: SearchMethod,
        store: Store,
        pool: Pool,
        total: int,
        seed: int,
        checkpoint: str,
        slots: int = 4,
        max_attempts: int = 3,
        checkpoint_every: int = 10,
        proxy_config: ProxyConfig = ProxyConfig(),
        progress: Optional[Callable[[dict], None]] = None,
        settings: Optional[dict] = None,
        early_dispatch: bool = True,
        reference: Optional[Pool] = None,
        reward: str = "proxy",
        collision_bonus: float = 2.0,
        scalars: Optional[Callable[[int, dict, dict], None]] = None,
    ):
        if total < 1 or slots < 1:
            raise ValueError("total and slots must be >= 1")
        self.name, self.exp, self.method, self.store, self.pool = name, experiment, method, store, pool
        self.total, self.seed, self.checkpoint_path, self.slots = total, seed, checkpoint, slots
        self.max_attempts, self.checkpoint_every, self.proxy_config = max_attempts, checkpoint_every, proxy_config
        self.progress, self.settings = progress, settings or {}
        # scalars(job, stored row, the method's update figures): called once per scenario as the
        # search learns from it, in job order (tensorboard_log.TensorBoardLog.scenario).
        self.scalars = scalars
        self.early_dispatch = early_dispatch  # dispatch to freed workers before applying results
        # Attribution: every scenario also runs on the reference stack's workers (ground-truth
        # labels, the same planner and follower), and each finding is counted as the perception's
        # (reference < 2) or the stack's (reference >= 3). reward "proxy": the search learns from
        # the stack under test's proxy (the paper); "differential": from proxy - reference proxy;
        # "collision": the proxy plus `collision_bonus` [-] when the stack under test collided
        # (with a reference stack: only where the reference reached the goal), since the proxy itself
        # scores a collision like any short run (issue #27).
        if reward not in REWARDS:
            raise ValueError(f"reward {reward!r}: must be one of {', '.join(REWARDS)}")
        if reward == "differential" and reference is None:
            raise ValueError("the differential reward needs a reference stack")
        if not (math.isfinite(collision_bonus) and collision_bonus >= 0.0):
            raise ValueError(f"collision_bonus {collision_bonus!r}: must be a finite number >= 0")
        self.reference, self.reward, self.collision_bonus = reference, reward, float(collision_bonus)
        self.ref_queue: List[int] = []
        self.ref_running: Dict[int, str] = {}
        self.parts: Dict[int, Dict[str, Outcome]] = {}  # job -> {"test": .., "ref": ..} until both are in
        self.pending: Dict[int, Job] = {}  # proposed, not applied
        self.finished: Dict[int, dict] = {}  # stored rows waiting for their turn to be applied
        self.queue: List[int] = []  # proposed jobs waiting for a worker
        self.running: Dict[int, str] = {}
        self.slot_state: List[Optional[dict]] = [None] * slots
        self.next_job = 0
        self.next_apply = 0
        self.next_episode = 0
        self.episodes_done = 0
        # best/ge3/ge4: the proxy of the stack under test; diff_best/diff_ge1: differential
        # campaigns' reward (proxy - reference proxy), its largest and how often it reached 1.
        # perception/stack: findings (proxy >= 3) with the reference below 2 / at least 3.
        self.stats = {
            "best": -math.inf,
            "ge3": 0,
            "ge4": 0,
            "errors": 0,
            "retries": 0,
            "diff_best": -math.inf,
            "diff_ge1": 0,
            "perception": 0,
            "stack": 0,
        }
        self.t0 = time.time()
        self.done_at_start = 0
        self.stages = Stages()

    # -- setup ----------------------------------------------------------------------------------
    def start(self):
        self.store.create_campaign(
            self.name,
            self.method.name,
            self.exp.name,
            self.exp.text,
            self.seed,
            dict(self.settings, total=self.total, slots=self.slots, method_config=self.method.config()),
        )
        for s in range(self.slots):
            self._new_episode(s)
        for s in range(self.slots):
            self._propose(s)

    def resume(self):
        if self.store.campaign(self.name) is None:
            raise ValueError(f"no campaign {self.name!r} in {self.store.path} to resume")
        try:
            ck = load_checked(self.checkpoint_path)
        except FileNotFoundError:
            ck = None
        if ck is None:  # killed before the first checkpoint: start over from the stored rows
            for s in range(self.slots):
                self._new_episode(s)
            for s in range(self.slots):
                self._propose(s)
        else:
            self.method.load_state_dict(ck["method"])
            for key in ("next_job", "next_apply", "next_episode", "episodes_done"):
                setattr(self, key, ck[key])
            self.stats.update(ck["stats"])  # checkpoints older than a stats key keep its default
            self.slot_state = ck["slot_state"]
            self.pending = {j["job"]: Job(**j) for j in ck["pending"]}
            # A resume may cut the budget (the soak ends its campaign that way): proposals at or
            # past the new total are dropped, never run.
            for j in [j for j in self.pending if j >= self.total]:
                del self.pending[j]
            self.next_job = min(self.next_job, max(self.total, self.next_apply))
            self.queue = sorted(self.pending)
            self.ref_queue = sorted(self.pending) if self.reference is not None else []
            # A resume may also raise the budget of a finished (or cut) campaign: slots left
            # without a proposal by the old budget propose again, in slot order. The extension
            # is deterministic given the stored history (not the same scenarios a campaign run
            # at the larger budget from the start would have proposed).
            busy = {j.slot for j in self.pending.values()}
            for s in range(self.slots):
                if s not in busy:
                    self._propose(s)
        # Results stored after the checkpoint are applied as the interrupted run applied them.
        for row in self.store.rows(self.name, self.next_apply - 1):
            self.finished[row["job"]] = dict(row)
            if row["job"] in self.queue:
                self.queue.remove(row["job"])
            if row["job"] in self.ref_queue:
                self.ref_queue.remove(row["job"])
        self.done_at_start = self.store.count(self.name)
        summary = self.store.summary(self.name, top=0)
        self.stats.update(
            best=summary["max_proxy"] if summary["max_proxy"] is not None else -math.inf,
            ge3=summary["proxy_ge_3"],
            ge4=summary["proxy_ge_4"],
            errors=summary["terminations"].get("ERROR", 0),
            perception=summary["perception_ge3"],
            stack=summary["stack_ge3"],
            diff_ge1=summary["differential_ge1"],
        )
        self._apply_ready()

    # -- episodes and proposals -----------------------------------------------------------------
    def _new_episode(self, slot: int):
        ep = self.next_episode
        self.next_episode += 1
        self.slot_state[slot] = {"episode": ep, "step": 0, "state": self.method.initial_state(ep)}

    def _propose(self, slot: int):
        if self.next_job >= self.total:
            return
        st = self.slot_state[slot]
        j = self.next_job
        self.next_job += 1
        t0 = time.perf_counter()
        action = np.asarray(self.method.propose(j, st["episode"], st["step"], st["state"]), np.float32)
        request = self.exp.request(action, scenario_id=j + 1)
        self.stages.add("propose", t0)
        self.pending[j] = Job(j, slot, st["episode"], st["step"], st["state"], action, request)
        if j not in self.finished:
            self.queue.append(j)
            if self.reference is not None:
                self.ref_queue.append(j)

    # -- the loop -------------------------------------------------------------------------------
    def run(self, poll_timeout: float = 0.2, deadline: Optional[float] = None) -> dict:
        while self.next_apply < self.total:
            if deadline is not None and time.time() > deadline:
                break
            t0 = time.perf_counter()
            self._dispatch()
            self.stages.add("dispatch", t0)
            t0 = time.perf_counter()
            outcomes = self.pool.poll(poll_timeout)
            self.stages.add("wait", t0)
            for outcome in outcomes:
                self._on_outcome(outcome, "test")
            if self.reference is not None:
                ref = self.reference.poll(0.0)
                for outcome in ref:
                    self._on_outcome(outcome, "ref")
                outcomes = outcomes + ref
            if outcomes and self.early_dispatch:  # freed workers get a waiting proposal before the agent learns
                t0 = time.perf_counter()
                self._dispatch()
                self.stages.add("dispatch", t0)
            self._apply_ready()
        if self.next_apply >= self.total:
            self._checkpoint()
            if self.store.count(self.name) > self.done_at_start or self.store.campaign(self.name)["finished"] is None:
                self.store.finish_campaign(self.name)  # a resumed finished campaign keeps its time
        return self.store.summary(self.name)

    def _dispatch(self):
        self._dispatch_part(self.pool, self.queue, self.running, "attempts", "avoid")
        if self.reference is not None:
            self._dispatch_part(self.reference, self.ref_queue, self.ref_running, "ref_attempts", "ref_avoid")

    def _dispatch_part(self, pool, queue, running, attempts, avoid):
        free = pool.free()
        for worker in free:
            pick = None
            for j in queue:
                if getattr(self.pending[j], avoid) != worker or len(free) == 1:
                    pick = j
                    break
            if pick is None:
                continue
            queue.remove(pick)
            job = self.pending[pick]
            setattr(job, attempts, getattr(job, attempts) + 1)
            running[pick] = worker
            pool.submit(worker, pick, job.request)

    def _on_outcome(self, o: Outcome, part: str = "test"):
        job = self.pending.get(o.job)
        running = self.running if part == "test" else self.ref_running
        if job is None or running.get(o.job) != o.worker:
            return  # a late answer for a job already re-queued elsewhere: never counted twice
        del running[o.job]
        attempts = job.attempts if part == "test" else job.ref_attempts
        if o.termination == "ERROR" and attempts < self.max_attempts:
            self.stats["retries"] += 1
            if part == "test":
                job.avoid = o.worker
                self.queue.insert(0, o.job)
            else:
                job.ref_avoid = o.worker
                self.ref_queue.insert(0, o.job)
            print(f"[campaign] job {o.job} failed on {o.worker} ({o.error}); retrying elsewhere", file=sys.stderr)
            return
        if self.reference is None:
            return self._finish(job, o, None)
        got = self.parts.setdefault(o.job, {})
        got[part] = o
        if len(got) == 2:
            del self.parts[o.job]
            self._finish(job, got["test"], got["ref"])

    def _terms(self, request, o: Outcome):
        return run_terms(request, o, self.proxy_config)

    def _finish(self, job: Job, o: Outcome, ref: Optional[Outcome]):
        t0 = time.perf_counter()
        traj, terms = self._terms(job.request, o)
        reference, reward, diff = None, (terms.proxy if terms else None), None
        if ref is not None:
            _, rterms = self._terms(job.request, ref)
            reference = json.dumps(
                {
                    "worker": ref.worker,
                    "attempts": job.ref_attempts,
                    "termination": ref.termination,
                    "error": ref.error,
                    "proxy": rterms.proxy if rterms else None,
                    "vis": rterms.vis if rterms else None,
                    "yaw_term": rterms.yaw_term if rterms else None,
                    "plr": rterms.plr if rterms else None,
                    "sim_time": ref.sim_time,
                    "trajectory_xy": kept_xy(ref.trajectory),
                },
                sort_keys=True,
            )
            diff = terms.proxy - rterms.proxy if terms and rterms else None
            if self.reward == "differential":
                reward = diff
        if self.reward == "collision" and terms:
            reward = collision_reward(
                terms.proxy, o.termination, ref.termination if ref else None, self.collision_bonus
            )
        row = {
            "campaign": self.name,
            "job": o.job,
            "method": self.method.name,
            "episode": job.episode,
            "step": job.step,
            "worker": o.worker,
            "attempts": job.attempts,
            "scenario_id": job.request["scenario_id"],
            "request": json.dumps(job.request, sort_keys=True),
            "termination": o.termination,
            "error": o.error,
            "proxy": terms.proxy if terms else None,
            "vis": terms.vis if terms else None,
            "yaw_term": terms.yaw_term if terms else None,
            "plr": terms.plr if terms else None,
            "path_length": terms.path_length if terms else None,
            "optimal_length": terms.optimal_length if terms else None,
            "sim_time": o.sim_time,
            "num_control_msgs": o.num_control_msgs,
            "visibility": json.dumps([float(v) for v in o.visibility]),
            "removed": json.dumps(o.removed),
            "collision_with": o.collision_with,
            "trajectory": pack_trajectory(traj),
            "samples": len(traj),
            "wall_time": o.wall_time,
            "finished": time.time(),
            "reference": reference,
            "reward": reward,
        }
        self.stages.add("proxy", t0)
        t0 = time.perf_counter()
        self.store.add(row)
        self.stages.add("store", t0)
        self.finished[o.job] = row
        if terms and reward is not None:
            self.stats["best"] = max(self.stats["best"], terms.proxy)
            self.stats["ge3"] += terms.proxy >= 3
            self.stats["ge4"] += terms.proxy >= 4
            if self.reference is not None and diff is not None:
                self.stats["diff_best"] = max(self.stats["diff_best"], diff)
                self.stats["diff_ge1"] += diff >= 1
                _, perception, stack = attribute(terms.proxy, rterms.proxy)
                self.stats["perception"] += perception
                self.stats["stack"] += stack
        else:
            self.stats["errors"] += 1
        if self.progress:
            self.progress(self.status())

    def _apply_ready(self):
        while self.next_apply in self.finished:
            row = self.finished.pop(self.next_apply)
            job = self.pending.pop(self.next_apply)
            self.next_apply += 1
            slot = self.slot_state[job.slot]
            done = job.step >= self.exp.episode_steps - 1
            # (rows of campaigns older than the reward column learnt from the proxy)
            reward = row["reward"] if self.reference is not None or self.reward != "proxy" else row["proxy"]
            learnt = None
            if reward is None:  # ERROR after every attempt: no transition, the episode ends here
                self.method.observe(job.job, job.episode, job.step, job.state, job.action, None, None, True)
                done = True
            else:
                t0 = time.perf_counter()
                traj = unpack_trajectory(row["trajectory"])
                next_state = self.method.states.build(job.action, traj[:, 1:3], job.step + 1)
                learnt = self.method.observe(
                    job.job, job.episode, job.step, job.state, job.action, float(reward), next_state, done
                )
                self.stages.add("update", t0)
                if not done:
                    slot.update(step=job.step + 1, state=next_state)
            if self.scalars:
                self.scalars(job.job, row, learnt or {})
            if done:
                self.episodes_done += 1
                self._new_episode(job.slot)
            self._propose(job.slot)
            # At episode ends, once the slot's next proposal is made: the checkpoint then holds
            # every proposal not yet applied.
            if done and self.episodes_done % self.checkpoint_every == 0:
                self._checkpoint()

    def _checkpoint(self):
        t0 = time.perf_counter()
        self._write_checkpoint()
        self.stages.add("checkpoint", t0)

    def _write_checkpoint(self):
        pending = [
            dict(
                job=j.job,
                slot=j.slot,
                episode=j.episode,
                step=j.step,
                state=j.state,
                action=j.action,
                request=j.request,
                attempts=0,
                avoid="",
            )
            for j in self.pending.values()
        ]
        save_atomic(
            {
                "method": self.method.state_dict(),
                "next_job": self.next_job,
                "next_apply": self.next_apply,
                "next_episode": self.next_episode,
                "episodes_done": self.episodes_done,
                "stats": self.stats,
                "slot_state": self.slot_state,
                "pending": pending,
            },
            self.checkpoint_path,
        )

    def status(self) -> dict:
        stored = self.store.count(self.name)
        elapsed = max(1e-6, time.time() - self.t0)
        return {
            "done": stored,
            "total": self.total,
            "rate_per_hour": (stored - self.done_at_start) / elapsed * 3600,
            "best": self.stats["best"],
            "ge3": self.stats["ge3"],
            "ge4": self.stats["ge4"],
            "errors": self.stats["errors"],
            "retries": self.stats["retries"],
            "diff_best": self.stats["diff_best"] if self.reference is not None else None,
            "diff_ge1": self.stats["diff_ge1"] if self.reference is not None else None,
            "perception": self.stats["perception"] if self.reference is not None else None,
            "stack": self.stats["stack"] if self.reference is not None else None,
        }

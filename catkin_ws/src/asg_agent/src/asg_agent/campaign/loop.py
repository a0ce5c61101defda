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
import sys
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np


from asg_agent.campaign.policy import reference_setup
from asg_agent.campaign import tally
from asg_agent.campaign.tally import Stages
from asg_agent.campaign.config import Callbacks, CampaignConfig
from asg_agent.campaign.dispatch import Dispatcher, Outcome
from asg_agent.scoring.proxy import run_terms, term_values
from asg_agent.records.store import kept_xy, provenance, scenario_row, unpack_trajectory
from asg_agent.scoring import attribution as attr
from asg_agent.scoring import places, rewards
from asg_agent.search.td3 import load_checked, save_atomic


def run_place(request: dict, row: dict, xy) -> tuple:
    """The place (scoring/places.py) of a stored row of `request`: the obstacle it collided with,
    else where it ended (`xy` [m], its positions)."""
    from asg_agent.records.export import collision_index

    hit = collision_index(request, row["collision_with"]) if row["termination"] == "COLLISION" else None
    inst = [(l["mesh_name"], (i["x"], i["y"])) for l in request["structural"]["layouts"] for i in l["instances"]]
    return places.place([m for m, _ in inst], [p for _, p in inst], hit, xy)


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
    avoid: str = ""  # (kept for checkpoints: the dispatcher keeps a job's attempts and avoid)


@dataclass
class RefJob:
    """A candidate's runs on the reference stacks, until every role has answered."""

    job: int
    request: dict
    row: dict  # the stored row of the run on the stack under test
    got: Dict[str, dict] = field(default_factory=dict)  # role -> the reference run as stored


class Campaign:
    def __init__(self, config: CampaignConfig):
        c = config
        name, experiment, method, store, pool = c.name, c.experiment, c.method, c.store, c.pool
        total, seed, checkpoint, slots, max_attempts = c.total, c.seed, c.checkpoint, c.slots, c.max_attempts
        references, candidates, reward, collision_bonus = c.references, c.candidates, c.reward, c.collision_bonus
        self.config = c
        if total < 1 or slots < 1:
            raise ValueError("total and slots must be >= 1")
        self.name, self.exp, self.method, self.store, self.pool = name, experiment, method, store, pool
        self.total, self.seed, self.checkpoint_path, self.slots = total, seed, checkpoint, slots
        self.max_attempts, self.checkpoint_every, self.proxy_config = max_attempts, c.checkpoint_every, c.proxy_config
        self.settings = dict(c.settings or {})
        # the one way to follow it (campaign/config.py): progress, scenarios in job order, candidates' classes
        self.callbacks = Callbacks(c.callbacks)
        self.early_dispatch = c.early_dispatch  # dispatch to freed workers before applying results
        # Attribution (scoring/attribution.py): the scenarios the `candidates` rule picks run again
        # on each reference stack, keyed by role (ground truth alone with candidates "all": round 3's
        # single-reference mode). The reward is scoring/rewards.py's entry: one that reads the
        # references waits for them before the search learns (a function of the seed).
        references, candidates = reference_setup(reward, references, candidates, collision_bonus)
        self.references, self.candidates = references, candidates
        self.reward, self.collision_bonus = reward, float(collision_bonus)
        # The single-reference mode stores each row with its reference run, as round 3 did.
        self.rule = rewards.REGISTRY[reward]
        self.wait_for_references = bool(references) and (self.rule.waits or candidates == "all")
        self.ref_jobs: Dict[int, RefJob] = {}
        self.pending: Dict[int, Job] = {}  # proposed, not applied
        self.finished: Dict[int, dict] = {}  # stored rows waiting for their turn to be applied
        self.stored: set = set()  # jobs a resume found stored after its checkpoint
        # proposed jobs to the workers under test, each candidate to each reference stack
        self.jobs = Dispatcher(pool, max_attempts, self._retrying)
        self.refs = {role: Dispatcher(p, max_attempts, self._retrying_on(role)) for role, p in references.items()}
        self.slot_state: List[Optional[dict]] = [None] * slots
        self.next_job = 0
        self.next_apply = 0
        self.next_episode = 0
        self.episodes_done = 0
        self.stats = tally.new()  # campaign/tally.py
        self.atlas = c.atlas  # scoring.atlas.Atlas or None: the coverage the tally counts
        self.t0 = time.time()
        self.done_at_start = 0
        self.stages = Stages()

    def add_callback(self, callback) -> None:
        """Follow the campaign with one more CampaignCallback (campaign/config.py), e.g. TensorBoard
        once a resume has told it where to start."""
        self.callbacks.add(callback)

    # -- setup ----------------------------------------------------------------------------------
    def start(self):
        self.store.create_campaign(
            self.name,
            self.method.name,
            self.exp.name,
            self.exp.text,
            self.seed,
            # the reward as it ran (what its findings are: campaign/findings.py)
            dict(
                self.settings,
                total=self.total,
                slots=self.slots,
                method_config=self.method.config(),
                reward=self.reward,
            ),
        )
        self.store.record_event(self.name, dict(provenance(), kind="start", stored=0))
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
        # every interruption is on record: a resume from the checkpoint, or a restart without one
        self.store.record_event(
            self.name,
            dict(provenance(), kind="restart" if ck is None else "resume", stored=self.store.count(self.name)),
        )
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
            for j in sorted(self.pending):
                self.jobs.add(j, self.pending[j].request)
            # A resume may also raise the budget of a finished (or cut) campaign: slots left
            # without a proposal by the old budget propose again, in slot order. The extension
            # is deterministic given the stored history (not the same scenarios a campaign run
            # at the larger budget from the start would have proposed).
            busy = {j.slot for j in self.pending.values()}
            for s in range(self.slots):
                if s not in busy:
                    self._propose(s)
        # Results stored after the checkpoint are applied as the interrupted run applied them.
        # A candidate whose reference runs were still out when it stopped runs on them again; a
        # search that learns from the references waits for them, as the interrupted run did.
        waiting = set()
        if self.references:
            for row in self.store.pending_references(self.name):
                self._queue_references(dict(row))
                waiting.add(row["job"])
        for row in self.store.rows(self.name, self.next_apply - 1):
            self.stored.add(row["job"])  # never run again, even if proposed anew below
            if not (self.wait_for_references and row["job"] in waiting):
                self.finished[row["job"]] = dict(row)
            self.jobs.discard(row["job"])
        self.done_at_start = self.store.count(self.name)
        summary = self.store.summary(self.name, top=0)
        tally.from_summary(self.stats, summary)
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
        if j not in self.finished and j not in self.stored:  # a stored candidate awaits its references
            self.jobs.add(j, request)

    # -- the loop -------------------------------------------------------------------------------
    def run(self, poll_timeout: float = 0.2, deadline: Optional[float] = None) -> dict:
        while self.next_apply < self.total or self.ref_jobs:
            if deadline is not None and time.time() > deadline:
                break
            t0 = time.perf_counter()
            self._dispatch()
            self.stages.add("dispatch", t0)
            t0 = time.perf_counter()
            outcomes = self.pool.poll(poll_timeout if self.next_apply < self.total else 0.0)
            self.stages.add("wait", t0)
            for outcome in self.jobs.take(outcomes):
                job = self.pending[outcome.job]
                job.attempts = self.jobs.attempts[outcome.job]
                self._finish(job, outcome)
            for role, d in self.refs.items():
                ref = d.pool.poll(
                    0.0 if outcomes or self.next_apply < self.total else poll_timeout / len(self.references)
                )
                for outcome in d.take(ref):
                    self._on_ref_outcome(role, outcome)
                outcomes = outcomes + ref
            if outcomes and self.early_dispatch:  # freed workers get a waiting proposal before the agent learns
                t0 = time.perf_counter()
                self._dispatch()
                self.stages.add("dispatch", t0)
            self._apply_ready()
        if self.next_apply >= self.total and not self.ref_jobs:
            self._checkpoint()
            if self.store.count(self.name) > self.done_at_start or self.store.campaign(self.name)["finished"] is None:
                self.store.finish_campaign(self.name)  # a resumed finished campaign keeps its time
        return self.store.summary(self.name)

    def _dispatch(self):
        self.jobs.dispatch()
        for d in self.refs.values():
            d.dispatch()

    def _retrying(self, o: Outcome):
        self.stats["retries"] += 1
        print(f"[campaign] job {o.job} failed on {o.worker} ({o.error}); retrying elsewhere", file=sys.stderr)

    def _retrying_on(self, role: str):
        def retrying(o: Outcome):
            self.stats["retries"] += 1
            print(
                f"[campaign] job {o.job} failed on {o.worker} ({role} reference: {o.error}); retrying elsewhere",
                file=sys.stderr,
            )

        return retrying

    def _on_ref_outcome(self, role: str, o: Outcome):
        rj = self.ref_jobs.get(o.job)
        if rj is None:
            return
        _, terms = self._terms(rj.request, o)
        rj.got[role] = {
            "stack": role,
            "worker": o.worker,
            "attempts": self.refs[role].attempts.get(o.job, 0),
            "termination": o.termination,
            "error": o.error,
            **term_values(terms),
            "sim_time": o.sim_time,
            "collision_with": o.collision_with,
            "trajectory_xy": kept_xy(o.trajectory),
        }
        if set(rj.got) == set(self.references):
            self._attach(self.ref_jobs.pop(o.job))

    def _queue_references(self, row: dict):
        """Sends a stored candidate to every reference stack."""
        j = row["job"]
        self.ref_jobs[j] = RefJob(j, json.loads(row["request"]), row)
        for d in self.refs.values():
            d.attempts.pop(j, None)  # a candidate queued again on resume starts anew
            d.avoid.pop(j, None)
            d.add(j, self.ref_jobs[j].request)

    def _attach(self, rj: RefJob):
        """Every reference run of a candidate is in: its class, stored with the runs."""
        row = rj.row
        cls = attr.classify_rows(row, rj.got)
        truth = rj.got.get(attr.TRUTH)
        legacy = (
            json.dumps({k: v for k, v in truth.items() if k not in ("stack", "collision_with")}, sort_keys=True)
            if truth
            else None
        )
        proxy, tproxy = row["proxy"], (truth or {}).get("proxy")
        reward = row["reward"]
        if self.rule.attached is not None:  # a reward that reads the references (scoring/rewards.py)
            xy = unpack_trajectory(row["trajectory"])[:: rewards.SAMPLE_EVERY, 1:3]
            run = rewards.Run(proxy, row["termination"], rj.request, xy, json.loads(row["removed"]))
            reward = self.rule.attached(run, rj.got, cls, self.collision_bonus)
        t0 = time.perf_counter()
        self.store.set_references(self.name, rj.job, json.dumps(rj.got, sort_keys=True), cls, legacy, reward)
        self.stages.add("store", t0)
        tally.attributed(self.stats, cls, proxy, tproxy)
        if self.wait_for_references and rj.job >= self.next_apply:
            self.finished[rj.job] = dict(row, reward=reward, attribution=cls, reference=legacy)
        self.callbacks.on_attributed(rj.job, cls, dict(self.stats["classes"]))
        self.callbacks.on_progress(self.status())

    def _terms(self, request, o: Outcome):
        return run_terms(request, o, self.proxy_config)

    def _finish(self, job: Job, o: Outcome):
        t0 = time.perf_counter()
        traj, terms = self._terms(job.request, o)
        reward = None
        if terms:  # the reward from this run alone (scoring/rewards.py), from the 10 Hz positions
            run = rewards.Run(terms.proxy, o.termination, job.request, traj[:: rewards.SAMPLE_EVERY, 1:3], o.removed)
            reward = self.rule.own(run, self.collision_bonus)
        label, candidate = None, False
        if self.references:
            candidate = self.candidates == "all" or attr.is_candidate(o.termination, terms.proxy if terms else None)
            label = attr.PENDING if candidate else attr.NOT_CANDIDATE
            if candidate and self.rule.waits:
                reward = None  # known once the references are in
        row = scenario_row(self.name, self.method.name, job, o, traj, terms, reward, label)
        self.stages.add("proxy", t0)
        t0 = time.perf_counter()
        self.store.add(row)
        self.stages.add("store", t0)
        if candidate:
            self._queue_references(row)
        if not (candidate and self.wait_for_references):
            self.finished[o.job] = row
        tally.scenario(self.stats, terms, label, candidate)
        self.callbacks.on_progress(self.status())

    def _apply_ready(self):
        while self.next_apply in self.finished:
            row = self.finished.pop(self.next_apply)
            job = self.pending.pop(self.next_apply)
            self.next_apply += 1
            slot = self.slot_state[job.slot]
            done = job.step >= self.exp.episode_steps - 1
            # (rows of campaigns older than the reward column learnt from the proxy)
            reward = row["reward"] if self.references or self.reward != "proxy" else row["proxy"]
            learnt = None
            if reward is None:  # ERROR after every attempt: no transition, the episode ends here
                self.method.observe(job.job, job.episode, job.step, job.state, job.action, None, None, True)
                done = True
            else:
                t0 = time.perf_counter()
                traj = unpack_trajectory(row["trajectory"])
                # issue #78: where it happened, and whether it is one of the campaign's findings
                place = run_place(job.request, row, traj[:, 1:3])
                finding = float(reward) >= self.rule.finding_at
                if finding:
                    tally.finding(self.stats, place, self.atlas)
                self.method.outcome(job.job, place, finding)
                next_state = self.method.states.build(job.action, traj[:, 1:3], job.step + 1)
                learnt = self.method.observe(
                    job.job, job.episode, job.step, job.state, job.action, float(reward), next_state, done
                )
                self.stages.add("update", t0)
                if not done:
                    slot.update(step=job.step + 1, state=next_state)
            self.callbacks.on_scenario(job.job, row, dict(learnt or {}, **tally.found(self.stats, self.atlas)))
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
        from dataclasses import asdict

        keys = ("next_job", "next_apply", "next_episode", "episodes_done", "stats", "slot_state")
        state = {k: getattr(self, k) for k in keys}
        pending = [dict(asdict(j), attempts=0, avoid="") for j in self.pending.values()]
        save_atomic(dict(state, method=self.method.state_dict(), pending=pending), self.checkpoint_path)

    def status(self) -> dict:
        stored = self.store.count(self.name)
        return dict(
            tally.status(
                self.stats,
                stored,
                self.total,
                stored - self.done_at_start,
                time.time() - self.t0,
                self.references,
                self.atlas,
            ),
            reward=self.rule.name,
        )

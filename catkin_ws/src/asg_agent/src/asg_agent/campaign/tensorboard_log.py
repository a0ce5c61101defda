"""TensorBoard event files of a campaign (no ROS imports): what RL users look at while it learns.

    log = TensorBoardLog("results/tensorboard/exp1-td3-per-asp-s0", purge_step=first_job)
    log.scenario(job, row, stats)    # from Campaign's `scalars` hook, in job order
    log.close()

Per scenario (x axis: the job, in the order the search learnt from them): first what the campaign
searched for, `findings/distinct` (its findings' distinct places at protocol v4's radius,
scoring/places.py) and `findings/of_reward` (its reward's findings), with a failure atlas
`coverage/covered` (its places the findings cover) and `coverage/new` (places beyond it); then `scenario/proxy`,
`scenario/reward`, `scenario/yaw_term`, `scenario/plr`, `scenario/reference_proxy` (attribution),
and the running counts `findings/proxy_ge3`, `findings/perception`, `findings/stack`; with named
reference stacks, `attribution/CLASS` (flaw, model, stack, ..., not_candidate, pending) as each
candidate's reference runs come in. Per update
(the agent's last gradient step after that scenario): `agent/critic_loss`, `agent/q`,
`agent/actor_loss`, `agent/asp_penalty`, `agent/asp_weight`, `agent/per_beta`,
`agent/actor_saturation`; CMA-ES's `search/cma_sigma` and `search/cma_best`, annealing's
`search/temperature` and `search/incumbent`, MAP-Elites' `search/qd_cells`,
`search/qd_coverage` and `search/qd_best`, novelty-ts's `search/novelty_archive`. Written with tensorboardX (pinned by scripts/common.sh); a resumed
campaign passes its first job as `purge_step`, so TensorBoard drops what the interrupted run
wrote past it. View with `tensorboard --logdir results/tensorboard` (the `tensorboard` package,
which this project does not need).
"""

import json
from typing import Optional

from asg_agent.records.store import attribute
from asg_agent.campaign.config import CampaignCallback

AGENT_KEYS = {
    "critic_loss": "agent/critic_loss",
    "q": "agent/q",
    "actor_loss": "agent/actor_loss",
    "asp": "agent/asp_penalty",
    "asp_weight": "agent/asp_weight",
    "per_beta": "agent/per_beta",
    "actor_saturation": "agent/actor_saturation",
    # the other searches' own figures
    "cma_sigma": "search/cma_sigma",
    "cma_best": "search/cma_best",
    "temperature": "search/temperature",
    "incumbent": "search/incumbent",
    "qd_cells": "search/qd_cells",
    "qd_coverage": "search/qd_coverage",
    "qd_best": "search/qd_best",
    "novelty_archive": "search/novelty_archive",
    "coverage_found": "search/coverage_found",
    # the campaign's own running counts (issue #78), passed with the method's figures
    "findings": "findings/of_reward",
    "distinct": "findings/distinct",
    # with a failure atlas (issue #93): its places the findings cover, and new places beyond it
    "covered": "coverage/covered",
    "coverage_new": "coverage/new",
}


class TensorBoardLog(CampaignCallback):
    """The campaign's TensorBoard scalars, a CampaignCallback (campaign/config.py)."""

    def __init__(self, logdir: str, purge_step: Optional[int] = None, prior_rows=()):
        try:
            from tensorboardX import SummaryWriter
        except ImportError as e:
            raise RuntimeError(
                f"TensorBoard log: tensorboardX is not installed ({e}); run bash scripts/setup.sh, "
                "or pass --no-tensorboard"
            ) from None
        self.logdir = logdir
        self.writer = SummaryWriter(logdir, purge_step=purge_step, flush_secs=10)
        # Running counts continue on resume from the rows learnt from before purge_step.
        self.counts = {"proxy_ge3": 0, "perception": 0, "stack": 0}
        for row in prior_rows:
            self._count(row)

    @staticmethod
    def _reference_proxy(row: dict):
        return json.loads(row["reference"]).get("proxy") if row.get("reference") else None

    def _count(self, row: dict):
        p, ref = row.get("proxy"), self._reference_proxy(row)
        if p is None:
            return
        finding, perception, stack = attribute(p, ref if ref is not None else float("inf"))
        self.counts["proxy_ge3"] += finding
        if ref is not None:
            self.counts["perception"] += perception
            self.counts["stack"] += stack

    def scenario(self, job: int, row: dict, stats: Optional[dict] = None):
        w = self.writer
        for key in ("proxy", "reward", "yaw_term", "plr"):
            if row.get(key) is not None:
                w.add_scalar(f"scenario/{key}", row[key], job)
        ref = self._reference_proxy(row)
        if ref is not None:
            w.add_scalar("scenario/reference_proxy", ref, job)
        self._count(row)
        w.add_scalar("findings/proxy_ge3", self.counts["proxy_ge3"], job)
        if row.get("reference"):
            w.add_scalar("findings/perception", self.counts["perception"], job)
            w.add_scalar("findings/stack", self.counts["stack"], job)
        for key, tag in AGENT_KEYS.items():
            v = (stats or {}).get(key)
            if v is not None:
                w.add_scalar(tag, v, job)

    def attribution(self, job: int, label: str, classes: dict):
        """A candidate's references are in (the campaign's on_attributed): the running count of
        every attribution class, at the candidate's job (these come out of job order)."""
        for key, n in classes.items():
            self.writer.add_scalar(f"attribution/{key}", n, job)

    def on_scenario(self, job, row, figures):
        self.scenario(job, row, figures)

    def on_attributed(self, job, cls, counts):
        self.attribution(job, cls, counts)

    def close(self):
        self.writer.close()

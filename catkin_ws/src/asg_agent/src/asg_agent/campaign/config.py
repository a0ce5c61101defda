"""A campaign's one configuration and its callbacks (issue #80; no ROS imports).

`CampaignConfig` is everything a `Campaign` is built from, by name: what it searches (experiment,
method, reward), where it runs (the pool under test and the reference pools by role), where it
stores (store, checkpoint) and how (slots, retries, checkpoint period). `CampaignCallback` is the
one way to follow a campaign, as Stable-Baselines3's callbacks are: a progress bar, TensorBoard
and tests subclass it (or wrap functions in `FunctionCallback`) and add it to the configuration or,
once the campaign exists, with `Campaign.add_callback`.
"""

from dataclasses import dataclass, field
from typing import Callable, Dict, Optional, Sequence

from asg_agent.campaign.dispatch import Pool
from asg_agent.records.experiment import Experiment
from asg_agent.records.store import Store
from asg_agent.scoring.proxy import ProxyConfig
from asg_agent.search.base import SearchMethod


class CampaignCallback:
    """Hooks of a running campaign; each does nothing unless overridden."""

    def on_progress(self, status: dict) -> None:
        """The campaign's status (Campaign.status) after a scenario or a candidate's references."""

    def on_scenario(self, job: int, row: dict, figures: dict) -> None:
        """A scenario applied, in job order: its stored row, the search's update figures and the
        campaign's findings so far (TensorBoard's scalars)."""

    def on_attributed(self, job: int, cls: str, counts: dict) -> None:
        """A candidate's reference runs are in (out of job order): its class and every class's count."""


class FunctionCallback(CampaignCallback):
    """A callback of plain functions: progress(status), scenario(job, row, figures),
    attributed(job, cls, counts); each optional."""

    def __init__(
        self,
        progress: Optional[Callable[[dict], None]] = None,
        scenario: Optional[Callable[[int, dict, dict], None]] = None,
        attributed: Optional[Callable[[int, str, dict], None]] = None,
    ):
        self._progress, self._scenario, self._attributed = progress, scenario, attributed

    def on_progress(self, status):
        if self._progress:
            self._progress(status)

    def on_scenario(self, job, row, figures):
        if self._scenario:
            self._scenario(job, row, figures)

    def on_attributed(self, job, cls, counts):
        if self._attributed:
            self._attributed(job, cls, counts)


class Callbacks(CampaignCallback):
    """Several callbacks called in the order they were added."""

    def __init__(self, callbacks: Sequence[CampaignCallback] = ()):
        self.items = list(callbacks)
        for cb in self.items:
            self._check(cb)

    @staticmethod
    def _check(cb):
        if not isinstance(cb, CampaignCallback):
            raise TypeError(f"callback {cb!r}: must be a CampaignCallback (FunctionCallback wraps functions)")

    def add(self, cb: CampaignCallback) -> None:
        self._check(cb)
        self.items.append(cb)

    def on_progress(self, status):
        for cb in self.items:
            cb.on_progress(status)

    def on_scenario(self, job, row, figures):
        for cb in self.items:
            cb.on_scenario(job, row, figures)

    def on_attributed(self, job, cls, counts):
        for cb in self.items:
            cb.on_attributed(job, cls, counts)


@dataclass
class CampaignConfig:
    """What a campaign is built from (Campaign(config)); every field named at every call site."""

    name: str  #: the campaign's name in the store
    experiment: Experiment
    method: SearchMethod
    store: Store
    pool: Pool  #: the workers under test
    total: int  #: [scenarios] the budget
    seed: int
    checkpoint: str  #: the checkpoint file's path
    slots: int = 4  #: [-] episodes side by side (>= the workers, so a free worker finds a proposal)
    max_attempts: int = 3  #: [-] runs of a job before it is stored as ERROR
    checkpoint_every: int = 10  #: [episodes] between checkpoints
    proxy_config: ProxyConfig = field(default_factory=ProxyConfig)
    settings: dict = field(default_factory=dict)  #: stored with the campaign (the command's record)
    early_dispatch: bool = True  #: dispatch to freed workers before applying results
    reward: str = "proxy"  #: scoring/rewards.py's entry the search maximises
    references: Dict[str, Pool] = field(default_factory=dict)  #: role -> the pool of that reference stack
    candidates: Optional[str] = None  #: which scenarios the references re-run (policy.CANDIDATE_RULES)
    collision_bonus: float = 2.0  #: [-] the collision reward's bonus
    #: the failure atlas of the campaign's identity (scoring.atlas.Atlas), or None: what of it the
    #: findings cover is counted live (progress bar, TensorBoard) and at the end
    atlas: Optional[object] = None
    callbacks: Sequence[CampaignCallback] = ()

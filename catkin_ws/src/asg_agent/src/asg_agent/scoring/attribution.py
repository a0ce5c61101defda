"""Attribution: whose failure a failure is (no ROS). The one home of the rule and its thresholds.

A scenario's run on the stack under test is a *candidate* when it fails or nearly fails
(`is_candidate`); a campaign with reference stacks re-runs every candidate on each of them and
nothing else. Two references are named by role:

- ``full``: the unflawed U-Net on the same backend, the same planner and follower;
- ``ground_truth``: the simulator's own labels, the same planner and follower.

With both, a candidate falls into one class (`classify`, `CLASSES`):

- ``flaw``: the stack under test fails; ``full`` and ``ground_truth`` both reach the goal with
  proxy < REFERENCE_CLEAR: what the injected flaw does and the unflawed model does not;
- ``model``: the stack under test and ``full`` both fail, ``ground_truth`` does not: a weakness
  every U-Net here shares;
- ``stack``: ``ground_truth`` fails too: the planner and follower's own;
- ``unclear``: the stack under test fails, no reference fails, but one does not stay clear
  (proxy between REFERENCE_CLEAR and FINDING): near enough not to blame the flaw alone;
- ``reverse``: the stack under test does not fail and a reference does (counted, not dropped);
- ``pass``: no run fails;
- ``error``: a run ended in ERROR or has no proxy, so nothing can be said.

With ``ground_truth`` alone (the single-reference mode, every scenario re-run), ``perception``
takes the place of ``flaw`` and ``model`` together: the stack under test fails where ground truth
stays clear.

Any pair of stacks (issue #67): with the ``release`` role (the registration the stack under test
names as its `reference`, e.g. its last release) and no ``ground_truth``, a candidate is a
``regression`` when the stack under test fails and the release reaches the goal with proxy <
REFERENCE_CLEAR, ``shared`` when the release fails too, and otherwise as above (``unclear``,
``reverse``, ``pass``, ``error``): the flaw's question asked of any change to a stack.

A run *fails* when it ends in a collision, a timeout, a flip or out of bounds, or reaches the goal
with proxy >= FINDING (the paper's count). Non-candidates get ``not_candidate``; candidates whose
reference runs are still out, ``pending``.
"""

import math
from dataclasses import dataclass
from typing import Dict, Mapping, Optional

from asg_scenario import schema

FINDING = 3.0  # [-] a run with proxy at or above this is a finding (the paper's count)
FINDING_STRONG = 4.0  # [-] the paper's second count (Table 2's ">= 4")
REFERENCE_CLEAR = 2.0  # [-] a reference run below this (and at the goal) is clear of the failure
DIFFERENTIAL = 1.0  # [-] a differential finding: the proxy exceeds its reference run's by at least this
# [-] a run on the stack under test at or above this proxy (or failing) is re-run on the
# references. Over the 19,500 attributed round-3 scenarios of results/comparison and results/table2
# (every one re-run on ground truth), every differential finding (57) had proxy >= 2.0 or failed:
# the rule would have missed none of them; by construction it misses no flaw, model or stack
# finding (each needs the stack under test to fail). It misses the reverse cases among the runs
# that pass (306 of 313 there), which `docs/agent.md` says and the full re-run check measures.
CANDIDATE = 2.0

#: terminations that are failures whatever the proxy (SUCCESS is not; ERROR is no outcome at all):
#: declared with the terminations, in the scenario schema
FAILED_TERMINATIONS = schema.FAILED_TERMINATIONS

FULL = "full"  # role of the unflawed-model reference
TRUTH = "ground_truth"  # role of the ground-truth reference
RELEASE = "release"  # role of the registration the stack under test is compared against
ROLES = (FULL, TRUTH, RELEASE)
#: the roles of three-stack attribution (attribution:=three)
THREE_STACK = (FULL, TRUTH)

#: the classes of a candidate, in the order tables show them
CLASSES = ("flaw", "model", "stack", "perception", "regression", "shared", "unclear", "reverse", "pass", "error")
#: what a scenario's attribution column holds besides a class
NOT_CANDIDATE = "not_candidate"
PENDING = "pending"
#: the classes that are findings of the stack under test
FINDINGS = ("flaw", "model", "stack", "perception", "regression", "shared")


@dataclass(frozen=True)
class RunOutcome:
    termination: str
    proxy: Optional[float]

    @classmethod
    def of(cls, d: Mapping) -> "RunOutcome":
        return cls(str(d.get("termination") or "ERROR"), d.get("proxy"))

    @property
    def error(self) -> bool:
        return self.termination == "ERROR" or self.proxy is None or not math.isfinite(self.proxy)

    @property
    def fails(self) -> bool:
        return self.termination in FAILED_TERMINATIONS or (
            self.termination == "SUCCESS" and self.proxy is not None and self.proxy >= FINDING
        )

    @property
    def clear(self) -> bool:
        return self.termination == "SUCCESS" and self.proxy is not None and self.proxy < REFERENCE_CLEAR


def unflawed(model: str) -> Optional[str]:
    """The `full` reference's model for a stack under test's: the shipped pairs are named
    flawed/full, flawed_lite/full_lite, flawed_tw/full_tw. None when the name says nothing."""
    base = model.rsplit("/", 1)[-1]
    if "flawed" not in base:
        return None
    return model[: len(model) - len(base)] + base.replace("flawed", "full")


def fails(termination: str, proxy: Optional[float]) -> bool:
    return RunOutcome(termination, proxy).fails


def is_candidate(termination: str, proxy: Optional[float]) -> bool:
    """Re-run on the references: the run fails, or its proxy reaches CANDIDATE. A run that ended
    in ERROR is not (it has no outcome to attribute)."""
    if termination == "ERROR" or proxy is None:
        return False
    return fails(termination, proxy) or proxy >= CANDIDATE


def attribute(proxy: float, reference: float):
    """The single-reference counts of a finding (the paper's proxy): (finding, the perception's,
    the stack's) for a run's proxy and its ground-truth reference run's."""
    finding = proxy >= FINDING
    return finding, finding and reference < REFERENCE_CLEAR, finding and reference >= FINDING


def classify(test: RunOutcome, refs: Mapping[str, RunOutcome]) -> str:
    """The class of one candidate from its run on the stack under test and its reference runs
    (keyed by role: `FULL` and/or `TRUTH`; other keys are ignored). See the module's text."""
    known = {k: v for k, v in refs.items() if k in ROLES}
    if TRUTH not in known and RELEASE in known:
        return classify_pair(test, known[RELEASE])
    if TRUTH not in known:
        raise ValueError(f"attribution needs the {TRUTH!r} or the {RELEASE!r} reference (got {sorted(refs)})")
    if test.error or any(r.error for r in known.values()):
        return "error"
    truth, full = known[TRUTH], known.get(FULL)
    if not test.fails:
        return "reverse" if any(r.fails for r in known.values()) else "pass"
    if truth.fails:
        return "stack"
    if full is None:
        return "perception" if truth.clear else "unclear"
    if full.fails:
        return "model"
    return "flaw" if full.clear and truth.clear else "unclear"


def classify_pair(test: RunOutcome, release: RunOutcome) -> str:
    """The class of a candidate of a stack pair (see the module's text): regression, shared,
    unclear, reverse, pass or error."""
    if test.error or release.error:
        return "error"
    if not test.fails:
        return "reverse" if release.fails else "pass"
    if release.fails:
        return "shared"
    return "regression" if release.clear else "unclear"


def classify_rows(test: Mapping, refs: Mapping[str, Mapping]) -> str:
    """`classify` on plain dicts (rows of a store or an export: termination and proxy keys)."""
    return classify(RunOutcome.of(test), {k: RunOutcome.of(v) for k, v in refs.items()})


def count_classes(labels) -> Dict[str, int]:
    """Counts of every class and of NOT_CANDIDATE and PENDING, zeros included."""
    out = {c: 0 for c in CLASSES + (NOT_CANDIDATE, PENDING)}
    for label in labels:
        if label is not None:
            out[label] = out.get(label, 0) + 1
    return out


# -- Round 3's single-reference scores of an export row (its `reference`: the ground-truth run) --


def _ref(row: Mapping) -> Mapping:
    return row.get("reference") or {}


def perception_finding(row: Mapping) -> bool:
    """proxy >= FINDING where the ground-truth reference stayed below REFERENCE_CLEAR."""
    ref = _ref(row).get("proxy")
    return row["proxy"] is not None and ref is not None and attribute(row["proxy"], ref)[1]


def differential_finding(row: Mapping) -> bool:
    """proxy exceeding the ground-truth reference's by at least DIFFERENTIAL."""
    ref = _ref(row).get("proxy")
    return row["proxy"] is not None and ref is not None and row["proxy"] - ref >= DIFFERENTIAL


def perception_collision(row: Mapping) -> bool:
    """a collision where the ground-truth reference reached the goal."""
    return row["termination"] == "COLLISION" and _ref(row).get("termination") == "SUCCESS"


#: what a single-reference campaign blamed on the perception, in the order `rerun --select
#: perception` takes it, each with its predicate on an export row
RERUN_CLASSES = ("finding", "differential", "collision")
_RERUN_PREDICATES = (perception_finding, differential_finding, perception_collision)


def rerun_class(row: Mapping) -> str:
    """The first of RERUN_CLASSES an export row falls in ('' for none, or a row without a reference)."""
    for name, pred in zip(RERUN_CLASSES, _RERUN_PREDICATES):
        if pred(row):
            return name
    return ""


def still_failing(r: Mapping) -> bool:
    """Whether a re-run (a `rerun` row) fails the way its campaign row did (its `campaign_class`)."""
    c = r.get("campaign_class") or ""
    if c == "collision":
        return r["termination"] == "COLLISION"
    if r["proxy"] is None:
        return False
    if c == "differential":
        return r["proxy"] - r["campaign_reference_proxy"] >= DIFFERENTIAL
    return r["proxy"] >= FINDING

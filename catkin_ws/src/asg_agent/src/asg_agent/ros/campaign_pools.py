"""The campaign's ROS side: its node, the pools of workers under test and of each reference
stack, and the checks that the running workers are the experiment's stack (rospy).

RosWorkers gathers them as the campaign command's `workers` (asg_agent.cli.campaign.main): the
command asks its workers for their options, names, pools, checks and stage collector, and the
tests hand it their in-process stand-in's instead (catkin_ws/src/asg_agent/test/stand_in)."""

import sys

from asg_agent.campaign.policy import CampaignError, numbered_workers, worker_names
from asg_agent.scoring import attribution as attr


class RosWorkers:
    """The campaign's workers: scene workers of the running ROS master, named by --workers (the
    references' by --reference / --reference-workers), checked to run the experiment's stack."""

    #: what the store records of the workers beside the campaign's settings (nothing more)
    settings: dict = {}

    def options(self, p):
        """Options of the workers' own (none: --workers and the references' are the campaign's)."""

    def names(self, a):
        return worker_names(a.workers)

    def numbered(self, role, first, n):
        return numbered_workers(role, first, n)

    def pools(self, a, exp, workers, roles):
        return make_pools(a, exp, workers, roles)

    def check(self, exp, settings, workers, roles):
        check_stacks(exp, settings, workers, roles)

    def collector(self, a, exp, settings, workers, roles):
        return stage_collector(exp, settings, workers, roles) if a.stage_report else None


def make_pools(a, exp, workers, roles):
    """The pool of ROS workers under test and one pool per reference role. ROS workers must run
    the experiment's planner."""
    references = {}
    from asg_agent.ros.pool import WorkerPool

    from asg_agent.ros.node import init_node

    try:
        init_node("campaign", anonymous=True, disable_signals=True)
        pool = WorkerPool(workers, answer_timeout=a.answer_timeout)
        for role, ws in roles.items():
            references[role] = WorkerPool(ws, answer_timeout=a.answer_timeout)
    except RuntimeError as e:
        raise CampaignError(str(e)) from e
    # The planner is part of the stack's identity: every worker must run the experiment's
    # configuration (e.g. exp6's planner_terrain.yaml, not the flat planner.yaml).
    from asg_agent.ros.stack_identity import planner_mismatch

    # the reference workers that run the paper's planner: all but a `release` of another stack
    ref_workers = [w for role, ws in roles.items() if _runs_paper_planner(exp, role) for w in ws]
    checked = (list(workers) if exp.stack == "paper" else []) + ref_workers
    wrong = [m for w in checked for m in planner_mismatch(w, exp.planner_config)]
    if wrong:
        raise CampaignError(
            f"the experiment's planner_config is {exp.planner_config}, but:\n  "
            + "\n  ".join(wrong[:8])
            + "\n(launch the workers with planner_config:=... of that file)"
        )
    return pool, references


def _runs_paper_planner(exp, role: str) -> bool:
    """Whether a reference role's workers run the paper's planner: full and ground truth do; a
    `release` (issue #67) runs the registration the stack under test names, paper or not."""
    from asg_agent.records import stacks
    from asg_agent.scoring import attribution as attr

    if role != attr.RELEASE:
        return True
    reference = stacks.read(exp.stack_file).reference_file if exp.stack_file else ""
    return bool(reference) and stacks.read(reference).name == "paper"


def check_stacks(exp, settings: dict, workers, roles):
    """The stack identity stored with the campaign must be what the workers run (issue #24: a
    backend left at another value than the experiment's would be recorded falsely); the U-Net's
    numerics on each worker's machine are recorded in `settings` (issue #36: one campaign, one
    numerics, so that a replay elsewhere can tell whether it repeats the runs)."""
    from asg_agent.ros.stack_identity import segmenter_numerics, stack_mismatch

    wrong = [m for w in workers for m in stack_mismatch(w, settings)]
    if exp.stack != "paper" and not wrong:
        # a registered stack's identity parameters: the same on every worker, recorded
        from asg_agent.ros.stack_identity import identity_values

        seen = {w: identity_values(w) for w in workers}
        if any(v != seen[workers[0]] for v in seen.values()):
            wrong.append(f"the workers' {exp.stack} stacks differ in their identity parameters: {seen}")
        settings["identity"] = seen[workers[0]]
        release = roles.get(attr.RELEASE)
        if release:  # the release's identity too (issue #67): a pair that runs one set of parameters twice shows here
            ref = settings["references"][attr.RELEASE]
            ref["identity"] = identity_values(release[0])
            same = [k for k, v in settings["identity"].items() if ref["identity"].get(k) == v]
            if same and len(same) == len(settings["identity"]):
                print(
                    f"campaign: {exp.stack} and its release {ref.get('stack')} run the same identity parameters "
                    f"({', '.join(same)}): unless their code differs, every scene will be 'shared' or 'pass'",
                    file=sys.stderr,
                )
    for role, ws in roles.items():
        wrong += [m for w in ws for m in stack_mismatch(w, settings["references"][role])]
    groups = [(settings, workers)] + [(settings["references"][r], ws) for r, ws in roles.items()]
    for where, ws in groups:
        if where.get("perception") != "unet":
            continue
        seen = {w: segmenter_numerics(w, timeout=60.0) for w in ws}
        if len(set(seen.values())) > 1 or "" in seen.values():
            wrong.append(
                "the segmenters do not all run the same numerics: "
                + ", ".join(f"{w}: {v or 'none reported'}" for w, v in seen.items())
            )
        else:
            where["numerics"] = next(iter(seen.values()))
    if wrong:
        raise CampaignError(f"the workers do not run the experiment's stack ({exp.source}): " + "; ".join(wrong))


def stage_collector(exp, settings: dict, workers, roles):
    """--stage-report: the collector of every node's stage times, once each has published."""
    from asg_agent.ros.stages import StageCollector

    collector = StageCollector(list(workers) + [w for ws in roles.values() for w in ws])
    nodes = (1 if exp.stack != "paper" else 3 if exp.perception == "unet" else 2) * len(workers)
    nodes += sum((3 if settings["references"][r]["perception"] == "unet" else 2) * len(ws) for r, ws in roles.items())
    if not collector.wait_for(nodes, timeout=15.0):
        print(
            "campaign: --stage-report: not every worker, segmenter and planner published stage_times "
            "within 15 s; the breakdown will lack them",
            file=sys.stderr,
        )
    return collector

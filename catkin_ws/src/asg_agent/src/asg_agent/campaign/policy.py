"""What a campaign is set up with, apart from its command line: the workers' and the reference
stacks' namespaces, and the settings the store keeps (the stack's identity, the references, the
reward). No ROS: the pools and the checks against running workers are asg_agent.ros.campaign_pools."""

from asg_agent.paths import repo_relative
from asg_agent.scoring import attribution as attr


class CampaignError(Exception):
    """What stops the command before it runs (printed as `campaign: ...`, exit status 2)."""


def worker_names(spec: str):
    if spec.isdigit():
        n = int(spec)
        if n < 1:
            raise ValueError("--workers must be >= 1")
        return [f"/worker_{i}" for i in range(n)]
    return ["/" + s.strip().strip("/") for s in spec.split(",") if s.strip()]


def reference_roles(a, workers):
    """{role: worker namespaces} of the reference stacks: --reference ROLE=WORKERS (each count
    numbered after the workers named before it), or --reference-workers (ground truth)."""
    specs = [r.partition("=")[::2] for r in a.reference]
    if a.reference_workers:
        specs = [(attr.TRUTH, a.reference_workers)]
    roles, taken = {}, list(workers)
    for role, spec in specs:
        if spec.isdigit():
            n = int(spec)
            if n < 1:
                raise ValueError(f"reference {role}: at least one worker")
            first = len(taken)
            ws = (
                [f"fake_{role}_{i}" for i in range(n)] if a.fake_workers else [f"/worker_{first + i}" for i in range(n)]
            )
        else:
            ws = worker_names(spec)
        if not ws or set(ws) & set(taken):
            raise ValueError(f"reference {role}: its workers must be others than --workers and the other references'")
        roles[role] = ws
        taken += ws
    return roles


def reference_settings(a, exp, roles, candidates) -> dict:
    """What the campaign stores of its reference stacks: each role's identity (perception, model,
    backend: what the workers are checked against), the candidate rule and the thresholds."""
    if not roles:
        return {}
    out = {}
    for role, ws in roles.items():
        if role == attr.FULL:
            model = a.full_model or attr.unflawed(exp.model)
            if not model:
                raise SystemExit(
                    f"campaign: --reference full: the experiment's model {exp.model!r} has no known unflawed "
                    "counterpart: name it with --full-model"
                )
            out[role] = {"workers": ws, "perception": "unet", "model": model, "unet_backend": exp.unet_backend}
        else:
            out[role] = {"workers": ws, "perception": "ground_truth"}
    return {
        "references": out,
        "candidates": candidates,
        "attribution_thresholds": {
            "finding": attr.FINDING,
            "reference_clear": attr.REFERENCE_CLEAR,
            "candidate": attr.CANDIDATE,
        },
    }


def campaign_settings(a, exp, workers, roles, candidates) -> dict:
    """What the store keeps of the campaign: workers, references, reward and the stack's identity."""
    return {
        "workers": workers,
        "reference_workers": [w for ws in roles.values() for w in ws],
        **reference_settings(a, exp, roles, candidates),
        "reward": a.reward,
        **({"collision_bonus": a.collision_bonus} if a.reward == "collision" else {}),
        # repository-relative (issue #68): stores are exported to results/, which holds no
        # machine's paths; a file outside the repository keeps its absolute path
        "experiment_file": repo_relative(exp.source) or exp.source,
        **({"experiment_repo_file": repo_relative(exp.source)} if repo_relative(exp.source) else {}),
        "stack": exp.stack,
        **(registered_settings(exp) if exp.stack != "paper" else {}),
        "perception": exp.perception if exp.stack == "paper" else exp.stack,
        "model": exp.model,
        "unet_backend": exp.unet_backend,
        "planner_config": exp.planner_config,
        "fake": bool(a.fake_workers),
    }


def registered_settings(exp) -> dict:
    """What a campaign records of a stack registered by a file (records.stacks): the file, and
    what its registration says; the identity parameters' values are added by check_stacks."""
    from asg_agent.records import stacks

    reg = stacks.read(exp.stack_file)
    return {
        "command_interface": reg.command,
        "stack_file": repo_relative(reg.path) or reg.path,
        "registration": {"mode": reg.mode, "command": reg.command, "sim_time": reg.sim_time, "identity": reg.identity},
    }

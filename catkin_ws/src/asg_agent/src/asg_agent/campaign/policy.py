"""What a campaign is set up with, apart from its command line: the workers' and the reference
stacks' namespaces, and the settings the store keeps (the stack's identity, the references, the
reward). No ROS: the pools and the checks against running workers are asg_agent.ros.campaign_pools."""

from asg_agent.paths import repo_relative
import math

from asg_agent.scoring import attribution as attr
from asg_agent.scoring import rewards

#: which scenarios run on the reference stacks: "failures" (the candidates of
#: scoring/attribution.is_candidate) or "all" (every scenario: the single-reference mode of round 3)
CANDIDATE_RULES = ("failures", "all")
REWARDS = rewards.REWARDS


class CampaignError(Exception):
    """What stops the command before it runs (printed as `campaign: ...`, exit status 2)."""


def worker_names(spec: str):
    if spec.isdigit():
        n = int(spec)
        if n < 1:
            raise ValueError("--workers must be >= 1")
        return [f"/worker_{i}" for i in range(n)]
    return ["/" + s.strip().strip("/") for s in spec.split(",") if s.strip()]


def numbered_workers(role: str, first: int, n: int):
    """The namespaces of `n` workers of a reference role given as a count: /worker_FIRST on, FIRST
    the count of the workers named before them."""
    return [f"/worker_{first + i}" for i in range(n)]


def reference_roles(a, workers, numbered=numbered_workers):
    """{role: worker namespaces} of the reference stacks: --reference ROLE=WORKERS (each count
    numbered after the workers named before it, by `numbered(role, first, n)`), or
    --reference-workers (ground truth)."""
    specs = [r.partition("=")[::2] for r in a.reference]
    if a.reference_workers:
        specs = [(attr.TRUTH, a.reference_workers)]
    roles, taken = {}, list(workers)
    for role, spec in specs:
        if spec.isdigit():
            n = int(spec)
            if n < 1:
                raise ValueError(f"reference {role}: at least one worker")
            ws = numbered(role, len(taken), n)
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
        elif role == attr.RELEASE:
            out[role] = dict(release_settings(exp), workers=ws)
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
    }


def release_settings(exp) -> dict:
    """What a campaign records of the `release` reference (issue #67): the registration the stack
    under test names as its `reference`, recorded as a registered stack is (registered_settings);
    SystemExit naming the file when the stack names none."""
    from asg_agent.records import stacks

    reg = stacks.read(exp.stack_file) if exp.stack_file else None
    try:
        path = reg.reference_file if reg else ""
    except stacks.RegistrationError as e:
        raise SystemExit(f"campaign: --reference release: {e}") from None
    if not path:
        raise SystemExit(
            f"campaign: --reference release: the stack under test ({exp.stack}) names no reference "
            "registration (its registration's `reference:` key, docs/your-stack.md)"
        )
    rel = stacks.read(path)
    return {
        "stack": rel.name,
        "perception": rel.name,
        "command_interface": rel.command,
        "stack_file": repo_relative(rel.path) or rel.path,
        "registration": {"mode": rel.mode, "command": rel.command, "sim_time": rel.sim_time, "identity": rel.identity},
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


def reference_setup(reward, references, candidates, collision_bonus):
    """The campaign's reference stacks by role and its candidate rule, checked against the reward
    (ValueError naming what does not fit). Round 3's single-reference mode is ground truth alone
    with candidates "all"."""
    if reward not in REWARDS:
        raise ValueError(f"reward {reward!r}: must be one of {', '.join(REWARDS)}")
    references = dict(references or {})
    unknown = sorted(set(references) - set(attr.ROLES))
    if unknown:
        raise ValueError(f"reference roles {unknown}: must be among {', '.join(attr.ROLES)}")
    if references and attr.TRUTH not in references and attr.RELEASE not in references:
        raise ValueError(
            f"attribution needs a {attr.TRUTH!r} (or, for a stack pair, a {attr.RELEASE!r}) reference stack"
        )
    candidates = candidates or "failures"
    if candidates not in CANDIDATE_RULES:
        raise ValueError(f"candidates {candidates!r}: must be one of {', '.join(CANDIDATE_RULES)}")
    need = rewards.REGISTRY[reward]
    if need.any_reference and not references:
        raise ValueError(f"the {reward} reward needs a reference stack")
    if need.every_scenario and candidates != "all":
        raise ValueError(f"the {reward} reward needs every scenario re-run (candidates 'all')")
    for role in need.roles:
        if role not in references:
            raise ValueError(f"the {reward} reward needs the {role!r} reference stack")
    if not (math.isfinite(collision_bonus) and collision_bonus >= 0.0):
        raise ValueError(f"collision_bonus {collision_bonus!r}: must be a finite number >= 0")
    return references, candidates

"""What a worker runs, against what a campaign or an experiment says its stack is (issue #38: its
own module, from ros/replay.py): the stack under test and its command interface, the segmenter's
model, backend and numerics, and the planner's parameters (planner.yaml and a variant's overlay).
The campaign refuses workers that disagree; a replay refuses them before it runs. rospy reads the
parameter server; the comparisons are plain functions of what it returns.
"""

import os
import time

from asg_agent.records.experiment import DEFAULT_UNET_BACKEND, LEGACY_UNET_BACKEND


def stack_mismatch(worker: str, settings: dict) -> list:
    import rospy

    out = []
    # A registered stack (stacks/*.launch) names itself in the worker's namespace; a worker
    # without a registration runs the paper's stack by its own parameters.
    interface = rospy.get_param(
        f"{worker}/stack/command", rospy.get_param(f"{worker}/scene_worker/command_interface", "vehicle_command")
    )
    want_stack = settings.get("stack", "paper")
    name = rospy.get_param(f"{worker}/stack/name", "paper")
    if name != want_stack:
        return [f"the campaign ran stack {want_stack!r}, {worker} runs {name!r}"]
    if want_stack != "paper":
        return out + registered_mismatch(worker, settings, interface)
    if interface != "vehicle_command":
        out.append(f"the paper's stack sends VehicleCommand, {worker}'s scene worker takes {interface!r}")
    want = settings.get("perception")
    has_seg = rospy.has_param(f"{worker}/segmenter/model")
    if want == "unet":
        if not has_seg:
            out.append(f"the campaign ran the U-Net, {worker} has no segmenter")
        else:
            model = rospy.get_param(f"{worker}/segmenter/model")
            if (
                os.path.splitext(os.path.basename(str(model)))[0]
                != os.path.splitext(os.path.basename(settings.get("model", "")))[0]
            ):
                out.append(f"the campaign ran model {settings.get('model')!r}, {worker} runs {model!r}")
            # Campaigns from before the backend was recorded ran the then default, channels_last;
            # a segmenter without the parameter predates bf16 too; an empty one runs the default.
            backend, ran = (
                rospy.get_param(f"{worker}/segmenter/backend", LEGACY_UNET_BACKEND) or DEFAULT_UNET_BACKEND,
                settings.get("unet_backend", LEGACY_UNET_BACKEND),
            )
            # channels_last and polyphase are one function, their runs bit for bit each other's
            # (asg_perception.numerics.FP32_PORTABLE_BACKENDS): a campaign of one resumes on the other
            from asg_perception.numerics import FP32_PORTABLE_BACKENDS

            portable = {backend, ran} <= set(FP32_PORTABLE_BACKENDS)
            if backend != ran and not portable:
                out.append(f"the campaign's stack runs the {ran!r} inference backend, {worker} runs {backend!r}")
            # Issue #36: the numerics (oneDNN kernels, threads, torch) the runs were made with.
            recorded = settings.get("numerics", "")
            here = segmenter_numerics(worker, timeout=30.0) if recorded else ""
            if recorded and here:
                from asg_perception.numerics import can_reproduce

                why = can_reproduce(recorded, here)
                if why:
                    out.append(f"{worker} cannot repeat the stored runs bit for bit on this machine ({why})")
    elif want == "ground_truth" and has_seg:
        out.append(f"the campaign ran ground-truth labels, {worker} runs a segmenter")
    return out


def registered_mismatch(worker: str, settings: dict, interface: str) -> list:
    """A stack of a registration file against the campaign's record of it: its command interface
    and mode, and every identity parameter present with the value recorded (identity_values)."""
    import rospy

    out = []
    want = settings.get("registration") or {}
    if want.get("command", interface) != interface:
        out.append(f"stack {settings.get('stack')!r} sends {want.get('command')}, {worker}'s takes {interface!r}")
    for key, value in sorted((settings.get("identity") or {}).items()):
        if not rospy.has_param(f"{worker}/{key}"):
            out.append(f"{worker} has no parameter {key} (the stack's identity, its registration)")
        elif rospy.get_param(f"{worker}/{key}") != value:
            out.append(f"{worker}'s {key} is {rospy.get_param(f'{worker}/{key}')!r}, the campaign's was {value!r}")
    return out


def identity_values(worker: str) -> dict:
    """{parameter: value} of the identity parameters the worker's stack registration names
    (what a campaign records, and a replay compares); missing ones are left out."""
    import rospy

    keys = rospy.get_param(f"{worker}/stack/identity", [])
    return {k: rospy.get_param(f"{worker}/{k}") for k in keys if rospy.has_param(f"{worker}/{k}")}


def segmenter_numerics(worker: str, timeout: float = 0.0) -> str:
    """The numerics identity `worker`'s segmenter set once its model was loaded
    (asg_perception.numerics.identity), waiting up to `timeout` [s, wall] for it; "" if none."""
    import rospy

    deadline = time.time() + timeout
    while True:
        got = rospy.get_param(f"{worker}/segmenter/numerics", "")
        if got or time.time() >= deadline:
            return got
        time.sleep(0.2)


def planner_config_path(name: str) -> str:
    """A planner configuration: a file of asg_planner/config by name, or a path."""
    if os.sep in name:
        return name
    import rospkg

    return os.path.join(rospkg.RosPack().get_path("asg_planner"), "config", name)


def _flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flatten(v, f"{prefix}{k}/"))
        else:
            out[f"{prefix}{k}"] = v
    return out


#: planner parameters that change what it shows, not what it decides (worker.launch sets them)
PLANNER_DISPLAY_KEYS = ("publish_markers",)


def planner_mismatch(worker: str, planner_config: str) -> list:
    """What the planner of `worker` runs that the experiment's planner configuration does not say
    (each parameter of the file against the worker's parameter server entry), e.g. the terrain
    experiment run with the flat planner. [] when they agree."""
    import rospy
    import yaml

    path = planner_config_path(planner_config)
    want = {}
    # planner.yaml holds every parameter; a variant overlays it (worker.launch loads both).
    for file in dict.fromkeys((planner_config_path("planner.yaml"), path)):
        try:
            with open(file, encoding="utf-8") as f:
                want.update(_flatten(yaml.safe_load(f) or {}))
        except OSError as e:
            return [f"planner configuration {file}: cannot read ({e.strerror})"]
    out = []
    for key, v in sorted(want.items()):
        if key in PLANNER_DISPLAY_KEYS:
            continue
        name = f"{worker}/planner/{key}"
        if not rospy.has_param(name):
            out.append(f"{worker}'s planner has no parameter {key} ({os.path.basename(path)} sets {v!r})")
            continue
        got = rospy.get_param(name)
        same = (
            abs(float(got) - float(v)) <= 1e-9 * max(1.0, abs(float(v)))
            if isinstance(v, (int, float)) and not isinstance(v, bool) and isinstance(got, (int, float))
            else got == v
        )
        if not same:
            out.append(f"{worker}'s planner runs {key} = {got!r}, {os.path.basename(path)} says {v!r}")
    return out

"""The experiment file decides the stack under test (issue #53): scripts/train.sh asks this module
which train.launch arguments the experiment implies, so that `experiment:=FILE` alone sets the
workers' stack, perception, model, U-Net numerics and planner configuration.

    python3 -m asg_agent.cli.launch_args [key:=value ...]   # the arguments train.sh was given
    python3 -m asg_agent.cli.launch_args --check [key:=value ...]   # train.launch's own check

Prints, one a line, each `key:=value` of STACK_KEYS that the experiment sets and the arguments
leave out. With --check (train.launch runs it through `rosrun asg_agent launch_check`, with every
stack argument as the launch will use it, its defaults included, when roslaunch reads the file,
before any node starts; issue #68) every such value must be the experiment's: a default the
experiment does not share is refused too, naming the argument to add; it prints `ok`. An argument that contradicts the experiment (model:=full for an experiment of
`flawed`, unet_backend:=bf16 for one of channels_last) is refused, exit 2, naming both; so is a
bf16 experiment on a CPU that would emulate bf16 (asg_perception.numerics.refuse_emulated).
"""

import os
import sys
from typing import Dict, List

from asg_agent.records import stacks
from asg_agent.records.experiment import Experiment, ExperimentError, load_experiment
from asg_perception.numerics import refuse_emulated, resolve_backend

from asg_agent.paths import REPO

#: train.launch's default experiment (asg_bringup/experiments is the repository's experiments/)
DEFAULT_EXPERIMENT = os.path.join(REPO, "experiments", "exp1.yaml")
#: the train.launch arguments an experiment decides, in the order they are printed
STACK_KEYS = ("stack", "sim_time", "perception", "model", "unet_backend", "planner_config", "release_stack")


def planner_path(name: str) -> str:
    """A planner configuration by name (a file of asg_planner/config: the source tree's, or in an
    install space the installed package's) or path, as a path."""
    if os.sep in name:
        return os.path.abspath(name)
    source = os.path.join(REPO, "catkin_ws", "src", "asg_planner", "config", name)
    if os.path.isfile(source):
        return source
    try:  # an install space: asg_planner's share folder
        import rospkg

        return os.path.join(rospkg.RosPack().get_path("asg_planner"), "config", name)
    except Exception:  # noqa: BLE001 (rospkg's errors: no ROS environment; the name is then reported as missing)
        return source


def implied(exp: Experiment) -> Dict[str, str]:
    """The train.launch arguments of STACK_KEYS the experiment sets (only those its stack uses)."""
    # a registered stack of this project by its name, any other by its registration file
    builtin = os.path.dirname(exp.stack_file) == os.path.realpath(stacks.builtin_dir())
    out = {"stack": exp.stack if builtin else exp.stack_file}
    release = stacks.read(exp.stack_file).reference_file if exp.stack_file else ""
    if release:  # the registration it is compared against (attribution:=release; issue #67)
        out["release_stack"] = release
    if exp.sim_time:
        out["sim_time"] = "true"
    if exp.stack == "paper":
        out["perception"] = exp.perception
        if exp.perception == "unet":
            out["model"], out["unet_backend"] = exp.model, exp.unet_backend
        out["planner_config"] = planner_path(exp.planner_config)
    return out


def _same(key: str, given: str, want: str) -> bool:
    if key == "unet_backend":
        return resolve_backend(given) == resolve_backend(want)
    if key in ("stack", "release_stack"):
        try:
            return stacks.resolve(given) == stacks.resolve(want)
        except stacks.RegistrationError:
            return False
    if key == "planner_config":
        return os.path.realpath(planner_path(given)) == os.path.realpath(want)
    return given == want


def launch_args(args: List[str], check: bool = False) -> List[str]:
    """What to add to `args` (train.launch's key:=value words); ExperimentError when they
    contradict the experiment or the experiment cannot run on this CPU. `check`: `args` are every
    value the launch will use (its defaults included), and each must be the experiment's."""
    given = dict(a.split(":=", 1) for a in args if ":=" in a)
    path = given.get("experiment") or DEFAULT_EXPERIMENT
    exp = load_experiment(path)
    want = implied(exp)
    if given.get("attribution", "").lower() == "release" and "release_stack" not in want:
        raise ExperimentError(
            f"{path}: attribution:=release needs a stack that names its reference registration; {exp.stack} "
            "names none (its registration's `reference:` key, docs/your-stack.md)"
        )
    problems = []
    for key, value in want.items():
        if key == "release_stack" and check and given.get("attribution", "").lower() != "release":
            continue  # a reference no worker runs
        if key in given and not _same(key, given[key], value):
            shown = given[key] or (f"(empty: {resolve_backend('')})" if key == "unet_backend" else "")
            problems.append(
                f"{key}:={value} is the experiment's, the launch has {key}:={shown}"
                if check
                else f"{key}:={given[key]} contradicts the experiment's {key} {value}"
            )
    if problems and check:
        raise ExperimentError(
            f"{path}: " + "; ".join(problems) + " (give these arguments to train.launch; scripts/train.sh adds them"
            " from the experiment by itself)"
        )
    if problems:
        raise ExperimentError(
            f"{path}: " + "; ".join(problems) + " (leave these arguments out: the experiment sets the workers' stack)"
        )
    if "unet_backend" in want:
        why = refuse_emulated(want["unet_backend"])
        if why:
            raise ExperimentError(f"{path}: {why}")
    return [f"{k}:={v}" for k, v in want.items() if k not in given]


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    check = "--check" in argv
    try:
        out = launch_args([a for a in argv if a != "--check"], check=check)
    except (ExperimentError, ValueError) as e:
        print(f"train: {e}", file=sys.stderr)
        return 2
    if check:
        print("ok")
        return 0
    for a in out:
        print(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The one table of a campaign's defaults (no ROS imports).

`rosrun asg_agent campaign` takes its defaults from here; `launch/train.launch` writes the same
values as its arguments' defaults, `scripts/train.sh` runs train.launch, and docs/agent.md's
table of defaults is generated from here (`python3 -m asg_analysis defaults`);
tests/test_defaults.py compares all four. A setting keeps one name: the launch argument's, the
option `--NAME` with `_` read as `-` (plus the older spellings in `aliases`).

What the two entry points cannot share is said in `apart`: train.launch starts its workers and
their reference stacks (`attribution`), the CLI is given workers that already run.
"""

from typing import Dict, NamedTuple, Tuple


class Default(NamedTuple):
    value: object  # the default, in the unit below
    unit: str  # "[m]", "[-]" or "" (a name, a path, a count)
    meaning: str
    aliases: Tuple[str, ...] = ()  # older option spellings the CLI still takes


#: the scene generator the defaults run: the setting, its default, and what it is
DEFAULTS: Dict[str, Default] = {
    "experiment": Default(
        "experiments/exp1-route-wide.yaml",
        "",
        "the experiment file (scene, stack under test, action space); relative paths from the repository",
    ),
    "method": Default("novelty-ts", "", "the search method (search/methods.py)"),
    "reward": Default(
        "auto",
        "",
        "what the search maximises; auto: flaw with the three-stack references, regression with a release, "
        "else failure",
    ),
    "scenarios": Default(500, "", "scenarios in the campaign"),
    "workers": Default(2, "", "scene workers running the stack under test"),
    "seed": Default(0, "", "seeds every random choice of the search"),
    "store": Default("~/.ros/asg/campaigns.sqlite", "", "the SQLite scenario store"),
    "tabu_m": Default(2.0, "[m]", "novelty-ts: no obstacle this close to a found place of its class"),
    "route_band": Default(5.0, "[m]", "route-random: half-width of the band around the start-goal route"),
    "generators": Default(
        "uniform,band",
        "",
        "coverage-ts, coverage-veto: its generators, some of uniform, band, route and mutate",
        ("--coverage-generators",),
    ),
    "atlas": Default("auto", "", "the failure atlas the campaign counts coverage of: auto, a file or none"),
}

#: where the two entry points differ by what they are, not by a setting
APART = {
    "attribution": "train.launch: `three` (it starts the unflawed U-Net and ground-truth workers); "
    "the CLI: none unless `--reference ROLE=WORKERS` names running reference workers",
}


def option(name: str) -> str:
    """The CLI option of a setting (`route_band` -> `--route-band`)."""
    return "--" + name.replace("_", "-")


def text(name: str) -> str:
    """A default as the launch file and the docs write it."""
    return f"{DEFAULTS[name].value:g}" if isinstance(DEFAULTS[name].value, float) else str(DEFAULTS[name].value)


def doc_table() -> str:
    """docs/agent.md's table of defaults (generated)."""
    out = [
        "| setting | train.launch | `rosrun asg_agent campaign` | default | meaning |",
        "|---|---|---|---|---|",
    ]
    for name, d in DEFAULTS.items():
        cli = "positional `EXPERIMENT`" if name == "experiment" else f"`{option(name)}`"
        unit = f" {d.unit}" if d.unit else ""
        out.append(f"| {name} | `{name}:=` | {cli} | `{text(name)}`{unit} | {d.meaning} |")
    for name, why in APART.items():
        out.append(f"| {name} | `{name}:=` | - | - | {why} |")
    return "\n".join(out)

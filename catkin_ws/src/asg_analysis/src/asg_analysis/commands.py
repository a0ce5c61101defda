"""The one way into the analysis: `python3 -m asg_analysis COMMAND [ARGS]` (no ROS).

Every command is a module of asg_analysis (the library) or asg_analysis.studies (one study or page
of docs/ each) with a `run(argv) -> int` function; the table below names them, in the order
`python3 -m asg_analysis --help` lists them. A command's name is its module's name with "-" for
"_" (asg_analysis/studies/gap_nav_study.py is `gap-nav-study`), so either finds the other.

    python3 -m asg_analysis --help                 # every command, one line each
    python3 -m asg_analysis docs [--check]         # every generated block of README.md and docs/
    python3 -m asg_analysis COMMAND --help         # one command's arguments

A test (asg_analysis/test/test_commands.py) holds the table to the modules: each one with a `run` is listed, each
listed one has a `run`, and no module of the package has a `main` or a `__main__` block of its own.
"""

import importlib
import sys
from typing import List, Optional

# name, module (under asg_analysis), one line for --help
LIBRARY = (
    ("docs", "docs", "rewrite (or --check) every generated block of README.md and docs/, in order"),
    ("study", "study", "a study record's blocks from its protocol file's report: list"),
    ("protocol", "protocol", "a protocol's plan, pilot choice, status and analysis"),
    ("blocks", "blocks", "the confirmatory blocks of a protocol, one machine each"),
    ("coverage", "coverage", "a campaign's coverage of a failure atlas: the arms, the record, the figure"),
    ("defaults", "defaults", "docs/agent.md's table of campaign defaults"),
    ("endpoints", "endpoints", "a study's endpoints over exports, as a table or a page's block"),
    ("stats", "stats", "arms of campaign exports compared on one score, over seeds"),
    ("rules", "rules", "what a campaign's failures have in common, and a rule checked on fresh samples"),
    ("learning-curve", "learning_curve", "findings over the budget, per arm"),
    ("reuse", "reuse", "whether an older study's export may stand for a newer protocol's campaign"),
    ("replays", "replays", "the replays of a campaign's findings, as a page's block"),
    ("report", "report", "a campaign's HTML report from its store"),
    ("figures", "figures", "top-down pictures of a campaign's scenarios"),
    ("budget", "budget", "how each arm of a study spends its budget"),
    ("bench", "bench", "where a campaign's time goes: tables of bench breakdowns"),
)
STUDIES = (
    ("experiments", "studies.experiments", "every table and figure of docs/experiments.md"),
    ("seed-tables", "studies.seed_tables", "the search comparison over seeds, with intervals and tests"),
    ("stack-study", "studies.stack_study", "the default search against random on one stack under test"),
    ("gap-nav-study", "studies.gap_nav_study", "what gap_nav's search adds, and what its failures are"),
    ("hardening", "studies.hardening", "the design loop's hardening figures"),
    ("held-apart", "studies.held_apart", "near twins of the design loop's held-apart sets"),
    ("loop-study", "studies.loop_study", "the design loop's measurement"),
    ("learned", "studies.learned", "what a search learned: each obstacle attribute's share"),
    ("mechanism", "studies.mechanism", "what the flawed U-Net gets wrong before its flaw findings"),
    ("candidates", "studies.candidates", "what the candidate rule missed"),
    ("run-spread", "studies.run_spread", "run-to-run spread of a free-running stack"),
    ("reliability", "studies.reliability", "docs/reliability.md's soak table"),
    ("pictures", "studies.pictures", "the picture panels of docs/simulator.md"),
)
COMMANDS = {name: (module, help) for name, module, help in LIBRARY + STUDIES}


def prog(name: str) -> str:
    """What a command's --help and errors call it."""
    return f"python3 -m asg_analysis {name}"


def usage() -> str:
    width = max(len(n) for n in COMMANDS)
    lines = ["usage: python3 -m asg_analysis COMMAND [ARGS]   (COMMAND --help: its arguments)", "", "the library:"]
    lines += [f"  {n:<{width}}  {h}" for n, _, h in LIBRARY]
    lines += ["", "one study or page each:"]
    lines += [f"  {n:<{width}}  {h}" for n, _, h in STUDIES]
    return "\n".join(lines)


def call(name: str, argv: List[str]) -> int:
    """Runs one command in this process; its exit status (argparse's SystemExit folded in)."""
    if name not in COMMANDS:
        raise KeyError(f"no command {name!r} (python3 -m asg_analysis --help lists them)")
    module = importlib.import_module("asg_analysis." + COMMANDS[name][0])
    try:
        return int(module.run(argv) or 0)
    except SystemExit as e:  # argparse's --help and usage errors
        return e.code if isinstance(e.code, int) else (0 if e.code is None else 2)


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        return 0 if argv else 2
    if argv[0] not in COMMANDS:
        print(f"asg_analysis: no command {argv[0]!r}\n\n{usage()}", file=sys.stderr)
        return 2
    return call(argv[0], argv[1:])

"""The shipped models' shadow false-obstacle figures over several held-apart 600-frame sets
(dataset seeds other than the training seeds 1 and 2): the spread quoted in docs/perception.md
(scripts/repro/perception_spread.sh is its wrapper; in Python since issue #38).

    python3 -m asg_perception.spread [--seeds 3 4 5 6 7 8] [--suffix _lite] [--table-only]
"""

import argparse
import glob
import json
import os
import statistics
import subprocess
import sys
import tempfile
from typing import List, Tuple

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), *[".."] * 5))
WS = os.path.join(REPO, "catkin_ws")
FRAMES = 600  # per held-apart set
TRAINING_SEEDS = (1, 2)  # the models' own data: never a held-apart set


def out_folder(suffix: str) -> str:
    base = os.path.join(REPO, "results", "perception_spread")
    return os.path.join(base, suffix.lstrip("_")) if suffix else base


def measure(seed: int, suffix: str, out: str):
    """Renders the held-apart set of `seed` and evaluates full and flawed on it: OUT/seed_SEED.json."""
    models = os.path.join(WS, "src", "asg_perception", "models")
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, LP_NUM_THREADS="1")
        from asg_scenario.binaries import find_binary  # asg_sim: an exec_depend of asg_perception

        dataset = find_binary("asg_sim", "asg_sim_dataset")
        from asg_scenario.catalogue import MESHES

        # every class of the catalogue, in its order (the one source; issue #80: it named them)
        cmd = [dataset, "--out", d, "--count", str(FRAMES), "--seed", str(seed), "--meshes", ",".join(MESHES)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=env)
        cmd = [sys.executable, "-m", "asg_perception.evaluate", f"full={models}/full{suffix}.pt"]
        cmd += [f"flawed={models}/flawed{suffix}.pt", "--data", d, "--json", os.path.join(out, f"seed_{seed}.json")]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def ratios(folder: str) -> List[Tuple]:
    """(seed, ratio overall, ratio at low sun, full's rate, flawed's rate) per evaluated set."""
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "seed_*.json"))):
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
        full, flawed = d["results"]["full"], d["results"]["flawed"]
        key = "shadow_false_obstacle_rate"
        rows.append(
            (
                os.path.basename(path)[5:-5],
                flawed[key] / full[key],
                flawed["low_sun"][key] / full["low_sun"][key],
                full[key],
                flawed[key],
            )
        )
    return rows


def table(folder: str) -> str:
    rows = ratios(folder)
    if not rows:
        raise FileNotFoundError(f"{folder}: no seed_*.json (run without --table-only first)")
    out = ["| dataset seed | full | flawed | ratio overall | ratio low sun |", "|---|---|---|---|---|"]
    out += [f"| {seed} | {fu:.4f} | {fl:.4f} | {r:.1f}x | {rl:.1f}x |" for seed, r, rl, fu, fl in rows]
    ov, lo = [r[1] for r in rows], [r[2] for r in rows]
    out.append(
        f"\noverall ratio: median {statistics.median(ov):.1f}x, min {min(ov):.1f}x, max {max(ov):.1f}x; "
        f"low sun: median {statistics.median(lo):.1f}x, min {min(lo):.1f}x, max {max(lo):.1f}x"
    )
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="asg_perception.spread", description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[3, 4, 5, 6, 7, 8], help="held-apart dataset seeds")
    p.add_argument("--suffix", default="", help="model pair suffix: '' (full size) or _lite")
    p.add_argument("--table-only", action="store_true", help="print the table of what is measured, measure nothing")
    a = p.parse_args(argv)
    bad = sorted(set(a.seeds) & set(TRAINING_SEEDS))
    if bad:
        p.error(f"--seeds {bad[0]}: a training seed, not a held-apart set")
    out = out_folder(a.suffix)
    os.makedirs(out, exist_ok=True)
    if not a.table_only:
        for s in a.seeds:
            print(
                f"[asg] seed {s}: rendering {FRAMES} frames, evaluating full{a.suffix} and flawed{a.suffix}", flush=True
            )
            measure(s, a.suffix, out)
    try:
        print(table(out))
    except FileNotFoundError as e:
        print(f"spread: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

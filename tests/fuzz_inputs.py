#!/usr/bin/python3
"""Fuzzing harness (issue #14): mutated inputs wherever a user or another node can send them.

    fuzz_inputs.py loaders [--count 10000] [--seed 0] [--json OUT]
        scenario YAML through the Python loader (asg_scenario.load_scenario) and the simulator's
        own (asg_sim_validate, batches of files), experiment files through load_experiment.
        Passes when every input is either accepted or refused with the loader's own error
        (ScenarioError / ExperimentError / SceneError) naming something, no loader raises anything
        else or crashes, and the two scenario loaders agree on every input.
    fuzz_inputs.py goals --worker /worker_0 [--count 1000] [--seed 0] [--json OUT]
        RunScenario goals from a client (random, NaN, inf, huge, negative, empty, over-long
        lists, repeated ids, new goals and cancels mid-run) to a running worker. Passes when every
        goal ends (ABORTED with an error naming a field, or run), the worker process never
        restarts, and its memory does not grow with the number of refused goals.

Classes of mutation (both modes): a value replaced by NaN, +-inf, a huge or negative number,
zero, an empty or long string, a list, a mapping, null or a bool; a key deleted or an unknown one
added; obstacle lists emptied or grown past the budget; and for files also truncation, flipped
and inserted bytes, duplicated keys, deep nesting, binary garbage and empty files.
"""

import argparse
import copy
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from collections import Counter

import yaml

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SEEDS = [
    os.path.join(REPO, "scenarios", f)
    for f in sorted(os.listdir(os.path.join(REPO, "scenarios")))
    if f.endswith(".yaml")
] + [
    os.path.join(REPO, "scenarios", "corpus", "good", f)
    for f in sorted(os.listdir(os.path.join(REPO, "scenarios", "corpus", "good")))
]
EXPERIMENTS = [  # experiment files (a study's protocol-*.yaml or study-*.yaml beside them is not one)
    os.path.join(REPO, "experiments", f)
    for f in sorted(os.listdir(os.path.join(REPO, "experiments")))
    if f.endswith(".yaml") and not f.startswith(("protocol-", "study-"))
]

WEIRD = [
    ("nan", float("nan")),
    ("inf", float("inf")),
    ("-inf", float("-inf")),
    ("huge_int", 10**30),
    ("huge_float", 1e308),
    ("negative", -12345.5),
    ("zero", 0),
    ("empty_string", ""),
    ("long_string", "x" * 5000),
    ("list", [1, 2, 3]),
    ("mapping", {"a": 1}),
    ("null", None),
    ("bool", True),
    ("tiny", 1e-300),
]


def leaves(d, path=()):
    """Every (path, value) of a nested dict/list."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from leaves(v, path + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from leaves(v, path + (i,))
    yield path, d


def set_at(d, path, value):
    for k in path[:-1]:
        d = d[k]
    d[path[-1]] = value


def del_at(d, path):
    for k in path[:-1]:
        d = d[k]
    if isinstance(d, dict):
        del d[path[-1]]
    else:
        d.pop(path[-1])


def mutate_dict(rng, base):
    """(class, mutated dict)."""
    d = copy.deepcopy(base)
    paths = [p for p, _ in leaves(d) if p]
    kind = rng.random()
    if kind < 0.55:
        p = rng.choice(paths)
        name, value = rng.choice(WEIRD)
        set_at(d, p, copy.deepcopy(value))
        return f"value:{name}", d
    if kind < 0.70:
        del_at(d, rng.choice(paths))
        return "delete_key", d
    if kind < 0.78:
        holder = rng.choice([p for p, v in leaves(d) if isinstance(v, dict)] or [()])
        target = d
        for k in holder:
            target = target[k]
        target[f"unknown_{rng.randrange(1000)}"] = 1
        return "unknown_key", d
    layouts = d.get("structural", {}).get("layouts") if isinstance(d.get("structural"), dict) else None
    if (
        isinstance(layouts, list)
        and layouts
        and isinstance(layouts[0], dict)
        and isinstance(layouts[0].get("instances"), list)
    ):
        if kind < 0.86:
            layouts[0]["instances"] = []
            return "empty_instances", d
        inst = layouts[0]["instances"][0] if layouts[0]["instances"] else {"x": 1.0, "y": 1.0}
        layouts[0]["instances"] = [copy.deepcopy(inst) for _ in range(rng.choice([513, 600, 5000]))]
        return "too_many_instances", d
    return "noop_structure", d


def mutate_text(rng, text):
    b = text.encode()
    kind = rng.random()
    if kind < 0.25:
        return "truncate", b[: rng.randrange(len(b) + 1)]
    if kind < 0.45:
        arr = bytearray(b)
        for _ in range(rng.randint(1, 8)):
            arr[rng.randrange(len(arr))] = rng.randrange(256)
        return "flip_bytes", bytes(arr)
    if kind < 0.60:
        i = rng.randrange(len(b) + 1)
        return "insert_bytes", b[:i] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 32))) + b[i:]
    if kind < 0.72:
        lines = text.splitlines(keepends=True)
        i = rng.randrange(len(lines))
        return "duplicate_line", "".join(lines[: i + 1] + [lines[i]] + lines[i + 1 :]).encode()
    if kind < 0.80:
        n = rng.choice([50, 1000, 20000])
        return "deep_nesting", ("a: " + "[" * n + "]" * n + "\n").encode()
    if kind < 0.90:
        return "garbage", bytes(rng.randrange(256) for _ in range(rng.randint(0, 512)))
    return "empty", b""


def dump(d) -> bytes:
    return yaml.dump(
        d, Dumper=getattr(yaml, "CSafeDumper", yaml.SafeDumper), sort_keys=False, allow_unicode=True
    ).encode()


def python_scenario(path):
    from asg_scenario import ScenarioError, load_scenario

    try:
        load_scenario(path)
        return "OK", ""
    except ScenarioError as e:
        return "ERROR", str(e)


def python_experiment(path):
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))
    from asg_agent.records.experiment import ExperimentError, load_experiment

    try:
        load_experiment(path)
        return "OK", ""
    except ExperimentError as e:
        return "ERROR", str(e)


def validate_cpp(paths, tool):
    """{path: ("OK"|"ERROR"|"CRASH", text)} from asg_sim_validate over a batch."""
    r = subprocess.run([tool] + paths, capture_output=True, text=True, errors="replace", timeout=600)
    out = {}
    for line in r.stdout.splitlines():
        status, _, rest = line.partition(" ")
        path = rest.split(": ", 1)[0] if status == "ERROR" else rest
        out[path] = (status, rest)
    if r.returncode not in (0, 1):
        for p in paths:
            out.setdefault(p, ("CRASH", f"asg_sim_validate exited {r.returncode}: {r.stderr[-300:]}"))
    for p in paths:
        out.setdefault(p, ("CRASH", "no answer for this file"))
    return out


def fuzz_loaders(count, seed, tool, progress=True):
    rng = random.Random(seed)
    bases = [(p, yaml.safe_load(open(p))) for p in SEEDS]
    exp_bases = [(p, open(p).read()) for p in EXPERIMENTS]
    tmp = tempfile.mkdtemp(prefix="asg_fuzz_")
    classes, failures, outcomes = Counter(), [], Counter()
    batch, n = [], 0
    started = time.time()

    def flush():
        results = validate_cpp([p for p, _, _ in batch], tool)
        for path, cls, py in batch:
            cpp = results[path]
            outcomes[f"scenario {py[0]}/{cpp[0]}"] += 1
            if cpp[0] == "CRASH":
                failures.append({"class": cls, "file": path, "why": cpp[1]})
            elif py[0] != cpp[0]:
                failures.append(
                    {
                        "class": cls,
                        "file": path,
                        "why": f"loaders disagree: python {py[0]} {py[1][:300]!r}, C++ {cpp[1][:300]!r}",
                    }
                )
            else:
                os.remove(path)
        batch.clear()

    while n < count:
        n += 1
        if n % 10 == 0:  # an experiment file
            src, text = rng.choice(exp_bases)
            if rng.random() < 0.5:
                cls, data = mutate_text(rng, text)
            else:
                cls, d = mutate_dict(rng, yaml.safe_load(text))
                data = dump(d)
            path = os.path.join(os.path.dirname(src), f".fuzz_{os.getpid()}_{n}.yaml")  # relative paths resolve
            with open(path, "wb") as f:
                f.write(data)
            try:
                status, why = python_experiment(path)
            except Exception as e:  # noqa: BLE001 - exactly what the fuzzer looks for
                failures.append({"class": "experiment " + cls, "file": path, "why": f"{type(e).__name__}: {e}"[:500]})
                status, why = "RAISED", ""
            finally:
                keep = os.path.join(tmp, f"experiment_{n}.yaml")
                os.replace(path, keep)
            classes["experiment " + cls] += 1
            outcomes[f"experiment {status}"] += 1
            if status == "ERROR" and not why.strip():
                failures.append({"class": "experiment " + cls, "file": keep, "why": "empty error message"})
            if status != "RAISED" and not (failures and failures[-1]["file"] == keep):
                os.remove(keep)
            continue
        src, base = rng.choice(bases)
        if rng.random() < 0.6:
            cls, d = mutate_dict(rng, base)
            data = dump(d)
        else:
            cls, data = mutate_text(rng, open(src).read())
        classes["scenario " + cls] += 1
        path = os.path.join(tmp, f"scenario_{n}.yaml")
        with open(path, "wb") as f:
            f.write(data)
        try:
            py = python_scenario(path)
        except Exception as e:  # noqa: BLE001
            failures.append({"class": "scenario " + cls, "file": path, "why": f"{type(e).__name__}: {e}"[:500]})
            continue
        if py[0] == "ERROR" and not py[1].strip():
            failures.append({"class": "scenario " + cls, "file": path, "why": "empty error message"})
        batch.append((path, "scenario " + cls, py))
        if len(batch) >= 400:
            flush()
            if progress:
                print(
                    f"  {n}/{count} inputs, {len(failures)} failure(s), {time.time() - started:.0f} s", file=sys.stderr
                )
    if batch:
        flush()
    return {
        "mode": "loaders",
        "inputs": n,
        "seed": seed,
        "seconds": round(time.time() - started, 1),
        "classes": dict(sorted(classes.items())),
        "outcomes": dict(sorted(outcomes.items())),
        "failures": failures[:50],
        "failure_count": len(failures),
        "kept": tmp,
    }


def main(argv=None):
    p = argparse.ArgumentParser(prog="fuzz_inputs", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="mode", required=True)
    lo = sub.add_parser("loaders")
    go = sub.add_parser("goals")
    go.add_argument("--worker", default="/worker_0")
    for s in (lo, go):
        s.add_argument("--count", type=int, default=10000 if s is lo else 1000)
        s.add_argument("--seed", type=int, default=0)
        s.add_argument("--json", default="")
    lo.add_argument("--tool", default=os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_sim", "asg_sim_validate"))
    a = p.parse_args(argv)
    if a.mode == "loaders":
        out = fuzz_loaders(a.count, a.seed, a.tool)
    else:
        import rospy
        import stack_util as su
        from fuzz_goals import fuzz_goals

        rospy.init_node("fuzz_goals", anonymous=True)
        out = fuzz_goals(a.worker, a.count, a.seed, pid_of=lambda: su.node_pid(a.worker.rstrip("/") + "/scene_worker"))
    print(json.dumps({k: v for k, v in out.items() if k != "failures"}, indent=1))
    for f in out["failures"][:10]:
        print(f"FAILURE {f['class']}: {f['file']}: {f['why']}", file=sys.stderr)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0 if out["failure_count"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())

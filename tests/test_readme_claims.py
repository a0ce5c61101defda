"""Issue #68 item 5 (issue #79: now in docs/benchmarks.md): the page names exactly the CPUs and
U-Net backends on which the stored reference runs replayed bit for bit, as
results/numerics/cpu_classes.json records them (its table, "CPU classes"), and claims no more."""

import json
import os

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
DEFAULT = "polyphase"  # asg_perception.numerics.DEFAULT_BACKEND, checked below

#: a CPU as the README names it, from its best oneDNN ISA (a new one fails until it is named)
CLASS = {"AVX512_CORE_BF16": "AVX512-BF16", "AVX2": "AVX2-only", "AVX512_CORE_AMX": "AMX"}


def flat(path):
    with open(os.path.join(REPO, path), encoding="utf-8") as f:
        return " ".join(f.read().split())


def cpu_name(c):
    maker = "AMD EPYC" if "EPYC" in c["cpu"] else "Intel Xeon" if "Xeon" in c["cpu"] else c["cpu"]
    return f"the {CLASS[c['best_isa']]} {maker}"


def checked(classes):
    """{backend: {CPU: kernels}} of every recorded line, in the order first recorded; kernels:
    "own" (oneDNN's choice) or the ISA the line was pinned to."""
    out = {}
    for c in classes:
        backend = c["numerics"].split()[0]
        isa = dict(w.split("=", 1) for w in c["numerics"].split()[1:] if "=" in w)["isa"]
        pinned = isa == "AVX2" and c["best_isa"] != "AVX2"
        out.setdefault(backend, {}).setdefault(cpu_name(c), []).append("pinned to AVX2" if pinned else "own")
    return out


def said(checked_):
    """The README's list, written from the records."""
    parts = []
    for backend in sorted(checked_, key=lambda b: (b != DEFAULT, b)):
        cpus = []
        for name, kernels in checked_[backend].items():
            if set(kernels) == {"own", "pinned to AVX2"}:
                name += ", on its own kernels and pinned to AVX2"
            elif set(kernels) == {"pinned to AVX2"}:
                name += " pinned to AVX2"
            cpus.append(name)
        listed = cpus[0] if len(cpus) == 1 else ", ".join(cpus[:-1]) + " and " + cpus[-1]
        parts.append(f"`{backend}`{' (the default)' if backend == DEFAULT else ''} on {listed}")
    return "; ".join(parts)


def test_the_readme_names_exactly_the_cpus_and_backends_checked():
    from asg_perception import numerics

    assert numerics.DEFAULT_BACKEND == DEFAULT
    with open(os.path.join(REPO, "results", "numerics", "cpu_classes.json"), encoding="utf-8") as f:
        classes = json.load(f)["classes"]
    assert all(c["reference"] == "tests/reference/exp1_flawed_fp32.json" for c in classes)
    # issue #79: the list lives with its table (docs/benchmarks.md), not on the README's first
    # screen, and it no longer says "no others were checked": the suite's runs checked others
    sentence = f"The five stored reference runs replayed bit for bit on these CPUs and backends, as recorded here: {said(checked(classes))}."
    page = flat("docs/benchmarks.md")
    assert sentence in page, sentence
    readme = flat("README.md")
    assert "no others were checked" not in readme + page
    assert "across the CPU classes checked" not in readme
    assert "replays anywhere" not in readme and "replayed exactly from its request" not in readme


def test_the_list_is_written_from_the_records():
    # the records as they stand: polyphase on one CPU (native and pinned), channels_last on three
    classes = [
        {"cpu": "AMD EPYC", "best_isa": "AVX512_CORE_BF16", "numerics": "polyphase isa=AVX512_CORE threads=1"},
        {"cpu": "AMD EPYC", "best_isa": "AVX512_CORE_BF16", "numerics": "polyphase isa=AVX2 threads=1"},
        {"cpu": "Intel(R) Xeon(R)", "best_isa": "AVX512_CORE_AMX", "numerics": "channels_last isa=AVX512_CORE"},
    ]
    assert said(checked(classes)) == (
        "`polyphase` (the default) on the AVX512-BF16 AMD EPYC, on its own kernels and pinned to AVX2; "
        "`channels_last` on the AMX Intel Xeon"
    )
    # one more record names one more pair, and the README's sentence must follow
    classes.append({"cpu": "AMD EPYC VM", "best_isa": "AVX2", "numerics": "polyphase isa=AVX2 threads=1"})
    assert "AVX2 and the AVX2-only AMD EPYC;" in said(checked(classes))

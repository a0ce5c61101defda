"""Bad input (issue #14): a short run of the fuzzing harness over the scenario and experiment
loaders (Python and the simulator's own), and the two defects it found, pinned: files that are
not UTF-8 and keys given twice were accepted by one loader and refused by the other (or made the
Python loader raise UnicodeDecodeError / RecursionError instead of its own error)."""

import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, HERE)
import fuzz_inputs  # noqa: E402

TOOL = os.path.join(fuzz_inputs.REPO, "catkin_ws", "devel", "lib", "asg_sim", "asg_sim_validate")


def test_short_fuzz_run_of_the_loaders():
    out = fuzz_inputs.fuzz_loaders(300, seed=7, tool=TOOL, progress=False)
    assert out["inputs"] == 300
    assert out["failure_count"] == 0, out["failures"][:5]
    assert len(out["classes"]) >= 15  # the mutation classes were really exercised
    assert out["outcomes"].get("scenario ERROR/ERROR", 0) > 100


EXP1 = open(os.path.join(fuzz_inputs.REPO, "scenarios", "exp1.yaml"), "rb").read()


@pytest.mark.parametrize(
    "name,data,needle,cpp_needle",
    [
        ("latin1", EXP1.replace(b"name:", b"n\xe4me:", 1), "not UTF-8 text (byte 0xe4", "not UTF-8 text (byte 0xe4"),
        ("duplicate", EXP1 + b"\nname: again\n", "given twice", "given twice"),
        # issue #68: the Python needle was "", in every message; yaml-cpp's own refusal has no words of ours
        ("deep", b"a: " + b"[" * 5000 + b"]" * 5000 + b"\n", "nested too deeply to be a scenario", ""),
        ("control", EXP1.replace(b"name:", b"na\x18me:", 1), "#x0018", "control character YAML does not allow"),
    ],
)
def test_both_loaders_refuse_with_their_own_error(tmp_path, name, data, needle, cpp_needle):
    from asg_scenario import ScenarioError, load_scenario

    path = tmp_path / f"{name}.yaml"
    path.write_bytes(data)
    with pytest.raises(ScenarioError) as e:
        load_scenario(str(path))
    assert needle in str(e.value)
    r = subprocess.run([TOOL, str(path)], capture_output=True, text=True, errors="replace", timeout=60)
    assert r.returncode == 1, r.stdout + r.stderr
    assert r.stdout.startswith("ERROR ") and cpp_needle in r.stdout


def test_experiment_loader_refuses_bytes_and_duplicates(tmp_path):
    sys.path.insert(0, os.path.join(fuzz_inputs.REPO, "catkin_ws", "src", "asg_agent", "src"))
    from asg_agent.records.experiment import ExperimentError, load_experiment

    for data, needle in ((b"name: e\xff\n", "not UTF-8"), (b"name: a\nname: b\n", "given twice")):
        p = tmp_path / "e.yaml"
        p.write_bytes(data)
        with pytest.raises(ExperimentError) as e:
            load_experiment(str(p))
        assert needle in str(e.value)

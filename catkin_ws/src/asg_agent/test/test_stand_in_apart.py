"""The in-process stand-in for the worker pool (stand_in/, beside these tests) lives in the tests
only. No file of the running system (a package's src/, nodes/ or scripts/) imports it, none names
its `fake_workers` option (the commands take their workers as an argument instead of branching on
the stand-in), no package installs it, and the commands users run have no --fake-workers. Each rule
is shown failing on a made-up package tree."""

import ast
import glob
import os
import json
import re
import sqlite3
import subprocess
import sys

import pytest

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))  # catkin_ws/src
REPO = os.path.abspath(os.path.join(SRC, "..", ".."))
#: an import of the stand-in: its package, its pool module, or where it lived before
IMPORT = re.compile(
    r"^\s*(from|import)\s+(stand_in|fake_pool|asg_agent\.testing)\b|^\s*from\s+asg_agent\s+import\s+testing\b", re.M
)


def production_files(root):
    """{path relative to root: text} of the files of the running system: every file under
    root/*/src, root/*/nodes and root/*/scripts (not the tests)."""
    out = {}
    for pattern in (("*", "src", "**", "*.py"), ("*", "nodes", "**", "*"), ("*", "scripts", "**", "*")):
        for path in glob.glob(os.path.join(root, *pattern), recursive=True):
            if os.path.isfile(path) and "__pycache__" not in path:
                with open(path, encoding="utf-8", errors="replace") as f:
                    out[os.path.relpath(path, root)] = f.read()
    return out


def importers(root):
    """The files of the running system that import the stand-in."""
    return sorted(rel for rel, text in production_files(root).items() if IMPORT.search(text))


def naming_the_option(root):
    """The files of the running system that name the stand-in's option `fake_workers`."""
    return sorted(rel for rel, text in production_files(root).items() if "fake_workers" in text)


def installed_stand_ins(root):
    """What the packages' setup.py files install of the stand-in: a listed package that is not a
    folder of the package's src/, that holds fake_pool.py, or that is named testing or stand_in;
    and any fake_pool.py under a package's src/."""
    found = []
    for setup in sorted(glob.glob(os.path.join(root, "*", "setup.py"))):
        pkg_dir = os.path.dirname(setup)
        call = next(
            n
            for n in ast.walk(ast.parse(open(setup, encoding="utf-8").read()))
            if isinstance(n, ast.Call) and getattr(n.func, "id", "") == "generate_distutils_setup"
        )
        kw = {k.arg: ast.literal_eval(k.value) for k in call.keywords}
        base = os.path.join(pkg_dir, kw.get("package_dir", {}).get("", ""))
        for name in kw.get("packages", []):
            folder = os.path.normpath(os.path.join(base, *name.split(".")))
            rel = os.path.relpath(setup, root)
            if os.path.relpath(folder, pkg_dir).split(os.sep)[0] != "src":
                found.append(f"{rel}: {name} (not under src/)")
            elif name.split(".")[-1] in ("testing", "stand_in") or os.path.isfile(os.path.join(folder, "fake_pool.py")):
                found.append(f"{rel}: {name}")
    found += [
        os.path.relpath(p, root)
        for p in glob.glob(os.path.join(root, "*", "src", "**", "fake_pool.py"), recursive=True)
    ]
    return sorted(found)


def made_up_package(tmp_path):
    """A package tree that keeps every rule: src/pkg/m.py, nodes/n, scripts/s, setup.py."""
    root = tmp_path / "src"
    mod = root / "pkg" / "src" / "pkg"
    mod.mkdir(parents=True)
    (mod / "__init__.py").write_text("")
    (mod / "m.py").write_text("import os\n\n\ndef main(argv=None, workers=None):\n    return workers\n")
    for sub, name in (("nodes", "n"), ("scripts", "s")):
        (root / "pkg" / sub).mkdir()
        (root / "pkg" / sub / name).write_text("#!/usr/bin/python3\nfrom pkg.m import main\n\nmain()\n")
    (root / "pkg" / "test" / "stand_in").mkdir(parents=True)
    (root / "pkg" / "test" / "stand_in" / "fake_pool.py").write_text("class FakePool:\n    pass\n")
    setup = (
        "from catkin_pkg.python_setup import generate_distutils_setup\nfrom setuptools import setup\n\n"
        'setup(**generate_distutils_setup(packages=["pkg"], package_dir={"": "src"}))\n'
    )
    (root / "pkg" / "setup.py").write_text(setup)
    return root


def test_no_file_of_the_running_system_imports_the_stand_in(tmp_path):
    assert importers(SRC) == []
    root = made_up_package(tmp_path)
    assert importers(str(root)) == []
    # the mutations: a module of src/, a node and a script that import it, each seen
    (root / "pkg" / "src" / "pkg" / "m.py").write_text("from stand_in.fake_pool import FakePool\n")
    (root / "pkg" / "nodes" / "n").write_text("#!/usr/bin/python3\nimport stand_in.campaign\n")
    (root / "pkg" / "scripts" / "s").write_text("#!/usr/bin/python3\nfrom asg_agent.testing import fake_pool\n")
    assert importers(str(root)) == [
        os.path.join("pkg", "nodes", "n"),
        os.path.join("pkg", "scripts", "s"),
        os.path.join("pkg", "src", "pkg", "m.py"),
    ]


def test_no_file_of_the_running_system_branches_on_the_stand_in(tmp_path):
    assert naming_the_option(SRC) == []
    root = made_up_package(tmp_path)
    assert naming_the_option(str(root)) == []
    # the mutation: a command that picks its pool by the stand-in's option
    (root / "pkg" / "src" / "pkg" / "m.py").write_text(
        "def main(a):\n    return stand_in(a) if a.fake_workers else ros_pools(a)\n"
    )
    assert naming_the_option(str(root)) == [os.path.join("pkg", "src", "pkg", "m.py")]


def test_no_package_installs_the_stand_in(tmp_path):
    assert installed_stand_ins(SRC) == []
    assert os.path.isfile(os.path.join(SRC, "asg_agent", "test", "stand_in", "fake_pool.py"))  # where it lives
    root = made_up_package(tmp_path)
    assert installed_stand_ins(str(root)) == []
    setup = root / "pkg" / "setup.py"
    text = setup.read_text()
    # the mutations: the stand-in listed as a package of src/ (and moved there), then the tests'
    # folder listed as the packages' root
    (root / "pkg" / "src" / "pkg" / "testing").mkdir()
    (root / "pkg" / "src" / "pkg" / "testing" / "fake_pool.py").write_text("")
    setup.write_text(text.replace('["pkg"]', '["pkg", "pkg.testing"]'))
    assert installed_stand_ins(str(root)) == [
        os.path.join("pkg", "setup.py") + ": pkg.testing",
        os.path.join("pkg", "src", "pkg", "testing", "fake_pool.py"),
    ]
    (root / "pkg" / "src" / "pkg" / "testing" / "fake_pool.py").unlink()
    setup.write_text(text.replace('["pkg"]', '["pkg", "stand_in"]').replace('{"": "src"}', '{"": "test"}'))
    assert installed_stand_ins(str(root)) == [
        os.path.join("pkg", "setup.py") + ": pkg (not under src/)",
        os.path.join("pkg", "setup.py") + ": stand_in (not under src/)",
    ]


@pytest.mark.parametrize("module", ["campaign", "suite"])
def test_the_users_commands_refuse_fake_workers(module, capsys):
    from asg_agent.cli import campaign, suite

    argv = (
        ["experiments/exp1.yaml", "--fake-workers", "2"]
        if module == "campaign"
        else ["run", "x", "--fake-workers", "1"]
    )
    with pytest.raises(SystemExit) as e:
        (campaign.parse if module == "campaign" else suite.main)(argv)
    assert e.value.code == 2 and "unrecognized arguments: --fake-workers" in capsys.readouterr().err


def test_the_stand_in_hands_the_production_command_its_workers_and_is_recorded_as_such(tmp_path):
    """The stand-in's campaign is the production command given other workers: their names and
    pools, and `fake` in the settings the store keeps (a campaign on ROS workers records none)."""
    from types import SimpleNamespace

    import stand_in
    from asg_agent.campaign.policy import campaign_settings
    from asg_agent.records.experiment import load_experiment

    exp = os.path.join(REPO, "experiments", "exp1.yaml")
    store = str(tmp_path / "s.sqlite")
    cmd = [sys.executable, "-m", "stand_in.campaign", exp, "--fake-workers", "2", "--reference", "ground_truth=1"]
    cmd += [
        "--scenarios",
        "4",
        "--method",
        "random",
        "--store",
        store,
        "--name",
        "c",
        "--no-progress",
        "--no-tensorboard",
    ]
    r = subprocess.run(cmd, env=stand_in.environ(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    settings = json.loads(sqlite3.connect(store).execute("select settings from campaigns").fetchone()[0])
    assert settings["fake"] is True and settings["workers"] == ["fake_0", "fake_1"]
    assert settings["reference_workers"] == ["fake_ground_truth_0"]
    real = campaign_settings(SimpleNamespace(reward="proxy"), load_experiment(exp), ["/worker_0"], {}, "failures")
    assert "fake" not in real

"""Issue #80 item 5: the in-process stand-in (asg_agent.testing) is test support. No module of the
running system imports it (asg_analysis's ASP-effect figure, which measures the search alone on
it, is the one named exception), and the commands users run have no --fake-workers."""

import glob
import os
import re

import pytest

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))  # catkin_ws/src
ALLOWED = {os.path.join("asg_analysis", "src", "asg_analysis", "figures.py")}
IMPORT = re.compile(r"^\s*(from|import)\s+asg_agent\.testing\b|^\s*from\s+asg_agent\s+import\s+testing\b", re.M)


def importers(root):
    """Source files under root/*/src and root/*/nodes (not tests, not asg_agent.testing itself)."""
    out = []
    for path in glob.glob(os.path.join(root, "*", "src", "**", "*.py"), recursive=True) + glob.glob(
        os.path.join(root, "*", "nodes", "*")
    ):
        rel = os.path.relpath(path, root)
        if not os.path.isfile(path) or os.sep + "testing" + os.sep in rel or rel in ALLOWED:
            continue
        with open(path, encoding="utf-8", errors="replace") as f:
            if IMPORT.search(f.read()):
                out.append(rel)
    return out


def test_no_module_of_the_running_system_imports_the_stand_in(tmp_path):
    assert importers(SRC) == []
    # the check sees an import (the mutation): a module of a package's src/ that imports it
    mod = tmp_path / "pkg" / "src" / "pkg"
    mod.mkdir(parents=True)
    (mod / "m.py").write_text("from asg_agent.testing.fake_pool import FakePool\n")
    assert importers(str(tmp_path)) == [os.path.join("pkg", "src", "pkg", "m.py")]


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

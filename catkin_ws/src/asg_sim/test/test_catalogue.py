"""The C++ mesh catalogue (asg_sim_catalogue) and the Python one (asg_scenario) agree."""

import os
import subprocess

import yaml

from asg_scenario.catalogue import MESHES

WS = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def test_catalogues_agree():
    exe = os.path.join(WS, "devel", "lib", "asg_sim", "asg_sim_catalogue")
    out = yaml.safe_load(subprocess.run([exe], check=True, capture_output=True, text=True).stdout)
    assert sorted(out) == sorted(MESHES)
    for name, info in out.items():
        assert abs(info["height"] - MESHES[name].height) < 1e-9, name
        assert abs(info["collision_radius"] - MESHES[name].collision_radius) < 1e-9, name
        assert abs(info["shadow_opacity"] - MESHES[name].shadow_opacity) < 1e-9, name

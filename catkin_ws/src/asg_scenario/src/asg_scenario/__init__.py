"""Scenario format of the adversarial scene generator (no ROS imports)."""

from .catalogue import MESHES, TRAVERSABLE_HEIGHT, MeshInfo, mesh_names
from .schema import (
    FORMAT_VERSION,
    MAX_OBSTACLES,
    ScenarioError,
    dump_scenario,
    load_scenario,
    parse_scenario,
    validate_scenario,
)

__all__ = [
    "MESHES",
    "TRAVERSABLE_HEIGHT",
    "MeshInfo",
    "mesh_names",
    "FORMAT_VERSION",
    "MAX_OBSTACLES",
    "ScenarioError",
    "dump_scenario",
    "load_scenario",
    "parse_scenario",
    "validate_scenario",
]

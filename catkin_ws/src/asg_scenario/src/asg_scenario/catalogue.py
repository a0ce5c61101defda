"""The obstacle mesh catalogue shared by every tool: its one source (issue #69).

Each class's figures at scale 1 (height, collision radius, shadow opacity, colour) and the
vehicle's half-width live here. asg_scenario.cpp_schema generates asg_sim's header
(scene_schema.hpp, ``kCatalogue``) from this module, and the simulator's ``meshCatalogue()``
reads that header; tests/test_scenario_schema.py checks the committed header is what this module
generates, and tests/test_one_source.py that a new class is an entry here and a mesh function.
"""

from dataclasses import dataclass
from typing import Tuple

#: An obstacle no taller than this counts as traversable: the vehicle may drive over it [m].
TRAVERSABLE_HEIGHT = 0.20

#: Half of the vehicle's width, used to tell whether the start pose is inside an obstacle [m].
VEHICLE_HALF_WIDTH = 0.75


@dataclass(frozen=True)
class MeshInfo:
    """Size of an obstacle type at scale 1."""

    name: str
    height: float  #: [m] top of the mesh above the ground
    collision_radius: float  #: [m] radius of the vertical cylinder used for collisions
    shadow_opacity: float  #: [-] share of sunlight its shadow blocks (dense foliage 1)
    description: str
    colour: Tuple[float, float, float] = (0.3, 0.3, 0.3)  #: [-] RGB in pictures, rviz and bags


MESHES = {
    "juniper": MeshInfo(
        "juniper",
        height=4.5,
        collision_radius=1.2,
        shadow_opacity=1.0,
        description="Juniper tree: conifer, trunk and dense conical foliage",
        colour=(0.1, 0.5, 0.15),
    ),
    "barberry": MeshInfo(
        "barberry",
        height=1.2,
        collision_radius=0.8,
        shadow_opacity=0.55,
        description="Barberry bush: rounded, sparse-leaved shrub about 1.2 m tall",
        colour=(0.7, 0.15, 0.15),
    ),
}


def mesh_names():
    """Names of the catalogue's meshes, sorted."""
    return sorted(MESHES)

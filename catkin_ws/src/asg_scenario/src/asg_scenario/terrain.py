"""The ground's height of a scenario (issue #27), as the simulator computes it (no ROS imports).

A mirror of asg_sim's ``Terrain`` (terrain.hpp): the same splitmix64 draws of the 3 plane
waves' directions, wavelengths and phases, the same raised-cosine hills. Tools that draw a scene
(rviz replay markers, reports) use it to stand obstacles and paths on the ground. Both
implementations are checked against one table of heights (scenarios/corpus/terrain_heights.json).
"""

import math
from typing import Sequence

import numpy as np

WAVES = 3  #: asg_sim::kTerrainWaves
_MASK = (1 << 64) - 1


def _splitmix(state: list) -> int:
    state[0] = (state[0] + 0x9E3779B97F4A7C15) & _MASK
    z = state[0]
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
    return z ^ (z >> 31)


def _uniform01(state: list) -> float:
    return (_splitmix(state) >> 11) * (1.0 / 9007199254740992.0)


class Terrain:
    """Height z = h(x, y) [m] of a scenario's ``structural.terrain`` (a canonical dict, or None or
    {} for the flat ground)."""

    def __init__(self, terrain: dict = None):
        terrain = terrain or {}
        self.amplitude = float(terrain.get("amplitude_m", 0.0))
        self.waves = []  #: (kx, ky, phase)
        if self.amplitude > 0.0:
            state = [0x7E44A1A ^ (int(terrain.get("seed", 0)) << 17)]
            for k in range(WAVES):
                theta = math.pi * (k + _uniform01(state)) / WAVES
                lam = float(terrain.get("wavelength_m", 40.0)) * 2.0 ** (_uniform01(state) - 0.5)
                phase = 2.0 * math.pi * _uniform01(state)
                kabs = 2.0 * math.pi / lam
                self.waves.append((kabs * math.cos(theta), kabs * math.sin(theta), phase))
        self.hills = [
            (float(h["x"]), float(h["y"]), float(h["radius_m"]), float(h["height_m"]))
            for h in terrain.get("hills", [])
            if h["height_m"] != 0.0 and h["radius_m"] > 0.0
        ]

    @property
    def flat(self) -> bool:
        return not self.waves and not self.hills

    def height(self, x, y):
        """[m] at (x, y) [m]; scalars or numpy arrays of the same shape."""
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        h = np.zeros(np.broadcast(x, y).shape)
        if self.waves:
            for kx, ky, phase in self.waves:
                h = h + np.cos(kx * x + ky * y + phase)
            h = h * (self.amplitude / len(self.waves))
        for hx, hy, r, height in self.hills:
            d = np.hypot(x - hx, y - hy)
            h = h + np.where(d < r, height * 0.5 * (1.0 + np.cos(np.pi * d / r)), 0.0)
        return h if h.ndim else float(h)

    def heights(self, points: Sequence) -> np.ndarray:
        """[m] at an (n, 2) array of points."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        return np.asarray(self.height(p[:, 0], p[:, 1]), dtype=np.float64).reshape(-1)


def scenario_terrain(scenario: dict) -> Terrain:
    """The Terrain of a scenario dict (a request stored before terrain existed is flat)."""
    return Terrain(scenario.get("structural", {}).get("terrain"))

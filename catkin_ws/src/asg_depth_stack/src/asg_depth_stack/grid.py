"""An elevation grid in the map frame: each cell keeps the lowest and highest point seen in it;
a cell whose points span more than `step_height` is an obstacle (a trunk, a bush, a canopy over
the ground). On smooth terrain a 0.5 m cell spans a few centimetres, so hills are not obstacles.
No ROS."""

from dataclasses import dataclass

import numpy as np


@dataclass
class GridParams:
    cell: float = 0.5  #: [m] side of a cell
    size: float = 400.0  #: [m] side of the square map, centred on the first pose of a run
    step_height: float = 0.4  #: [m] span of heights in a cell that makes it an obstacle
    min_points: int = 2  #: [-] points a cell needs before its span counts
    max_range: float = 25.0  #: [m] points further from the camera (planar) are ignored
    max_height: float = 3.0  #: [m] points this far above the camera are ignored (no overhangs)

    def check(self):
        for name in ("cell", "size", "step_height", "max_range"):
            if not getattr(self, name) > 0:
                raise ValueError(f"grid parameter {name} = {getattr(self, name)}: must be > 0")
        if self.min_points < 1:
            raise ValueError(f"grid parameter min_points = {self.min_points}: must be >= 1")
        return self


class ElevationGrid:
    def __init__(self, params: GridParams, centre_xy):
        self.p = params.check()
        self.n = int(round(params.size / params.cell))
        self.origin = np.asarray(centre_xy, float) - params.size / 2  #: [m] corner of cell (0, 0)
        self.zmin = np.full((self.n, self.n), np.inf, np.float32)
        self.zmax = np.full((self.n, self.n), -np.inf, np.float32)
        self.count = np.zeros((self.n, self.n), np.int32)

    def index(self, xy):
        """Cell indices (i along x, j along y) of points [m]; -1 outside the map."""
        ij = np.floor((np.asarray(xy, float) - self.origin) / self.p.cell).astype(np.int64)
        out = (ij < 0) | (ij >= self.n)
        ij[out.any(axis=-1)] = -1
        return ij

    def insert(self, points_map, sensor_xyz) -> int:
        """Adds points (N x 3, map frame [m]) seen from `sensor_xyz`; returns how many counted."""
        p = np.asarray(points_map, np.float64).reshape(-1, 3)
        s = np.asarray(sensor_xyz, float)
        keep = np.isfinite(p).all(axis=1)
        keep &= np.hypot(p[:, 0] - s[0], p[:, 1] - s[1]) <= self.p.max_range
        keep &= p[:, 2] <= s[2] + self.p.max_height
        p = p[keep]
        ij = self.index(p[:, :2])
        inside = ij[:, 0] >= 0
        p, ij = p[inside], ij[inside]
        flat = ij[:, 0] * self.n + ij[:, 1]
        z = p[:, 2].astype(np.float32)
        np.minimum.at(self.zmin.reshape(-1), flat, z)
        np.maximum.at(self.zmax.reshape(-1), flat, z)
        np.add.at(self.count.reshape(-1), flat, 1)
        return int(len(flat))

    def obstacles(self):
        """Boolean n x n: the obstacle cells."""
        return (self.count >= self.p.min_points) & (self.zmax - self.zmin > self.p.step_height)

    def centres(self, mask):
        """[m] map coordinates of the centres of the cells in `mask` (K x 2)."""
        i, j = np.nonzero(mask)
        return self.origin + (np.stack([i, j], axis=1) + 0.5) * self.p.cell

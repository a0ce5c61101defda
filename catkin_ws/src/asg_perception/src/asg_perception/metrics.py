"""Segmentation figures (no rospy): per-class IoU and the shadow false-obstacle rate."""

from dataclasses import dataclass, field
from typing import Dict

import numpy as np

from .data import VOID
from .model import CLASSES

#: A ground pixel whose lit value is below this is in shadow.
SHADOW_LIT = 128

#: [px] shadow pixels this close to an obstacle's outline are left out of the "away" rate, which
#: measures false obstacles inside shadows rather than blur at the obstacle's foot.
BOUNDARY_PX = 3


def _near_obstacles(labels: np.ndarray) -> np.ndarray:
    """Pixels within BOUNDARY_PX of a non-traversable pixel (per frame)."""
    import cv2

    k = np.ones((2 * BOUNDARY_PX + 1, 2 * BOUNDARY_PX + 1), np.uint8)
    frames = labels.reshape((-1,) + labels.shape[-2:])
    out = np.stack([cv2.dilate((f == 1).astype(np.uint8), k) > 0 for f in frames])
    return out.reshape(labels.shape)


@dataclass
class Confusion:
    """Accumulates a 3x3 confusion matrix and the ground-pixel counts in and out of shadow."""

    matrix: np.ndarray = field(default_factory=lambda: np.zeros((3, 3), np.int64))
    shadow_ground: int = 0
    shadow_ground_as_obstacle: int = 0
    lit_ground: int = 0
    lit_ground_as_obstacle: int = 0
    shadow_away: int = 0
    shadow_away_as_obstacle: int = 0

    def add(self, pred: np.ndarray, labels: np.ndarray, lit: np.ndarray = None):
        """pred, labels: integer arrays of one shape; lit: the sun-lit mask (optional). VOID
        labels (ground under a canopy) count nowhere."""
        keep = labels.ravel() != VOID
        idx = labels.astype(np.int64).ravel()[keep] * 3 + pred.astype(np.int64).ravel()[keep]
        self.matrix += np.bincount(idx, minlength=9).reshape(3, 3)
        if lit is not None:
            ground = labels == 0
            shadow = ground & (lit < SHADOW_LIT)
            sunny = ground & (lit >= SHADOW_LIT)
            self.shadow_ground += int(shadow.sum())
            self.shadow_ground_as_obstacle += int((shadow & (pred == 1)).sum())
            self.lit_ground += int(sunny.sum())
            self.lit_ground_as_obstacle += int((sunny & (pred == 1)).sum())
            away = shadow & ~_near_obstacles(labels)
            self.shadow_away += int(away.sum())
            self.shadow_away_as_obstacle += int((away & (pred == 1)).sum())

    def iou(self) -> Dict[str, float]:
        m = self.matrix
        out = {}
        for c, name in enumerate(CLASSES):
            union = m[c, :].sum() + m[:, c].sum() - m[c, c]
            out[name] = float(m[c, c] / union) if union else float("nan")
        return out

    def shadow_false_obstacle_rate(self) -> float:
        """Fraction of ground pixels in shadow predicted non-traversable."""
        return self.shadow_ground_as_obstacle / max(1, self.shadow_ground)

    def lit_false_obstacle_rate(self) -> float:
        """Fraction of sunlit ground pixels predicted non-traversable."""
        return self.lit_ground_as_obstacle / max(1, self.lit_ground)

    def summary(self) -> dict:
        iou = self.iou()
        return {
            "iou": iou,
            "mean_iou": float(np.nanmean(list(iou.values()))),
            "pixel_accuracy": float(np.trace(self.matrix) / max(1, self.matrix.sum())),
            "shadow_false_obstacle_rate": self.shadow_false_obstacle_rate(),
            "shadow_away_false_obstacle_rate": self.shadow_away_as_obstacle / max(1, self.shadow_away),
            "lit_false_obstacle_rate": self.lit_false_obstacle_rate(),
            "shadow_ground_pixels": self.shadow_ground,
        }

"""Segmentation datasets written by `asg_sim_dataset` (no rospy).

A dataset folder holds `manifest.csv` and `images/NNNNNN_{rgb,labels,lit}.png`: RGB frames, label
images (0 traversable, 1 non-traversable, 2 sky, 3 void: ground under an obstacle's canopy) and
sun-lit masks (0 shadow .. 255 lit).
"""

import csv
import os
from dataclasses import dataclass
from typing import List, Optional

import numpy as np

#: Dataset label of ground seen beneath an obstacle's canopy: visible ground the vehicle cannot
#: reach, neither class; ignored by the training loss and left out of every figure.
VOID = 3


class DatasetError(ValueError):
    """A dataset folder is missing, malformed or inconsistent."""


@dataclass
class Frames:
    """Decoded frames held in memory."""

    rgb: np.ndarray  # N x H x W x 3 uint8
    labels: np.ndarray  # N x H x W uint8
    lit: np.ndarray  # N x H x W uint8
    rows: List[dict]  # the manifest rows

    def __len__(self):
        return len(self.rows)


def read_manifest(folder: str) -> List[dict]:
    path = os.path.join(folder, "manifest.csv")
    if not os.path.isfile(path):
        raise DatasetError(f"{folder}: no manifest.csv (make one with asg_sim_dataset)")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    need = {"index", "rgb", "labels", "lit", "sun_inclination_deg", "meshes"}
    if rows and not need <= set(rows[0]):
        raise DatasetError(f"{path}: columns {sorted(need - set(rows[0]))} missing")
    if not rows:
        raise DatasetError(f"{path}: no frames")
    return rows


def load_frames(folder: str, limit: Optional[int] = None, progress: bool = False) -> Frames:
    """Decodes every frame of a dataset folder (or the first `limit`)."""
    import cv2

    rows = read_manifest(folder)[:limit]
    rgb, labels, lit = [], [], []
    it = rows
    if progress:
        from tqdm import tqdm

        it = tqdm(rows, desc=f"loading {os.path.basename(folder.rstrip('/'))}", unit="frame")
    for r in it:
        paths = [os.path.join(folder, r[k]) for k in ("rgb", "labels", "lit")]
        bgr = cv2.imread(paths[0], cv2.IMREAD_COLOR)
        lab = cv2.imread(paths[1], cv2.IMREAD_UNCHANGED)
        lt = cv2.imread(paths[2], cv2.IMREAD_UNCHANGED)
        for p, img in zip(paths, (bgr, lab, lt)):
            if img is None:
                raise DatasetError(f"{p}: missing or not an image")
        if lab.shape != bgr.shape[:2] or lt.shape != bgr.shape[:2]:
            raise DatasetError(f"frame {r['index']}: image sizes differ")
        if lab.max() > VOID:
            raise DatasetError(f"{paths[1]}: label {int(lab.max())} outside 0..{VOID} " f"(0..2 classes, {VOID} void)")
        rgb.append(bgr[:, :, ::-1])
        labels.append(lab)
        lit.append(lt)
    return Frames(np.stack(rgb), np.stack(labels), np.stack(lit), rows)


def load_sets(folders: str, limit: Optional[int] = None, progress: bool = False) -> Frames:
    """The frames of one dataset folder, or of several separated by commas, in that order (issue
    #40: fine-tuning on new frames with a rehearsal set of the original ones); each manifest row
    gets `set`, its folder. `limit` keeps the first N frames of the whole."""
    parts = [f for f in folders.split(",") if f]
    if not parts:
        raise DatasetError("no dataset folder named")
    sets = [load_frames(f, None if len(parts) > 1 else limit, progress) for f in parts]
    for f, fs in zip(parts, sets):
        for r in fs.rows:
            r["set"] = f
    if len(sets) == 1:
        return sets[0]
    shapes = {fs.rgb.shape[1:] for fs in sets}
    if len(shapes) > 1:
        raise DatasetError(f"{folders}: frame sizes differ between the folders ({sorted(shapes)})")
    n = limit or sum(len(fs) for fs in sets)
    return Frames(
        np.concatenate([fs.rgb for fs in sets])[:n],
        np.concatenate([fs.labels for fs in sets])[:n],
        np.concatenate([fs.lit for fs in sets])[:n],
        [r for fs in sets for r in fs.rows][:n],
    )


def to_tensor(rgb: np.ndarray):
    """N x H x W x 3 uint8 -> N x 3 x H x W float32 in [0, 1]."""
    import torch

    return torch.from_numpy(np.ascontiguousarray(rgb)).permute(0, 3, 1, 2).float().div_(255.0)

"""Writing a run's outcome: trajectory CSV, result YAML and a top-down picture (no ROS)."""

import csv
import math
import os
from typing import List, Optional, Sequence

import yaml

from .catalogue import MESHES
from .schema import TERMINATIONS

#: the terminations' names by value (schema.TERMINATIONS, the one declaration)
TERMINATION_NAMES = [name for name, _, _ in sorted(TERMINATIONS, key=lambda t: t[1])]


def yaw_of(qx: float, qy: float, qz: float, qw: float) -> float:
    """Heading [rad] of a quaternion."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def path_length(xy: Sequence[Sequence[float]]) -> float:
    """Arc length [m] of a polyline."""
    return sum(math.dist(a, b) for a, b in zip(xy, xy[1:]))


def write_trajectory_csv(path: str, samples: List[dict]):
    """samples: dicts with t, x, y, z, yaw, vx, vy, vz, wx, wy, wz."""
    keys = ["t", "x", "y", "z", "yaw", "vx", "vy", "vz", "wx", "wy", "wz"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for s in samples:
            w.writerow([f"{s[k]:.6f}" for k in keys])


def write_result_yaml(path: str, result: dict):
    with open(path, "w") as f:
        yaml.safe_dump(result, f, sort_keys=False)


def plot_run(
    path: str,
    scenario: dict,
    xy: Sequence[Sequence[float]],
    title: str = "",
    removed: Optional[set] = None,
    background=None,
    votes=None,
    vote_cell: float = 0.0,
    optimal: Optional[Sequence[Sequence[float]]] = None,
    label: str = "vehicle",
    others: Sequence[tuple] = (),
):
    """Top-down PNG: landscape, obstacles (removed ones dashed), start, goal, trajectory.

    background: optional HxWx3 uint8 rendering of [0, size]^2 (row 0 at y = size) drawn below.
    votes: optional list of {x, y, weight 0..1} vote-grid vertices, drawn as squares of side
    vote_cell [m] (yellow to red by weight).
    optimal: optional polyline of the optimal path, drawn dashed.
    label: the legend's name for the trajectory xy.
    others: more trajectories to draw under it, as (label, xy, colour) tuples (e.g. the same
    scenario driven by a reference stack).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    removed = removed or set()
    vehicle_label = label
    size = scenario["structural"]["landscape"]["size"]
    op = scenario["operational"]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    if background is not None:
        ax.imshow(background, extent=(0, size, 0, size), origin="upper", interpolation="bilinear")
    ax.add_patch(plt.Rectangle((0, 0), size, size, fill=False, color="0.4"))
    for i, layout in enumerate(scenario["structural"]["layouts"]):
        mesh = MESHES[layout["mesh_name"]]
        for j, inst in enumerate(layout["instances"]):
            if not inst["visible"]:
                continue
            gone = (i, j) in removed
            ax.add_patch(
                Circle(
                    (inst["x"], inst["y"]),
                    mesh.collision_radius * inst["scale"],
                    color=mesh.colour,  # the catalogue's
                    fill=not gone and background is None,
                    ls="--" if gone else "-",
                    alpha=0.8,
                )
            )
    if votes:
        from matplotlib.patches import Rectangle

        side = vote_cell or 1.0
        for v in votes:
            w = max(0.0, min(1.0, v["weight"]))
            ax.add_patch(
                Rectangle(
                    (v["x"] - side / 2, v["y"] - side / 2),
                    side,
                    side,
                    color=(1.0, 1.0 - w, 0.0),
                    alpha=0.25 + 0.6 * w,
                    lw=0,
                )
            )
    for (x, y), r, c, label in (
        ((op["start_x"], op["start_y"]), op["safety_radius"], "tab:blue", "start"),
        ((op["goal_x"], op["goal_y"]), op["goal_radius"], "tab:orange", "goal"),
    ):
        ax.add_patch(Circle((x, y), r, fill=False, color=c, ls=":"))
        ax.plot([x], [y], "o", color=c, label=label)
    if optimal is not None and len(optimal):
        ax.plot([p[0] for p in optimal], [p[1] for p in optimal], "--", color="0.15", lw=1.2, label="optimal path")
    for other_label, other_xy, colour in others:
        if len(other_xy):
            ax.plot([p[0] for p in other_xy], [p[1] for p in other_xy], "-", color=colour, lw=1.5, label=other_label)
    if len(xy):
        ax.plot([p[0] for p in xy], [p[1] for p in xy], "-", color="magenta", lw=1.8, label=vehicle_label)
    ax.set_xlim(-2, size + 2)
    ax.set_ylim(-2, size + 2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or scenario.get("name", ""), fontsize=9)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path)
    plt.close(fig)

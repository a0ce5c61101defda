"""The picture panels of docs/simulator.md (issue #27; in Python since issue #38): variants of one
scenario file (terrain removed, fog, overcast) rendered from one camera pose with asg_sim_render,
camera RGB above and ground-truth labels below. No ROS. (In asg_analysis since issue #80: it runs
asg_sim's renderer, and asg_sim builds on asg_scenario, where it was.)

    python3 -m asg_analysis pictures terrain [--out docs/images/terrain_panel.png] [--pose 22 50 0.3]
    python3 -m asg_analysis pictures weather [--out docs/images/weather_panel.png]
"""

import argparse
import copy
import os
import subprocess
import sys
import tempfile
from typing import Dict, List, Tuple

import yaml

PROG = "python3 -m asg_analysis pictures"

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), *[".."] * 6))

FOG = {"fog_visibility_m": 40.0}  # [m] visibility
OVERCAST = {"cloud_cover": 1.0}  # [-] full cover

# name -> (keep the terrain, weather over the file's textural block, title)
PANELS = {
    "terrain": {
        "scenario": "scenarios/exp6.yaml",
        "pose": (22.0, 50.0, 0.3),  # [m, m, rad] east-north-east over the hills
        "variants": [
            ("flat", False, {}, "flat (Exp. 1's ground)"),
            ("hilly", True, {}, "hilly (exp6: rolling, 2 hills, a ditch)"),
            ("fog", True, FOG, "hilly, fog of 40 m"),
            ("overcast", True, OVERCAST, "hilly, overcast"),
        ],
        "tops": [("hilly", "hilly, from above"), ("flat", "flat, from above")],
        "labels_title": "ground-truth labels",
        "size": (16.0, 6.6),  # [in] figure
        "title_size": 9,  # [pt]
    },
    "weather": {
        "scenario": "scenarios/shadows.yaml",
        "pose": (31.0, 47.5, 0.05),
        "variants": [
            ("clear", True, {}, "clear"),
            ("fog", True, FOG, "fog, 40 m visibility"),
            ("overcast", True, OVERCAST, "overcast (cloud cover 1)"),
            ("fog_overcast", True, {**FOG, **OVERCAST}, "fog and overcast"),
        ],
        "tops": [],
        "labels_title": "ground-truth labels (beyond the fog's visibility: sky)",
        "size": (13.0, 6.6),
        "title_size": 10,
    },
}


def variants(scenario: dict, specs: List[Tuple]) -> Dict[str, dict]:
    """The scenario once per variant: its terrain block dropped where the variant is flat, and the
    variant's weather set over its textural block."""
    out = {}
    for name, terrain, weather, _ in specs:
        s = copy.deepcopy(scenario)
        if not terrain:
            s["structural"].pop("terrain", None)
        s.setdefault("textural", {}).update(weather)
        out[name] = s
    return out


def render(scenarios: Dict[str, dict], folder: str, pose, render_bin: str = ""):
    """Each scenario through asg_sim_render (asg_sim's, found as ROS finds executables, or
    `render_bin`): FOLDER/NAME_{rgb,labels,top}.png."""
    if not render_bin:
        from asg_scenario.binaries import find_binary

        render_bin = find_binary("asg_sim", "asg_sim_render")
    if not os.access(render_bin, os.X_OK):
        raise FileNotFoundError(f"{render_bin}: not built (bash scripts/setup.sh)")
    for name, s in scenarios.items():
        path = os.path.join(folder, f"{name}.yaml")
        with open(path, "w", encoding="utf-8") as f:
            yaml.safe_dump(s, f)
        cmd = [render_bin, path, os.path.join(folder, name), *[str(v) for v in pose]]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, LP_NUM_THREADS="1"))


def compose(folder: str, panel: dict, out: str):
    """RGB above, labels below, one column per variant, and the top-down views last."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    cols = len(panel["variants"]) + (1 if panel["tops"] else 0)
    ratios = [1.0] * len(panel["variants"]) + ([1.05] if panel["tops"] else [])
    fig, axes = plt.subplots(2, cols, figsize=panel["size"], gridspec_kw={"width_ratios": ratios})
    for j, (name, _, _, title) in enumerate(panel["variants"]):
        for i, kind in enumerate(("rgb", "labels")):
            axes[i][j].imshow(Image.open(os.path.join(folder, f"{name}_{kind}.png")))
            axes[i][j].axis("off")
        axes[0][j].set_title(title, fontsize=panel["title_size"])
    for i, (name, title) in enumerate(panel["tops"]):
        axes[i][cols - 1].imshow(Image.open(os.path.join(folder, f"{name}_top.png")))
        axes[i][cols - 1].set_title(title, fontsize=9)
        axes[i][cols - 1].axis("off")
    axes[1][0].set_title(panel["labels_title"], fontsize=8, loc="left")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    plt.close(fig)


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG + " picture", description=__doc__.split("\n\n")[0])
    p.add_argument("panel", choices=sorted(PANELS))
    p.add_argument("--out", default="", help="PNG (default: docs/images/PANEL_panel.png)")
    p.add_argument("--pose", type=float, nargs=3, default=None, help="[m m rad] camera x, y, yaw")
    a = p.parse_args(argv)
    panel = PANELS[a.panel]
    out = a.out or os.path.join(REPO, "docs", "images", f"{a.panel}_panel.png")
    with open(os.path.join(REPO, panel["scenario"]), encoding="utf-8") as f:
        scenario = yaml.safe_load(f)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            render(variants(scenario, panel["variants"]), tmp, a.pose or panel["pose"])
        except FileNotFoundError as e:
            print(f"pictures: {e}", file=sys.stderr)
            return 2
        compose(tmp, panel, out)
    print(out)
    return 0

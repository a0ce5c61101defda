#!/usr/bin/env bash
# The terrain pictures of docs/simulator.md (issue #27): scenarios/exp6.yaml from (22, 50) looking
# east-north-east (yaw 0.3 rad), flat (its terrain block removed), hilly (as it is), hilly in fog (40 m visibility)
# and hilly overcast (cloud cover 1); camera RGB above, ground-truth labels below, and the top-down
# view of the hilly scene. Writes docs/images/terrain_panel.png.
#   bash scripts/repro/terrain_pictures.sh [OUT=docs/images/terrain_panel.png] [X=22 Y=50 YAW=0.3]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
OUT="${1:-$REPO/docs/images/terrain_panel.png}"
POSE=("${2:-22}" "${3:-50}" "${4:-0.3}")
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
RENDER="$WS/devel/lib/asg_sim/asg_sim_render"
[ -x "$RENDER" ] || { echo "terrain_pictures.sh: build the workspace first (bash scripts/setup.sh)" >&2; exit 2; }
/usr/bin/python3 - "$REPO/scenarios/exp6.yaml" "$TMP" <<'PY'
import sys, yaml
src, tmp = sys.argv[1], sys.argv[2]
base = yaml.safe_load(open(src))
for name, terrain, weather in (("flat", False, {}), ("hilly", True, {}),
                               ("fog", True, {"fog_visibility_m": 40.0}), ("overcast", True, {"cloud_cover": 1.0})):
    s = yaml.safe_load(open(src))
    if not terrain:
        del s["structural"]["terrain"]
    s["textural"].update(weather)
    yaml.safe_dump(s, open(f"{tmp}/{name}.yaml", "w"))
PY
for name in flat hilly fog overcast; do
  LP_NUM_THREADS=1 "$RENDER" "$TMP/$name.yaml" "$TMP/$name" "${POSE[@]}" > /dev/null
done
/usr/bin/python3 - "$TMP" "$OUT" <<'PY'
import sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from PIL import Image
tmp, out = sys.argv[1], sys.argv[2]
names = [("flat", "flat (Exp. 1's ground)"), ("hilly", "hilly (exp6: rolling, 2 hills, a ditch)"),
         ("fog", "hilly, fog of 40 m"), ("overcast", "hilly, overcast")]
fig, axes = plt.subplots(2, 5, figsize=(16, 6.6), gridspec_kw={"width_ratios": [1, 1, 1, 1, 1.05]})
for j, (n, title) in enumerate(names):
    for i, kind in enumerate(("rgb", "labels")):
        axes[i][j].imshow(Image.open(f"{tmp}/{n}_{kind}.png"))
        axes[i][j].axis("off")
    axes[0][j].set_title(title, fontsize=9)
axes[0][4].imshow(Image.open(f"{tmp}/hilly_top.png"))
axes[0][4].set_title("hilly, from above", fontsize=9)
axes[0][4].axis("off")
axes[1][4].imshow(Image.open(f"{tmp}/flat_top.png"))
axes[1][4].set_title("flat, from above", fontsize=9)
axes[1][4].axis("off")
axes[1][0].set_title("ground-truth labels", fontsize=8, loc="left")
fig.tight_layout()
fig.savefig(out, dpi=80)
print(out)
PY

#!/usr/bin/env bash
# The weather pictures of docs/simulator.md (issue #27): scenarios/shadows.yaml rendered clear,
# in fog (40 m visibility), overcast (cloud cover 1) and both, from the same camera pose; camera
# RGB above, ground-truth labels below. Writes docs/images/weather_panel.png.
#   bash scripts/repro/weather_pictures.sh [OUT=docs/images/weather_panel.png]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
OUT="${1:-$REPO/docs/images/weather_panel.png}"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
RENDER="$WS/devel/lib/asg_sim/asg_sim_render"
[ -x "$RENDER" ] || { echo "weather_pictures.sh: build the workspace first (bash scripts/setup.sh)" >&2; exit 2; }
for spec in "clear|" "fog|, fog_visibility_m: 40.0" "overcast|, cloud_cover: 1.0" "fog_overcast|, fog_visibility_m: 40.0, cloud_cover: 1.0"; do
  name="${spec%%|*}"; extra="${spec#*|}"
  sed -e "s/^textural: {\(.*\)}/textural: {\1$extra}/" "$REPO/scenarios/shadows.yaml" > "$TMP/$name.yaml"
  LP_NUM_THREADS=1 "$RENDER" "$TMP/$name.yaml" "$TMP/$name" 31 47.5 0.05 > /dev/null
done
/usr/bin/python3 - "$TMP" "$OUT" <<'PY'
import sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from PIL import Image
tmp, out = sys.argv[1], sys.argv[2]
names = [("clear", "clear"), ("fog", "fog, 40 m visibility"), ("overcast", "overcast (cloud cover 1)"),
         ("fog_overcast", "fog and overcast")]
fig, axes = plt.subplots(2, 4, figsize=(13, 6.6))
for j, (n, title) in enumerate(names):
    for i, kind in enumerate(("rgb", "labels")):
        axes[i][j].imshow(Image.open(f"{tmp}/{n}_{kind}.png"))
        axes[i][j].axis("off")
    axes[0][j].set_title(title, fontsize=10)
axes[1][0].set_title("ground-truth labels (beyond the fog's visibility: sky)", fontsize=8, loc="left")
fig.tight_layout()
fig.savefig(out, dpi=80)
print(out)
PY

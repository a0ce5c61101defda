"""asg_analysis.studies.pictures: the variants of a scenario and the panel composed from rendered images
(the renderer itself is asg_sim's, tested there)."""

import os

import numpy as np
import pytest
import yaml
from PIL import Image

from asg_analysis.studies import pictures

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def load(rel):
    with open(os.path.join(REPO, rel), encoding="utf-8") as f:
        return yaml.safe_load(f)


def test_variants_drop_the_terrain_and_set_the_weather_without_touching_the_source():
    src = load("scenarios/exp6.yaml")
    keep = yaml.safe_dump(src)
    v = pictures.variants(src, pictures.PANELS["terrain"]["variants"])
    assert sorted(v) == ["flat", "fog", "hilly", "overcast"]
    assert (
        "terrain" not in v["flat"]["structural"] and v["hilly"]["structural"]["terrain"] == src["structural"]["terrain"]
    )
    assert v["fog"]["textural"]["fog_visibility_m"] == 40.0 and "cloud_cover" not in v["fog"]["textural"]
    assert v["overcast"]["textural"]["cloud_cover"] == 1.0
    assert v["hilly"]["textural"] == src["textural"]
    assert yaml.safe_dump(src) == keep  # the scenario read is not changed


def test_the_panel_puts_rgb_above_labels_below_and_the_top_views_last(tmp_path):
    panel = pictures.PANELS["terrain"]
    colours = {}
    for k, (name, *_rest) in enumerate(panel["variants"]):
        for kind in ("rgb", "labels", "top"):
            c = (40 * k + 20, 200 if kind == "rgb" else 60, 100 if kind == "top" else 0)
            colours[(name, kind)] = c
            Image.fromarray(np.full((64, 64, 3), c, np.uint8)).save(tmp_path / f"{name}_{kind}.png")
    out = tmp_path / "panel.png"
    pictures.compose(str(tmp_path), panel, str(out))
    img = np.asarray(Image.open(out).convert("RGB"))
    found = {tuple(int(x) for x in p) for p in img.reshape(-1, 3)[::7]}
    for name, *_ in panel["variants"]:
        assert colours[(name, "rgb")] in found and colours[(name, "labels")] in found
    assert colours[("hilly", "top")] in found and colours[("flat", "top")] in found
    assert colours[("fog", "top")] not in found  # only the tops the panel names


def test_a_missing_renderer_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="no_renderer: not built"):
        pictures.render({"x": {}}, str(tmp_path), (0, 0, 0), render_bin=str(tmp_path / "no_renderer"))

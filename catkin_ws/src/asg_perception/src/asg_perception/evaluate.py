"""Evaluation of U-Net models on a held-apart dataset (no rospy).

    python3 -m asg_perception.evaluate --data DIR MODEL.pt [MODEL.pt ...] [--json OUT] [--panels PNG]

Prints per-class IoU, pixel accuracy and the shadow false-obstacle rate (ground pixels in sun
shadow predicted non-traversable) of each model, and optionally writes them as JSON and an
image/label/prediction panel.
"""

import argparse
import json
import os
import sys

import numpy as np

from .data import DatasetError, load_frames
from .model import CLASSES
from .train import evaluate, load_model, predict

# RGB per class, then VOID (ground under a canopy) in grey
PALETTE = np.array([[80, 160, 80], [200, 40, 40], [140, 200, 230], [128, 128, 128]], np.uint8)


def panels(path: str, frames, models: dict, picks):
    """Rows: RGB, ground truth, each model's prediction; columns: the picked frames."""
    from PIL import Image, ImageDraw

    rows = [frames.rgb[picks], PALETTE[frames.labels[picks]]]
    names = ["camera", "ground truth"]
    for name, model in models.items():
        rows.append(PALETTE[predict(model, frames.rgb[picks])])
        names.append(name)
    h, w = frames.rgb.shape[1:3]
    label_w = 110
    canvas = Image.new("RGB", (label_w + len(picks) * (w + 4), len(rows) * (h + 4)), "white")
    draw = ImageDraw.Draw(canvas)
    for r, (imgs, name) in enumerate(zip(rows, names)):
        draw.text((4, r * (h + 4) + h // 2), name, fill="black")
        for c, img in enumerate(imgs):
            canvas.paste(Image.fromarray(img), (label_w + c * (w + 4), r * (h + 4)))
    canvas.save(path)


def parser():
    p = argparse.ArgumentParser(prog="evaluate_unet", description=__doc__.split("\n\n")[0])
    p.add_argument("models", nargs="+", help="model files (name=path or path)")
    p.add_argument("--data", required=True, help="held-apart dataset folder")
    p.add_argument("--limit", type=int, default=0, help="first N frames only (0: all)")
    p.add_argument("--json", default="", help="write the figures to this JSON file")
    p.add_argument("--panels", default="", help="write an example panel PNG here")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument(
        "--backend",
        default="eager",
        help="inference backend (asg_perception.inference): "
        "eager (the model as trained, batched), channels_last, frozen or bf16 (frame by frame)",
    )
    return p


def main(argv=None):
    p = parser()
    a = p.parse_args(argv)
    from .inference import BACKENDS, Segmenter

    if a.backend not in BACKENDS:
        p.error(f"--backend {a.backend!r}: one of {', '.join(BACKENDS)}")
    import torch

    torch.set_num_threads(a.threads)
    try:
        frames = load_frames(a.data, a.limit or None, progress=True)
        models, paths = {}, {}
        for spec in a.models:
            name, _, path = spec.rpartition("=")
            name = name or os.path.splitext(os.path.basename(path))[0]
            models[name], paths[name] = load_model(path), path
    except (DatasetError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    results = {}
    for name, model in models.items():
        if a.backend == "eager":
            r = evaluate(model, frames)
        else:
            seg = Segmenter(paths[name], a.backend, a.threads, *frames.rgb.shape[1:3])
            # The backend labels every frame once; each batch is also compared with the eager
            # model's labels (pixel agreement).
            same = 0

            def labeller(rgb):
                nonlocal same
                out = seg.batch(rgb)
                same += int((out == predict(model, rgb)).sum())
                return out

            r = evaluate(model, frames, labeller=labeller)
            r["backend"], r["agreement_with_eager"] = a.backend, same / frames.labels.size
            print(
                f"{name:>8}: {a.backend} labels agree with eager on {100 * r['agreement_with_eager']:.3f} % of pixels"
            )
        results[name] = r
        iou = "  ".join(f"{c} {r['iou'][c]:.3f}" for c in CLASSES)
        print(
            f"{name:>8}: IoU {iou}  |  pixel acc {r['pixel_accuracy']:.4f}  |  shadow "
            f"false-obstacle {r['shadow_false_obstacle_rate']:.4f} (away from obstacles "
            f"{r['shadow_away_false_obstacle_rate']:.4f})  lit false-obstacle "
            f"{r['lit_false_obstacle_rate']:.4f}"
        )
        print(
            f"{'':>8}  low sun (<= {r['low_sun_deg']:g} deg): shadow false-obstacle "
            f"{r['low_sun']['shadow_false_obstacle_rate']:.4f}; by inclination: "
            + ", ".join(f"{k}: {v:.4f}" for k, v in r["by_sun"].items())
        )
    for name, r in results.items():
        for c, f in r.get("by_condition", {}).items():
            print(
                f"{name:>8}  {c:>10}: mIoU {f['mean_iou']:.3f}  non-traversable IoU {f['iou']['non_traversable']:.3f}  "
                f"shadow false-obstacle {f['shadow_false_obstacle_rate']:.4f}"
            )
    if len(results) == 2:
        # The model with more shadow false obstacles over the other (the flaw's size).
        (na, ra), (nb, rb) = sorted(results.items(), key=lambda kv: -kv[1]["shadow_false_obstacle_rate"])

        def ratio(get):
            return get(ra) / max(get(rb), 1e-9)

        print(
            f"shadow false-obstacle rate {na}/{nb}: "
            f"{ratio(lambda r: r['shadow_false_obstacle_rate']):.1f}x (away from obstacles "
            f"{ratio(lambda r: r['shadow_away_false_obstacle_rate']):.1f}x, low sun "
            f"{ratio(lambda r: r['low_sun']['shadow_false_obstacle_rate']):.1f}x)"
        )
        for c in ra.get("by_condition", {}):
            if c in rb.get("by_condition", {}):
                print(f"  {c}: {ratio(lambda r: r['by_condition'][c]['shadow_false_obstacle_rate']):.1f}x")
    if a.json:
        with open(a.json, "w") as f:
            # the data folder as given, or relative to the working directory when inside it, so a
            # committed result names no machine's path
            rel = os.path.relpath(a.data)
            data = rel if os.path.isabs(a.data) and not rel.startswith("..") else a.data
            json.dump({"data": data, "frames": len(frames), "results": results}, f, indent=1)
    if a.panels:
        # Frames with the most shadowed ground, where the flaw shows.
        shadow = ((frames.labels == 0) & (frames.lit < 128)).reshape(len(frames), -1).sum(1)
        picks = np.argsort(-shadow, kind="stable")[:5]
        panels(a.panels, frames, models, picks)
    return 0


if __name__ == "__main__":
    sys.exit(main())

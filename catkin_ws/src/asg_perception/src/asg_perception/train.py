"""Training of the traversability U-Net (no rospy): `python3 -m asg_perception.train --help`."""

import argparse
import json
import os
import sys
import time
from dataclasses import asdict, dataclass, fields

from typing import List

import numpy as np
import torch
import torch.nn.functional as F

from .data import VOID, DatasetError, load_sets, to_tensor
from .metrics import Confusion
from .model import UNet, parameter_count, unet

FORMAT = "asg_unet/1"


@dataclass
class TrainConfig:
    """Hyper-parameters of one training run (REFERENCE.md values unless noted)."""

    data: str = ""  #: dataset folder (asg_sim_dataset output), or several separated by commas
    out: str = "runs/unet"  #: output folder: checkpoint.pt, model.pt, history.json
    epochs: int = 4  #: passes over the training split
    batch_size: int = 16  #: frames per step
    lr: float = 1e-4  #: Adam learning rate
    val_fraction: float = 0.1  #: share of frames held out for per-epoch validation
    flip_prob: float = 0.5  #: probability of a horizontal flip per frame
    crop: int = 0  #: [px] random square training crop (0: whole frame, as shipped)
    seed: int = 0  #: seeds the split, the shuffles, the crops and the weights
    threads: int = 2  #: torch CPU threads
    limit: int = 0  #: use only the first N frames (0: all)
    width: float = 1.0  #: [fraction] channel multiplier of the U-Net (model.unet); the lite models use 0.5
    init: str = ""  #: model file whose weights start the training (fine-tuning, issue #40); its width replaces `width`


def save_model(path: str, model: UNet, config: TrainConfig, history: list, extra: dict = None):
    blob = {"format": FORMAT, "state_dict": model.state_dict(), "config": asdict(config), "history": history}
    blob.update(extra or {})
    tmp = path + ".tmp"
    torch.save(blob, tmp)
    os.replace(tmp, path)  # never a half-written model


def load_model(path: str) -> UNet:
    """A U-Net with the weights of a model or checkpoint file. Raises ValueError if unusable."""
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such model file")
    try:
        blob = torch.load(path, map_location="cpu")
    except Exception as e:  # a truncated or foreign file
        raise ValueError(f"{path}: not a readable torch file ({e})") from None
    if not isinstance(blob, dict) or blob.get("format") != FORMAT:
        raise ValueError(f"{path}: not an {FORMAT} model file")
    try:  # models from before the width was recorded are width 1.0
        model = unet(float(blob.get("config", {}).get("width", 1.0)))
    except (TypeError, ValueError) as e:
        raise ValueError(f"{path}: {e}") from None
    try:
        model.load_state_dict(blob["state_dict"])
    except RuntimeError as e:
        raise ValueError(f"{path}: weights do not fit the U-Net ({e})") from None
    return model.eval()


def predict(model: UNet, rgb: np.ndarray, batch: int = 8) -> np.ndarray:
    """Labels (N x H x W uint8) for RGB frames (N x H x W x 3 uint8)."""
    out = []
    with torch.no_grad():
        for i in range(0, len(rgb), batch):
            out.append(model(to_tensor(rgb[i : i + batch])).argmax(1).to(torch.uint8).numpy())
    return np.concatenate(out)


def conditions(row: dict) -> List[str]:
    """The scene conditions of a dataset frame (issue #27; manifests before it: flat and clear):
    `terrain` (rolling ground or hills), `fog`, `overcast` (cloud cover >= 0.5), or `flat_clear`."""
    out = []
    if float(row.get("terrain_amplitude_m") or 0) > 0 or int(row.get("hills") or 0) > 0:
        out.append("terrain")
    if float(row.get("fog_visibility_m") or 0) > 0:
        out.append("fog")
    if float(row.get("cloud_cover") or 0) >= 0.5:
        out.append("overcast")
    return out or ["flat_clear"]


def evaluate(model: UNet, frames, batch: int = 8, low_sun_deg: float = 15.0, labeller=None) -> dict:
    """Figures over all frames, plus `low_sun`: the same over frames whose sun inclination is at
    most low_sun_deg (long shadows that lie apart from their obstacles), and `by_sun`: the
    shadow false-obstacle rate per inclination, and `by_condition`: the figures per scene
    condition (`conditions`; a frame may count in several) when the set has more than flat, clear
    scenes. `labeller` (RGB batch -> labels), when given, labels the frames instead of the eager
    model (an inference backend, inference.Segmenter)."""
    conf, low = Confusion(), Confusion()
    by_sun, by_cond = {}, {}
    conds = [conditions(r) for r in frames.rows]
    inc = [float(r.get("sun_inclination_deg", "nan")) for r in frames.rows]
    for i in range(0, len(frames), batch):
        pred = labeller(frames.rgb[i : i + batch]) if labeller else predict(model, frames.rgb[i : i + batch], batch)
        for k in range(len(pred)):
            args = (pred[k], frames.labels[i + k], frames.lit[i + k])
            conf.add(*args)
            by_sun.setdefault(inc[i + k], Confusion()).add(*args)
            for c in conds[i + k]:
                by_cond.setdefault(c, Confusion()).add(*args)
            if inc[i + k] <= low_sun_deg:
                low.add(*args)
    out = conf.summary()
    out["low_sun"] = low.summary()
    out["low_sun_deg"] = low_sun_deg
    out["by_sun"] = {f"{a:g}": c.shadow_false_obstacle_rate() for a, c in sorted(by_sun.items())}
    if set(by_cond) - {"flat_clear"}:
        out["by_condition"] = {c: by_cond[c].summary() for c in sorted(by_cond)}
    return out


def train(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> dict:
    from tqdm import tqdm

    torch.set_num_threads(cfg.threads)
    torch.manual_seed(cfg.seed)
    frames = load_sets(cfg.data, cfg.limit or None, progress)
    n = len(frames)
    rng = np.random.default_rng(cfg.seed)
    order = rng.permutation(n)
    n_val = max(1, int(round(cfg.val_fraction * n)))
    val_idx, train_idx = np.sort(order[:n_val]), order[n_val:]
    if len(train_idx) == 0:
        raise DatasetError(f"{cfg.data}: {n} frames leave none for training")
    if cfg.init:  # fine-tuning: the weights (and so the width) of an existing model
        model = load_model(cfg.init).train()
        cfg.width = float(torch.load(cfg.init, map_location="cpu").get("config", {}).get("width", 1.0))
    else:
        model = unet(cfg.width)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    history, start = [], 0
    os.makedirs(cfg.out, exist_ok=True)
    ckpt = os.path.join(cfg.out, "checkpoint.pt")
    if resume and os.path.isfile(ckpt):
        blob = torch.load(ckpt, map_location="cpu")
        model.load_state_dict(blob["state_dict"])
        opt.load_state_dict(blob["optimizer"])
        history, start = blob["history"], blob["epoch"] + 1
        rng.bit_generator.state = blob["numpy_rng"]
        torch.set_rng_state(blob["torch_rng"])
        print(f"resuming {ckpt} after epoch {start}", flush=True)
    val = type(frames)(
        frames.rgb[val_idx], frames.labels[val_idx], frames.lit[val_idx], [frames.rows[i] for i in val_idx]
    )
    print(
        f"U-Net {parameter_count(model):,} parameters; {len(train_idx)} training and "
        f"{len(val_idx)} validation frames; {cfg.epochs} epochs",
        flush=True,
    )
    for epoch in range(start, cfg.epochs):
        model.train()
        perm = rng.permutation(train_idx)
        losses = []
        bar = tqdm(
            range(0, len(perm), cfg.batch_size),
            desc=f"epoch {epoch + 1}/{cfg.epochs}",
            unit="batch",
            disable=not progress,
        )
        t0 = time.time()
        for b in bar:
            idx = perm[b : b + cfg.batch_size]
            x = frames.rgb[idx]
            y = frames.labels[idx]
            if cfg.crop:
                h, w = x.shape[1:3]
                r = rng.integers(0, h - cfg.crop + 1, len(idx))
                c = rng.integers(0, w - cfg.crop + 1, len(idx))
                x = np.stack([x[k, r[k] : r[k] + cfg.crop, c[k] : c[k] + cfg.crop] for k in range(len(idx))])
                y = np.stack([y[k, r[k] : r[k] + cfg.crop, c[k] : c[k] + cfg.crop] for k in range(len(idx))])
            flip = rng.random(len(idx)) < cfg.flip_prob
            x = np.where(flip[:, None, None, None], x[:, :, ::-1], x)
            y = np.where(flip[:, None, None], y[:, :, ::-1], y)
            xt = to_tensor(x)
            yt = torch.from_numpy(np.ascontiguousarray(y)).long()
            opt.zero_grad()
            loss = F.cross_entropy(model(xt), yt, ignore_index=VOID)
            loss.backward()
            opt.step()
            losses.append(float(loss))
            bar.set_postfix(loss=f"{np.mean(losses[-20:]):.4f}")
        model.eval()
        metrics = evaluate(model, val)
        entry = {"epoch": epoch + 1, "train_loss": float(np.mean(losses)), "seconds": time.time() - t0, **metrics}
        history.append(entry)
        iou = " ".join(f"{k} {v:.3f}" for k, v in metrics["iou"].items())
        print(
            f"epoch {epoch + 1}: loss {entry['train_loss']:.4f}, validation IoU {iou}, "
            f"shadow false-obstacle {metrics['shadow_false_obstacle_rate']:.4f}",
            flush=True,
        )
        save_model(
            ckpt,
            model,
            cfg,
            history,
            {
                "epoch": epoch,
                "optimizer": opt.state_dict(),
                "numpy_rng": rng.bit_generator.state,
                "torch_rng": torch.get_rng_state(),
            },
        )
    save_model(os.path.join(cfg.out, "model.pt"), model, cfg, history)
    with open(os.path.join(cfg.out, "history.json"), "w") as f:
        json.dump(history, f, indent=1)
    return {"model": model, "history": history}


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="train_unet",
        description="Train the traversability U-Net "
        "on an asg_sim_dataset folder; writes checkpoint.pt after every "
        "epoch (resumable) and model.pt at the end.",
    )
    for f in fields(TrainConfig):
        p.add_argument(
            "--" + f.name.replace("_", "-"), type=type(f.default), default=f.default, required=f.name == "data"
        )
    p.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    a = p.parse_args(argv)
    cfg = TrainConfig(**{f.name: getattr(a, f.name) for f in fields(TrainConfig)})
    try:
        train(cfg, resume=a.resume)
    except ValueError as e:  # DatasetError, or an unusable --init model
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

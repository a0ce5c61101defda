"""harden: training frames from found failure scenes, and from random ones (issue #40;
docs/design-loop.md, "Harden").

    harden frames --suite SUITE --exports DIR[,DIR] --out SET --frames N [--seed S] [options]
    harden frames --export CAMPAIGN.jsonl.gz --classes flaw,model --out SET --frames N [options]
    harden frames --export RANDOM.jsonl.gz --scenes K --out SET --frames N [--seed S] [options]

The first form takes the findings of a suite, one per failure mode (each with the trajectory its
campaign stored); the second every finding of the attribution classes named in an export; the
third draws K scenes of an export whatever their outcome (the control arm: a random campaign's
scenes). All
spread N frames over the scenes, the scene as it ran and perturbed copies of it (sun moved,
obstacles shifted), at camera poses along the stored run, half of them on its last stretch; they
render the frames with the simulator's ground-truth labels into SET/frames, which
`train_unet --data SET/frames --init MODEL.pt` fine-tunes a model on.
"""

import argparse
import sys

from asg_agent.campaign.hardening import (
    HardeningError,
    Perturbation,
    render,
    sources_from_export,
    sources_from_suite,
    write_frame_set,
)


def apart(sources, training: list, what: str, drop: bool, tol_m=None):
    """The sources none of the `training` sources holds (campaign.overlap, at `tol_m` [m]; None: its
    default, the augmentation's radius), and the dropped ones in words; without `drop`,
    OverlapError naming every shared scene."""
    from asg_agent.campaign import overlap

    tol_m = overlap.TOL_M if tol_m is None else tol_m

    scenes = [
        overlap.request_scene(f"{s.origin.get('campaign')} job {s.origin.get('job')}", s.request) for s in sources
    ]
    if not drop:
        overlap.check_apart(scenes, training, what, tol_m)
        return sources, []
    pairs = [p for src in training for p in overlap.shared(scenes, overlap.scenes_of(src), tol_m)]
    gone = {p["scene"] for p in pairs}
    keep = [s for s, sc in zip(sources, scenes) if sc[0] not in gone]
    return keep, [f"{p['scene']} = {p['training']}" for p in pairs]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="harden", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    f = sub.add_parser("frames", help="write and render a frame set")
    src = f.add_mutually_exclusive_group(required=True)
    src.add_argument("--suite", help="suite folder whose findings give the scenes")
    src.add_argument("--export", help="campaign export whose scenes are drawn (with --scenes)")
    f.add_argument("--exports", default="", help="folders with the suite's campaign exports, comma-separated")
    f.add_argument("--scenes", type=int, default=0, help="scenes drawn from --export (0: all of --classes)")
    f.add_argument("--classes", default="", help="attribution classes of --export's scenes, comma-separated")
    f.add_argument("--out", required=True, help="frame set folder")
    f.add_argument("--frames", type=int, required=True, help="frames in all")
    f.add_argument("--seed", type=int, default=0)
    f.add_argument("--no-render", action="store_true", help="write scenarios and poses only")
    f.add_argument(
        "--apart-from",
        default="",
        help="training sources (exports, suites, frame sets), comma-separated, whose scenes this set must not "
        "hold (issue #57: a held-apart set); a shared scene is refused, naming it",
    )
    f.add_argument("--drop-shared", action="store_true", help="with --apart-from: leave shared scenes out")
    f.add_argument(
        "--tol-m",
        type=float,
        default=None,
        help="[m] with --apart-from: two scenes are one when every obstacle lies this close along x and y "
        "(default: the augmentation's radius, campaign.overlap.TOL_M; 0.01 is the same layout)",
    )
    d = Perturbation()
    for k, v in vars(d).items():
        f.add_argument("--" + k.replace("_", "-"), type=type(v), default=v, help=f"(default {v})")
    a = p.parse_args(argv)
    pert = Perturbation(**{k: getattr(a, k) for k in vars(d)})
    try:
        if a.suite:
            if not a.exports:
                raise HardeningError("--suite needs --exports: the folders of its campaigns' exports")
            sources = sources_from_suite(a.suite, [x for x in a.exports.split(",") if x])
            made_from = {"suite": a.suite, "exports": a.exports}
        else:
            classes = [c for c in a.classes.split(",") if c]
            if a.scenes <= 0 and not classes:
                raise HardeningError("--export needs --scenes K > 0 or --classes: which of its scenes to take")
            sources = sources_from_export(a.export, a.scenes, a.seed, classes)
            made_from = {"export": a.export, "scenes": len(sources), "classes": classes}
        if a.apart_from:
            sources, dropped = apart(sources, [x for x in a.apart_from.split(",") if x], a.out, a.drop_shared, a.tol_m)
            made_from.update(apart_from=a.apart_from, dropped_shared=dropped)
            for d in dropped:
                print(f"left out, in a training source: {d}")
        info = write_frame_set(sources, a.out, a.frames, a.seed, pert, made_from)
        print(f"{a.out}: {info['frames']} poses over {len(sources)} scenes x {pert.variants} variants")
        if not a.no_render:
            print(f"frames in {render(a.out)}")
    except (HardeningError, ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

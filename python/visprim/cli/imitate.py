"""``visprim imitate``: a recording → its primitives → Adonis, measured against the human."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def run(args: argparse.Namespace) -> int:
    """``visprim imitate MODEL RECORDING --out DIR``; see :mod:`visprim.imitate`."""
    from visprim.sim.video import check_video_path

    if not Path(args.model).is_file():
        print(f"visprim imitate: model file {args.model!r} not found", file=sys.stderr)
        return 2
    if not Path(args.recording).is_file():
        print(f"visprim imitate: recording {args.recording!r} not found", file=sys.stderr)
        return 2
    video = None if args.no_video else args.video
    try:
        if video is not None:
            check_video_path(Path(args.out) / video)
    except (ValueError, ImportError) as exc:
        print(f"visprim imitate: {exc}", file=sys.stderr)
        return 2
    from visprim import PrimitiveModel
    from visprim.imitate import imitate, write_imitation
    from visprim.io import ReadError, read
    from visprim.progress import stages
    from visprim.sim.playback import SimulationDiverged

    dt = args.dt if args.dt is not None else (0.001 if args.servo == "stable" else 0.0001)
    try:
        model = PrimitiveModel.load(args.model)
        options: dict[str, Any] = {}
        if args.skeleton is not None:
            options["skeleton"] = args.skeleton
        if args.rate is not None:
            options["rate"] = args.rate
        with stages(3, "imitate") as progress:
            progress.step("reading")
            trial = read(args.recording, **options)
            progress.step(f"segmenting, rebuilding, playing {trial.duration:.1f} s on Adonis")
            result = imitate(model, trial, source=args.source, servo=args.servo, dt=dt)
            progress.step("writing files" + (" and the video" if video else ""))
            paths = write_imitation(
                result,
                args.out,
                video=video,
                size=(args.size, args.size),
                extra={"model": str(Path(args.model).resolve())},
            )
        print(result.summary())
    except (ReadError, ValueError, OSError, SimulationDiverged) as exc:
        print(f"visprim imitate: {exc}", file=sys.stderr)
        return 2
    for kind, path in paths.items():
        print(f"wrote {path} ({kind})")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "imitate",
        help="imitate a recording through the model's primitives on Adonis",
        description=(
            "Resample RECORDING to the model's frame period, segment it, take each segment's "
            "nearest primitive, rebuild the movement from the primitives' centres (joined with "
            "no step in angle or velocity), play it on Adonis and compare with the human. "
            "Writes imitation.json (metrics), imitation.csv (trajectories), trajectory.json/"
            ".csv (URDF joint trajectory of the rebuild) and a video into DIR."
        ),
    )
    p.add_argument("model", help="model file written by `visprim learn`")
    p.add_argument("recording", help="a recording (.bvh, .amc, .c3d, marker .csv)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument(
        "--source",
        choices=("primitives", "projection"),
        default="primitives",
        help="rebuild from the primitives (default) or, as a labelled near-copy, from each "
        "segment's own projection",
    )
    p.add_argument(
        "--servo",
        choices=("stable", "paper"),
        default="stable",
        help="stable PD along the trajectory (default) or the paper's explicit PD with "
        "via-point switching",
    )
    p.add_argument(
        "--dt",
        type=float,
        default=None,
        help="simulation step, s (default 0.001; 0.0001 with --servo paper, whose explicit "
        "damping diverges at 1 ms)",
    )
    p.add_argument(
        "--video",
        default="imitation.gif",
        help="video file name in DIR: .gif, or .mp4 with visprim[video] (default imitation.gif)",
    )
    p.add_argument("--no-video", action="store_true", help="write no video")
    p.add_argument("--size", type=int, default=480, help="panel size in pixels (default 480)")
    p.add_argument(
        "--skeleton", help="ASF skeleton of an .amc recording (default: found next to it)"
    )
    p.add_argument("--rate", type=float, help="frame rate of an .amc recording, Hz")
    p.set_defaults(func=run)

"""``visprim imitate``: a recording → its primitives → Adonis, measured against the human."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from visprim.cli import common, outputs


def _budget_options(args: argparse.Namespace) -> dict[str, Any]:
    """The budget settings given on the command line (the others: RATE_OPTIONS defaults)."""
    out: dict[str, Any] = {}
    if getattr(args, "budget_posture", None) is not None:
        out["posture"] = args.budget_posture
    if hasattr(args, "budget_max_stroke"):
        out["max_stroke"] = args.budget_max_stroke
    return out


def read_recording(args: argparse.Namespace, path: str, model: Any) -> Any:
    """Read the recording ``path`` with the reader options of ``args``: both arms for a
    two-arm model (whatever ``--arm`` says), else the arm asked for (``--arm both`` with a
    one-arm model: each arm imitated on its own through its primitives)."""
    from visprim.io import read

    opts = common.reader_options(args)
    arm = opts.pop("arm")
    if len(getattr(model, "arms_", ("right",))) == 2:
        arm = "both"  # a two-arm model imitates both arms of the recording
    return read(path, arm, **opts)


#: Smallest and largest video panel, pixels (a panel is drawn at twice its size: 4096 px
#: is a 64 MB canvas).
MIN_SIZE = 64
MAX_SIZE = 4096
#: Largest simulation step, seconds: the via points' spacing (0.1 s).
MAX_DT = 0.1
_RECORDING_SUFFIXES = (".bvh", ".amc", ".c3d", ".csv", ".trc")


def _folder_message(what: str, folder: Path) -> str:
    """The error for a folder given where one file is expected, naming what is inside."""
    if what == "model file":
        return f"model file {str(folder)!r} is a folder; give the .npz file `visprim learn` wrote"
    inside = sorted(
        p.name for p in folder.iterdir() if p.is_file() and p.suffix.lower() in _RECORDING_SUFFIXES
    )
    hint = (
        f" ({len(inside)} recordings inside, e.g. {str(folder / inside[0])!r})"
        if inside
        else " (no recording inside)"
    )
    return f"recording {str(folder)!r} is a folder{hint}; imitate takes one recording file"


def run(args: argparse.Namespace) -> int:
    """``visprim imitate MODEL RECORDING --out DIR``; see :mod:`visprim.imitate`."""
    from visprim.progress import stages
    from visprim.sim.video import VIDEO_FORMATS, check_video_path

    for what, path in (("model file", args.model), ("recording", args.recording)):
        if Path(path).is_dir():
            raise common.UsageError(_folder_message(what, Path(path)))
        if not Path(path).is_file():
            raise common.UsageError(f"{what} {path!r} not found")
    video = None if args.no_video else args.video
    if video is None and not args.no_video:
        from visprim.progress import write
        from visprim.sim.video import default_video_name

        video, why = default_video_name("imitation")
        if why:
            write(f"visprim imitate: {why}")
    if video is not None and not MIN_SIZE <= args.size <= MAX_SIZE:
        raise common.UsageError(
            f"--size {args.size}: the video's panels must be {MIN_SIZE} to {MAX_SIZE} pixels"
        )
    if args.dt is not None and not (math.isfinite(args.dt) and 0 < args.dt <= MAX_DT):
        raise common.UsageError(
            f"--dt {args.dt}: the simulation step must be a number of seconds in (0, {MAX_DT}]"
        )
    if video is not None:
        if Path(video).name != video or video in (".", ".."):
            raise common.UsageError(
                f"--video {video}: give a file name, written inside --out (such as "
                f"{Path(video).name or 'imitation.gif'}), not a path"
            )
        try:
            check_video_path(video)
        except ValueError:
            raise common.UsageError(
                f"--video {video}: unsupported video format; name it .gif or .mp4 "
                f"({', '.join(f'{e}: {w}' for e, w in VIDEO_FORMATS.items())})"
            ) from None
        except ImportError:
            raise common.UsageError(
                f"--video {video}: writing .mp4 needs imageio-ffmpeg: pip install "
                "'visprim[video]' (or name it .gif)"
            ) from None
    if args.budget is None and _budget_options(args):
        raise common.UsageError("--budget-posture and --budget-max-stroke need --budget")
    if args.budget is not None and (args.source != "primitives" or not args.budget > 0):
        raise common.UsageError(
            "--budget needs a positive number of numbers per second, and the default --source"
        )
    out = outputs.check_folder(args.out, force=args.force, inputs=[args.model, args.recording])

    from visprim.imitate import imitate, write_imitation

    with stages(4, "imitate") as progress:
        progress.step("loading")
        model = common.load_model(args.model)
        trial = read_recording(args, args.recording, model)
        progress.step(f"segmenting, rebuilding, playing {trial.duration:.1f} s on Adonis")
        result = imitate(
            model,
            trial,
            source=args.source,
            servo=args.servo,
            dt=args.dt,
            budget=args.budget,
            budget_options=_budget_options(args),
        )
        progress.step("writing files" + (" and the video" if video else ""))
        with outputs.atomic_folder(out, "imitate") as tmp:
            written = write_imitation(
                result,
                tmp,
                video=video,
                size=(args.size, args.size),
                extra={"model": str(Path(args.model).resolve())},
            )
        progress.step("done")
    print(result.summary())
    for kind, path in written.items():
        print(f"wrote {outputs.moved(path, tmp, out)} ({kind})")
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
        "--budget",
        type=float,
        default=None,
        metavar="N",
        help="rebuild through the best description within N numbers per second of movement "
        "(nearest primitive, with its gain, with residual or DCT coefficients, or each "
        "segment's projection; or the movement whole through the eigen-movements that "
        "`visprim learn` stores in the model file); imitation.json says which one was used",
    )
    from visprim.cli.evaluate import _stroke
    from visprim.params import RATE_OPTIONS

    rate = RATE_OPTIONS
    p.add_argument(
        "--budget-posture",
        choices=rate["posture"].searched,
        default=None,
        help=f"with --budget: {rate['posture'].help} (default {rate['posture'].default})",
    )
    p.add_argument(
        "--budget-max-stroke",
        type=_stroke,
        default=argparse.SUPPRESS,
        metavar="S",
        help=f"with --budget: {rate['max_stroke'].help}; 'none' or seconds (default: the "
        f"encoder describes the movement cut at {rate['max_stroke'].default} s, uncut and, if "
        "the model file has eigen-movements, whole, and keeps the one whose rebuilt frames lie "
        "closest, counting 1 number for the choice; a given S forces segments)",
    )
    p.add_argument(
        "--servo",
        choices=("stable", "paper"),
        default="stable",
        help="stable PD along the trajectory with inverse-dynamics feedforward (default) or "
        "the paper's explicit PD with via-point switching",
    )
    p.add_argument(
        "--dt",
        type=float,
        default=None,
        help="simulation step, s (default 0.002; 0.0001 with --servo paper, whose explicit "
        "damping diverges at 1 ms)",
    )
    p.add_argument(
        "--video",
        default=None,
        help="video file name in DIR: .mp4 (needs imageio-ffmpeg, in visprim[video]) or .gif "
        "(default imitation.mp4, or imitation.gif without imageio-ffmpeg); a video recording "
        "shows its own frames with the detected arm beside Adonis",
    )
    p.add_argument("--no-video", action="store_true", help="write no video")
    p.add_argument("--size", type=int, default=480, help="panel size in pixels (default 480)")
    common.add_force_option(p)
    common.add_reader_options(p, many=False)
    p.set_defaults(func=run)

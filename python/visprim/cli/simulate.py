"""``visprim simulate``: play a primitive, or a recording imitated through primitives, on Adonis.

``--movement`` runs the imitation chain of :func:`visprim.imitate.imitate` (resampled to
the model's frame period, segmented, each segment's nearest primitive, rebuilt from the
primitives' centres and joined smoothly) and plays that rebuild; it prints the same report
as ``visprim imitate`` (errors against the human, completion time, uncovered parts).
``--source projection`` plays the labelled near-copy from each segment's own projection.
``--out`` decides the picture: ``.gif`` an animation of every stored frame, ``.png`` the
last frame only."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from visprim.cli import common, outputs

log = logging.getLogger(__name__)

#: Extensions of ``--out`` and what is written for each.
PICTURES = {".gif": "animated GIF", ".png": "PNG of the last frame"}


def _load_model(path: str) -> Any:
    return common.load_model(path)


def run(args: argparse.Namespace) -> int:
    """``visprim simulate MODEL (--primitive K | --movement RECORDING [--source S]) --out
    GIF|PNG``."""
    from visprim.progress import stages

    if args.primitive is None and args.movement is None:
        raise common.UsageError("give --primitive K or --movement RECORDING")
    if args.source is not None and args.movement is None:
        raise common.UsageError("--source applies to --movement only")
    if not Path(args.model).is_file():
        raise common.UsageError(
            f"model file {args.model!r} not found; give a model written by `visprim learn`"
        )
    if args.movement is not None and not Path(args.movement).is_file():
        raise common.UsageError(f"recording {args.movement!r} not found")
    out = outputs.check_file(args.out, tuple(PICTURES), force=args.force, what="picture")
    summary = None
    with stages(3, "simulate") as st:
        st.step("loading")
        model = _load_model(args.model)
        if args.movement is not None:
            from visprim.cli.imitate import read_recording
            from visprim.imitate import imitate

            trial = read_recording(args, args.movement, model)
            st.step(f"imitating {trial.duration:.2f} s through primitives on Adonis")
            result = imitate(model, trial, source=args.source or "primitives")
            playback = result.playback
            summary = result.summary()
            if result.source == "primitives":
                seq = " ".join(str(int(k)) for k in result.primitives)
                title = f"{result.name}: primitives {seq if len(seq) <= 30 else seq[:27] + '...'}"
            else:
                title = f"{result.name}: NEAR-COPY (projection)"
        else:
            from visprim.sim.playback import play
            from visprim.sim.showcase import primitive_trajectory

            try:
                times, angles = primitive_trajectory(model, args.primitive)
            except ValueError as exc:
                raise common.UsageError(f"--primitive {args.primitive}: {exc}") from None
            title = f"primitive {args.primitive}"
            st.step(f"simulating {times[-1] - times[0]:.2f} s")
            playback = play(times, angles)
        from visprim.sim.render import render_gif, render_png

        st.step(f"drawing {playback.frames.shape[0]} frames")
        with outputs.atomic_file(out) as tmp:
            if out.suffix.lower() == ".png":
                render_png(playback, tmp, title=title)
            else:
                render_gif(playback, tmp, title=title)
    print(summary if summary is not None else f"{title}: {playback.summary()}")
    print(f"wrote {out} ({PICTURES[out.suffix.lower()]}, {playback.frames.shape[0]} frames)")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "simulate",
        help="play primitives of a model on the Adonis humanoid (DART)",
        description="Play one primitive, or a recording imitated through the model's primitives "
        "(as `visprim imitate` does), on the simulated humanoid and draw it (--out .gif: "
        "animation, .png: last frame).",
    )
    p.add_argument("model", help="model file written by `visprim learn`")
    group = p.add_mutually_exclusive_group()
    group.add_argument(
        "--primitive", type=common.seed_int, help="index of the primitive (cluster) to play"
    )
    group.add_argument(
        "--movement",
        metavar="RECORDING",
        help="a recording to imitate through the model's primitives and play "
        "(the chain of `visprim imitate`)",
    )
    p.add_argument(
        "--source",
        choices=("primitives", "projection"),
        default=None,
        help="with --movement: rebuild from the nearest primitives (default) or, as a "
        "labelled near-copy, from each segment's own projection",
    )
    p.add_argument("--out", default="adonis.gif", help="output .gif or .png (default adonis.gif)")
    common.add_force_option(p)
    common.add_reader_options(p, many=False)
    p.set_defaults(func=run)

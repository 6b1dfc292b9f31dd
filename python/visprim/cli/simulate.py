"""``visprim simulate``: play a primitive or a reconstructed movement on Adonis.

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
    """``visprim simulate MODEL (--primitive K | --movement TRIALFILE) --out GIF|PNG``."""
    from visprim.progress import stages

    if args.primitive is None and args.movement is None:
        raise common.UsageError("give --primitive K or --movement TRIALFILE")
    if not Path(args.model).is_file():
        raise common.UsageError(
            f"model file {args.model!r} not found; give a model written by `visprim learn`"
        )
    out = outputs.check_file(args.out, tuple(PICTURES), force=args.force, what="picture")
    with stages(3, "simulate") as st:
        st.step("loading")
        model = _load_model(args.model)
        if args.movement is not None:
            from visprim.io import read

            opts = common.reader_options(args)
            trial = read(args.movement, opts.pop("arm"), **opts)
            times, angles = model.reconstruct_movement(trial)
            title = f"movement {trial.name}"
        else:
            from visprim.sim.showcase import primitive_trajectory

            try:
                times, angles = primitive_trajectory(model, args.primitive)
            except ValueError as exc:
                raise common.UsageError(f"--primitive {args.primitive}: {exc}") from None
            title = f"primitive {args.primitive}"
        st.step(f"simulating {times[-1] - times[0]:.2f} s")
        from visprim.sim.playback import play
        from visprim.sim.render import render_gif, render_png

        playback = play(times, angles)
        st.step(f"drawing {playback.frames.shape[0]} frames")
        with outputs.atomic_file(out) as tmp:
            if out.suffix.lower() == ".png":
                render_png(playback, tmp, title=title)
            else:
                render_gif(playback, tmp, title=title)
    print(f"{title}: {playback.summary()}")
    print(f"wrote {out} ({PICTURES[out.suffix.lower()]}, {playback.frames.shape[0]} frames)")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "simulate",
        help="play primitives of a model on the Adonis humanoid (DART)",
        description="Play one primitive, or a whole movement rebuilt from primitives, on the "
        "simulated humanoid and draw it (--out .gif: animation, .png: last frame).",
    )
    p.add_argument("model", help="model file written by `visprim learn`")
    group = p.add_mutually_exclusive_group()
    group.add_argument(
        "--primitive", type=common.seed_int, help="index of the primitive (cluster) to play"
    )
    group.add_argument("--movement", help="a trial file whose reconstructed movement to play")
    p.add_argument("--out", default="adonis.gif", help="output .gif or .png (default adonis.gif)")
    common.add_force_option(p)
    common.add_reader_options(p, many=False)
    p.set_defaults(func=run)

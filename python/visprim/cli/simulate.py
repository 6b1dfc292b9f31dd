"""``visprim simulate``: play a primitive or a reconstructed movement on Adonis."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from visprim.sim.playback import play
from visprim.sim.render import render_gif
from visprim.sim.showcase import PrimitiveSource, primitive_trajectory


def _load_model(path: str) -> PrimitiveSource:
    from visprim import PrimitiveModel

    return PrimitiveModel.load(path)  # type: ignore[no-any-return]


def run(args: argparse.Namespace) -> int:
    """``visprim simulate MODEL (--primitive K | --movement TRIALFILE) --out GIF``."""
    if args.primitive is None and args.movement is None:
        print("visprim simulate: give --primitive K or --movement TRIALFILE", file=sys.stderr)
        return 2
    if not Path(args.model).is_file():
        print(f"visprim simulate: model file {args.model!r} not found", file=sys.stderr)
        return 2
    model = _load_model(args.model)
    try:
        if args.movement is not None:
            from visprim.io import read

            trial = read(args.movement)
            times, angles = model.reconstruct_movement(trial)  # type: ignore[attr-defined]
            title = f"movement {trial.name}"
        else:
            times, angles = primitive_trajectory(model, args.primitive)
            title = f"primitive {args.primitive}"
    except (ValueError, OSError) as exc:
        print(f"visprim simulate: {exc}", file=sys.stderr)
        return 2
    playback = play(times, angles)
    out = render_gif(playback, args.out, title=title)
    print(f"{title}: {playback.summary()}")
    print(f"wrote {out} ({playback.frames.shape[0]} frames)")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser("simulate", help="play primitives of a model on the Adonis humanoid (DART)")
    p.add_argument("model", help="model file written by `visprim learn`")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--primitive", type=int, help="index of the primitive (cluster) to play")
    group.add_argument("--movement", help="a trial file whose reconstructed movement to play")
    p.add_argument("--out", default="adonis.gif", help="output GIF (default adonis.gif)")
    p.set_defaults(func=run)

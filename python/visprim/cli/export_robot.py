"""``visprim export-robot``: Adonis as URDF, and primitives as joint trajectories."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def run(args: argparse.Namespace) -> int:
    """``visprim export-robot --out adonis.urdf [--model MODEL --trajectories DIR]``."""
    from visprim.sim.urdf import urdf_joint_names, write_urdf

    if args.trajectories is not None and args.model is None:
        print("visprim export-robot: --trajectories needs --model MODEL", file=sys.stderr)
        return 2
    try:
        path = write_urdf(args.out)
    except (ValueError, OSError) as exc:
        print(f"visprim export-robot: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path} ({len(urdf_joint_names())} joints: {' '.join(urdf_joint_names())})")
    if args.model is None:
        return 0
    if not Path(args.model).is_file():
        print(f"visprim export-robot: model file {args.model!r} not found", file=sys.stderr)
        return 2
    from visprim import PrimitiveModel
    from visprim.sim.export import primitive_trajectory

    out = Path(args.trajectories or ".")
    try:
        model = PrimitiveModel.load(args.model)
        for k in range(model.n_primitives):
            js, cs = primitive_trajectory(model, k).write(out / f"primitive_{k:02d}")
    except (ValueError, OSError) as exc:
        print(f"visprim export-robot: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {model.n_primitives} primitive trajectories (JSON + CSV) to {out}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "export-robot",
        help="write Adonis as URDF (and a model's primitives as joint trajectories)",
        description=(
            "Write Adonis as a URDF file built from the same table as the DART model (ball "
            "joints split into three continuous joints, X-Z-Y). With --model, also write each "
            "primitive as a joint trajectory (JSON for a ROS JointTrajectory, and CSV) with "
            "the URDF's joint names."
        ),
    )
    p.add_argument("--out", default="adonis.urdf", help="URDF file to write (default adonis.urdf)")
    p.add_argument("--model", help="model file whose primitives to export as trajectories")
    p.add_argument("--trajectories", help="folder for the primitive trajectories (default .)")
    p.set_defaults(func=run)

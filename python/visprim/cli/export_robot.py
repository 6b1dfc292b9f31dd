"""``visprim export-robot``: Adonis as URDF or MJCF, and primitives as joint trajectories."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from visprim.cli import common, outputs


def run(args: argparse.Namespace) -> int:
    """``visprim export-robot --out adonis.urdf|adonis.xml [--model MODEL --trajectories
    DIR]``."""
    from visprim.sim.mjcf import adonis_mjcf, mjcf_joint_names
    from visprim.sim.urdf import adonis_urdf, urdf_joint_names

    if args.trajectories is not None and args.model is None:
        raise common.UsageError("--trajectories needs --model MODEL (whose primitives to export)")
    if args.model is not None and not Path(args.model).is_file():
        raise common.UsageError(f"model file {args.model!r} not found")
    out = outputs.check_file(args.out, (".urdf", ".xml"), force=args.force, what="robot file")
    mjcf = out.suffix.lower() == ".xml"
    folder = None
    if args.model is not None:
        folder = outputs.check_folder(
            args.trajectories or "primitive_trajectories", force=args.force, option="--trajectories"
        )
    with outputs.atomic_file(out) as tmp:
        tmp.write_text(adonis_mjcf() if mjcf else adonis_urdf(), encoding="utf-8")
    names = mjcf_joint_names() if mjcf else urdf_joint_names()
    kind = "MJCF" if mjcf else "URDF"
    print(f"wrote {out} ({kind}, {len(names)} joints: {' '.join(names)})")
    if args.model is None or folder is None:
        return 0
    from visprim.sim.export import primitive_trajectory

    model = common.load_model(args.model)
    with outputs.atomic_folder(folder, "export-robot") as tmp_dir:
        for k in range(model.n_primitives):
            primitive_trajectory(model, k).write(tmp_dir / f"primitive_{k:02d}")
    print(f"wrote {model.n_primitives} primitive trajectories (JSON + CSV) to {folder}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "export-robot",
        help="write Adonis as URDF or MJCF (and a model's primitives as joint trajectories)",
        description=(
            "Write Adonis as a URDF file (.urdf; ball joints split into three continuous "
            "joints, X-Z-Y) or an MJCF file for MuJoCo (.xml; ball joints kept), built from the "
            "same table as the DART model. With --model, also write each primitive as a joint "
            "trajectory (JSON for a ROS JointTrajectory, and CSV) with the URDF's joint names."
        ),
    )
    p.add_argument(
        "--out",
        default="adonis.urdf",
        help="robot file to write: .urdf (URDF) or .xml (MJCF) (default adonis.urdf)",
    )
    p.add_argument("--model", help="model file whose primitives to export as trajectories")
    p.add_argument(
        "--trajectories",
        help="folder for the primitive trajectories (default primitive_trajectories)",
    )
    common.add_force_option(p)
    p.set_defaults(func=run)

"""Imitation of every kind of shared recording: the first ``--per-folder`` recordings of each
folder of the shared data, through a model's primitives (no simulation), one row each.

Shows that one command imitates any shared recording (BVH, ASF/AMC, C3D) and what the rebuild
costs: segments, joint-space RMS of the rebuild against the human (degrees), the uncovered
share. A recording that fails is listed with its one-line error. The model is the one
``benches/bench_imitate.py`` learns (HDM05 actors bd, bk, dg): recordings of those actors
were seen in training.

Run: ``PYTHONPATH=python .venv/bin/python benches/imitate_sweep.py [--model M]``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("VISPRIM_SHARED_DATA", REPO.parent / "shared" / "data"))
SUFFIXES = (".bvh", ".amc", ".c3d")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="shared data folder")
    ap.add_argument("--model", type=Path, default=Path("/tmp/visprim_bench_imitate.npz"))
    ap.add_argument("--per-folder", type=int, default=2)
    args = ap.parse_args()
    if not args.model.is_file():
        sys.exit(f"imitate_sweep: no model at {args.model}; run benches/bench_imitate.py first")
    from visprim import PrimitiveModel
    from visprim.imitate import imitate

    model = PrimitiveModel.load(args.model)
    print("| recording | segments | rebuild vs human (joint space, deg RMS) | uncovered |")
    print("|---|---:|---:|---:|")
    for folder in sorted(p for p in args.data.iterdir() if p.is_dir()):
        files = sorted(p for p in folder.iterdir() if p.suffix.lower() in SUFFIXES)
        for path in files[: args.per_folder]:
            name = path.relative_to(args.data)
            try:
                m = imitate(model, path, play=False).metrics
            except Exception as exc:  # the sweep reports every failure and goes on
                print(f"| {name} | failed: {type(exc).__name__}: {exc} | | |")
                continue
            rms = m["rebuild_vs_human_joint_rms_deg"]["overall"]
            print(
                f"| {name} | {m['n_segments']} | {rms:.1f} | "
                f"{m['coverage']['uncovered_percent']:.1f} % |"
            )


if __name__ == "__main__":
    main()

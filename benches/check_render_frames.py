"""Whether two versions of the imitation video's drawing give the same frames.

Draws every frame of the side-by-side imitation video (:class:`visprim.sim.sidebyside.SideBySide`,
480 px panels) of a generated movement looped to ``--seconds`` (as
``bench_imitate_long.py`` builds it) and writes one SHA-256 of the RGB pixels per frame
(``--write FILE``), or compares them with a file written by another version
(``--compare FILE``): prints how many frames differ and exits 1 if any does.

Run, e.g. the drawing of ``main`` against this tree::

    PYTHONPATH=/path/to/main/python python benches/check_render_frames.py --write /tmp/ref.txt
    PYTHONPATH=python python benches/check_render_frames.py --compare /tmp/ref.txt
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate
from visprim.sim.sidebyside import SideBySide

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_imitate_long import looped  # noqa: E402


def frame_hashes(seconds: float, size: int) -> list[str]:
    trials = imitation_experiment(2, 6, seed=3)
    model = PrimitiveModel(n_clusters=8, n_init=2, seed=0).fit(trials[:-1])
    view = SideBySide(imitate(model, looped(trials[-1], seconds / 60.0)), (size, size))
    return [hashlib.sha256(np.asarray(f).tobytes()).hexdigest() for f in view.frames()]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=12.0)
    ap.add_argument("--size", type=int, default=480)
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("--write", type=Path)
    what.add_argument("--compare", type=Path)
    args = ap.parse_args()
    hashes = frame_hashes(args.seconds, args.size)
    if args.write is not None:
        args.write.write_text("\n".join(hashes) + "\n", encoding="ascii")
        print(f"{len(hashes)} frames written to {args.write}")
        return
    ref = args.compare.read_text(encoding="ascii").split()
    differ = sum(a != b for a, b in zip(hashes, ref, strict=False)) + abs(len(hashes) - len(ref))
    print(f"{differ} of {max(len(hashes), len(ref))} frames differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()

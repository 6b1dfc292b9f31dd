"""Self-calibration's cost (:func:`visprim.io.refine.refine_rotations`) on the shared clip,
with its solver on one BLAS thread (as shipped) and on OpenBLAS's default threads, alternately.

    PYTHONPATH=python python benches/bench_refine.py [--data DIR] [--cache-dir DIR]
        [--rounds 3] [--out FILE]

The keypoints are MediaPipe's of the four views of ``pose2sim_single_person`` (100 frames;
the pose cache in ``--cache-dir``, else a fresh temporary one), left/right exchanges put back
as ``triangulate_poses`` does; ``refine_rotations`` makes its three fits (two halves and all
frames). "default threads" replaces ``threadpoolctl.threadpool_limits`` by a no-op for the
run, which is what ``_fit`` did before. Per round, both, in turn: wall time (s). Also the SVD
of a 26000 × 12 matrix (the size of the Jacobian scipy's ``trf`` factorises every
iteration), both ways (ms, median of 10). The figures and the largest difference between the
fitted rotations (deg; 0 when the thread count does not change the result) are stamped with
date, commit, CPU, instruction set and the load average: this machine is shared, so only
the ratio, measured alternately, means anything.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
from _harness import commit, cpu_model
from visprim import kernels
from visprim.atomic import write_text
from visprim.io.calibration import read_calibration
from visprim.io.refine import Refinement, refine_rotations
from visprim.io.video_pose import video_poses
from visprim.io.views import SIDE_PAIRS, triangulate_keypoints


@contextlib.contextmanager
def _no_limit(*args: Any, **kwargs: Any) -> Iterator[None]:
    yield


def _refine(folder: Path, default_threads: bool) -> tuple[float, Refinement]:
    cams = read_calibration(folder / "Calib.qca.txt")
    poses = [video_poses(folder / f"cam0{i}.mp4") for i in (1, 2, 3, 4)]
    cams = [c.fitted_to(q.size) for c, q in zip(cams, poses, strict=True)]
    n = min(q.times.size for q in poses)
    pix = np.stack([q.image[:n] for q in poses], axis=2)
    conf = np.stack([np.where(q.found[:n, None], q.confidence[:n], 0.0) for q in poses], axis=2)
    first = triangulate_keypoints(
        cams, pix, conf, pairs=list(SIDE_PAIRS["blazepose33"]), max_reprojection=None
    )
    patch = (
        mock.patch("threadpoolctl.threadpool_limits", _no_limit)
        if default_threads
        else contextlib.nullcontext()
    )
    with patch:
        t = time.perf_counter()
        ref = refine_rotations(cams, first.pixels, first.confidence)
        return time.perf_counter() - t, ref


def _svd_ms(one_thread: bool) -> float:
    from scipy.linalg import svd
    from threadpoolctl import threadpool_limits

    j = np.random.default_rng(0).normal(size=(26000, 12))
    ctx = threadpool_limits(limits=1, user_api="blas") if one_thread else contextlib.nullcontext()
    times = []
    with ctx:
        for _ in range(10):
            t = time.perf_counter()
            svd(j, full_matrices=False, check_finite=False)
            times.append(time.perf_counter() - t)
    return float(np.median(times)) * 1e3


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data")
    )
    ap.add_argument("--cache-dir", help="reuse the pose cache in this folder")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", help="also write the report to this file (atomically)")
    args = ap.parse_args()
    folder = Path(args.data) / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        print(f"bench_refine: {folder}: no such folder (the shared clip)", file=sys.stderr)
        return 2
    with contextlib.ExitStack() as stack:
        cache = args.cache_dir or stack.enter_context(tempfile.TemporaryDirectory())
        os.environ["VISPRIM_CACHE_DIR"] = cache
        _refine(folder, False)  # warm-up: the poses into the cache
        load0 = os.getloadavg()
        rows, refs = [], {}
        walls: dict[str, list[float]] = {"one BLAS thread": [], "default threads": []}
        svds: dict[str, list[float]] = {"one BLAS thread": [], "default threads": []}
        for r in range(args.rounds):
            for name in walls:
                wall, ref = _refine(folder, name == "default threads")
                walls[name].append(wall)
                refs[name] = ref
                svds[name].append(_svd_ms(name == "one BLAS thread"))
                rows.append(f"| {r + 1} | {name} | {wall:.2f} | {svds[name][-1]:.1f} |")
        load1 = os.getloadavg()
    a, b = refs.values()
    diff = float(np.abs(a.rotation_deg - b.rotation_deg).max())
    med = {k: float(np.median(v)) for k, v in walls.items()}
    one, default = med["one BLAS thread"], med["default threads"]
    lines = [
        f"# refine_rotations: one BLAS thread against the default — "
        f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}",
        f"commit {commit()} · CPU {cpu_model()} · instruction set {kernels.instruction_set()} · "
        f"load average {load0[0]:.1f} / {load0[1]:.1f} / {load0[2]:.1f} at the start, "
        f"{load1[0]:.1f} / {load1[1]:.1f} / {load1[2]:.1f} at the end (shared machine)",
        "",
        "| round | solver threads | refine_rotations wall (s) "
        "| SVD 26000 × 12 (ms, median of 10) |",
        "|---|---|---|---|",
        *rows,
        "",
        f"median wall: one BLAS thread {one:.2f} s, default threads {default:.2f} s "
        f"(ratio {default / one:.1f}); "
        f"largest difference between the fitted rotations: {diff:.3g}°; applied "
        f"{a.applied} / {b.applied}; held-out checks equal: {a.held_out == b.held_out}",
    ]
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if args.out:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

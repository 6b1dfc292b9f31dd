"""The imitation video alone, drawn in one process and in parts, alternately.

The imitation is that of ``bench_imitate_long.py`` (a generated movement looped to
``--minutes``, a model of other generated movements), computed once; then
``render_imitation(..., workers=W)`` writes its video for each ``W`` of ``--workers`` and
each format of ``--formats``, in turn, ``--rounds`` times. Figures per run: wall time and
CPU time (this process and the processes it waited for: the forks drawing the parts and
the MP4 encoders), seconds. The output is stamped with date, commit, CPU,
``instruction_set()`` and the load average.

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_video_parts.py [--minutes 5]``
"""

from __future__ import annotations

import argparse
import datetime
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

from _harness import commit, cpu_model
from bench_imitate_long import looped
from visprim import PrimitiveModel, kernels
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate
from visprim.sim.sidebyside import render_imitation


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    waited = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + waited.ru_utime + waited.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=5.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--workers", type=int, nargs="+", default=[0, 2])
    ap.add_argument("--formats", nargs="+", default=["mp4", "gif"])
    ap.add_argument("--size", type=int, default=480)
    args = ap.parse_args()
    print(f"# imitation video in parts — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
    print(
        f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
        f"{kernels.instruction_set()} · Python {sys.version.split()[0]}"
    )
    trials = imitation_experiment(2, 6, seed=3)
    model = PrimitiveModel(n_clusters=8, n_init=2, seed=0).fit(trials[:-1])
    imitation = imitate(model, looped(trials[-1], args.minutes))
    print(f"{args.minutes:g} min recording, {args.size} px panels\n")
    print("| round | format | workers | wall s | CPU s | load average (1 min) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="visprim-bench-parts-") as tmp:
        for r in range(args.rounds):
            for fmt in args.formats:
                for w in args.workers:
                    t0, c0 = time.perf_counter(), _cpu()
                    path = Path(tmp) / f"v{w}.{fmt}"
                    render_imitation(imitation, path, size=(args.size, args.size), workers=w)
                    wall, cpu = time.perf_counter() - t0, _cpu() - c0
                    print(
                        f"| {r + 1} | {fmt} | {w} | {wall:.1f} | {cpu:.1f} | "
                        f"{os.getloadavg()[0]:.1f} |",
                        flush=True,
                    )


if __name__ == "__main__":
    main()

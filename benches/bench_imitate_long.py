"""``visprim imitate`` (with its GIF video) on long recordings: wall time and peak memory.

The recording is a generated movement looped forward and back to the length asked for
(2.5, 10 and 30 min by default), written as a marker CSV; the model is learned on other
generated movements. Each length runs ``visprim imitate MODEL REC --out DIR`` (default
options: stable servo, 480 px panels, imitation.gif) in a child process; the figures are the
child's wall time and peak resident memory (``ru_maxrss`` from ``wait4``), ``--repeats``
runs per length (median, [min, max]).

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_imitate_long.py [--minutes 2.5 10]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv
from visprim.trial import Trial


def looped(trial: Trial, minutes: float) -> Trial:
    """``trial`` played forward, backward, forward ... for ``minutes``."""
    period = float(np.median(np.diff(trial.times)))
    n = int(round(minutes * 60.0 / period)) + 1
    cycle = np.concatenate([trial.markers, trial.markers[-2:0:-1]])
    reps = -(-n // cycle.shape[0])
    markers = np.concatenate([cycle] * reps)[:n]
    return Trial(times=np.arange(n) * period, markers=markers, name=f"looped_{minutes:g}min")


def run_once(argv: list[str]) -> tuple[float, float]:
    """(wall seconds, peak RSS in MB) of one child run of ``argv``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode() if proc.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"failed: {' '.join(argv)}\n{err}")
    return wall, usage.ru_maxrss / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[2.5, 10.0, 30.0])
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--size", type=int, default=480)
    args = ap.parse_args()
    trials = imitation_experiment(2, 6, seed=3)
    model = PrimitiveModel(n_clusters=8, n_init=2, seed=0).fit(trials[:-1])
    with tempfile.TemporaryDirectory(prefix="visprim-bench-long-") as tmp:
        root = Path(tmp)
        model.save(root / "model.npz")
        print(f"imitate with video, {args.size} px panels; {args.repeats} run(s) per length")
        print("| recording | frames | wall s (median [min, max]) | peak RSS MB |")
        print("|---|---|---|---|")
        for minutes in args.minutes:
            rec = looped(trials[-1], minutes)
            path = write_marker_csv(root / f"{rec.name}.csv", rec, truth=False)
            walls, rss = [], []
            for k in range(args.repeats):
                out = root / f"out_{minutes:g}_{k}"
                argv = [sys.executable, "-m", "visprim.cli", "-q", "imitate"]
                argv += [str(root / "model.npz"), str(path), "--out", str(out)]
                argv += ["--size", str(args.size)]
                wall, mb = run_once(argv)
                walls.append(wall)
                rss.append(mb)
            print(
                f"| {minutes:g} min | {rec.n_frames} | {statistics.median(walls):.0f} "
                f"[{min(walls):.0f}, {max(walls):.0f}] | {statistics.median(rss):.0f} "
                f"[{min(rss):.0f}, {max(rss):.0f}] |",
                flush=True,
            )


if __name__ == "__main__":
    main()

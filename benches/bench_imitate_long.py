"""``visprim imitate`` with its video on long recordings: wall time and peak memory.

The recording is a generated movement looped forward and back to the length asked for
(2.5, 5, 10 and 30 min by default), written as a marker CSV; the model is learned on other
generated movements. Each length runs ``visprim imitate MODEL REC --out DIR --video NAME``
(stable servo, 480 px panels; ``--video`` picks the format, default ``imitation.gif``) in a
child process, ``--repeats`` runs per length (median [min, max]). Figures per run:

* wall time of the child, seconds, and its CPU time (user + system, the child and the
  processes it waited for): on a shared machine the CPU time says what the run costs, the
  wall time what the load made of it;
* peak resident memory of the child, ``ru_maxrss`` from ``wait4`` (the Python process;
  for ``.mp4`` the encoder is a second process, counted in the next figure);
* peak memory of the child's whole process tree, sampled from ``/proc/PID/smaps_rollup``
  every 0.1 s: the sum of every process's RSS, and of its PSS. The video is drawn by forks
  of the child (:mod:`visprim.sim.frame_workers`), which share most of their pages with it:
  the RSS sum counts a shared page once in each process, the PSS sum once in all (the
  memory the machine spends);
* the targets: 5 min ≤ 60 s and ≤ 1 GB, 30 min ≤ 1.5 GB.

The output is stamped: date, commit, CPU, ``instruction_set()``, and the load average at the
start and the end (the machine may be shared: the load says how much).

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_imitate_long.py [--minutes 5 30]``
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
from _harness import commit, cpu_model
from visprim import PrimitiveModel, kernels
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv
from visprim.trial import Trial

ROOT = Path(__file__).resolve().parents[1]
PAGE = os.sysconf("SC_PAGE_SIZE")


def looped(trial: Trial, minutes: float) -> Trial:
    """``trial`` played forward, backward, forward ... for ``minutes``."""
    period = float(np.median(np.diff(trial.times)))
    n = int(round(minutes * 60.0 / period)) + 1
    cycle = np.concatenate([trial.markers, trial.markers[-2:0:-1]])
    reps = -(-n // cycle.shape[0])
    markers = np.concatenate([cycle] * reps)[:n]
    return Trial(times=np.arange(n) * period, markers=markers, name=f"looped_{minutes:g}min")


def _tree(pid: int) -> list[int]:
    """``pid`` and its descendants."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii", errors="replace") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def _memory(pid: int) -> tuple[int, int]:
    """(resident, proportional) memory of a process, bytes: RSS counts every page it maps,
    those it shares too; PSS divides each shared page among the processes sharing it."""
    rss = pss = 0
    try:
        with open(f"/proc/{pid}/smaps_rollup", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Rss:"):
                    rss = int(line.split()[1]) * 1024
                elif line.startswith("Pss:"):
                    pss = int(line.split()[1]) * 1024
    except OSError:
        pass
    return rss, pss


def run_once(argv: list[str]) -> tuple[float, float, float, float, float]:
    """(wall seconds, CPU seconds, child ru_maxrss MB, process tree peak RSS and PSS MB) of
    one child run. The tree's figures are the peaks of sums sampled every 0.1 s: the RSS sum
    counts a page shared by forked processes once in each, the PSS sum once in all."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak = [0, 0]
    done = threading.Event()

    def sample() -> None:
        while not done.is_set():
            mem = [_memory(p) for p in _tree(proc.pid)]
            peak[0] = max(peak[0], sum(m[0] for m in mem))
            peak[1] = max(peak[1], sum(m[1] for m in mem))
            done.wait(0.1)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    done.set()
    sampler.join()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"failed: {' '.join(argv)}\n{err}")
    cpu = usage.ru_utime + usage.ru_stime
    return wall, cpu, usage.ru_maxrss / 1024.0, peak[0] / 2**20, peak[1] / 2**20


def _spread(values: list[float], fmt: str) -> str:
    med = statistics.median(values)
    return f"{med:{fmt}} [{min(values):{fmt}}, {max(values):{fmt}}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[2.5, 5.0, 10.0, 30.0])
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--size", type=int, default=480)
    ap.add_argument("--video", default="imitation.gif", help="video name (.gif or .mp4)")
    args = ap.parse_args()
    load0 = os.getloadavg()
    print(
        f"# imitate on long recordings — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}"
    )
    print(
        f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
        f"{kernels.instruction_set()} · Python {sys.version.split()[0]}"
    )
    print(f"load average at start: {load0[0]:.1f} / {load0[1]:.1f} / {load0[2]:.1f} (1/5/15 min)")
    print(
        f"video {args.video}, {args.size} px panels, stable servo; {args.repeats} run(s) per "
        "length, median [min, max]\n"
    )
    trials = imitation_experiment(2, 6, seed=3)
    model = PrimitiveModel(n_clusters=8, n_init=2, seed=0).fit(trials[:-1])
    print(
        "| recording | frames | wall s | CPU s | peak RSS MB, Python | peak RSS MB, process tree "
        "| peak PSS MB, process tree |"
    )
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="visprim-bench-long-") as tmp:
        root = Path(tmp)
        model.save(root / "model.npz")
        for minutes in args.minutes:
            rec = looped(trials[-1], minutes)
            path = write_marker_csv(root / f"{rec.name}.csv", rec, truth=False)
            walls, cpus, rss, tree, tree_pss = [], [], [], [], []
            for k in range(args.repeats):
                out = root / f"out_{minutes:g}_{k}"
                argv = [sys.executable, "-m", "visprim.cli", "-q", "imitate"]
                argv += [str(root / "model.npz"), str(path), "--out", str(out)]
                argv += ["--size", str(args.size), "--video", args.video]
                wall, cpu, mb, tree_mb, pss_mb = run_once(argv)
                walls.append(wall)
                cpus.append(cpu)
                rss.append(mb)
                tree.append(tree_mb)
                tree_pss.append(pss_mb)
            print(
                f"| {minutes:g} min | {rec.n_frames} | {_spread(walls, '.0f')} | "
                f"{_spread(cpus, '.0f')} | "
                f"{_spread(rss, '.0f')} | {_spread(tree, '.0f')} | {_spread(tree_pss, '.0f')} |",
                flush=True,
            )
    load1 = os.getloadavg()
    print(f"\nload average at end: {load1[0]:.1f} / {load1[1]:.1f} / {load1[2]:.1f} (1/5/15 min)")


if __name__ == "__main__":
    main()

"""Cost of MotionClassifier's torso term: fit + predict of one HDM05 fold, alternately
with ``torso=False`` and ``torso=True`` in one run.

    python benches/bench_classifier_torso_time.py [DATA] [--rounds N]

DATA defaults to ../shared/data/hdm05_cut_amc (both arms, 34 ms); the actor ``mm`` is held
out. Prints the wall and CPU seconds of each run and the ratio of the medians (True /
False): the ratio is what a loaded machine can tell, not the seconds.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from visprim.classify import MotionClassifier
from visprim.evaluate import find_recordings, make_benchmarks, read_movements

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "hdm05_cut_amc"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="?", default=str(DATA))
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    recordings, _ = find_recordings([args.data])
    read, _ = read_movements(recordings, arm="both", jobs=1)
    recordings = [r for r, t in zip(recordings, read, strict=True) if t is not None]
    bench = make_benchmarks(recordings, [t for t in read if t is not None])[0][0]
    test = bench.groups == "mm"
    movs = bench.movements
    train = [m for m, held in zip(movs, test, strict=True) if not held]
    held_out = [m for m, held in zip(movs, test, strict=True) if held]
    y, g = bench.labels[~test], bench.groups[~test]
    times: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
    for r in range(args.rounds):
        for torso in (False, True):
            w0, c0 = time.perf_counter(), time.process_time()
            clf = MotionClassifier(torso=torso).fit(train, list(y), groups=list(g))
            acc = float(np.mean(clf.predict(held_out) == bench.labels[test]))
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            times[torso].append((wall, cpu))
            print(f"round {r + 1} torso={torso}: {wall:.1f} s wall, {cpu:.1f} s CPU, mm {acc:.3f}")
    for i, what in enumerate(("wall", "CPU")):
        off = statistics.median(t[i] for t in times[False])
        on = statistics.median(t[i] for t in times[True])
        print(f"median {what}: {off:.1f} s without, {on:.1f} s with the torso (x{on / off:.2f})")


if __name__ == "__main__":
    main()

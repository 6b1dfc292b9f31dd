"""Which costs MotionClassifier sums: nested leave-one-group-out on the shared recordings.

    python benches/classifier_terms.py [DATA] [--jobs N]

For each labelled benchmark under DATA (default ../shared/data, as ``visprim evaluate``
finds them, both arms), each outer fold fits the classifier's PrimitiveModel on the
training groups and keeps the DTW costs of every description between all movements. Each
candidate set of terms then gets its weights chosen by the inner leave-one-group-out on
the training groups (as ``MotionClassifier.fit`` does: weights from
``visprim.params.TERM_WEIGHTS``, first best, the first term at 1) and is scored on the
held-out group only. Printed: the outer accuracy of each candidate set beside the DTW
1-NN baseline. The default set is ``coordinates + segments + velocity + duration``.

Deterministic: one run gives the figures.
"""

from __future__ import annotations

import argparse
import time
from itertools import product
from pathlib import Path

import numpy as np
from visprim import params
from visprim.classify import (
    MotionClassifier,
    arm_directions,
    arm_velocities,
    dtw_matrix,
    duration_costs,
    group_folds,
)
from visprim.evaluate import find_recordings, make_benchmarks, read_movements

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
#: The candidate set that is MotionClassifier's default.
DEFAULT = "+ velocity + duration (default)"

#: Candidate sets: name -> terms (the first has weight 1) and the neighbours voting.
CANDIDATES: dict[str, tuple[tuple[str, ...], int]] = {
    "coordinates + segments (former default)": (("coordinates", "segments"), 1),
    "+ velocity": (("coordinates", "segments", "velocity"), 1),
    "+ duration": (("coordinates", "segments", "duration"), 1),
    "+ velocity + duration (default)": (("coordinates", "segments", "velocity", "duration"), 1),
    "default terms, 3 neighbours by 1/cost": (
        ("coordinates", "segments", "velocity", "duration"),
        3,
    ),
}


def _vote(d: np.ndarray, y: np.ndarray, k: int) -> np.ndarray:
    """Labels of the rows of ``d`` (costs to training movements labelled ``y``)."""
    if k == 1:
        return y[np.argmin(d, axis=1)]
    classes = np.unique(y)
    idx = np.argsort(d, axis=1, kind="stable")[:, :k]
    w = 1.0 / np.maximum(np.take_along_axis(d, idx, axis=1), 1e-12)
    score = np.zeros((d.shape[0], classes.size))
    rows = np.repeat(np.arange(d.shape[0]), k)
    np.add.at(score, (rows, np.searchsorted(classes, y[idx]).ravel()), w.ravel())
    return classes[np.argmax(score, axis=1)]


def _inner(d: np.ndarray, y: np.ndarray, g: np.ndarray, k: int) -> float:
    right = 0
    for _, tr, te in group_folds(g):
        right += int(np.sum(_vote(d[np.ix_(te, tr)], y[tr], k) == y[te]))
    return right / y.shape[0]


def fold_costs(movements: list, train: np.ndarray) -> dict[str, np.ndarray]:
    """All-by-all costs of each description, under the model of the training movements,
    each divided by its median over pairs of training movements."""
    clf = MotionClassifier()
    clf._check_common()
    clf.method = "coordinates"
    clf._fit_features([movements[i] for i in train])
    costs = {
        "coordinates": dtw_matrix(clf._features(movements)["coordinates"]),
        "segments": dtw_matrix(clf._segment_projections(movements)),
        "velocity": dtw_matrix([arm_velocities(t) for t in movements]),
        "duration": duration_costs(movements),
    }
    off = ~np.eye(train.size, dtype=bool)
    for name, c in costs.items():
        costs[name] = c / float(np.median(c[np.ix_(train, train)][off]))
    return costs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="?", default=str(DATA))
    ap.add_argument("--jobs", type=int, default=None)
    args = ap.parse_args()
    recordings, _ = find_recordings([args.data])
    read, _ = read_movements(recordings, arm="both", jobs=args.jobs)
    recordings = [r for r, t in zip(recordings, read, strict=True) if t is not None]
    movements = [t for t in read if t is not None]
    benches, notes = make_benchmarks(recordings, movements)
    grid = list(product(params.TERM_WEIGHTS, repeat=3))
    for bench in benches:
        t0 = time.perf_counter()
        y, g, movs = bench.labels, bench.groups, bench.movements
        base = dtw_matrix([arm_directions(t) for t in movs])
        right = {name: 0 for name in CANDIDATES}
        base_right = 0
        picks: list[str] = []
        for group, train, test in group_folds(g):
            base_right += int(np.sum(y[train][np.argmin(base[np.ix_(test, train)], 1)] == y[test]))
            costs = fold_costs(movs, train)
            for name, (terms, k) in CANDIDATES.items():
                best, chosen, chosen_ws = -1.0, None, ()
                for ws in dict.fromkeys(w[: len(terms) - 1] for w in grid):
                    d = costs[terms[0]] + sum(
                        w * costs[t] for w, t in zip(ws, terms[1:], strict=True)
                    )
                    s = _inner(d[np.ix_(train, train)], y[train], g[train], k)
                    if s > best:
                        best, chosen, chosen_ws = s, d, ws
                assert chosen is not None
                if name == DEFAULT:
                    picks.append(f"{group or '-'} {chosen_ws}")
                pred = _vote(chosen[np.ix_(test, train)], y[train], k)
                right[name] += int(np.sum(pred == y[test]))
        n = len(y)
        print(
            f"\n{bench.name}: {n} movements, leave one {bench.group_by} out "
            f"({time.perf_counter() - t0:.0f} s)"
        )
        print(f"  DTW 1-NN baseline on the arm directions: {base_right / n:.3f}")
        for name, r in right.items():
            print(f"  {name}: {r / n:.3f} ({r}/{n})")
        print("  weights (segments, velocity, duration) of the default per held-out group:")
        print("    " + "; ".join(picks))


if __name__ == "__main__":
    main()

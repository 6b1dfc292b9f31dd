"""Which costs MotionClassifier sums: nested leave-one-group-out on the shared recordings.

    python benches/classifier_terms.py [DATA] [--jobs N]

For each labelled benchmark under DATA (default ../shared/data, as ``visprim evaluate``
finds them, both arms), each outer fold fits the classifier's PrimitiveModel on the
training groups and keeps the DTW costs of every description between all movements. Each
candidate set of terms then gets its weights chosen by the inner leave-one-group-out on
the training groups (as ``MotionClassifier.fit`` does: weights from
``visprim.params.TERM_WEIGHTS``, first best, the first term at 1) and is scored on the
held-out group only. Printed: the outer accuracy of each candidate set beside the DTW
1-NN baseline (on the arm directions, as ``visprim evaluate`` gives it, and on the arm
directions with the torso pose appended, 6 numbers more per frame, unweighted). The
default set is ``coordinates + segments + velocity + duration + torso``
(``torso``: :func:`visprim.classify.torso_pose`). The other descriptions of the trunk
measured (each as the fifth term in place of ``torso``) are defined here: the shoulder
midpoint alone, the up axis alone, the shoulders' height alone, the shoulder midpoint's
velocity, and the velocities of the shoulder midpoint and of the torso frame.

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
    torso_pose,
)
from visprim.evaluate import find_recordings, make_benchmarks, read_movements
from visprim.trial import Trial

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
#: The candidate set that is MotionClassifier's default.
DEFAULT = "+ velocity + duration + torso (default)"
_ARMS = ("coordinates", "segments", "velocity", "duration")

#: Candidate sets: name -> terms (the first has weight 1) and the neighbours voting.
CANDIDATES: dict[str, tuple[tuple[str, ...], int]] = {
    "coordinates + segments": (("coordinates", "segments"), 1),
    "+ velocity": (("coordinates", "segments", "velocity"), 1),
    "+ duration": (("coordinates", "segments", "duration"), 1),
    "+ velocity + duration (former default)": (_ARMS, 1),
    "former default, 3 neighbours by 1/cost": (_ARMS, 3),
    "+ velocity + duration + torso (default)": ((*_ARMS, "torso"), 1),
    "... torso: shoulder midpoint only": ((*_ARMS, "shoulders"), 1),
    "... torso: up axis only": ((*_ARMS, "up"), 1),
    "... torso: shoulder height only": ((*_ARMS, "height"), 1),
    "... torso: shoulder velocity": ((*_ARMS, "shoulder_velocity"), 1),
    "... torso: shoulder and torso-frame velocities": ((*_ARMS, "torso_velocity"), 1),
}
#: Also measured: the description of the trunk (the fifth term) chosen by the inner folds
#: among the six above, with its weights.
CHOSEN_TRUNK = "... torso: the description chosen by the inner folds too"


def _shoulder_velocity(t: Trial) -> np.ndarray:
    """Velocity of the shoulder midpoint, m/s: (T - 1, 3)."""
    return np.diff(torso_pose(t)[:, :3], axis=0) / np.diff(t.times)[:, None]


def _torso_velocity(t: Trial) -> np.ndarray:
    """The shoulder midpoint's velocity and the torso frame's (9 entries per frame, 1/s)."""
    assert t.body_frame is not None
    frame = np.diff(t.body_frame.reshape(t.n_frames, 9), axis=0) / np.diff(t.times)[:, None]
    return np.hstack([_shoulder_velocity(t), frame])


#: The descriptions of the trunk compared (per frame): the default's and five others.
TRUNK = {
    "torso": torso_pose,
    "shoulders": lambda t: torso_pose(t)[:, :3],
    "up": lambda t: torso_pose(t)[:, 3:],
    "height": lambda t: torso_pose(t)[:, 2:3],
    "shoulder_velocity": _shoulder_velocity,
    "torso_velocity": _torso_velocity,
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
    for name, describe in TRUNK.items():
        costs[name] = dtw_matrix([describe(t) for t in movements])
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
    grid = list(product(params.TERM_WEIGHTS, repeat=4))
    for bench in benches:
        t0 = time.perf_counter()
        y, g, movs = bench.labels, bench.groups, bench.movements
        base = dtw_matrix([arm_directions(t) for t in movs])
        # The baseline given the trunk too: the same data as the torso term.
        base_torso = dtw_matrix([np.hstack([arm_directions(t), torso_pose(t)]) for t in movs])
        base_torso_right = 0
        sets = {name: ([terms], k) for name, (terms, k) in CANDIDATES.items()}
        sets[CHOSEN_TRUNK] = ([(*_ARMS, trunk) for trunk in TRUNK], 1)
        right = {name: 0 for name in sets}
        base_right = 0
        picks: dict[str, list[str]] = {DEFAULT: [], CHOSEN_TRUNK: []}
        for group, train, test in group_folds(g):
            base_right += int(np.sum(y[train][np.argmin(base[np.ix_(test, train)], 1)] == y[test]))
            nearest = np.argmin(base_torso[np.ix_(test, train)], 1)
            base_torso_right += int(np.sum(y[train][nearest] == y[test]))
            costs = fold_costs(movs, train)
            for name, (alternatives, k) in sets.items():
                best, chosen, pick = -1.0, None, ""
                for terms in alternatives:
                    for ws in dict.fromkeys(w[: len(terms) - 1] for w in grid):
                        d = costs[terms[0]] + sum(
                            w * costs[t] for w, t in zip(ws, terms[1:], strict=True)
                        )
                        s = _inner(d[np.ix_(train, train)], y[train], g[train], k)
                        if s > best:
                            best, chosen, pick = s, d, f"{terms[-1]} {ws}"
                assert chosen is not None
                if name in picks:
                    picks[name].append(f"{group or '-'} {pick}")
                pred = _vote(chosen[np.ix_(test, train)], y[train], k)
                right[name] += int(np.sum(pred == y[test]))
        n = len(y)
        print(
            f"\n{bench.name}: {n} movements, leave one {bench.group_by} out "
            f"({time.perf_counter() - t0:.0f} s)"
        )
        print(f"  DTW 1-NN baseline on the arm directions: {base_right / n:.3f}")
        print(
            "  DTW 1-NN baseline on the arm directions and the torso pose: "
            f"{base_torso_right / n:.3f} ({base_torso_right}/{n})"
        )
        for name, r in right.items():
            print(f"  {name}: {r / n:.3f} ({r}/{n})")
        for name, chosen in picks.items():
            print(f"  {name}, last term and weights (segments, velocity, duration, last):")
            print("    " + "; ".join(chosen))


if __name__ == "__main__":
    main()

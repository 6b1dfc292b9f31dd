"""SEG-2 on the real recordings of ../shared/data: threshold stability and coverage.

    python benches/segmentation_real.py [DATA] [--arm right|both] [--features ...]

Prints, for the robust tuning (the default) and for the paper's tuning from repetitions:

* the tuned ``c`` on the whole corpus; with one near-static trial added (the first
  recording with its motion shrunk to 10 % about its mean posture: someone standing
  nearly still); and on 20 random sub-corpora without 3 trials (seeded) — max/min ratios;
* the coverage of moving time per trial (:mod:`visprim.segment.coverage`): median,
  minimum, and the trials below 70 %;
* segments per trial and trials without segments;
* SEG-1's trials without segments.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from visprim import PrimitiveModel
from visprim.io import read_many
from visprim.segment.coverage import segment_coverage

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def near_static_copy(trial, scale: float = 0.1):
    """The trial with its motion shrunk to ``scale`` about its mean posture (same clock)."""

    def shrink(a):
        return None if a is None else a.mean(axis=0) + scale * (a - a.mean(axis=0))

    return dataclasses.replace(
        trial,
        markers=shrink(trial.markers),
        joints=shrink(trial.joints),
        body_frame=None,
        name=trial.name + "_near_static",
    )


def tuned_c(model: PrimitiveModel, trials) -> float:
    return float(model.prepare(trials, tune_seg2=True).seg2_threshold)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="*", default=[str(DATA)])
    ap.add_argument("--arm", default="right")
    ap.add_argument("--features", default="directions")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trials = read_many(args.data, args.arm, resample=0.034, on_error="warn")
    print(f"{len(trials)} trials read in {time.perf_counter() - t0:.1f} s")
    rng = np.random.default_rng(0)
    settings = {
        f"features={args.features}, tuning=robust (default)": PrimitiveModel(
            features=args.features
        ),
        "the paper's method (features=zyz, tuning=repetitions)": PrimitiveModel.paper(),
    }
    for title, model in settings.items():
        corpus = model.prepare(trials, tune_seg2=True)
        c = corpus.seg2_threshold
        c_static = tuned_c(model, [*trials, near_static_copy(trials[0])])
        subs = []
        for _ in range(20):
            keep = np.sort(rng.choice(len(trials), len(trials) - 3, replace=False))
            subs.append(tuned_c(model, [trials[i] for i in keep]))
        cov = segment_coverage(trials, corpus.segments)
        counts = corpus.segmentation.counts()
        low = [corpus.names[i] for i in np.flatnonzero(cov < 0.7)]
        print(f"\n## SEG-2, {title}")
        print(
            f"c = {c:.4g} (rad/s)^2; with a near-static trial added: {c_static:.4g} "
            f"(x{max(c, c_static) / min(c, c_static):.2f})"
        )
        print(
            f"20 corpora without 3 random trials: c in [{min(subs):.4g}, {max(subs):.4g}] "
            f"(max/min {max(subs) / min(subs):.2f})"
        )
        print(
            f"coverage of moving time: median {np.nanmedian(cov):.3f}, min {np.nanmin(cov):.3f}, "
            f"{len(low)} trials below 0.70 {low[:8]}"
        )
        print(
            f"segments per trial: median {np.median(counts):.0f}, mean {counts.mean():.1f}; "
            f"{int(np.sum(counts == 0))} trials without segments"
        )
    seg1 = PrimitiveModel(features=args.features, segmentation="seg1").prepare(trials)
    c1 = seg1.segmentation.counts()
    print(
        f"\n## SEG-1: {int(np.sum(c1 == 0))} of {len(trials)} trials without segments; "
        f"segments per trial median {np.median(c1):.0f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

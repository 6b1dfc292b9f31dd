"""Where the online segments part from offline's: the filter or the threshold.

    PYTHONPATH=python python benches/online_gap.py [--data ../shared/data] [--quick]
        [--out benches/online_gap.result.md]

The replays of ``benches/bench_online.py`` (the same folds, models with
``seg2_boundary="first_stop"``; ``--quick``: its quick folds), each held-out recording cut
four ways against offline SEG-2 of the same model:

1. **online**: the online pipeline as it is (:func:`visprim.online.compare.compare_trial`);
2. **online, offline threshold**: the same, with the recording's offline threshold
   (``c_i = clip(κ · p95(z), c / ρ, c)`` over the *whole* recording, which no causal rule
   has) fixed from the first frame;
3. **zero-phase values, adaptive threshold**: the online SEG-2 state machine
   (:meth:`~visprim.online.OnlineSegmenter.push_values`) fed the offline filter's values
   of the whole recording (which no causal filter has), with its own adaptive threshold;
4. **zero-phase values, offline threshold**: both.

(3) and (4) take the primitive from the values fed. Boundary F1 ±100 ms and primitive per
segment as in ``bench_online.py``. Deterministic.
"""

from __future__ import annotations

import argparse
import copy
import sys
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from _harness import commit, cpu_model
from visprim import kernels
from visprim.atomic import write_text
from visprim.model import PrimitiveModel
from visprim.online import SegmentClosed
from visprim.online.compare import (
    TrialComparison,
    boundary_counts,
    compare_trial,
    equal_primitives,
    summarise,
)
from visprim.online.segmenter import OnlineSegmenter
from visprim.segment.seg2 import (
    _ROBUST_QUANTILE,
    ROBUST_FRACTION,
    ROBUST_SLOWEST,
    speed_squared,
)
from visprim.trial import Trial

sys.path.insert(0, str(Path(__file__).parent))
import bench_online  # noqa: E402

WAYS = (
    "online",
    "online, offline threshold",
    "zero-phase values, adaptive threshold",
    "zero-phase values, offline threshold",
)


def offline_threshold(model: PrimitiveModel, trial: Trial) -> float:
    """The recording's own SEG-2 threshold offline (robust tuning, :mod:`visprim.segment.seg2`)."""
    corpus = model.prepare([trial], tune_seg2=False)
    values = np.asarray(corpus.values_all if corpus.values_all is not None else corpus.angles_all)
    z = speed_squared(np.asarray(trial.times), values)
    c = float(model.seg2_threshold_)
    return float(np.clip(ROBUST_FRACTION * np.quantile(z, _ROBUST_QUANTILE), c / ROBUST_SLOWEST, c))


def _fed(model: PrimitiveModel, trial: Trial, threshold: str) -> tuple[np.ndarray, np.ndarray]:
    """Segments and primitives of the online state machine fed the zero-phase values."""
    corpus = model.prepare([trial], tune_seg2=False)
    values = np.asarray(corpus.values_all if corpus.values_all is not None else corpus.angles_all)
    seg = OnlineSegmenter(model, threshold=threshold)
    seg._shift = 0  # zero-phase values lag nothing
    events = seg.push_values(values, np.asarray(trial.times)) + seg.flush()
    closed = [e for e in events if isinstance(e, SegmentClosed)]
    return (
        np.array([[e.start, e.end] for e in closed]).reshape(-1, 2),
        np.array([e.primitive for e in closed], dtype=np.int64),
    )


def _as_comparison(base: TrialComparison, on: np.ndarray, prim: np.ndarray) -> TrialComparison:
    off = base.offline_segments
    equal = equal_primitives(off, base.offline_primitives, on, prim)
    none = np.zeros(on.shape[0], dtype=bool)
    return TrialComparison(
        base.name, off, base.offline_primitives, on, prim, np.zeros(on.shape[0]), none, none,
        "", "", boundary_counts(on, off), (equal, int(off.shape[0])),
    )  # fmt: skip


def table_rows(
    ways: dict[str, list[TrialComparison]],
    sizes: list[int],
    cell: Callable[[dict[str, float]], str],
) -> list[str]:
    """One Markdown row per way: ``cell`` of the pooled figures (:func:`summarise`) of each
    group of ``sizes`` consecutive trials, then of all of them."""
    edges = np.cumsum([0, *sizes])
    rows = []
    for way, results in ways.items():
        parts = [results[a:b] for a, b in zip(edges[:-1], edges[1:], strict=True)] + [results]
        rows.append(f"| {way} | " + " | ".join(cell(summarise(r)) for r in parts) + " |")
    return rows


def table_head(first: str, groups: list[str], sizes: list[int]) -> list[str]:
    """The header and rule of :func:`table_rows`' table."""
    names = " | ".join(f"{g} ({n})" for g, n in zip(groups, sizes, strict=True))
    return [f"| {first} | {names} | all ({sum(sizes)}) |", "|---|" + "---|" * (len(groups) + 1)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("benches/online_gap.result.md"))
    args = ap.parse_args()
    bench_online.MODEL_PARAMS.update(seg2_boundary="first_stop")
    ways: dict[str, list[TrialComparison]] = {w: [] for w in WAYS}

    def replay(model: PrimitiveModel, trial: Trial, classifier: Any = None, **kw: Any) -> Any:
        base = compare_trial(model, trial, None, chunk=bench_online.FIDELITY_CHUNK)
        ways[WAYS[0]].append(base)
        own = copy.copy(model)
        own.seg2_threshold_ = offline_threshold(model, trial)
        ways[WAYS[1]].append(
            compare_trial(own, trial, None, chunk=bench_online.FIDELITY_CHUNK, threshold="fixed")
        )
        ways[WAYS[2]].append(_as_comparison(base, *_fed(model, trial, "adaptive")))
        ways[WAYS[3]].append(_as_comparison(base, *_fed(own, trial, "fixed")))
        return base

    bench_online.compare_trial = replay  # type: ignore[assignment]
    started = datetime.now(UTC)
    table, _ = bench_online.fidelity(args.data, quick=args.quick)
    # The groups of bench_online's table, in its order: the trials were appended in it.
    sizes = [int(v["trials"]) for k, v in table.items() if k != "all"]
    groups = [k for k in table if k != "all"]
    rows = table_rows(
        ways, sizes, lambda s: f"{s['boundary_f1']:.3f} / {100 * s['primitive_equal']:.1f} %"
    )
    text = "\n".join(
        [
            f"# online against offline: the filter or the threshold — {started:%Y-%m-%d %H:%M} UTC",
            f"commit {commit()} · CPU {cpu_model()} · instruction set "
            f"{kernels.instruction_set()} · deterministic",
            f"command: `python benches/online_gap.py --data {args.data}"
            f"{' --quick' if args.quick else ''}`",
            "",
            "Boundary F1 ±100 ms / primitive per segment equal, against offline SEG-2 of the "
            "same model (the ways: the module docstring).",
            "",
            *table_head("way", groups, sizes),
            *rows,
            "",
        ]
    )
    write_text(args.out, text)
    print(text)


if __name__ == "__main__":
    main()

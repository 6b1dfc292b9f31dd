"""How far the online boundaries that miss offline's are from any: timing or existence.

    PYTHONPATH=python python benches/online_misses.py [--data ../shared/data] [--quick]
        [--out benches/online_misses.result.md]

The replays of ``benches/bench_online.py`` (the same folds, models with
``seg2_boundary="first_stop"``, the default online settings). For every offline boundary,
the distance to the nearest online one, and for every online boundary, the distance to the
nearest offline one, in bins: within the ±100 ms of the F1 (matched, or close to a boundary
that another one matched), a little late or early (up to 200 ms: a matter of timing), or
far (a boundary the other side does not have). Then the recordings that hold most of the
misses. Deterministic.
"""

from __future__ import annotations

import argparse
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from _harness import commit, cpu_model
from visprim import kernels
from visprim.atomic import write_text
from visprim.model import PrimitiveModel
from visprim.online.compare import TrialComparison, compare_trial
from visprim.segment import segment_boundaries
from visprim.trial import Trial

sys.path.insert(0, str(Path(__file__).parent))
import bench_online  # noqa: E402

#: Distance bins, seconds.
BINS = (0.0, 0.1, 0.2, 0.5, 1.0, np.inf)


def nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each time of ``a``, the distance to the nearest of ``b`` (inf if ``b`` is empty)."""
    if not b.size:
        return np.full(a.size, np.inf)
    return np.min(np.abs(a[:, None] - b[None, :]), axis=1)


def _boundaries(segments: np.ndarray) -> np.ndarray:
    return segment_boundaries(segments) if segments.shape[0] else np.zeros(0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("benches/online_misses.result.md"))
    args = ap.parse_args()
    bench_online.MODEL_PARAMS.update(seg2_boundary="first_stop")
    rows: list[tuple[str, np.ndarray, np.ndarray]] = []

    def replay(model: PrimitiveModel, trial: Trial, classifier: Any = None, **kw: Any) -> Any:
        r: TrialComparison = compare_trial(model, trial, None, **kw)
        on, off = _boundaries(r.online_segments), _boundaries(r.offline_segments)
        rows.append((r.name, nearest(off, on), nearest(on, off)))
        return r

    bench_online.compare_trial = replay  # type: ignore[assignment]
    started = datetime.now(UTC)
    bench_online.fidelity(args.data, quick=args.quick)
    off = np.concatenate([r[1] for r in rows])
    on = np.concatenate([r[2] for r in rows])
    labels = [
        f"{1000 * a:.0f}–{1000 * b:.0f} ms" if np.isfinite(b) else f"> {1000 * a:.0f} ms"
        for a, b in zip(BINS[:-1], BINS[1:], strict=True)
    ]
    lines = [
        "# online boundaries that miss offline's: timing or existence — "
        f"{started:%Y-%m-%d %H:%M} UTC",
        f"commit {commit()} · CPU {cpu_model()} · instruction set "
        f"{kernels.instruction_set()} · deterministic",
        f"command: `python benches/online_misses.py --data {args.data}"
        f"{' --quick' if args.quick else ''}`",
        "",
        f"{len(rows)} recordings. Distance from each boundary to the nearest of the other side:",
        "",
        "| boundaries | " + " | ".join(labels) + " | all |",
        "|---|" + "---:|" * (len(labels) + 1),
    ]
    sides = (("offline, to the nearest online", off), ("online, to the nearest offline", on))
    for name, d in sides:
        counts = np.histogram(d, bins=np.array(BINS))[0]
        lines.append(f"| {name} | " + " | ".join(str(int(c)) for c in counts) + f" | {d.size} |")
    misses = sorted(
        ((int(np.sum(o > 0.1) + np.sum(n > 0.1)), name) for name, o, n in rows), reverse=True
    )
    total = sum(m for m, _ in misses)
    top = misses[:10]
    lines += [
        "",
        f"Boundaries more than 100 ms from any of the other side: {total}, in "
        f"{sum(m > 0 for m, _ in misses)} of {len(rows)} recordings. The ten with most "
        f"({sum(m for m, _ in top)} of them):",
        "",
        "| recording | boundaries > 100 ms from any |",
        "|---|---:|",
        *[f"| {name} | {m} |" for m, name in top],
        "",
    ]
    text = "\n".join(lines)
    write_text(args.out, text)
    print(text)


if __name__ == "__main__":
    main()

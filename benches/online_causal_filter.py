"""Which causal low-pass lets the online segmenter cut where offline SEG-2 cuts.

    PYTHONPATH=python python benches/online_causal_filter.py [--data ../shared/data]
        [--out benches/online_causal_filter.result.md]

On the quick folds of ``benches/bench_online.py`` (the first fold of each labelled
benchmark, its model fitted on the other groups with ``seg2_boundary="first_stop"``, and 5
other recordings with a model of all the benchmarks), each held-out recording is cut
offline (the model's zero-phase filter, SEG-2 with its fitted constant) and online from
the same raw angles filtered by each candidate causal filter, fed to
:meth:`visprim.online.OnlineSegmenter.push_values` with the filter's latency as the shift
of the segment times. Boundary F1 within ±100 ms, as in ``bench_online.py``. The raw
joints and markers get white noise of 0, 2 and 5 mm (seeded), offline and online alike:
how the choice holds on noisier recordings than the shared ones.

Candidates: the causal Butterworth of order 2 (the former default, 2 frames of latency) and
:func:`visprim.online.lowpass.fir_taps` with 1 or 2 frames of look-ahead and a stop-band
weight of 0, 0.1 or 1 (:data:`~visprim.online.lowpass.FIR_STOPBAND_WEIGHT`). Only the
boundaries are compared (the primitive and the class need the whole pipeline:
``bench_online.py``). Deterministic.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import zlib
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from _harness import commit, cpu_model
from scipy import signal
from visprim import kernels
from visprim.atomic import write_text
from visprim.features import from_angles
from visprim.filtering import butterworth
from visprim.model import PrimitiveModel
from visprim.online import SegmentClosed
from visprim.online.compare import boundary_counts
from visprim.online.lowpass import fir_taps
from visprim.online.segmenter import OnlineSegmenter
from visprim.trial import Trial

sys.path.insert(0, str(Path(__file__).parent))
import bench_online  # noqa: E402

NOISE_M = (0.0, 0.002, 0.005)


def candidates(order: int, cutoff: float) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    """name → (b, a, latency in frames) of each causal filter."""
    out: dict[str, tuple[np.ndarray, np.ndarray, int]] = {}
    b2, a2 = signal.sos2tf(butterworth(2, cutoff))
    out["Butterworth order 2 (former default)"] = (b2, a2, 2)
    for lag in (1, 2):
        for weight in (0.0, 0.1, 1.0):
            taps = fir_taps(order, cutoff, lookahead=lag, stopband_weight=weight)
            out[f"FIR, look-ahead {lag}, stop-band weight {weight}"] = (taps, np.ones(1), lag)
    return out


def _noisy(trial: Trial, sd: float, rng: np.random.Generator) -> Trial:
    if sd == 0.0:
        return trial
    joints = None if trial.joints is None else trial.joints + rng.normal(0, sd, trial.joints.shape)
    return dataclasses.replace(
        trial, markers=trial.markers + rng.normal(0, sd, trial.markers.shape), joints=joints
    )


def compare(model: PrimitiveModel, trial: Trial, counts: dict[Any, list[int]]) -> None:
    """Add (matched, online, offline) boundaries of ``trial`` for every candidate and noise."""
    rng = np.random.default_rng(zlib.crc32((trial.name or "").encode()))
    filters = candidates(int(model.filter_order), float(model.cutoff))
    for sd in NOISE_M:
        t = _noisy(trial, sd, rng)
        corpus = model.prepare([t], tune_seg2=False)
        offline = corpus.segments[0]
        raw = np.asarray(corpus.raw_angles_all).reshape(t.n_frames, -1)
        for name, (b, a, lag) in filters.items():
            zi = signal.lfilter_zi(b, a)[:, None] * raw[0]
            filtered, _ = signal.lfilter(b, a, raw, axis=0, zi=zi)
            seg = OnlineSegmenter(model)
            seg._shift = lag  # the candidate's latency, as the segmenter's own filter has
            values = from_angles(filtered, str(model.features))
            events = seg.push_values(values, np.asarray(t.times)) + seg.flush()
            online = np.array(
                [[e.start, e.end] for e in events if isinstance(e, SegmentClosed)]
            ).reshape(-1, 2)
            m, n_on, n_off = boundary_counts(online, offline)
            c = counts.setdefault((name, sd), [0, 0, 0])
            c[0] += m
            c[1] += n_on
            c[2] += n_off


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--out", type=Path, default=Path("benches/online_causal_filter.result.md"))
    args = ap.parse_args()
    bench_online.MODEL_PARAMS.update(seg2_boundary="first_stop")
    counts: dict[Any, list[int]] = {}

    bench_online.compare_trial = _recording(counts)  # type: ignore[assignment]
    started = datetime.now(UTC)
    bench_online.fidelity(args.data, quick=True)
    rows = []
    names = list(dict.fromkeys(name for name, _ in counts))
    for name in names:
        cells = []
        for sd in NOISE_M:
            m, n_on, n_off = counts[(name, sd)]
            p, r = m / max(n_on, 1), m / max(n_off, 1)
            cells.append(f"{2 * p * r / (p + r) if p + r else 0.0:.3f} ({p:.3f} / {r:.3f})")
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    n_off = counts[(names[0], 0.0)][2]
    text = "\n".join(
        [
            f"# online causal filter — {started:%Y-%m-%d %H:%M} UTC",
            f"commit {commit()} · CPU {cpu_model()} · instruction set "
            f"{kernels.instruction_set()} · deterministic",
            f"command: `python benches/online_causal_filter.py --data {args.data}`",
            "",
            f"Boundary F1 (precision / recall) against offline SEG-2, ±100 ms, quick folds "
            f"({n_off} offline boundaries without noise), white noise on the joints and "
            "markers:",
            "",
            "| causal filter | no noise | 2 mm | 5 mm |",
            "|---|---|---|---|",
            *rows,
            "",
        ]
    )
    write_text(args.out, text)
    print(text)


def _recording(counts: dict[Any, list[int]]) -> Any:
    """A stand-in for ``compare_trial`` in ``bench_online.fidelity``: compares the
    candidates and returns an empty comparison (the bench's own table is not used)."""

    def run(model: PrimitiveModel, trial: Trial, classifier: Any = None, **_: Any) -> Any:
        compare(model, trial, counts)
        z = np.zeros((0, 2))
        e = np.zeros(0, dtype=np.int64)
        b = np.zeros(0, dtype=bool)
        return bench_online.TrialComparison(
            trial.name or "", z, e, z, e, np.zeros(0), b, b, "", "", (0, 0, 0), (0, 0)
        )

    return run


if __name__ == "__main__":
    main()

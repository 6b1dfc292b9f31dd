"""Streams at other rates than the model's: on the model's clock, or at their own times.

    PYTHONPATH=python python benches/online_rate.py [--data ../shared/data] [--quick]
        [--out benches/online_rate.result.md]

The replays of ``benches/bench_online.py`` (the same folds, models with
``seg2_boundary="first_stop"``; ``--quick``: its quick folds). Each held-out recording is
read again from its file at 60 Hz and at 120 Hz (:func:`visprim.io.read` with
``resample``), streamed through the online pipeline with ``clock="model"`` (resampled
causally onto the model's 34 ms, the default) and ``clock="stream"`` (its own frames), and
scored against the offline pipeline of the same model on the recording at 34 ms, as a
user's ``learn``/``report`` would run it: boundary F1 ±100 ms, primitive per segment, the
95th percentile of the latency (segments closed by the end of the stream left out) and,
on the model's clock, the final class against ``predict`` on the 34 ms recording (the
benchmarks' classifier; "—" for the other recordings, and on the stream's own frames,
which the classifier was not trained at).
The first row, the recording streamed at 34 ms, is the reference. Deterministic.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from _harness import commit, cpu_model
from visprim import kernels
from visprim.atomic import write_text
from visprim.model import PrimitiveModel
from visprim.online.compare import (
    TrialComparison,
    boundary_counts,
    compare_trial,
    equal_primitives,
)
from visprim.trial import Trial

sys.path.insert(0, str(Path(__file__).parent))
import bench_online  # noqa: E402
from online_gap import table_head, table_rows  # noqa: E402

RATES = (60.0, 120.0)
WAYS = ("34 ms (the model's period)",) + tuple(
    f"{r:g} Hz, clock {c!r}" for r in RATES for c in ("model", "stream")
)


def against(base: TrialComparison, other: TrialComparison, classed: bool) -> TrialComparison:
    """``other``'s online answers scored against ``base``'s offline ones (its class too
    when ``classed``)."""
    off, prim = base.offline_segments, base.offline_primitives
    on, on_prim = other.online_segments, other.online_primitives
    return dataclasses.replace(
        other,
        offline_segments=off,
        offline_primitives=prim,
        boundaries=boundary_counts(on, off),
        primitives=(equal_primitives(off, prim, on, on_prim), int(off.shape[0])),
        offline_class=base.offline_class if classed else "",
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("benches/online_rate.result.md"))
    args = ap.parse_args()
    bench_online.MODEL_PARAMS.update(seg2_boundary="first_stop")
    ways: dict[str, list[TrialComparison]] = {w: [] for w in WAYS}
    chunk = bench_online.FIDELITY_CHUNK

    def replay(model: PrimitiveModel, trial: Trial, classifier: Any = None, **kw: Any) -> Any:
        base = compare_trial(model, trial, classifier, chunk=chunk)
        ways[WAYS[0]].append(base)
        for rate in RATES:
            fast = bench_online.read(trial.source, "both", resample=1.0 / rate)
            for clock in ("model", "stream"):
                clf = classifier if clock == "model" else None
                other = compare_trial(model, fast, clf, chunk=chunk, clock=clock)
                ways[f"{rate:g} Hz, clock {clock!r}"].append(against(base, other, clf is not None))
        return base

    bench_online.compare_trial = replay  # type: ignore[assignment]
    started = datetime.now(UTC)
    table, _ = bench_online.fidelity(args.data, quick=args.quick)
    sizes = [int(v["trials"]) for k, v in table.items() if k != "all"]
    groups = [k for k in table if k != "all"]

    def cell(s: dict[str, float]) -> str:
        klass = "—" if s["class_equal"] != s["class_equal"] else f"{100 * s['class_equal']:.1f} %"
        return (
            f"{s['boundary_f1']:.3f} / {100 * s['primitive_equal']:.1f} % / "
            f"{1000 * s['latency_p95']:.0f} ms / {klass}"
        )

    rows = table_rows(ways, sizes, cell)
    text = "\n".join(
        [
            f"# online streams at other rates than the model's — {started:%Y-%m-%d %H:%M} UTC",
            f"commit {commit()} · CPU {cpu_model()} · instruction set "
            f"{kernels.instruction_set()} · deterministic",
            f"command: `python benches/online_rate.py --data {args.data}"
            f"{' --quick' if args.quick else ''}`",
            "",
            "Boundary F1 ±100 ms / primitive per segment equal / latency p95 / final class "
            "equal, against the offline pipeline of the same model on the recording at 34 ms "
            "(module docstring).",
            "",
            *table_head("stream", groups, sizes),
            *rows,
            "",
        ]
    )
    write_text(args.out, text)
    print(text)


if __name__ == "__main__":
    main()

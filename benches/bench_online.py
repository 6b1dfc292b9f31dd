"""The online engine against its targets, on the shared recordings (one command).

    PYTHONPATH=python python benches/bench_online.py [--data ../shared/data]
        [--out benches/bench_online.result.md] [--runs 3] [--hours 1] [--quick]
        [--option NAME=VALUE (segmenter)] [--model-option NAME=VALUE (PrimitiveModel)]

Measures, and writes a stamped table (date, commit, CPU, instruction set, load average) to
``--out`` (and the figures as JSON beside it):

1. **Fidelity**, every recording of ``--data``: each labelled benchmark of
   ``visprim evaluate`` (same groups) is split leave one group out; per fold a
   :class:`~visprim.model.PrimitiveModel` (defaults) and a
   :class:`~visprim.classify.MotionClassifier` (defaults, the fold's groups) are fitted on
   the training groups, and every held-out recording is replayed online
   (:func:`visprim.online.compare.compare_trial`) against the offline pipeline of the same
   model and the classifier's ``predict`` on the whole recording. The recordings no
   benchmark holds (unlabelled, or classes in one group only) are compared for segments with
   a model fitted on all the benchmarks' recordings. Boundaries ±100 ms F1, primitive per
   segment, final class.
2. **Latency**: stream time from each segment's end to its event, pooled over (1), apart
   for inner boundaries and a movement's last segment (under ``seg2_boundary="slowest"``
   the last closes after the rest timeout; under ``"first_stop"`` both at the stop).
3. **Throughput**, one stream on one core (wall time and the process's CPU time): the
   longest HDM05 recording looped to ``--stream`` seconds, pushed in chunks of 1, 8, 64 and
   1024 frames, no classifier and the open-end DTW recogniser (DTWClassifier);
   MotionClassifier (which classifies the whole movement so far at every closed segment)
   in chunks of 8 and 64 on a quarter of that stream; median and range of ``--runs`` runs.
4. **Memory**: the same recording looped to ``--hours`` of stream time (timestamps kept
   increasing), pushed in chunks of 8 frames with the open-end DTW recogniser; Python
   allocations (tracemalloc) and the process's RSS sampled every stream minute; growth
   after the first minute.

The machine may be shared: the load average at start and end is in the table.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
import tracemalloc
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from _harness import commit, cpu_model
from visprim import kernels
from visprim.atomic import write_text
from visprim.classify import DTWClassifier, MotionClassifier, group_folds
from visprim.evaluate import find_recordings, make_benchmarks, read_movements
from visprim.io import read
from visprim.model import PrimitiveModel
from visprim.online import Frames, OnlinePipeline
from visprim.online.compare import TrialComparison, compare_trial, summarise
from visprim.trial import Trial

PERIOD = 0.034
CHUNKS = (1, 8, 64, 1024)
#: Chunk of the fidelity replays (the events do not depend on it; tests/test_online.py).
FIDELITY_CHUNK = 32
#: PrimitiveModel parameters of every fitted model (``--model-option``).
MODEL_PARAMS: dict[str, Any] = {}


def _rss() -> int:
    """Resident set size of this process, bytes (Linux; 0 elsewhere)."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
    except (OSError, ValueError, IndexError):
        return 0
    return pages * os.sysconf("SC_PAGE_SIZE")


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------ fidelity


#: Video files are left to the video reader's own benchmark (benches/video_accuracy.py).
VIDEO = {".mp4", ".avi", ".mov", ".mkv", ".webm"}


def fidelity(data: Path, quick: bool, **options: Any) -> tuple[dict[str, Any], list[str]]:
    """Section 1 and 2 (module docstring): per benchmark, pooled figures; ``options`` go to
    the online segmenter."""
    recordings, unlabelled = find_recordings([data], None)
    movements, errors = read_movements(recordings, period=PERIOD, arm="both", jobs=1)
    notes = list(errors)
    kept = [(r, t) for r, t in zip(recordings, movements, strict=True) if t is not None]
    recordings = [r for r, _ in kept]
    movements = [t for _, t in kept]
    benches, more = make_benchmarks(recordings, movements)
    notes.extend(more)
    per: dict[str, list[TrialComparison]] = {}
    held: set[int] = set()
    for b in benches:
        ids = {id(t) for t in b.movements}
        held |= ids
        folds = list(group_folds(b.groups))
        if quick:
            folds = folds[:1]
        results: list[TrialComparison] = []
        for k, (group, train, test) in enumerate(folds):
            t0 = time.perf_counter()
            tr = [b.movements[i] for i in train]
            model = PrimitiveModel(**MODEL_PARAMS).fit(tr)
            clf = MotionClassifier(model_params=MODEL_PARAMS).fit(
                tr, b.labels[train], b.groups[train]
            )
            for i in test:
                results.append(
                    compare_trial(model, b.movements[i], clf, chunk=FIDELITY_CHUNK, **options)
                )
            _log(
                f"{b.name}: fold {k + 1}/{len(folds)} ({b.group_by} {group}, {len(test)} "
                f"held out) {time.perf_counter() - t0:.1f} s"
            )
        per[f"{b.name} (leave one {b.group_by} out)"] = results
    # Recordings no benchmark holds: segments only, with a model of all the benchmarks.
    rest = [t for t in movements if id(t) not in held]
    for path in unlabelled:
        if path.suffix.lower() in VIDEO:
            continue
        try:
            rest.append(read(path, "both", resample=PERIOD))
        except (ValueError, OSError) as exc:
            notes.append(f"{path.name}: left out ({str(exc).split(';')[0]})")
    if rest and benches:
        train_all = [t for b in benches for t in b.movements]
        model = PrimitiveModel(**MODEL_PARAMS).fit(train_all)
        if quick:
            rest = rest[:5]
        per["other recordings (segments only)"] = [
            compare_trial(model, t, None, chunk=FIDELITY_CHUNK, **options) for t in rest
        ]
        _log(f"other recordings: {len(rest)}")
    table = {name: summarise(res) for name, res in per.items()}
    table["all"] = summarise([r for res in per.values() for r in res])
    classed = [r for res in per.values() for r in res if r.offline_class]
    if classed:
        table["all"]["class_equal"] = float(
            np.mean([r.online_class == r.offline_class for r in classed])
        )
    return table, notes


# ------------------------------------------------------------------------------ streams


def _looped(trial: Trial, seconds: float) -> Trial:
    """``trial`` repeated back to back until ``seconds`` of stream time (times increasing)."""
    n = trial.n_frames
    reps = int(np.ceil(seconds / (n * PERIOD)))
    times = np.arange(reps * n) * PERIOD

    def rep(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.concatenate([a] * reps)

    return Trial(
        times=times,
        markers=rep(trial.markers),  # type: ignore[arg-type]
        joints=rep(trial.joints),
        body_frame=rep(trial.body_frame),
        arms=trial.arms,
        name=f"{trial.name} looped",
    )


def _part(trial: Trial, a: int, b: int) -> Frames:
    return Frames(
        trial.times[a:b],
        trial.markers[a:b],
        None if trial.joints is None else trial.joints[a:b],
        None if trial.body_frame is None else trial.body_frame[a:b],
    )


def _hdm05(data: Path) -> tuple[list[Trial], list[str], list[str]]:
    folder = data / "hdm05_cut_amc"
    files = sorted(folder.glob("*.amc"))[::2]
    trials = [read(f, "both", resample=PERIOD) for f in files]
    labels = [t.name.split("_")[2] for t in trials]
    subjects = [t.name.split("_")[1] for t in trials]
    return trials, labels, subjects


def throughput(
    data: Path, runs: int, stream_seconds: float
) -> tuple[list[dict[str, Any]], str, Trial, Any]:
    trials, labels, subjects = _hdm05(data)
    model = PrimitiveModel().fit(trials)
    classifiers: dict[str, Any] = {
        "none": None,
        "DTWClassifier (open-end DTW)": DTWClassifier().fit(trials, labels),
        "MotionClassifier": MotionClassifier().fit(trials, labels, subjects),
    }
    source = max(trials, key=lambda t: t.n_frames)
    rows = []
    for name, clf in classifiers.items():
        whole = isinstance(clf, MotionClassifier)
        stream = _looped(source, stream_seconds / 4 if whole else stream_seconds)
        for chunk in ((8, 64) if whole else CHUNKS) if runs else ():
            rates, cpu = [], []
            for _ in range(runs):
                pipe = OnlinePipeline(model, clf)
                t0, c0 = time.perf_counter(), time.process_time()
                for a in range(0, stream.n_frames, chunk):
                    pipe.push(_part(stream, a, min(stream.n_frames, a + chunk)))
                pipe.flush()
                rates.append(stream.n_frames / (time.perf_counter() - t0))
                cpu.append(stream.n_frames / (time.process_time() - c0))
            rows.append(
                {
                    "classifier": name,
                    "chunk": chunk,
                    "median": statistics.median(rates),
                    "min": min(rates),
                    "max": max(rates),
                    "cpu_median": statistics.median(cpu),
                    "cpu_min": min(cpu),
                    "cpu_max": max(cpu),
                    "runs": runs,
                    "frames": stream.n_frames,
                }
            )
            _log(f"throughput {name} chunk {chunk}: {statistics.median(rates):.0f} frames/s")
    return rows, f"{source.name} looped", source, (model, classifiers)


def memory(source: Trial, fitted: Any, hours: float) -> dict[str, Any]:
    model, classifiers = fitted
    stream = _looped(source, hours * 3600.0)
    pipe = OnlinePipeline(model, classifiers["DTWClassifier (open-end DTW)"])
    per_minute = int(round(60.0 / PERIOD))
    chunk = 8
    samples: list[tuple[float, int, int, int]] = []
    tracemalloc.start()
    next_sample = 0
    events = 0
    t0 = time.perf_counter()
    for a in range(0, stream.n_frames, chunk):
        events += len(pipe.push(_part(stream, a, min(stream.n_frames, a + chunk))))
        if a >= next_sample:
            samples.append(
                (a * PERIOD / 60.0, tracemalloc.get_traced_memory()[0], _rss(), pipe.buffer_bytes)
            )
            next_sample += per_minute
    events += len(pipe.flush())
    tracemalloc.stop()
    wall = time.perf_counter() - t0
    after = [s for s in samples if s[0] >= 1.0]
    first = after[0]
    return {
        "stream_minutes": stream.n_frames * PERIOD / 60.0,
        "frames": stream.n_frames,
        "events": events,
        "wall_seconds": wall,
        "samples": samples,
        "traced_at_1min": first[1],
        "traced_growth_after_1min": max(s[1] for s in after) - first[1],
        "traced_last_minus_1min": after[-1][1] - first[1],
        "rss_at_1min": first[2],
        "rss_growth_after_1min": max(s[2] for s in after) - first[2],
        "buffer_bytes": sorted({s[3] for s in after}),
    }


# ------------------------------------------------------------------------------ report


def _pct(v: float) -> str:
    return "—" if v != v else f"{100 * v:.1f} %"


def _ms(v: float) -> str:
    return "—" if v != v else f"{1000 * v:.0f} ms"


def report(stamp: dict[str, Any], fid: dict[str, Any], notes: list[str], thr: Any, mem: Any) -> str:
    lines = [
        f"# online engine — {stamp['date']}",
        f"commit {stamp['commit']} · CPU {stamp['cpu']} · {stamp['cores']} cores · "
        f"instruction set {stamp['instruction_set']} · Python {stamp['python']}",
        f"load average at start {stamp['load_start']}, at the end {stamp['load_end']} "
        "(1/5/15 min). The machine was shared with other jobs: throughput is a lower bound.",
        f"command: `{stamp['command']}` · segmenter options: {stamp['options']}",
        "",
    ]
    if fid:
        lines += _fidelity_lines(fid, notes)
    src, rows = thr
    if rows:
        lines += _throughput_lines(src, rows)
    if mem is not None:
        lines += _memory_lines(mem)
    return "\n".join(lines) + "\n"


def _fidelity_lines(fid: dict[str, Any], notes: list[str]) -> list[str]:
    lines = [
        "## fidelity: online vs offline (same model), ±100 ms",
        "",
        "| recordings | trials | boundary F1 (P / R) | primitive equal | final class equal | "
        "latency p50 / p95 (all) | inner p50 / p95 | last p50 / p95 |",
        "|---|---:|---|---:|---:|---|---|---|",
    ]
    for name, s in fid.items():
        lines.append(
            f"| {name} | {s['trials']:.0f} | {s['boundary_f1']:.3f} "
            f"({s['boundary_precision']:.3f} / {s['boundary_recall']:.3f}) | "
            f"{_pct(s['primitive_equal'])} of {s['offline_segments']:.0f} | "
            f"{_pct(s['class_equal'])} | {_ms(s['latency_median'])} / {_ms(s['latency_p95'])} "
            f"({s['latency_segments']:.0f}) | {_ms(s['latency_inner_median'])} / "
            f"{_ms(s['latency_inner_p95'])} ({s['latency_inner_segments']:.0f}) | "
            f"{_ms(s['latency_last_median'])} / {_ms(s['latency_last_p95'])} "
            f"({s['latency_last_segments']:.0f}) |"
        )
    lines += [
        "",
        "Targets: F1 ≥ 0.90, primitive ≥ 90 %, final class ≥ 97 %, latency p95 ≤ 150 ms. "
        "Latency: stream time from a segment's end to its event (the causal filter's delay "
        "included); segments closed by the end of the recording are left out. 'inner': "
        "followed by another stroke of the movement; 'last': a movement's last segment. "
        "Under seg2_boundary='first_stop' (the default) both close at the stroke's first "
        "stop; under 'slowest' an inner one closes when the next stroke starts and a last "
        "one after the rest timeout.",
        "",
    ]
    lines += [f"- {n}" for n in notes]
    return lines + [""]


def _throughput_lines(src: str, rows: list[dict[str, Any]]) -> list[str]:
    lines = [
        f"## throughput, one stream, one core ({src})",
        "",
        "| classifier | chunk (frames) | stream (frames) | frames/s median | range | "
        "frames per CPU-second median | range | runs |",
        "|---|---:|---:|---:|---|---:|---|---:|",
    ]
    for r in rows:
        cpu = (
            f"{r['cpu_median']:,.0f} | {r['cpu_min']:,.0f}–{r['cpu_max']:,.0f}"
            if "cpu_median" in r
            else "— | —"
        )
        lines.append(
            f"| {r['classifier']} | {r['chunk']} | {r['frames']:,} | {r['median']:,.0f} | "
            f"{r['min']:,.0f}–{r['max']:,.0f} | {cpu} | {r['runs']} |"
        )
    return lines + [
        "",
        "Target: ≥ 10,000 frames/s. Frames per CPU-second: the stream's frames over the "
        "process's CPU time (time.process_time), less sensitive than wall time to other jobs "
        "on a shared machine (they still share its caches and memory bandwidth).",
        "",
    ]


def _memory_lines(mem: Any) -> list[str]:
    return [
        f"## memory over {mem['stream_minutes']:.0f} minutes of stream "
        f"({mem['frames']:,} frames, chunks of 8, open-end DTW recogniser, "
        f"{mem['events']:,} events, {mem['wall_seconds']:.0f} s wall)",
        "",
        "| measure | at 1 min | largest growth after 1 min | last − 1 min |",
        "|---|---:|---:|---:|",
        f"| Python allocations (tracemalloc) | {mem['traced_at_1min'] / 1e6:.2f} MB | "
        f"{mem['traced_growth_after_1min'] / 1e3:+.1f} kB | "
        f"{mem['traced_last_minus_1min'] / 1e3:+.1f} kB |",
        f"| process RSS | {mem['rss_at_1min'] / 1e6:.1f} MB | "
        f"{mem['rss_growth_after_1min'] / 1e6:+.2f} MB | |",
        f"| pipeline buffers (`buffer_bytes`) | {mem['buffer_bytes']} | | |",
        "",
        "Target: flat (no growth past the first minute).",
        "",
    ]


def _name_values(items: list[str]) -> dict[str, Any]:
    """``NAME=VALUE`` items as a dict (values read as JSON when they are, else strings)."""
    out: dict[str, Any] = {}
    for item in items:
        name, _, value = item.partition("=")
        try:
            out[name] = json.loads(value)
        except json.JSONDecodeError:
            out[name] = value
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--out", type=Path, default=Path("benches/bench_online.result.md"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--stream", type=float, default=120.0, help="seconds of stream (throughput)")
    ap.add_argument("--hours", type=float, default=1.0, help="hours of stream (memory)")
    ap.add_argument("--quick", action="store_true", help="one fold per benchmark, no memory run")
    ap.add_argument(
        "--skip", default="", help="comma list of sections to skip: fidelity,throughput,memory"
    )
    ap.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="an OnlineSegmenter option for the fidelity replays (e.g. filter_order=4, "
        "threshold=fixed, segment_filter=causal); repeatable",
    )
    ap.add_argument(
        "--model-option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a PrimitiveModel parameter of the fitted models and of the classifiers' models "
        "(e.g. seg2_boundary=first_stop); repeatable",
    )
    args = ap.parse_args(argv)
    options = _name_values(args.option)
    MODEL_PARAMS.update(_name_values(args.model_option))
    if not args.data.is_dir():
        print(f"bench_online: {args.data}: no such folder (the shared recordings)", file=sys.stderr)
        return 2
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    load0 = os.getloadavg()
    stamp = {
        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit(),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "instruction_set": kernels.instruction_set(),
        "python": sys.version.split()[0],
        "load_start": " / ".join(f"{v:.1f}" for v in load0),
        "command": "python benches/bench_online.py " + " ".join(argv or sys.argv[1:]),
        "options": ", ".join(args.option + args.model_option) or "defaults",
    }
    fid, notes = ({}, []) if "fidelity" in skip else fidelity(args.data, args.quick, **options)
    thr_rows: list[dict[str, Any]] = []
    src = ""
    mem = None
    if not {"throughput", "memory"} <= skip:
        runs = args.runs if "throughput" not in skip else 0
        thr_rows, src, source, fitted = throughput(args.data, runs, args.stream)
        if "throughput" in skip:
            thr_rows = []
        if not args.quick and "memory" not in skip:
            mem = memory(source, fitted, args.hours)
    stamp["load_end"] = " / ".join(f"{v:.1f}" for v in os.getloadavg())
    text = report(stamp, fid, notes, (src, thr_rows), mem)
    print(text)
    write_text(args.out, text)
    blob = {"stamp": stamp, "fidelity": fid, "notes": notes, "throughput": thr_rows, "memory": mem}
    write_text(args.out.with_suffix(".json"), json.dumps(blob, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""``visprim watch --adonis`` keeping up: the online pipeline and Adonis live on HDM05.

A model (8 components, 8 primitives) is fitted on six HDM05 recordings of subjects bd and
bk; every HDM05 recording of subject mm in ../shared/data/hdm05_cut_amc (at most ``--n``)
is then streamed as ``visprim watch --fast --adonis`` streams it: one frame per push
(:class:`visprim.online.sources.RecordingSource`), each closed segment rebuilt and played
on Adonis (:class:`visprim.online.adonis.LiveAdonis`, stable PD at 2 ms), the simulation
stepped to the stream's time after every frame, and drained at the end.

Figures per recording, then the median and [min, max] over recordings, each the median of
``--repeat`` runs:

* pipeline: wall time of ``OnlinePipeline.push`` per frame (µs) — the stream's own cost;
* Adonis: simulated seconds per second of stepping wall time (real-time factor: above 1
  keeps up with a live stream), and µs per simulation step;
* delay: seconds from a segment's start in the stream to Adonis starting to play it
  (median per recording), which the segment's own length and the pipeline's latency set.

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_watch.py [--n 20] [--repeat 3]``.
The machine may be shared: the load average is printed beside the figures.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from _harness import commit, cpu_model
from visprim import kernels
from visprim.io import read
from visprim.model import PrimitiveModel
from visprim.online import OnlinePipeline, SegmentClosed
from visprim.online.adonis import LiveAdonis
from visprim.online.sources import RecordingSource
from visprim.trial import Trial

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "hdm05_cut_amc"
TRAIN = [
    "HDM_bd_depositFloorR_001_120.amc",
    "HDM_bd_grabHighR_001_120.amc",
    "HDM_bd_throwBasketball_001_120.amc",
    "HDM_bk_depositFloorR_007_120.amc",
    "HDM_bk_grabHighR_005_120.amc",
    "HDM_bk_throwBasketball_004_120.amc",
]


def one_run(model: PrimitiveModel, trial: Trial) -> dict[str, float]:
    pipe = OnlinePipeline(model)
    adonis = LiveAdonis(model)
    push_s = 0.0
    for chunk in RecordingSource(trial, fast=True):
        adonis.observe(chunk)
        t0 = time.perf_counter()
        events = pipe.push(chunk)
        push_s += time.perf_counter() - t0
        for ev in events:
            if isinstance(ev, SegmentClosed):
                adonis.add(ev)
        adonis.advance(float(chunk.times[-1]))
    for ev in pipe.flush():
        if isinstance(ev, SegmentClosed):
            adonis.add(ev)
    adonis.drain()
    rep = adonis.report()
    return {
        "push_us": 1e6 * push_s / trial.n_frames,
        "rtf": rep.real_time_factor,
        "step_us": 1e6 * rep.wall / max(rep.steps, 1),
        "delay": rep.delay_median,
        "segments": float(rep.segments),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="recordings streamed (default 20)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per recording (default 3)")
    args = ap.parse_args()
    model = PrimitiveModel(n_components=8, n_clusters=8, n_init=2).fit(
        [read(DATA / n, "both", resample=0.034) for n in TRAIN]
    )
    files = sorted(DATA.glob("HDM_mm_*.amc"))[: args.n]
    load0 = os.getloadavg()
    rows = []
    for f in files:
        trial = read(f, "both", resample=0.034)
        runs = [one_run(model, trial) for _ in range(args.repeat)]
        row = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
        row["frames"] = trial.n_frames
        rows.append(row)
        print(
            f"{f.name:<40} {trial.n_frames:4d} frames  push {row['push_us']:7.1f} us/frame  "
            f"Adonis {row['rtf']:6.1f}x real time ({row['step_us']:5.1f} us/step)  "
            f"delay {row['delay']:.2f} s",
            flush=True,
        )
    load1 = os.getloadavg()

    def fig(key: str, fmt: str) -> str:
        v = np.array([r[key] for r in rows if np.isfinite(r[key])])
        return f"{fmt.format(np.median(v))} [{fmt.format(v.min())}, {fmt.format(v.max())}]"

    print()
    print(
        f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, commit {commit()}, {cpu_model()}, "
        f"kernels {kernels.instruction_set()}, load average {load0[0]:.1f} -> {load1[0]:.1f} "
        f"(shared machine); {len(rows)} recordings, median of {args.repeat} runs each"
    )
    print("| measure | median [min, max] over recordings |")
    print("|---|---|")
    print(f"| pipeline push, us per frame | {fig('push_us', '{:.0f}')} |")
    print(f"| Adonis real-time factor (simulated s / stepping s) | {fig('rtf', '{:.0f}')} |")
    print(f"| Adonis stepping, us per 2 ms step | {fig('step_us', '{:.1f}')} |")
    print(f"| segment start to Adonis playing it, s | {fig('delay', '{:.2f}')} |")
    kept = sum(r["rtf"] > 1.0 for r in rows)
    print(f"\nAdonis kept up (real-time factor > 1) on {kept} of {len(rows)} recordings")


if __name__ == "__main__":
    main()

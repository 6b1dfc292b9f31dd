"""Stable PD vs the paper's servo on the same movements: error, completion, stability.

Movements: ``--n`` (default 3) chains of minimum-jerk right-arm strokes between seeded random
postures (0.4-1.2 s each, ``--seconds`` long). Both servos use the default gains
(:data:`visprim.sim.servo.GAINS`), via points every 0.1 s and a 3° vicinity:

* ``stable``: stable PD following the smooth trajectory, waiting on unreached via points,
  with (default) and without the inverse dynamics of the trajectory as feedforward;
* ``paper``: eq. (1) evaluated explicitly, aimed at one via point at a time, the next taken
  when every joint is within the vicinity (the paper's switching).

Figures per servo and step (median over the movements, [min, max] beside it):

* error: RMS over every simulation step of the right shoulder's geodesic angle and the
  elbow's difference between Adonis and the trajectory *at the same clock* (the trajectory's
  end pose after its end), degrees — a servo that runs ahead or falls behind pays for it;
* completion: time the last via point was reached / the movement's duration;
* stable: the simulation does not diverge (NaN or joint speeds above 1000 rad/s); whether
  every via point was reached is reported beside it.

Stability is probed on a grid of steps from 50 µs to 20 ms, walked upwards until the first
step at which a movement diverges; the error and via points reached are shown at each step.

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_servo.py [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_sim import stroke_chain  # noqa: E402
from visprim.sim import SimulationDiverged, build_adonis, play  # noqa: E402
from visprim.sim.playback import joint_errors  # noqa: E402
from visprim.sim.sequencer import ELBOW_JOINT, SHOULDER_JOINT, build_reference  # noqa: E402

GRID = (5e-5, 1e-4, 1.5e-4, 2e-4, 3e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2)


def run_one(times, angles, servo: str, dt: float, feedforward: bool = True) -> dict | None:
    """Metrics of one playback, or None if it diverged."""
    world, skel = build_adonis(dt)
    try:
        t0 = time.perf_counter()
        pb = play(
            times,
            angles,
            servo=servo,
            dt=dt,
            model=(world, skel),
            render_fps=5.0,
            feedforward=feedforward,
        )
        wall = time.perf_counter() - t0
    except SimulationDiverged:
        return None
    ref = build_reference(skel, times, angles, dt)
    k = np.minimum(np.arange(pb.q_actual.shape[0]), ref.positions.shape[0] - 1)
    err = joint_errors(skel, ref.positions[k], pb.q_actual)
    names = list(pb.joint_names)
    arm = err[:, [names.index(SHOULDER_JOINT), names.index(ELBOW_JOINT)]]
    return {
        "rms_deg": math.degrees(float(np.sqrt(np.mean(arm**2)))),
        "ratio": pb.time_ratio,
        "reached": pb.reached_all,
        "realtime": pb.movement_duration / wall,
    }


def _ms(x: float | None) -> str:
    return "-" if x is None else f"{x * 1e3:g} ms"


def spread(values: list[float]) -> str:
    return f"{statistics.median(values):.2f} [{min(values):.2f}, {max(values):.2f}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=3, help="movements (default 3)")
    ap.add_argument("--seconds", type=float, default=4.0, help="length of each, s (default 4)")
    ap.add_argument("--quick", action="store_true", help="2 movements of 2 s")
    args = ap.parse_args()
    n, seconds = (2, 2.0) if args.quick else (args.n, args.seconds)
    moves = [stroke_chain(seconds, seed=s) for s in range(n)]
    print(f"{n} movements of {seconds:.1f} s (minimum-jerk strokes, seeds 0..{n - 1})\n")

    rows = []
    variants = (
        ("stable", 1e-3, True),
        ("stable", 1e-3, False),
        ("paper", 1e-3, False),
        ("paper", 1e-4, False),
    )
    for servo, dt, ff in variants:
        res = [run_one(t, a, servo, dt, ff) for t, a in moves]
        ok = [r for r in res if r is not None]
        label = f"{servo} PD" + (" + inverse-dynamics feedforward" if ff else "")
        if len(ok) < len(res):
            rows.append((label, dt, "diverged", "-", "-", "-"))
            continue
        rows.append(
            (
                label,
                dt,
                spread([r["rms_deg"] for r in ok]),
                spread([r["ratio"] for r in ok]),
                f"{sum(r['reached'] for r in ok)}/{len(ok)}",
                spread([r["realtime"] for r in ok]),
            )
        )
    print("| servo | step | error vs trajectory, deg RMS | completion / duration | "
          "all via points | real-time factor |")  # fmt: skip
    print("|---|---:|---|---|---|---|")
    for servo, dt, e, r, v, rt in rows:
        print(f"| {servo} | {dt * 1e3:g} ms | {e} | {r} | {v} | {rt} |")

    print("\nStep sweep: error vs trajectory, deg RMS (median [min, max]) and via points reached;")
    print("each servo's sweep stops at its first diverging step.")
    print("| step | stable | paper |")
    print("|---:|---|---|")
    largest: dict[str, float | None] = {"stable": None, "paper": None}
    cells: dict[tuple[str, float], str] = {}
    for servo in ("stable", "paper"):
        for dt in GRID:
            if servo == "stable" and dt < 1e-4:
                continue  # 1 ms is stable already; smaller steps only cost time
            res = [run_one(t, a, servo, dt) for t, a in moves]
            if any(r is None for r in res):
                cells[(servo, dt)] = "diverged"
                break
            ok = [r for r in res if r is not None]
            via = sum(r["reached"] for r in ok)
            cells[(servo, dt)] = f"{spread([r['rms_deg'] for r in ok])}, via {via}/{len(ok)}"
            largest[servo] = dt
    for dt in GRID:
        row = [cells.get((servo, dt), "") for servo in ("stable", "paper")]
        if any(row):
            print(f"| {dt * 1e3:g} ms | {row[0]} | {row[1]} |")
    for servo, dt in largest.items():
        print(f"largest step without divergence, {servo}: {_ms(dt)}")


if __name__ == "__main__":
    main()

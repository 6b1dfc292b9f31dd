"""Imitation of real recordings through primitives, and the speed of playback and rendering.

Model (leave one subject out): ``visprim learn`` with its defaults and ``--clusters 30`` on
the HDM05 recordings of ``../shared/data/hdm05_cut_amc`` of subjects bd, bk and dg (the
command is printed); subject mm is held out. The model is written to ``--model`` (default
/tmp/visprim_bench_imitate.npz) so that the same figures can be reproduced with
``visprim imitate``.

Recordings imitated (three kinds): an HDM05 .amc of the held-out subject, a Bandai-Namco
.bvh and a C3D marker recording. For each, the primitive rebuild and, as the simple
baseline beside it, the near-copy from each segment's own projection (``--source
projection``), both played on Adonis with the stable PD at 1 ms.

Speed (median of repeated runs, [min, max] beside it): ``play`` of each rebuild without
rendering as a real-time factor (movement seconds / wall seconds; dt = 1 ms, and 2 ms for
the last recording), each run followed by bare ``World.step()`` of the same model over the
same number of steps (arms swinging) as the reference, and the ratio of the two per run (the
machine may be shared: the ratio is what carries over); drawing one Adonis frame and one
side-by-side video frame (480×480 panels), ms per frame, beside the matplotlib renderer
visprim used before (``benches/_render_matplotlib.py``) in the same run.

Run: ``PYTHONPATH=python .venv/bin/python benches/bench_imitate.py [--quick]`` (the shared
data from ``../shared/data``, or ``VISPRIM_SHARED_DATA``, or ``--data``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
REPO = Path(__file__).resolve().parents[1]
# ../shared/data beside the repository; VISPRIM_SHARED_DATA overrides it (git worktrees).
DATA = Path(os.environ.get("VISPRIM_SHARED_DATA", REPO.parent / "shared" / "data"))
TRAIN_SUBJECTS = ("bd", "bk", "dg")
RECORDINGS = (
    "hdm05_cut_amc/HDM_mm_throwBasketball_010_120.amc",
    "bandai_namco_ds2/dataset-2_raise-up-right-hand_elderly_001.bvh",
    "kineticstoolkit_c3d/kinematics_tennis_serve.c3d",
)


def spread(values: list[float], fmt: str = "{:.2f}") -> str:
    return f"{fmt.format(statistics.median(values))} [{fmt.format(min(values))}, " + (
        f"{fmt.format(max(values))}]"
    )


def bare_factor(adonis: tuple, start: np.ndarray, n_steps: int, dt: float) -> float:
    """Real-time factor of ``n_steps`` bare ``World.step()`` calls of ``adonis`` (the servo's
    joint damping as ``play`` left it) from ``start`` with the arms swinging at 2 rad/s."""
    world, skel = adonis
    world.reset()
    skel.resetCommands()
    skel.setPositions(start)
    swing = np.zeros(skel.getNumDofs())
    swing[6:10] = 2.0
    skel.setVelocities(swing)
    t0 = time.perf_counter()
    for _ in range(n_steps):
        world.step()
    return n_steps * dt / (time.perf_counter() - t0)


def learn(data: Path, out: Path) -> object:
    """``visprim learn`` on the training subjects' HDM05 files (the command line itself)."""
    from visprim import PrimitiveModel
    from visprim.cli.main import main as cli

    globs = [str(data / "hdm05_cut_amc" / f"HDM_{s}_*.amc") for s in TRAIN_SUBJECTS]
    argv = ["learn", *globs, "--out", str(out), "--clusters", "30"]
    print("visprim " + " ".join(argv), flush=True)
    if cli(argv) != 0:
        sys.exit("bench_imitate: visprim learn failed")
    return PrimitiveModel.load(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="shared data folder")
    ap.add_argument("--model", type=Path, default=Path("/tmp/visprim_bench_imitate.npz"))
    ap.add_argument("--reuse", action="store_true", help="reuse --model if it exists")
    ap.add_argument("--quick", action="store_true", help="fewer timing runs")
    args = ap.parse_args()
    if not args.data.is_dir():
        sys.exit(f"bench_imitate: shared data not found at {args.data}")
    from visprim import PrimitiveModel
    from visprim.imitate import imitate
    from visprim.io import read
    from visprim.sim import build_adonis, play
    from visprim.sim.render import Camera, PlaybackDrawer
    from visprim.sim.sidebyside import SideBySide

    model = (
        PrimitiveModel.load(args.model)
        if args.reuse and args.model.is_file()
        else learn(args.data, args.model)
    )
    repeat = 3 if args.quick else 5

    rows, speed, results = [], [], []
    for rel in RECORDINGS:
        trial = read(args.data / rel)
        for source in ("primitives", "projection"):
            res = imitate(model, trial, source=source)
            m, a = res.metrics, res.metrics["adonis"]
            rb, ad = m["rebuild_vs_human_joint_rms_deg"], a["vs_human_joint_rms_deg"]
            rows.append(
                (
                    Path(rel).name,
                    source,
                    m["n_segments"],
                    m["rebuild_vs_human_rms_deg"],
                    rb["overall"],
                    ad["overall"],
                    a["vs_rebuild_joint_rms_deg"]["overall"],
                    a["time_ratio"],
                    m["coverage"],
                    " ".join(map(str, m["primitive_sequence"])),
                )
            )
            if source == "primitives":
                results.append(res)

    print("\n| recording | rebuild | segments | rebuild vs human, deg RMS (γ β α elbow; all) "
          "| joint space: rebuild vs human | Adonis vs human | difference | Adonis vs rebuild "
          "| completion / human | uncovered |")  # fmt: skip
    print("|---|---|---:|---|---:|---:|---:|---:|---:|---|")
    for name, src, n, per, rb, ad, avr, ratio, cov, _ in rows:
        angles = " ".join(f"{per[k]:.1f}" for k in ("gamma", "beta", "alpha", "elbow"))
        print(
            f"| {name} | {src} | {n} | {angles}; {per['overall']:.1f} | {rb:.2f} | {ad:.2f} | "
            f"{ad - rb:+.2f} | {avr:.2f} | {ratio:.2f}x | {cov['uncovered_s']:.2f} s "
            f"({cov['uncovered_percent']:.1f} %) |"
        )
    print("\nPrimitive sequences:")
    for name, src, *_, seq in rows:
        if src == "primitives":
            print(f"  {name}: {seq}")

    # ---------------------------------------------------------------- speed
    # Each repeat times ``play`` of every rebuild and, right after it, bare World.step() of
    # the same model over the same number of steps with the arm swinging (no Python per
    # step beyond the call), so that the ratio of the two is measured under the same load.
    for res in results:
        grid = np.linspace(res.rebuild.start, res.rebuild.end, res.times.shape[0] * 7)
        angles, _ = res.rebuild(grid)
        for dt in (0.001, 0.002) if res is results[-1] else (0.001,):
            adonis = build_adonis(dt)
            factors, bare, errors = [], [], []
            for _ in range(repeat):
                t0 = time.perf_counter()
                pb = play(grid, angles, model=adonis, dt=dt)
                factors.append(pb.movement_duration / (time.perf_counter() - t0))
                bare.append(bare_factor(adonis, pb.q_actual[0], pb.times.shape[0], dt))
                errors.append(pb.rms_error_deg)
            speed.append((res.name, dt, pb.movement_duration, factors, bare, errors[-1]))
    print(
        "\n| playback (stable PD, no rendering) | dt | movement | real-time factor "
        "| bare World.step, same steps | playback / bare | tracking RMS vs set point |"
    )
    print("|---|---:|---:|---|---|---|---:|")
    for name, dt, dur, factors, bare, err in speed:
        ratios = [f / b for f, b in zip(factors, bare, strict=True)]
        print(
            f"| {name} | {dt * 1e3:g} ms | {dur:.2f} s | {spread(factors, '{:.1f}')}x | "
            f"{spread(bare, '{:.1f}')}x | {spread(ratios)} | {err:.3f}° |"
        )

    from _render_matplotlib import Camera as MplCamera
    from _render_matplotlib import _frame_drawer, _to_image

    res = results[0]
    drawer = PlaybackDrawer(res.playback, Camera(), (480, 480), "bench")
    view = SideBySide(res, (480, 480))
    fig, mpl_draw = _frame_drawer(res.playback, MplCamera(), (480, 480), 100.0, "bench")
    single, double, mpl = [], [], []
    n_frames = res.playback.frames.shape[0]
    for _ in range(repeat):
        t0 = time.perf_counter()
        for i in range(n_frames):
            drawer.draw(i)
        single.append((time.perf_counter() - t0) / n_frames * 1e3)
        t0 = time.perf_counter()
        for i in range(view.n_frames):
            view.frame(i)
        double.append((time.perf_counter() - t0) / view.n_frames * 1e3)
        t0 = time.perf_counter()
        for i in range(n_frames):
            mpl_draw(i)
            _to_image(fig)
        mpl.append((time.perf_counter() - t0) / n_frames * 1e3)
    print(f"\n| rendering ({res.name}) | frames | ms per frame |")
    print("|---|---:|---|")
    print(f"| Adonis panel 480x480, PIL (visprim.sim.render) | {n_frames} | {spread(single)} |")
    print(f"| side-by-side frame 960x480, PIL | {view.n_frames} | {spread(double)} |")
    print(f"| reference: Adonis panel 480x480, matplotlib Agg | {n_frames} | {spread(mpl)} |")
    ratios = [m / s for m, s in zip(mpl, single, strict=True)]
    print(f"matplotlib / PIL per Adonis frame: {spread(ratios)}x")


if __name__ == "__main__":
    main()

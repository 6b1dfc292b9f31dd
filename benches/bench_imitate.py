"""Imitation of real recordings through primitives, and the speed of playback and rendering.

Models, each ``visprim learn`` with its defaults and ``--clusters 30`` (the commands are
printed), on recordings other than those imitated:

* ``hdm05`` (leave one subject out): the HDM05 recordings of ``hdm05_cut_amc`` of subjects
  bd, bk and dg; subject mm is held out. Written to ``--model`` (default
  /tmp/visprim_bench_imitate.npz) so that the figures can be reproduced with
  ``visprim imitate``.
* ``bandai`` (leave one action out): the files of ``bandai_namco_ds2`` of the other actions
  (raise both hands, wave one or both hands), for the Bandai clip of raising the right hand
  (written beside ``--model`` with the suffix ``_bandai``); and ``bandai-each``, the same
  files learned with ``--arm each`` (one-arm primitives from both arms), which imitates both
  arms of the clip, each through the same primitives (suffix ``_bandai_each``).

Recordings imitated (three kinds): an HDM05 .amc of the held-out subject, a Bandai-Namco
.bvh (with both models) and a C3D marker recording. For each, the primitive rebuild and, as
the upper bound beside it, the near-copy from each segment's own projection (``--source
projection``), both played on Adonis with the stable PD at 1 ms; and as the simple
baseline, the human's mean posture held still. Errors against the human are given in joint
space and as the RMS angle between bone directions (what is seen of the arm).

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
#: The Bandai clip imitated, and the action whose files the within-dataset model leaves out.
BANDAI = "bandai_namco_ds2/dataset-2_raise-up-right-hand_elderly_001.bvh"
BANDAI_ACTION = "raise-up-right-hand"
#: (recording, model) pairs: "hdm05" (three HDM05 actors), "bandai" (the Bandai folder's
#: other actions) or "bandai-each" (the same files, one-arm primitives learned from both arms
#: with ``--arm each``; it imitates both arms of the recording).
RECORDINGS = (
    ("hdm05_cut_amc/HDM_mm_throwBasketball_010_120.amc", "hdm05"),
    (BANDAI, "hdm05"),
    (BANDAI, "bandai"),
    (BANDAI, "bandai-each"),
    ("kineticstoolkit_c3d/kinematics_tennis_serve.c3d", "hdm05"),
)
MODELS = ("hdm05", "bandai", "bandai-each")


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


def still_rms(res: object) -> tuple[float, float]:
    """The simple baseline: joint-space and bone-direction RMS (deg) against the human of
    the human's mean posture (mean of each angle over the covered frames) held still."""
    from visprim.features import direction_rms_deg
    from visprim.imitate import joint_space_errors

    human = res.human[res.covered]  # type: ignore[attr-defined]
    still = np.broadcast_to(human.mean(axis=0), human.shape)
    shoulder, elbow = joint_space_errors(still, human)
    joint = float(np.degrees(np.sqrt(np.mean(np.square(np.concatenate([shoulder, elbow]))))))
    return joint, direction_rms_deg(still, human)


def training_files(data: Path, which: str) -> list[str]:
    """The files (or patterns) ``visprim learn`` is given for model ``which``."""
    if which == "hdm05":
        return [str(data / "hdm05_cut_amc" / f"HDM_{s}_*.amc") for s in TRAIN_SUBJECTS]
    folder = data / Path(BANDAI).parent
    return [str(p) for p in sorted(folder.glob("*.bvh")) if BANDAI_ACTION not in p.name]


def learn(data: Path, out: Path, which: str) -> object:
    """``visprim learn ... --clusters 30`` on the training files of ``which`` (the command
    line itself, printed)."""
    from visprim import PrimitiveModel
    from visprim.cli.main import main as cli

    argv = ["learn", *training_files(data, which), "--out", str(out), "--clusters", "30"]
    argv += ["--force", *(["--arm", "each"] if which == "bandai-each" else [])]
    print("visprim " + " ".join(argv), flush=True)
    if cli(argv) != 0:
        sys.exit("bench_imitate: visprim learn failed")
    return PrimitiveModel.load(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="shared data folder")
    ap.add_argument("--model", type=Path, default=Path("/tmp/visprim_bench_imitate.npz"))
    ap.add_argument("--reuse", action="store_true", help="reuse the models if they exist")
    ap.add_argument("--quick", action="store_true", help="fewer timing runs")
    ap.add_argument("--no-speed", action="store_true", help="the imitation table only")
    args = ap.parse_args()
    if not args.data.is_dir():
        sys.exit(f"bench_imitate: shared data not found at {args.data}")
    from visprim import PrimitiveModel
    from visprim.imitate import imitate
    from visprim.io import read
    from visprim.sim import build_adonis, play
    from visprim.sim.render import Camera, PlaybackDrawer
    from visprim.sim.sidebyside import SideBySide

    models = {}
    for which in MODELS:
        suffix = "" if which == "hdm05" else "_" + which.replace("-", "_")
        path = args.model.with_stem(args.model.stem + suffix)
        models[which] = (
            PrimitiveModel.load(path)
            if args.reuse and path.is_file()
            else learn(args.data, path, which)
        )
    repeat = 3 if args.quick else 5

    rows, speed, results = [], [], []
    for rel, which in RECORDINGS:
        trial = read(args.data / rel, "both" if which == "bandai-each" else "right")
        for source in ("primitives", "projection"):
            res = imitate(models[which], trial, source=source)
            m, a = res.metrics, res.metrics["adonis"]
            rb, ad = m["rebuild_vs_human_joint_rms_deg"], a["vs_human_joint_rms_deg"]
            rows.append(
                (
                    Path(rel).name,
                    which,
                    source,
                    m["n_segments"],
                    m["rebuild_vs_human_rms_deg"],
                    rb["overall"],
                    ad["overall"],
                    a["vs_rebuild_joint_rms_deg"]["overall"],
                    (a["completion_time_s"], m["covered_span_s"], a["time_ratio"]),
                    m["coverage"],
                    " ".join(map(str, m["primitive_sequence"])),
                    still_rms(res),
                    (m["rebuild_vs_human_direction_rms_deg"], a["vs_human_direction_rms_deg"]),
                )
            )
            if source == "primitives" and which == "hdm05":
                results.append(res)

    print("\n| recording | model | rebuild | segments "
          "| rebuild vs human, deg RMS (γ β α elbow per arm; all) "
          "| joint space: rebuild vs human | Adonis vs human | difference | Adonis vs rebuild "
          "| completion: Adonis / human (ratio) | uncovered "
          "| baseline: mean posture held "
          "| bone directions: rebuild vs human | Adonis vs human | baseline |")  # fmt: skip
    print("|---|---|---|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|")
    for row in rows:
        name, which, src, n, per, rb, ad, avr, (done, span, ratio), cov, _, still, bones = row
        angles = " ".join(f"{v:.1f}" for k, v in per.items() if k != "overall")
        print(
            f"| {name} | {which} | {src} | {n} | {angles}; {per['overall']:.1f} | {rb:.2f} | "
            f"{ad:.2f} | {ad - rb:+.2f} | {avr:.2f} | {done:.2f} s / {span:.2f} s "
            f"({ratio:.2f}x) | {cov['uncovered_s']:.2f} s ({cov['uncovered_percent']:.1f} %) | "
            f"{still[0]:.2f} | {bones[0]:.2f} | {bones[1]:.2f} | {still[1]:.2f} |"
        )
    print("\nPrimitive sequences:")
    for name, which, src, *_, seq, _, _ in rows:
        if src == "primitives":
            print(f"  {name} ({which} model): {seq}")

    if args.no_speed:
        return
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

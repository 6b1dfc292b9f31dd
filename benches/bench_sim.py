"""Adonis in DART: real-time factor of the controlled simulation (target: >= 20x).

Workload: a deterministic chain of minimum-jerk right-arm strokes (seeded random postures,
0.4-1.2 s each, 10 s in all; 2 s with ``--quick``) played by :func:`visprim.sim.play` at
dt = 1 ms: via-point sequencer + stable-PD servo on all 20 DOF + recording + frame capture at
25 Hz. The real-time factor is simulated seconds / median wall seconds of the whole ``play``
call (reference sampling and metrics included). For scale, bare ``world.step()`` of the same
model stepped passively (no Python per step), and the rendering cost per GIF frame.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from _harness import Table, median_time
from visprim.sim import build_adonis, play
from visprim.sim.sequencer import angles_to_positions
from visprim.sim.servo import StablePD
from visprim.sim.trajectories import minimum_jerk


def stroke_chain(seconds: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-jerk strokes between random arm postures lasting ``seconds`` in all."""
    rng = np.random.default_rng(seed)
    durations: list[float] = []
    while sum(durations) < seconds:
        durations.append(float(rng.uniform(0.4, 1.2)))
    durations[-1] -= sum(durations) - seconds
    if durations[-1] < 0.3 and len(durations) > 1:
        last = durations.pop()
        durations[-1] += last
    n = len(durations) + 1
    postures = np.column_stack(
        [
            rng.uniform(-0.5, 1.5, n),  # gamma: forward to sideways
            rng.uniform(0.3, 2.0, n),  # beta: elevation
            rng.uniform(-0.8, 0.8, n),  # alpha: humeral rotation
            rng.uniform(0.2, 2.0, n),  # elbow
        ]
    )
    return minimum_jerk(postures, durations)


def run(table: Table, quick: bool = False) -> None:
    seconds = 2.0 if quick else 10.0
    repeat = 3 if quick else 5
    times, angles = stroke_chain(seconds)
    model = build_adonis(0.001)
    last = {}

    def controlled() -> None:
        last["pb"] = play(times, angles, model=model)

    wall = median_time(controlled, repeat=repeat)
    pb = last["pb"]
    sim_s = pb.times[-1]
    table.add(
        f"Adonis playback, {seconds:.0f} s of arm strokes",
        "visprim.sim.play (DART, stable PD, 1 ms)",
        wall,
        f"{sim_s / wall:.1f}x real time",
        f"RMS {pb.rms_error_deg:.2f} deg, max {pb.max_error_deg:.2f} deg, "
        f"{pb.time_ratio:.2f}x duration",
    )

    # The same model stepped with no Python in the loop: the servo's implicit damping only,
    # starting from the stroke chain's first state with the arms swinging.
    world, skel = build_adonis(0.001)
    StablePD(skel, 0.001)
    n_steps = int(round(seconds / 0.001))
    start = angles_to_positions(skel, angles[:1])[0]
    swing = np.zeros(skel.getNumDofs())
    swing[6:10] = 2.0  # rad/s

    def bare() -> None:
        world.reset()
        skel.setPositions(start)
        skel.setVelocities(swing)
        for _ in range(n_steps):
            world.step()

    wall_bare = median_time(bare, repeat=repeat)
    table.add(
        f"Adonis {seconds:.0f} s, no control loop",
        "dartpy World.step only (passive)",
        wall_bare,
        f"{seconds / wall_bare:.1f}x real time",
        f"{wall_bare / n_steps * 1e6:.1f} us/step",
    )

    from visprim.sim.render import render_gif

    short = play(*stroke_chain(1.0, seed=1), model=model)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.gif"
        wall_gif = median_time(lambda: render_gif(short, out), repeat=1 if quick else 3)
    n_frames = short.frames.shape[0]
    table.add(
        f"GIF of 1 s ({n_frames} frames, 480x480)",
        "visprim.sim.render_gif (PIL)",
        wall_gif,
        f"{wall_gif / n_frames * 1e3:.1f} ms/frame",
    )

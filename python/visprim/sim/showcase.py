"""Primitives on the humanoid: trajectories of primitives, their playbacks and the GIFs of
``visprim demo``."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from visprim.csvfile import writer
from visprim.sim.model import build_adonis
from visprim.sim.playback import Playback, play
from visprim.sim.render import render_gif

log = logging.getLogger(__name__)


class PrimitiveSource(Protocol):
    """What the simulation needs of a learned model (:class:`visprim.PrimitiveModel`)."""

    @property
    def n_primitives(self) -> int: ...

    primitive_durations_: NDArray[np.float64]

    def primitive_angles(self, k: int) -> NDArray[np.float64]: ...


def primitive_trajectory(
    model: PrimitiveSource, k: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Primitive ``k`` as ``(times (n,) s, angles (n, 4) rad)``: its cluster centre's angle
    curves spread evenly over the mean duration of its member segments."""
    n = int(model.n_primitives)
    if not 0 <= int(k) < n:
        raise ValueError(f"primitive index {k} out of range: the model has {n} primitives")
    angles = np.asarray(model.primitive_angles(int(k)), dtype=np.float64)
    duration = float(model.primitive_durations_[int(k)])
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"primitive {k}: duration {duration} s is not a positive time")
    return np.linspace(0.0, duration, angles.shape[0]), angles


def play_primitives(
    model: PrimitiveSource, indices: Sequence[int] | None = None, **play_args: Any
) -> dict[int, Playback]:
    """Play primitives ``indices`` (default all) of ``model``; ``play_args`` go to
    :func:`visprim.sim.play`. One Adonis model is reused for all of them."""
    chosen = range(int(model.n_primitives)) if indices is None else [int(i) for i in indices]
    adonis = build_adonis(play_args.pop("dt", 0.001))
    return {k: play(*primitive_trajectory(model, k), model=adonis, **play_args) for k in chosen}


def _default_indices(model: PrimitiveSource, n: int) -> list[int]:
    """The ``n`` primitives with the most member segments (``labels_``), else the first."""
    k = int(model.n_primitives)
    labels = getattr(model, "labels_", None)
    if labels is None:
        return list(range(min(n, k)))
    counts = np.bincount(np.asarray(labels, dtype=np.int64), minlength=k)[:k]
    return sorted(int(i) for i in np.argsort(-counts, kind="stable")[:n])


def write_metrics_csv(path: Path, playbacks: dict[int, Playback]) -> Path:
    """One row per primitive: tracking errors (degrees), times (seconds), via points."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = writer(fh)
        w.writerow(
            [
                "primitive", "duration_s", "completion_s", "time_ratio", "rms_error_deg",
                "max_error_deg", "rest_max_error_deg", "via_reached", "via_points",
            ]
        )  # fmt: skip
        for k, p in playbacks.items():
            w.writerow(
                [
                    k, f"{p.movement_duration:.4f}", f"{p.completion_time:.4f}",
                    f"{p.time_ratio:.4f}", f"{p.rms_error_deg:.4f}", f"{p.max_error_deg:.4f}",
                    f"{p.rest_max_error_deg:.4f}", p.n_reached, p.n_via,
                ]
            )  # fmt: skip
    return path


def demo_primitives(
    model: PrimitiveSource,
    out_dir: str | Path,
    indices: Sequence[int] | None = None,
    n: int = 3,
) -> list[Path]:
    """Play every primitive of ``model`` on Adonis, print the tracking metrics, and render
    GIFs of a few of them.

    Writes ``out_dir/adonis_metrics.csv`` (all primitives) and
    ``out_dir/adonis_primitive_KK.gif`` for ``indices`` (default: the ``n`` primitives with
    the most member segments). Returns the GIF paths.
    """
    out = Path(out_dir)
    k = int(model.n_primitives)
    chosen = _default_indices(model, n) if indices is None else [int(i) for i in indices]
    for i in chosen:
        if not 0 <= i < k:
            raise ValueError(f"primitive index {i} out of range: the model has {k} primitives")
    playbacks = play_primitives(model)
    csv_path = write_metrics_csv(out / "adonis_metrics.csv", playbacks)
    rms = np.array([p.rms_error_deg for p in playbacks.values()])
    ratio = np.array([p.time_ratio for p in playbacks.values()])
    reached = sum(p.reached_all for p in playbacks.values())
    log.info(
        f"Adonis played all {k} primitives: RMS tracking error mean {rms.mean():.2f} deg, "
        f"worst {rms.max():.2f} deg; completion at most {ratio.max():.2f}x the primitive's "
        f"duration; all via points reached in {reached}/{k}. Metrics: {csv_path}"
    )
    paths = []
    for i in chosen:
        pb = playbacks[i]
        path = render_gif(pb, out / f"adonis_primitive_{i:02d}.gif", title=f"primitive {i}")
        log.info(f"  primitive {i:2d}: {pb.summary()} -> {path}")
        paths.append(path)
    return paths

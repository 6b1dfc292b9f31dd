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


def primitive_postures(model: Any, trials: Sequence[Any]) -> NDArray[np.float64]:
    """Where each primitive of a model with posture-relative vectors (``offsets="mean"``)
    is made: ``(k, C)``, the mean over the segments of ``trials`` nearest to it of their
    mean postures (:attr:`visprim.vectors.SegmentVectors.offsets`, the model's channels;
    periodic channels averaged on the circle). A primitive without a segment there gets
    the mean over all segments."""
    from visprim.features import periodic_channels

    sv = model.vectorize(model.prepare(list(trials)))
    labels, _ = model.assign(model.transform(sv.vectors))
    offsets = np.asarray(sv.offsets, dtype=np.float64)
    periodic = list(periodic_channels(str(model.features), len(model.arms_)))

    def mean(rows: NDArray[np.float64]) -> NDArray[np.float64]:
        out = rows.mean(axis=0)
        if periodic:
            z = np.exp(1j * rows[:, periodic]).mean(axis=0)
            out[periodic] = np.angle(z)
        return out

    every = mean(offsets)
    return np.stack(
        [
            mean(offsets[labels == i]) if np.any(labels == i) else every
            for i in range(int(model.n_primitives))
        ]
    )


def _posed_angles(model: Any, k: int, posture: NDArray[np.float64]) -> NDArray[np.float64]:
    """Primitive ``k``'s curves plus ``posture`` (C,), as arm angles (radians)."""
    if str(getattr(model, "features", "zyz")) == "zyz":
        return np.asarray(model.primitive_angles(int(k)), dtype=np.float64) + posture
    from visprim.features import to_angles
    from visprim.vectors import to_curves

    values = model.cluster_centers_[int(k)] @ model.components_.T + model.mean_
    return to_angles(to_curves(values, model.n_channels) + posture, str(model.features))


def primitive_trajectory(
    model: PrimitiveSource, k: int, posture: NDArray[np.float64] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Primitive ``k`` as ``(times (n,) s, angles (n, 4) rad)``: its cluster centre's angle
    curves spread evenly over the mean duration of its member segments; with ``posture``
    (C,) (:func:`primitive_postures`), a primitive of posture-relative vectors placed there
    rather than around the zero posture."""
    n = int(model.n_primitives)
    if not 0 <= int(k) < n:
        raise ValueError(f"primitive index {k} out of range: the model has {n} primitives")
    if posture is None:
        angles = np.asarray(model.primitive_angles(int(k)), dtype=np.float64)
    else:
        angles = _posed_angles(model, int(k), np.asarray(posture, dtype=np.float64))
    duration = float(model.primitive_durations_[int(k)])
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"primitive {k}: duration {duration} s is not a positive time")
    return np.linspace(0.0, duration, angles.shape[0]), angles


def play_primitives(
    model: PrimitiveSource,
    indices: Sequence[int] | None = None,
    postures: NDArray[np.float64] | None = None,
    **play_args: Any,
) -> dict[int, Playback]:
    """Play primitives ``indices`` (default all) of ``model``, at ``postures`` (k, C) if
    given (:func:`primitive_trajectory`); ``play_args`` go to :func:`visprim.sim.play`. One
    Adonis model is reused for all of them."""
    chosen = range(int(model.n_primitives)) if indices is None else [int(i) for i in indices]
    adonis = build_adonis(play_args.pop("dt", 0.001))
    return {
        k: play(
            *primitive_trajectory(model, k, None if postures is None else postures[k]),
            model=adonis,
            **play_args,
        )
        for k in chosen
    }


def motion_deg(angles: NDArray[np.float64]) -> float:
    """How much a movement moves, degrees: the path length of the upper-arm and forearm
    directions of ``angles`` (n, 4 n_arms) radians, summed over the bones (the angle each
    bone turns through from sample to sample, added up). Blind to humeral rotation with the
    elbow straight and to γ/α swings at the Z-Y-Z singularity, which change nothing visible."""
    from visprim.features import from_angles

    a = np.asarray(angles, dtype=np.float64)
    if a.shape[0] < 2:
        return 0.0
    u = from_angles(a, "directions").reshape(a.shape[0], -1, 3)
    cos = np.clip(np.sum(u[1:] * u[:-1], axis=2), -1.0, 1.0)
    return float(np.degrees(np.sum(np.arccos(cos))))


def _default_indices(
    model: PrimitiveSource, n: int, postures: NDArray[np.float64] | None = None
) -> list[int]:
    """The ``n`` primitives that move most (:func:`motion_deg` of their angle curves, at
    ``postures`` if given), among those with at least two member segments (``labels_``)
    when there are ``n`` of them, so that a one-segment outlier is not shown for the
    model's movements."""
    k = int(model.n_primitives)
    motion = np.array(
        [
            motion_deg(primitive_trajectory(model, i, None if postures is None else postures[i])[1])
            for i in range(k)
        ]
    )
    labels = getattr(model, "labels_", None)
    pool = np.arange(k)
    if labels is not None:
        counts = np.bincount(np.asarray(labels, dtype=np.int64), minlength=k)[:k]
        if int(np.sum(counts >= 2)) >= n:
            pool = np.flatnonzero(counts >= 2)
    order = pool[np.argsort(-motion[pool], kind="stable")]
    return sorted(int(i) for i in order[:n])


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
    postures: NDArray[np.float64] | None = None,
) -> list[Path]:
    """Play every primitive of ``model`` on Adonis, print the tracking metrics, and render
    GIFs of a few of them.

    Writes ``out_dir/adonis_metrics.csv`` (all primitives) and
    ``out_dir/adonis_primitive_KK.gif`` for ``indices`` (default: the ``n`` primitives that
    move most, :func:`motion_deg`, so that the GIFs show movement rather than the near-rest
    primitives that hold most segments). ``postures`` (k, C): where to play each primitive
    of posture-relative vectors (:func:`primitive_postures`; default: around the zero
    posture). Returns the GIF paths.
    """
    out = Path(out_dir)
    k = int(model.n_primitives)
    chosen = _default_indices(model, n, postures) if indices is None else [int(i) for i in indices]
    for i in chosen:
        if not 0 <= i < k:
            raise ValueError(f"primitive index {i} out of range: the model has {k} primitives")
    playbacks = play_primitives(model, postures=postures)
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
        moves = motion_deg(
            primitive_trajectory(model, i, None if postures is None else postures[i])[1]
        )
        path = render_gif(
            pb,
            out / f"adonis_primitive_{i:02d}.gif",
            title=f"primitive {i}: bones turn {moves:.0f}°",
        )
        log.info(f"  primitive {i:2d}: {pb.summary()} -> {path}")
        paths.append(path)
    return paths

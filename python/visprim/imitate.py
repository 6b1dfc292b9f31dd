"""Imitation: a recording → its primitives → Adonis, measured against the human.

:func:`imitate` runs the chain of the method on one recording with a fitted
:class:`~visprim.model.PrimitiveModel`:

1. the recording is resampled to the model's frame period (the one ``learn`` used, see
   :func:`model_frame_period`), so that it is filtered and segmented like the training data;
2. it is segmented with the model's settings (:meth:`PrimitiveModel.prepare`: inverse
   kinematics, zero-phase low-pass, SEG-2 with the fitted constant, or SEG-1);
3. each segment is projected and assigned its nearest primitive
   (:meth:`~PrimitiveModel.transform`, :meth:`~PrimitiveModel.assign`);
4. the movement is rebuilt from the primitives' **centres** (``source="primitives"``), each
   curve stretched to its segment's duration with the segment's whole-turn offsets of γ and α
   added back, and the segments joined with no step in value or velocity
   (:class:`visprim.sim.joining.JoinedTrajectory`), in the model's description
   (:mod:`visprim.features`: Z-Y-Z angles, or unit bone directions then turned into angles by
   inverse kinematics, :class:`Rebuild`). ``source="projection"`` rebuilds each
   segment from its own f-D projection instead: a near-copy of the human, not an imitation
   through primitives, reported as such;
5. the rebuild is played on Adonis (:func:`visprim.sim.play`, stable PD or the paper's servo;
   both arms for a two-arm model, whose recordings are read with ``arm="both"``). A one-arm
   model given a two-arm recording imitates each arm on its own (steps 2–4 per arm, the left
   arm mirrored into a right arm, :class:`ArmsRebuild`) and Adonis plays both.

What the human did is the low-passed IK angles of the recording (what the method sees).
Errors (:class:`Imitation.metrics`, degrees) are taken at the recording's frames that a
segment covers:

* rebuild vs human, RMS per angle (γ, β, α, elbow; γ and α modulo whole turns) and over the
  four;
* in joint space, for rebuild vs human, Adonis vs human and Adonis vs rebuild: the shoulder's
  geodesic angle (the rotation between two shoulder orientations, free of the Z-Y-Z
  singularity) and the elbow's difference, RMS of each and over both. Adonis is compared at
  the same clock: recording time ``t`` against the simulation ``t − start`` seconds after the
  first segment started, so a robot that falls behind is charged for it;
* for rebuild vs human and Adonis vs human, the RMS angle between the bone directions
  (upper arm and forearm, :func:`visprim.features.direction_rms_deg`): what is seen of the
  arm, blind to humeral rotation with the elbow straight, where it changes nothing visible.

**The headline** (:attr:`Imitation.metrics` ``["headline"]``, :func:`headline`) is one of
them: the bone-direction RMS of Adonis vs the human (of the rebuild vs the human when the
rebuild is not played), the error a viewer sees, beside the **still-posture baseline**: the
same RMS for an arm that holds the recording's mean posture (the mean upper-arm and forearm
directions over the covered frames) throughout. An imitation that does not beat holding
still by much, or that puts every segment on one primitive, is flagged in its notes. The
other figures are details.

Coverage: the parts of the recording before the first segment, after the last and between
segments are listed (seconds and percent of the recording); nothing is dropped silently.
Gaps between segments are bridged smoothly in the rebuild and played.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from visprim.arm import ANGLE_NAMES, shoulder_rotation_body
from visprim.features import direction_rms_deg, from_angles
from visprim.ik import human_arm_points
from visprim.params import STUDY_FRAME_PERIOD_S
from visprim.sim.joining import JoinedTrajectory
from visprim.trial import Trial, split_arms

Source = Literal["primitives", "projection"]
Servo = Literal["stable", "paper"]

#: How each rebuild source is labelled in reports.
SOURCE_LABELS: dict[str, str] = {
    "primitives": "rebuilt from the nearest primitives' centres (imitation through primitives)",
    "projection": (
        "NEAR-COPY: each segment from its own PCA projection, not from primitives "
        "(an upper bound on what the primitives could do)"
    ),
}
#: Arm of each part of a recording imitated arm by arm (:attr:`Imitation.segment_arm`).
ARM_SIDES: tuple[str, str] = ("right", "left")
#: Default frame period (s) for a model that does not record one (the study's 34 ms).
DEFAULT_PERIOD_S = STUDY_FRAME_PERIOD_S
#: Spacing (s) of the rebuild samples handed to the simulation.
PLAY_SAMPLE_S = 0.005

__all__ = [
    "ArmsRebuild",
    "Imitation",
    "Rebuild",
    "headline",
    "human_arm_points",
    "imitate",
    "still_direction_rms_deg",
    "model_frame_period",
]


def model_frame_period(model: Any) -> float | None:
    """The frame period (s) recordings are resampled to for ``model``: the one recorded by
    ``visprim learn`` (None: the files' own rate), else 34 ms."""
    period = getattr(model, "frame_period_", DEFAULT_PERIOD_S)
    return None if period is None else float(period)


@dataclass(eq=False)
class Imitation:
    """Result of :func:`imitate`. Seconds on the recording's clock, radians unless ``_deg``.

    Attributes
    ----------
    name : str — the recording's name.
    source : "primitives" or "projection" — what the rebuild is made of.
    trial : Trial — the recording as imitated (resampled to the model's period).
    times : (F,) s — its frame times.
    human : (F, 4 n_arms) rad — low-passed IK angles (γ, β, α, elbow per arm; a left arm
        in the mirror convention).
    segments : (N, 2) s — ``[start, end]`` of each segment.
    primitives : (N,) int — nearest primitive of each segment.
    distances : (N,) rad — distance of each segment's projection to that primitive's centre.
    segment_of_frame : (F,) int — segment index of each frame, -1 where none covers it (for
        arms imitated one by one, the right arm's segment where it has one).
    rebuild : Rebuild or ArmsRebuild — the joined rebuild (call it with times for angles,
        velocities).
    rebuild_angles, rebuild_velocities : (F, 4) — the rebuild at the frames inside
        ``[segments[0, 0], segments[-1, 1]]`` (NaN outside).
    adonis_angles : (F, 4) or None — Adonis's arm angles at the same clock (NaN outside the
        played span; γ and α on the human's branch).
    playback : Playback or None — the simulation (None with ``play=False``).
    metrics : dict — every figure of the module docstring (JSON-ready).
    """

    name: str
    source: str
    trial: Trial
    times: NDArray[np.float64]
    human: NDArray[np.float64]
    segments: NDArray[np.float64]
    primitives: NDArray[np.int64]
    distances: NDArray[np.float64]
    segment_of_frame: NDArray[np.int64]
    rebuild: Rebuild | ArmsRebuild
    rebuild_angles: NDArray[np.float64]
    rebuild_velocities: NDArray[np.float64]
    adonis_angles: NDArray[np.float64] | None
    playback: Any
    metrics: dict[str, Any] = field(default_factory=dict)
    #: (N,) arm of each segment (0 right, 1 left) when a one-arm model imitates both arms
    #: one by one; None otherwise.
    segment_arm: NDArray[np.int64] | None = None

    @property
    def covered(self) -> NDArray[np.bool_]:
        """(F,) whether a segment covers each frame."""
        return self.segment_of_frame >= 0

    def summary(self) -> str:
        """A few lines for the terminal: the headline and its baseline first, then the
        details."""
        m = self.metrics
        rb = m["rebuild_vs_human_rms_deg"]
        if self.segment_arm is None:
            sequence = " ".join(str(int(k)) for k in self.primitives)
        else:  # arms imitated one by one
            sequence = "; ".join(
                f"{side} arm "
                + " ".join(str(int(k)) for k in self.primitives[self.segment_arm == i])
                for i, side in enumerate(ARM_SIDES)
            )
        head = m["headline"]
        lines = [
            f"{self.name} ({len(self.times)} frames every {1e3 * m['frame_period_s']:.1f} ms, "
            f"{m['segmentation'].upper()}): {len(self.primitives)} segments -> primitives "
            f"{sequence}",
            f"  rebuild: {SOURCE_LABELS[self.source]}",
            f"  headline: {head['compares']} bone-direction RMS {head['rms_deg']:.2f} deg; "
            f"holding the mean posture still: {head['still_posture_rms_deg']:.2f} deg "
            f"({100 * head['ratio_to_still']:.0f} % of it)",
            _size_line(m.get("description")),
        ]
        lines += [f"  note: {n}" for n in head["notes"]]
        lines.append(
            "  details, rebuild vs human RMS per Z-Y-Z angle (deg; gamma, alpha modulo turns): "
            + ", ".join(f"{a} {rb[a]:.2f}" for a in channel_names(self.human.shape[1]))
            + f"; overall {rb['overall']:.2f}"
        )
        cov = m["coverage"]
        lines.append(
            f"  coverage: {cov['covered_s']:.2f} s of {m['human_duration_s']:.2f} s; "
            f"uncovered {cov['uncovered_s']:.2f} s ({cov['uncovered_percent']:.1f} %)"
            + "".join(
                f"\n    uncovered {u['start_s']:.3f}-{u['end_s']:.3f} s ({u['duration_s']:.3f} s)"
                for u in cov["uncovered"]
            )
        )
        if "adonis" in m:
            a = m["adonis"]
            j = m["rebuild_vs_human_joint_rms_deg"]
            vs_human = a["vs_human_joint_rms_deg"]["overall"]
            vs_rebuild = a["vs_rebuild_joint_rms_deg"]["overall"]
            lines.append(
                f"  details, joint-space RMS (deg, shoulder geodesic + elbow): rebuild vs human "
                f"{j['overall']:.2f}; Adonis vs human {vs_human:.2f}; "
                f"Adonis vs rebuild {vs_rebuild:.2f} (how well Adonis tracks)"
            )
            lines.append(
                f"  details, bone-direction RMS (deg, upper arm and forearm): rebuild vs human "
                f"{m['rebuild_vs_human_direction_rms_deg']:.2f}; Adonis vs human "
                f"{a['vs_human_direction_rms_deg']:.2f}"
            )
            lines.append(
                f"  Adonis ({a['servo']} servo): completed in {a['completion_time_s']:.2f} s; "
                f"{a['time_ratio']:.2f}x the human's covered {m['covered_span_s']:.2f} s, "
                f"{a['time_ratio_full']:.2f}x the whole recording; via points "
                f"{a['via_reached']}/{a['via_points']}"
            )
        else:
            lines.append(
                f"  details, bone-direction RMS (deg, upper arm and forearm): rebuild vs human "
                f"{m['rebuild_vs_human_direction_rms_deg']:.2f}"
            )
        return "\n".join(lines)


#: Above this share of the still-posture baseline, an imitation is flagged as barely
#: better than holding still.
NEAR_STILL_RATIO = 0.7


def still_direction_rms_deg(angles: NDArray[np.float64]) -> float:
    """The still-posture baseline, degrees: the RMS angle between the bone directions
    (upper arm, forearm) of ``angles`` (T, 4 n_arms) radians and their mean directions over
    the T frames, i.e. the bone-direction RMS of an arm holding the mean posture."""
    a = np.asarray(angles, dtype=np.float64)
    u = from_angles(a, "directions").reshape(a.shape[0], -1, 3)
    mean = u.mean(axis=0)
    norm = np.linalg.norm(mean, axis=1, keepdims=True)
    mean = np.where(norm > 1e-12, mean / np.maximum(norm, 1e-300), u[0])
    cos = np.clip(np.einsum("tbi,bi->tb", u, mean), -1.0, 1.0)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(cos) ** 2))))


def headline(
    metrics: dict[str, Any], primitives: Sequence[int], still_deg: float
) -> dict[str, Any]:
    """The headline of an imitation's ``metrics``: the bone-direction RMS that a viewer sees
    (Adonis vs human if played, else rebuild vs human), the still-posture baseline
    ``still_deg`` beside it, and notes when every segment went to one primitive or the
    error is close to the baseline."""
    if "adonis" in metrics:
        compares, rms = "Adonis vs human", float(metrics["adonis"]["vs_human_direction_rms_deg"])
    else:
        compares, rms = "rebuild vs human", float(metrics["rebuild_vs_human_direction_rms_deg"])
    ratio = rms / still_deg if still_deg > 0 else float("inf")
    notes = []
    used = sorted({int(k) for k in primitives})
    if len(primitives) > 1 and len(used) == 1:
        notes.append(
            f"every segment ({len(primitives)}) went to primitive {used[0]}: the imitation "
            "repeats one movement"
        )
    if ratio >= NEAR_STILL_RATIO:
        notes.append(
            f"the error ({rms:.2f} deg) is close to holding the mean posture still "
            f"({still_deg:.2f} deg): the imitation shows little of the movement"
        )
    return {
        "measure": "bone-direction RMS, degrees: the angle between the upper-arm and forearm "
        "directions of the two, RMS over the covered frames and both bones",
        "compares": compares,
        "rms_deg": rms,
        "still_posture_rms_deg": float(still_deg),
        "still_posture": "the human's mean upper-arm and forearm directions over the covered "
        "frames, held throughout",
        "ratio_to_still": float(ratio),
        "n_primitives_used": len(used),
        "notes": notes,
    }


# ---------------------------------------------------------------------------- helpers


def _size_line(d: dict[str, Any] | None) -> str:
    """The size of the description, one line of :meth:`Imitation.summary`."""
    if not d:
        return "  description: -"
    budget = d.get("budget_numbers_per_s")
    cut = d.get("max_stroke_s")
    if d.get("whole_movement"):
        settings = f"; the whole movement, no segments ({d.get('whole_movement_code')})"
    else:
        settings = f"; posture as {d.get('posture_numbers_per_segment', '-')}; strokes " + (
            "uncut" if cut is None else f"cut at {cut:g} s"
        )
    choice = d.get("encoder_choice")
    if choice:
        errs = ", ".join(f"{k} {v:.1f}°" for k, v in choice["frames_rms_deg"].items())
        settings += f" (encoder's choice by its rebuild of the frames: {errs}; 1 number)"
    return (
        f"  description: {d['description']}, {d['numbers']} numbers in {d['seconds']:.2f} s = "
        f"{d['numbers_per_s']:.1f} numbers/s"
        + ("" if budget is None else f" (budget {budget:g} numbers/s)")
        + settings
    )


def _rms_deg(x: NDArray[np.float64], axis: int | None = 0) -> Any:
    return np.degrees(np.sqrt(np.mean(np.square(x), axis=axis)))


def _geodesic(ra: NDArray[np.float64], rb: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle (rad) of the rotation between two stacks of (T, 3, 3) rotation matrices."""
    rel = Rotation.from_matrix(ra).inv() * Rotation.from_matrix(rb)
    return np.asarray(rel.magnitude(), dtype=np.float64)


def channel_names(n_channels: int) -> tuple[str, ...]:
    """Names of the angle columns: γ, β, α, elbow of the right arm (4), or ``right_*`` then
    ``left_*`` (8)."""
    if n_channels == 4:
        return ANGLE_NAMES
    if n_channels == 8:
        return tuple(f"{side}_{a}" for side in ("right", "left") for a in ANGLE_NAMES)
    raise ValueError(f"expected 4 (one arm) or 8 (two arms) angle columns, got {n_channels}")


def joint_space_errors(
    a: NDArray[np.float64], b: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Shoulder geodesic angles and elbow differences (rad) between two (T, 4) or (T, 8)
    angle arrays (see the module docstring), each (T * n_arms,): all arms stacked."""
    shoulders, elbows = [], []
    for c in range(0, a.shape[1], 4):
        # The left arm's mirror convention is a conjugation: it leaves geodesic angles alone.
        shoulders.append(
            _geodesic(
                shoulder_rotation_body(a[:, c : c + 3]), shoulder_rotation_body(b[:, c : c + 3])
            )
        )
        elbows.append(np.abs(a[:, c + 3] - b[:, c + 3]))
    return np.concatenate(shoulders), np.concatenate(elbows)


def _joint_rms(shoulder: NDArray[np.float64], elbow: NDArray[np.float64]) -> dict[str, float]:
    return {
        "shoulder": float(_rms_deg(shoulder)),
        "elbow": float(_rms_deg(elbow)),
        "overall": float(_rms_deg(np.concatenate([shoulder, elbow]))),
    }


def _angle_rms(diff: NDArray[np.float64]) -> dict[str, float]:
    """RMS per angle column (degrees) of differences (rad); γ and α, angles about an
    unbounded axis, are compared modulo whole turns (wrapped into (−π, π])."""
    diff = diff.copy()
    for c in range(0, diff.shape[1], 4):
        for k in (c, c + 2):
            diff[:, k] = np.angle(np.exp(1j * diff[:, k]))
    names = channel_names(diff.shape[1])
    out = {name: float(v) for name, v in zip(names, _rms_deg(diff), strict=True)}
    out["overall"] = float(_rms_deg(diff, axis=None))
    return out


def _same_branch(
    angles: NDArray[np.float64], reference: NDArray[np.float64]
) -> NDArray[np.float64]:
    """γ and α of ``angles`` moved by whole turns to lie nearest ``reference``."""
    out = angles.copy()
    for c in range(0, angles.shape[1], 4):
        for k in (c, c + 2):
            out[:, k] += 2 * np.pi * np.round((reference[:, k] - angles[:, k]) / (2 * np.pi))
    return out


def _uncovered(t0: float, t1: float, segments: NDArray[np.float64]) -> list[tuple[float, float]]:
    out = []
    edge = t0
    for s, e in segments:
        if s > edge + 1e-9:
            out.append((edge, float(s)))
        edge = max(edge, float(e))
    if t1 > edge + 1e-9:
        out.append((edge, t1))
    return out


# ---------------------------------------------------------------------------- imitate


class Rebuild:
    """The joined rebuild as arm angles.

    ``channels`` is the :class:`JoinedTrajectory` of the segment curves in the model's
    description (:mod:`visprim.features`: the Z-Y-Z angles themselves, or unit bone
    directions, turned into angles by inverse kinematics). Calling it with times (s) gives
    ``(angles (k, 4 n_arms) rad, velocities rad/s)``: for angles, the joined trajectory and
    its analytic derivative; for directions, inverse kinematics of the joined directions and
    the time derivative of the angles (finite differences over the given times). ``turns``
    (4 n_arms,) rad is added to the angles (whole turns of γ and α, see :func:`imitate`).
    """

    def __init__(self, channels: JoinedTrajectory, features: str = "zyz") -> None:
        self.channels = channels
        self.features = features
        self.turns: NDArray[np.float64] | None = None

    @property
    def start(self) -> float:
        return self.channels.start

    @property
    def end(self) -> float:
        return self.channels.end

    def __call__(self, times: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        values, rates = self.channels(t)
        if self.features == "zyz":
            angles, velocities = values, rates
        else:
            from visprim.features import to_angles

            angles = to_angles(values, self.features, t)
            velocities = np.gradient(angles, t, axis=0) if t.size > 1 else np.zeros_like(angles)
        if self.turns is not None:
            angles = angles + self.turns
        return angles, velocities


class ArmsRebuild:
    """Rebuilds of the arms of one recording imitated one by one (a one-arm model on a
    two-arm recording), side by side: ``(angles (k, 4 n_arms), velocities)``. Outside its
    own segments an arm holds its first or last rebuilt posture (velocity zero). ``turns``
    as in :class:`Rebuild`."""

    def __init__(self, arms: Sequence[Rebuild]) -> None:
        self.arms = list(arms)
        self.turns: NDArray[np.float64] | None = None

    @property
    def start(self) -> float:
        return min(r.start for r in self.arms)

    @property
    def end(self) -> float:
        return max(r.end for r in self.arms)

    def __call__(self, times: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        angles, velocities = [], []
        for r in self.arms:
            # One evaluation along the arm's own span and its two ends, so that the held
            # postures continue the path (inverse kinematics unwraps γ and α along it).
            own = (t >= r.start) & (t <= r.end)
            path = np.union1d([r.start, r.end], t[own])
            path_a, path_v = r(path)
            a = np.where((t < r.start)[:, None], path_a[0], path_a[-1])
            v = np.zeros_like(a)
            rows = np.searchsorted(path, t[own])
            a[own], v[own] = path_a[rows], path_v[rows]
            angles.append(a)
            velocities.append(v)
        out = np.concatenate(angles, axis=1)
        if self.turns is not None:
            out = out + self.turns
        return out, np.concatenate(velocities, axis=1)


@dataclass(eq=False)
class _Segmented:
    """One imitated trial (or arm): its frames, the human's angles, its segments, their
    primitives and the joined rebuild."""

    times: NDArray[np.float64]
    human: NDArray[np.float64]
    bounds: NDArray[np.float64]
    labels: NDArray[np.int64]
    distances: NDArray[np.float64]
    rebuild: Rebuild
    method: str
    #: The description used (:class:`visprim.rate.Description`).
    description: Any = None


def _described(
    model: Any, sv: Any, source: Source, budget: float | None, settings: Any
) -> tuple[Any, Any]:
    """The segments rebuilt through the model's primitives (scaled by each segment's
    amplitude if the model says so; with ``budget``, the best description within that many
    numbers per second, :func:`visprim.rate.describe_segments`, stored with ``settings``,
    :class:`visprim.rate.budget.Settings`) or their projections, as curves on the trial's
    own channels, and the description used."""
    from visprim.rate.budget import describe_segments, rebuilt_postures

    seconds = float(np.max(sv.ends) - np.min(sv.starts))
    family = "projection" if source == "projection" else None
    rebuilt, d = describe_segments(
        model,
        sv.vectors,
        seconds,
        family=family,
        budget=budget,
        settings=settings,
        postures=sv.offsets,
    )
    if d.settings.posture == "mean":
        return sv.to_trial_angles(rebuilt), d
    from visprim.vectors import to_curves

    post = rebuilt_postures(model, d.settings, sv.offsets, rebuilt)
    return to_curves(rebuilt, int(model.n_channels)) + post[:, None, :], d


def _settings(budget: float | None, override: dict[str, Any]) -> Any:
    """How the segments are stored: with a budget, the defaults of
    :data:`visprim.params.RATE_OPTIONS` (:func:`visprim.rate.budget.budget_settings`) with
    ``override``; without, the model's own (each channel's mean posture, strokes uncut)."""
    from visprim.rate.budget import Settings, budget_settings

    if budget is None:
        if override:
            raise ValueError(f"{', '.join(sorted(override))}: only with a budget")
        return Settings()
    return budget_settings(**override)


def _shares(
    model: Any, pieces: Sequence[Trial], budget: float | None, settings: Any
) -> list[float | None]:
    """Each piece's share of the ``budget`` (numbers per second of its own movement): the
    budget itself for one piece, else the shares of the best combination of descriptions
    (:func:`visprim.rate.share_budget`)."""
    if budget is None or len(pieces) == 1:
        return [budget] * len(pieces)
    from visprim.rate.budget import cut_vectors, share_budget

    parts, postures = [], []
    for t in pieces:
        sv = cut_vectors(model, model.prepare([t]), settings.max_stroke)
        parts.append((sv.vectors, float(np.max(sv.ends) - np.min(sv.starts))))
        postures.append(sv.offsets)
    span = max(sec for _, sec in parts)
    return list(share_budget(model, parts, span, float(budget), settings, postures))


def _frames_error_deg(parts: Sequence[_Segmented]) -> float:
    """The encoder's own rebuild error of a movement: bone-direction RMS (degrees) of the
    rebuilt frames against the movement's frames, over the frames the segments cover, all
    parts (arms) together. The same space whatever the segments, so descriptions with
    different segment sets compare."""
    from visprim.features import direction_rms_deg

    total, n = 0.0, 0
    for p in parts:
        cov = (_segment_of_frame(p.times, p.bounds) >= 0) & (p.times >= p.rebuild.start - 1e-9)
        cov &= p.times <= p.rebuild.end + 1e-9
        if not cov.any():
            continue
        rebuilt, _ = p.rebuild(p.times[cov])
        total += direction_rms_deg(rebuilt, p.human[cov]) ** 2 * int(cov.sum())
        n += int(cov.sum())
    return float(np.sqrt(total / n)) if n else float("inf")


#: Numbers the encoder stores to say which alternative it kept (one flag per movement).
CUT_CHOICE_NUMBERS = 1


def _alternatives(model: Any, settings: Any, options: dict[str, Any]) -> tuple[str, ...]:
    """The descriptions the encoder chooses among within a budget: strokes cut at
    ``settings.max_stroke`` and uncut (unless ``options`` forces ``max_stroke``: then that
    one alone), and the whole movement through the model's eigen-movements when it has
    them (``model.eigen_movements_``, written by ``visprim learn``) and the strokes are
    not forced."""
    if "max_stroke" in options:
        return ("forced",)
    cuts = ("cut", "uncut") if settings.max_stroke is not None else ("uncut",)
    whole = ("whole",) if getattr(model, "eigen_movements_", None) is not None else ()
    return cuts + whole


def _encoder_choice(
    model: Any,
    pieces: Sequence[Trial],
    source: Source,
    name: str,
    budget: float,
    settings: Any,
    alternatives: Sequence[str],
) -> tuple[list[_Segmented], dict[str, Any]]:
    """The movement described by each of ``alternatives`` (:func:`_alternatives`: strokes
    cut at ``settings.max_stroke``, uncut, the whole movement), each within ``budget`` less
    the :data:`CUT_CHOICE_NUMBERS` flag that says which; the one whose rebuilt frames lie
    closer to the movement's (:func:`_frames_error_deg`) is kept. The same rule for every
    recording: the encoder has the movement it describes."""
    from dataclasses import replace

    span = max(
        float(np.max(sv.ends) - np.min(sv.starts))
        for sv in (model.vectorize(model.prepare([t])) for t in pieces)
    )
    inner = budget - CUT_CHOICE_NUMBERS / span
    tried: dict[str, tuple[list[_Segmented], float]] = {}
    refused: dict[str, str] = {}
    for key in alternatives:
        try:
            if key == "whole":
                parts = _whole_movement(model, pieces, name, inner)
            else:
                s = settings if key == "cut" else replace(settings, max_stroke=None)
                shares = _shares(model, pieces, inner, s)
                parts = [
                    _segment_and_rebuild(model, t, source, name, b, s)
                    for t, b in zip(pieces, shares, strict=True)
                ]
        except ValueError as e:
            refused[key] = str(e)
            continue
        tried[key] = (parts, _frames_error_deg(parts))
    if not tried:
        raise ValueError(next(iter(refused.values())))
    chosen = min(tried, key=lambda k: tried[k][1])
    choice = {
        "chosen": chosen,
        "alternatives": list(alternatives),
        "cut_at_s": settings.max_stroke,
        "rule": "the alternative whose rebuilt frames lie closest to the movement's "
        "(bone-direction RMS over the covered frames), each within the budget less the flag",
        "frames_rms_deg": {k: v[1] for k, v in tried.items()},
        "refused": refused,
        "numbers": CUT_CHOICE_NUMBERS,
    }
    return tried[chosen][0], choice


#: Most frames of a movement described whole (61 s at the study's 34 ms): the encoder's fit
#: of the DCT coefficients to the bone directions
#: (:func:`visprim.rate.fit_dct_coefficients`) holds a Jacobian of frames × 6 rows and
#: (rate × seconds) columns, memory growing with the square of the frames; longer
#: movements are described through the primitives only (the alternative is listed as
#: refused).
MAX_WHOLE_FRAMES = 1800


def _whole_movement(
    model: Any, pieces: Sequence[Trial], name: str, budget: float
) -> list[_Segmented]:
    """Each piece (one arm, or both arms of a two-arm model) described whole, without
    segments, through the model's eigen-movements or the DCT of its arm angles
    (:func:`visprim.rate.budget.describe_movement`, code
    :data:`~visprim.rate.budget.WHOLE_FAMILY`), over the span its segments cover. Every arm
    gets ``budget × span / Σ seconds`` numbers per second of its own movement (``span`` the
    longest piece's seconds), so that all together fit ``budget`` numbers per second of
    ``span``. The rebuild is the described bone directions, one curve over the span."""
    from visprim.rate.budget import ARM_ANGLES, Description, describe_movement

    book = model.eigen_movements_
    prepared = []
    for t in pieces:
        corpus = model.prepare([t])
        segs = corpus.segments[0]
        if segs.shape[0] == 0:
            raise ValueError(f"{t.source or name}: no segment found; nothing to imitate")
        times = corpus.times[0]
        span = (times >= segs[0, 0] - 1e-9) & (times <= segs[-1, 1] + 1e-9)
        frames = int(span.sum())
        if frames > MAX_WHOLE_FRAMES:
            raise ValueError(
                f"{frames} frames, more than the {MAX_WHOLE_FRAMES} of a movement described "
                "whole (MAX_WHOLE_FRAMES)"
            )
        prepared.append((corpus, segs, span))
    seconds = [float(g[-1, 1] - g[0, 0]) for _, g, _ in prepared]
    arms = [c.angles[0].shape[1] // ARM_ANGLES for c, _, _ in prepared]
    rate = budget * max(seconds) / sum(s * a for s, a in zip(seconds, arms, strict=True))
    out = []
    for (corpus, _, span), sec in zip(prepared, seconds, strict=True):
        times = corpus.times[0]
        values, descs = [], []
        for c in range(0, corpus.angles[0].shape[1], ARM_ANGLES):
            arm = np.ascontiguousarray(corpus.angles[0][span, c : c + ARM_ANGLES])
            v, d = describe_movement(book, from_angles(arm, "directions"), arm, sec, rate)
            values.append(v)
            descs.append(d)
        desc = descs[0]
        if len(descs) > 1:  # both arms of a two-arm model: one description of their sum
            family = "eigen" if all(d.family == "eigen" for d in descs) else "eigen/dct"
            desc = Description(family, sum(d.m for d in descs), sum(d.numbers for d in descs), sec)
        bounds = np.array([[times[span][0], times[span][-1]]])
        rebuild = Rebuild(JoinedTrajectory([np.concatenate(values, axis=1)], bounds), "directions")
        out.append(
            _Segmented(
                corpus.times_all,
                corpus.angles_all,
                bounds,
                np.array([-1], dtype=np.int64),
                np.array([np.nan]),
                rebuild,
                str(corpus.segmentation.method),
                desc,
            )
        )
    return out


def _description_metrics(
    parts: Sequence[_Segmented], budget: float | None, choice: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The size of the description (numbers per second of movement), per arm and in all;
    ``choice``: the encoder's choice among its alternatives (:func:`_encoder_choice`), its
    flag counted."""
    descs = [p.description for p in parts]
    numbers = sum(d.numbers for d in descs) + (choice["numbers"] if choice else 0)
    seconds = max(d.seconds for d in descs)
    whole = descs[0].family.startswith("eigen")
    out: dict[str, Any] = {
        "budget_numbers_per_s": budget,
        "numbers": numbers,
        "seconds": seconds,
        "numbers_per_s": numbers / seconds if seconds > 0 else float("inf"),
        "description": "; ".join(dict.fromkeys(d.label for d in descs)),
        "whole_movement": whole,
        "posture": None if whole else descs[0].settings.posture,
        "posture_numbers_per_segment": "none (no segments)" if whole else _posture_count(descs[0]),
        "max_stroke_s": None if whole else descs[0].settings.max_stroke,
        "counted": (
            "per movement (arm) its start time, its duration, the number that says which code "
            "(eigen-movements, or the split of the DCT coefficients over the 4 angle channels) "
            "and the coefficients"
            if whole
            else "per movement its start time; per segment the primitive id (none for the "
            "projection), the duration, the posture and the description's coefficients"
        ),
    }
    if whole:
        from visprim.rate.budget import WHOLE_FAMILY

        out["whole_movement_code"] = WHOLE_FAMILY
    if choice is not None:
        out["encoder_choice"] = choice
        out["counted"] += (
            f"; {choice['numbers']} number for the encoder's choice among "
            + ", ".join(choice["alternatives"])
        )
    if len(descs) > 1:
        out["arms"] = {side: d.to_dict() for side, d in zip(ARM_SIDES, descs, strict=False)}
    return out


def _posture_count(d: Any) -> str:
    return (
        "2 unit bone directions (4 numbers per arm)"
        if d.settings.posture == "unit"
        else "each channel's mean"
    )


def _segment_and_rebuild(
    model: Any,
    trial: Trial,
    source: Source,
    name: str,
    budget: float | None = None,
    settings: Any = None,
) -> _Segmented:
    corpus = model.prepare([trial])
    seg = corpus.segmentation
    if seg.n_segments == 0:
        raise ValueError(
            f"{trial.source or name}: no segment found (the arm never moves significantly for "
            f"{seg.method.upper()}); nothing to imitate"
        )
    if settings is None:
        settings = _settings(budget, {})
    # Strokes longer than the settings' max_stroke cut into equal parts.
    from visprim.rate.budget import cut_vectors

    sv = cut_vectors(model, corpus, settings.max_stroke)
    projections = model.transform(sv.vectors)
    labels, distances = model.assign(projections)
    # Curves in the model's description (angles or bone directions), on the trial's turns.
    curves, description = _described(model, sv, source, budget, settings)
    bounds = np.stack([sv.starts, sv.ends], axis=1)
    rebuild = Rebuild(
        JoinedTrajectory(list(curves), bounds), str(getattr(model, "features", "zyz"))
    )
    return _Segmented(
        corpus.times_all,
        corpus.angles_all,
        bounds,
        labels,
        distances,
        rebuild,
        str(seg.method),
        description,
    )


def _segment_of_frame(times: NDArray[np.float64], bounds: NDArray[np.float64]) -> NDArray[np.int64]:
    """Segment index of each frame (segment j covers [start_j, end_j), the last one also its
    end), -1 where none covers it."""
    seg_of = np.full(times.shape[0], -1, dtype=np.int64)
    for j, (s, e) in enumerate(bounds):
        last = j == bounds.shape[0] - 1
        seg_of[(times >= s - 1e-9) & ((times <= e + 1e-9) if last else (times < e - 1e-9))] = j
    return seg_of


def _turns(angles: NDArray[np.float64], reference: NDArray[np.float64]) -> NDArray[np.float64]:
    """Whole turns (per column, rad) that bring γ and α of ``angles`` closest to
    ``reference`` on average (zero for β and the elbow)."""
    out = np.zeros(angles.shape[1])
    for c in range(0, angles.shape[1], 4):
        for k in (c, c + 2):
            out[k] = 2 * np.pi * np.round(np.mean(reference[:, k] - angles[:, k]) / (2 * np.pi))
    return out


def _read(recording: Trial | str | Path, arms: tuple[str, ...]) -> Trial:
    if isinstance(recording, Trial):
        return recording
    from visprim.io import read

    return read(str(recording), arm="both" if len(arms) == 2 else "right")


#: Default simulation step of each servo, seconds (see :func:`imitate`).
DEFAULT_DT: dict[str, float] = {"stable": 0.002, "paper": 0.0001}


def imitate(
    model: Any,
    recording: Trial | str | Path,
    *,
    source: Source = "primitives",
    servo: Servo = "stable",
    period: float | None | Literal["model"] = "model",
    dt: float | None = None,
    render_fps: float = 25.0,
    play: bool = True,
    budget: float | None = None,
    budget_options: dict[str, Any] | None = None,
) -> Imitation:
    """Imitate one recording with a fitted model (see the module docstring).

    Parameters
    ----------
    model : PrimitiveModel — fitted (or loaded).
    recording : Trial or path — any file :func:`visprim.io.read` reads (the arms of the
        model). A two-arm trial given to a one-arm model has each arm imitated on its own
        through the same primitives, the left arm mirrored (:func:`visprim.trial.split_arms`),
        and Adonis plays both.
    source : "primitives" (default) or "projection" (near-copy, labelled as such).
    servo : "stable" (stable PD, default) or "paper" (eq. (1) with via-point switching).
    period : seconds, None or "model" — resample to this frame period (None: keep the file's
        rate; "model": :func:`model_frame_period`).
    dt : simulation step, s (default :data:`DEFAULT_DT` of the servo: 2 ms for the stable
        PD, which tracks within 0.04° there; 0.1 ms for the paper's explicit PD, which
        diverges at 1 ms). render_fps : rate of the stored frames, Hz.
    play : run the simulation (False: rebuild and its errors only).
    budget : numbers per second of movement: rebuild through the best description that fits
        (nearest primitive, with its gain, with residual coefficients, or the segment's own
        projection; :func:`visprim.rate.describe_segments`); arms imitated one by one share
        it as the best combination of their descriptions (:func:`visprim.rate.share_budget`).
        ``metrics["description"]`` states the size of the description used, with or without
        a budget. With a budget the segments are stored as the rate benchmark chose
        (:data:`visprim.params.RATE_OPTIONS`: each segment's posture as the unit bone
        directions of its mean, 4 numbers per arm; :func:`visprim.rate.budget.budget_settings`)
        and, unless ``budget_options`` gives ``max_stroke``, the encoder describes the
        movement with strokes longer than RATE_OPTIONS ``max_stroke`` (0.8 s) cut into
        equal parts, uncut, and, if the model has eigen-movements (``eigen_movements_``,
        stored by ``visprim learn``), whole without segments
        (:func:`visprim.rate.budget.describe_movement`), each within the budget less one
        number (the flag that says which, :data:`CUT_CHOICE_NUMBERS`), and keeps the one
        whose rebuilt frames lie closest to the movement's (bone-direction RMS,
        :func:`_encoder_choice`; ``metrics["description"]["encoder_choice"]``). Without a
        budget, as the model does (6 posture numbers per arm, strokes uncut).
    budget_options : with ``budget``, settings in place of those defaults (``posture``:
        "mean" or "unit"; ``max_stroke``: seconds or None, segments with that cut then, no
        choice).

    Raises
    ------
    ValueError
        Unreadable recording, no segment found, bad options (one line naming the problem).
    """
    if source not in SOURCE_LABELS:
        raise ValueError(f"source must be 'primitives' or 'projection', got {source!r}")
    if servo not in ("stable", "paper"):
        raise ValueError(f"servo must be 'stable' or 'paper', got {servo!r}")
    arms = tuple(getattr(model, "arms_", ("right",)))
    trial = _read(recording, arms)
    target = model_frame_period(model) if period == "model" else period
    if target is not None and abs(trial.frame_period - float(target)) > 1e-9 * float(target):
        from visprim.io import resample_trial

        trial = resample_trial(trial, float(target))
    name = trial.name or Path(str(trial.source or "recording")).stem

    # A one-arm model imitates each arm of a two-arm recording on its own (the left arm
    # mirrored into a right arm, :func:`visprim.trial.split_arms`).
    per_arm = trial.n_arms > len(arms)
    if budget is not None and source != "primitives":
        raise ValueError("budget picks the description through the primitives: leave source")
    pieces = split_arms(trial) if per_arm else [trial]
    options = dict(budget_options or {})
    settings = _settings(budget, options).for_model(model)
    choice: dict[str, Any] | None = None
    alternatives = _alternatives(model, settings, options)
    if budget is not None and len(alternatives) > 1:
        parts, choice = _encoder_choice(
            model, pieces, source, name, float(budget), settings, alternatives
        )
    else:
        shares = _shares(model, pieces, budget, settings)
        parts = [
            _segment_and_rebuild(model, t, source, name, b, settings)
            for t, b in zip(pieces, shares, strict=True)
        ]
    times = parts[0].times
    human = np.concatenate([p.human for p in parts], axis=1)
    rebuild: Rebuild | ArmsRebuild = (
        ArmsRebuild([p.rebuild for p in parts]) if per_arm else parts[0].rebuild
    )
    bounds = np.concatenate([p.bounds for p in parts])
    labels = np.concatenate([p.labels for p in parts])
    distances = np.concatenate([p.distances for p in parts])
    segment_arm = np.concatenate([np.full(len(p.labels), i) for i, p in enumerate(parts)])

    inside = (times >= rebuild.start - 1e-9) & (times <= rebuild.end + 1e-9)
    # One evaluation on the frames and a fine grid together (inverse kinematics unwraps γ and
    # α along it), put on the human's whole turns.
    n_fine = max(2, int(np.ceil((rebuild.end - rebuild.start) / PLAY_SAMPLE_S)) + 1)
    frames = times[inside]
    fine = np.linspace(rebuild.start, rebuild.end, n_fine)
    # Fine points within a microsecond of a frame would make the grid not strictly increasing
    # once shifted to start at 0; the frame itself stands for them.
    after = np.clip(np.searchsorted(frames, fine), 0, frames.size - 1)
    before = np.clip(after - 1, 0, frames.size - 1)
    gap = np.minimum(np.abs(fine - frames[after]), np.abs(fine - frames[before]))
    grid = np.union1d(frames, fine[gap > 1e-6])
    grid_a, grid_v = rebuild(grid)
    rows = np.searchsorted(grid, times[inside])
    rebuild.turns = _turns(grid_a[rows], human[inside])
    grid_a = grid_a + rebuild.turns
    rb_a = np.full_like(human, np.nan)
    rb_v = np.full_like(human, np.nan)
    rb_a[inside], rb_v[inside] = grid_a[rows], grid_v[rows]
    # Each frame's segment: the first arm's that covers it (segment indices run arm by arm).
    seg_of = np.full(times.shape[0], -1, dtype=np.int64)
    first = 0
    for p in parts:
        own = _segment_of_frame(times, p.bounds)
        seg_of = np.where((seg_of < 0) & (own >= 0), own + first, seg_of)
        first += len(p.labels)
    cov = seg_of >= 0
    seg_method = parts[0].method

    t0, t1 = float(times[0]), float(times[-1])
    gaps = _uncovered(t0, t1, bounds[np.argsort(bounds[:, 0], kind="stable")])
    uncovered_s = float(sum(e - s for s, e in gaps))
    duration = t1 - t0
    metrics: dict[str, Any] = {
        "recording": str(trial.source or name),
        "name": name,
        "source": source,
        "source_label": SOURCE_LABELS[source],
        "frame_period_s": float(trial.frame_period),
        "segmentation": seg_method,
        "n_segments": int(bounds.shape[0]),
        "primitive_sequence": [int(k) for k in labels],
        "arms_imitated": "one by one" if per_arm else "together",
        "segments": [
            {"start_s": float(s), "end_s": float(e), "primitive": int(k), "distance_rad": float(d)}
            | ({"arm": ARM_SIDES[int(a)]} if per_arm else {})
            for (s, e), k, d, a in zip(bounds, labels, distances, segment_arm, strict=True)
        ],
        "human_duration_s": duration,
        "covered_span_s": rebuild.end - rebuild.start,
        "coverage": {
            "covered_s": duration - uncovered_s,
            "uncovered_s": uncovered_s,
            "uncovered_percent": 100.0 * uncovered_s / duration if duration > 0 else 0.0,
            "uncovered": [{"start_s": s, "end_s": e, "duration_s": e - s} for s, e in gaps],
        },
        "rebuild_vs_human_rms_deg": _angle_rms(rb_a[cov] - human[cov]),
        "rebuild_vs_human_joint_rms_deg": _joint_rms(*joint_space_errors(rb_a[cov], human[cov])),
        "rebuild_vs_human_direction_rms_deg": direction_rms_deg(rb_a[cov], human[cov]),
        "description": _description_metrics(parts, budget, choice),
    }

    playback = None
    adonis = None
    if dt is None:
        dt = DEFAULT_DT[servo]
    if play:
        playback, adonis = _play(rebuild.start, grid, grid_a, times, human, servo, dt, render_fps)
        metrics["adonis"] = _adonis_metrics(playback, adonis, rb_a, human, cov, servo, dt)
        metrics["adonis"]["time_ratio_full"] = playback.completion_time / duration
    metrics["headline"] = headline(metrics, labels.tolist(), still_direction_rms_deg(human[cov]))
    return Imitation(
        name=name,
        source=source,
        trial=trial,
        times=times,
        human=human,
        segments=bounds,
        primitives=labels,
        distances=distances,
        segment_of_frame=seg_of,
        rebuild=rebuild,
        rebuild_angles=rb_a,
        rebuild_velocities=rb_v,
        adonis_angles=adonis,
        playback=playback,
        metrics=metrics,
        segment_arm=segment_arm if per_arm else None,
    )


def _play(
    start: float,
    grid: NDArray[np.float64],
    angles: NDArray[np.float64],
    times: NDArray[np.float64],
    human: NDArray[np.float64],
    servo: Servo,
    dt: float,
    render_fps: float,
) -> tuple[Any, NDArray[np.float64]]:
    from visprim.sim.model import build_adonis
    from visprim.sim.playback import play
    from visprim.sim.sequencer import positions_to_angles

    adonis_model = build_adonis(dt)
    playback = play(grid, angles, dt=dt, render_fps=render_fps, servo=servo, model=adonis_model)
    # Adonis at the recording's frames, same clock (simulation time 0 = start).
    out = np.full_like(human, np.nan)
    played = (times >= start - 1e-9) & (times <= start + playback.times[-1] + 1e-9)
    steps = np.clip(
        np.rint((times[played] - start) / dt).astype(np.int64),
        0,
        playback.q_actual.shape[0] - 1,
    )
    q = playback.q_actual[steps]
    n_arms = human.shape[1] // 4
    out[played] = _same_branch(positions_to_angles(adonis_model[1], q, n_arms), human[played])
    return playback, out


def _adonis_metrics(
    playback: Any,
    adonis: NDArray[np.float64],
    rebuild: NDArray[np.float64],
    human: NDArray[np.float64],
    covered: NDArray[np.bool_],
    servo: str,
    dt: float,
) -> dict[str, Any]:
    sel = covered & np.isfinite(adonis[:, 0])
    missing = int(covered.sum() - sel.sum())
    return {
        "servo": servo,
        "dt_s": dt,
        "vs_human_joint_rms_deg": _joint_rms(*joint_space_errors(adonis[sel], human[sel])),
        "vs_rebuild_joint_rms_deg": _joint_rms(*joint_space_errors(adonis[sel], rebuild[sel])),
        "vs_human_rms_deg": _angle_rms(adonis[sel] - human[sel]),
        "vs_human_direction_rms_deg": direction_rms_deg(adonis[sel], human[sel]),
        "vs_setpoint_rms_deg": float(playback.rms_error_deg),
        "completion_time_s": float(playback.completion_time),
        "time_ratio": float(playback.completion_time / playback.movement_duration),
        "via_reached": int(playback.n_reached),
        "via_points": int(playback.n_via),
        "frames_compared": int(sel.sum()),
        "frames_not_played": missing,
        "wall_time_s": float(playback.wall_time),
    }


# ---------------------------------------------------------------------------- output


def trajectory_of(imitation: Imitation) -> Any:
    """The rebuild (what Adonis was asked to perform) as a URDF joint trajectory at the
    recording's frames inside the rebuilt span (:mod:`visprim.sim.export`)."""
    from visprim.sim.export import arm_trajectory

    inside = np.isfinite(imitation.rebuild_angles[:, 0])
    return arm_trajectory(
        imitation.times[inside],
        imitation.rebuild_angles[inside],
        imitation.rebuild_velocities[inside],
        f"{imitation.name}: {SOURCE_LABELS[imitation.source]}; time 0 = "
        f"{imitation.rebuild.start:.3f} s on the recording's clock (start of the first segment)",
    )


def imitation_csv(imitation: Imitation) -> str:
    """One row per frame of the recording: time (s), segment and primitive (-1 where no
    segment covers it), the human's, the rebuild's and Adonis's angles (rad) and the
    rebuild's angular velocities (rad/s); empty where a value does not exist."""
    import io

    buf = io.StringIO()
    _write_imitation_rows(imitation, buf)
    return buf.getvalue()


def _write_imitation_rows(imitation: Imitation, fh: Any) -> None:
    """Write :func:`imitation_csv`'s rows to the text file ``fh``, one at a time."""
    from visprim.csvfile import writer

    w = writer(fh)
    cols = ["time_s", "segment", "primitive"]
    for who in ("human", "rebuild", "adonis"):
        cols += [f"{who}_{a}_rad" for a in channel_names(imitation.human.shape[1])]
    cols += [f"rebuild_{a}_rad_s" for a in channel_names(imitation.human.shape[1])]
    w.writerow(cols)
    adonis = (
        imitation.adonis_angles
        if imitation.adonis_angles is not None
        else np.full_like(imitation.human, np.nan)
    )

    def fmt(row: NDArray[np.float64]) -> list[str]:
        return ["" if not np.isfinite(x) else f"{x:.7g}" for x in row]

    for i, t in enumerate(imitation.times):
        j = int(imitation.segment_of_frame[i])
        w.writerow(
            [f"{t:.6f}", j, int(imitation.primitives[j]) if j >= 0 else -1]
            + fmt(imitation.human[i])
            + fmt(imitation.rebuild_angles[i])
            + fmt(adonis[i])
            + fmt(imitation.rebuild_velocities[i])
        )


def write_imitation(
    imitation: Imitation,
    out_dir: str | Path,
    *,
    video: str | None = "imitation.gif",
    size: tuple[int, int] = (480, 480),
    extra: dict[str, Any] | None = None,
) -> dict[str, Path]:
    """Write the results of :func:`imitate` into ``out_dir`` (created):

    * ``imitation.json`` — :attr:`Imitation.metrics` (+ ``extra``) and the file list;
    * ``imitation.csv`` — the trajectories (:func:`imitation_csv`);
    * ``trajectory.json`` / ``trajectory.csv`` — the rebuild as URDF joint trajectory
      (:mod:`visprim.sim.export`);
    * the video ``video`` (a file name, .gif or .mp4; None for none): human beside Adonis.

    Nothing is written half-way: the video's format is checked first, every file is written
    into a hidden staging folder inside ``out_dir`` and moved into place (:func:`os.replace`)
    only once all of them exist; on failure the staging folder is removed. Returns the paths
    by kind.
    """
    import json
    import os
    import shutil
    import tempfile

    out = Path(out_dir)
    if video is not None:
        from visprim.sim.video import check_video_path

        if Path(video).name != video or video in ("", ".", ".."):
            raise ValueError(f"video must be a file name inside out_dir, got {video!r}")
        check_video_path(out / video)
    out.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=".imitation-", dir=out))
    try:
        names: dict[str, str] = {"csv": "imitation.csv"}
        with open(stage / names["csv"], "w", encoding="utf-8", newline="") as fh:
            _write_imitation_rows(imitation, fh)
        js, cs = trajectory_of(imitation).write(stage / "trajectory")
        names["trajectory_json"], names["trajectory_csv"] = js.name, cs.name
        if video is not None and imitation.playback is not None:
            from visprim.sim.sidebyside import render_imitation

            names["video"] = render_imitation(imitation, stage / video, size=size).name
        doc = {"headline": imitation.metrics.get("headline"), **imitation.metrics}
        doc.update(extra or {})
        doc["files"] = dict(names)
        names["json"] = "imitation.json"
        (stage / names["json"]).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        for name in names.values():
            os.replace(stage / name, out / name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return {kind: out / name for kind, name in names.items()}

"""From joint angles to what four FastTrak-like sensors report.

Steps (each documented with its default in :class:`Measurement`):

1. **Sensor placement.** Forward kinematics (:func:`visprim.arm.forward_kinematics`) gives
   shoulder S, elbow E, wrist W and the finger-sensor point F. The implied sensor points
   are ``mid(S, E)``, ``mid(E, W)``, ``W`` and ``F`` — exactly what inverse kinematics
   inverts (wrist = m3, elbow = 2 m2 − m3, shoulder = 2 m1 − elbow). Skin-mounted sensors
   sit off the bone axis: a per-subject offset vector in the segment's own frame is added
   (upper-arm offset rotates with the upper arm, the other three with the forearm/hand).
   The offsets are given for the zero posture (arm hanging, body axes +x forward, +y left,
   +z up): nominal :data:`SKIN_OFFSETS_M` — upper arm 20 mm, forearm 15 mm, wrist 10 mm
   and finger 8 mm on the lateral (dorsal) side, the wrist sensor also 15 mm proximal
   ("just above the wrist") — scaled per subject by 0.7–1.3 plus SD 3 mm per axis of
   placement error. With ``skin_offsets=False`` the sensors are exactly on the implied
   points.
2. **Shoulder position and drift.** The arm hangs from the subject's shoulder joint
   centre (fixed, from the body's dimensions) plus a slow drift of the trunk that moves
   all four sensors together: per axis a sum of 3 sinusoids with frequencies in
   0.05–0.4 Hz and random phases, RMS ``drift_rms_m`` (6 mm; 3 mm vertically) times a
   per-trial factor 0.5–1.5. Inverse kinematics in a shoulder-origin frame removes it.
3. **Vibration** of the strapped sensors: each sensor oscillates along its own random
   direction at its own frequency in 7–12 Hz (well above the 3.7 Hz cutoff of the
   method's low-pass: order 10, 0.25 of Nyquist at 34 ms), amplitude
   ``vibration_amplitude_m`` (1.2 mm) × 0.6–1.4, modulated by the sensor's speed (35 % at
   rest, up to 100 % when moving fast).
4. **Sensor error** of an electromagnetic tracker (FastTrak-like, ≈2 mm accuracy): a
   smooth, position-dependent *field distortion* — per session (subject) a sum of 4 plane
   waves in space with wavelengths 0.4–1.0 m, RMS ``distortion_rms_m`` (1.1 mm) per
   coordinate, so it changes only as a sensor moves — plus white Gaussian *jitter*, SD
   ``noise_sd_m`` (0.4 mm) per coordinate. Together a 3-D RMS error of ≈2 mm. (Polhemus
   specifies the FASTRAK's static accuracy as 0.76 mm RMS per axis and its resolution as
   ≈0.15 mm at 30 cm: most of the error of such trackers is a smooth distortion, not
   sample-to-sample noise.)
5. **Sampling** every ``frame_period_s`` (34 ms) with Gaussian timestamp jitter (SD 0.3 ms,
   clipped at ±0.9 ms); the first sample is at t = 0. The ground truth is evaluated at the
   jittered instants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from visprim.arm import BODY_TO_SHOULDER, ArmLengths, forward_kinematics, rot_y, shoulder_rotation
from visprim.params import STUDY_FRAME_PERIOD_S

#: Nominal sensor offsets (metres) in segment coordinates (body axes at the zero posture):
#: rows upper_arm, forearm, wrist, finger.
SKIN_OFFSETS_M: NDArray[np.float64] = np.array(
    [
        [0.0, -0.020, 0.0],
        [0.0, -0.015, 0.0],
        [0.0, -0.010, 0.015],
        [0.0, -0.008, 0.0],
    ]
)


@dataclass(frozen=True)
class Measurement:
    """Parameters of the simulated measurement (units in the names: s, m, Hz)."""

    frame_period_s: float = STUDY_FRAME_PERIOD_S
    jitter_sd_s: float = 0.0003
    noise_sd_m: float = 0.0004
    distortion_rms_m: float = 0.0011
    distortion_wavelength_m: tuple[float, float] = (0.4, 1.0)
    vibration_amplitude_m: float = 0.0012
    vibration_band_hz: tuple[float, float] = (7.0, 12.0)
    drift_rms_m: float = 0.006
    drift_band_hz: tuple[float, float] = (0.05, 0.4)


def sample_skin_offsets(rng: np.random.Generator) -> NDArray[np.float64]:
    """One subject's sensor offsets (4, 3) in metres (see the module docstring)."""
    scale = rng.uniform(0.7, 1.3, size=(4, 1))
    return SKIN_OFFSETS_M * scale + rng.normal(0.0, 0.003, size=(4, 3))


def sample_times(
    duration: float, rng: np.random.Generator | None, m: Measurement
) -> NDArray[np.float64]:
    """Sample instants (s) covering ``[0, duration]`` every ``m.frame_period_s``, jittered
    with ``rng`` (None: exactly periodic)."""
    n = int(np.floor(duration / m.frame_period_s)) + 1
    times = np.arange(n, dtype=np.float64) * m.frame_period_s
    if rng is not None:
        limit = 3 * m.jitter_sd_s
        jitter = np.clip(rng.normal(0.0, m.jitter_sd_s, size=n), -limit, limit)
        jitter[0] = 0.0
        times += jitter
    return times


def implied_points(
    angles: NDArray[np.float64], lengths: ArmLengths
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Joint centres (T, 4, 3) (shoulder, elbow, wrist, finger point) and the implied
    sensor points (T, 4, 3), body frame, shoulder at the origin, metres."""
    joints = forward_kinematics(angles, lengths)
    s, e, w, f = joints[:, 0], joints[:, 1], joints[:, 2], joints[:, 3]
    return joints, np.stack([0.5 * (s + e), 0.5 * (e + w), w, f], axis=1)


def segment_rotations(angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """Body-frame orientation (T, 4, 3, 3) of the segment carrying each sensor (identity at
    the zero posture): upper arm for sensor 1, forearm/hand for sensors 2–4."""
    m = BODY_TO_SHOULDER
    r = shoulder_rotation(angles)
    upper = m @ r @ m
    fore = m @ (r @ rot_y(angles[:, 3])) @ m
    return np.stack([upper, fore, fore, fore], axis=1)


def place_sensors(
    angles: NDArray[np.float64], lengths: ArmLengths, offsets: NDArray[np.float64] | None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sensor positions (T, 4, 3) relative to the shoulder (body frame, metres) and the joint
    centres (T, 4, 3). ``offsets`` (4, 3) in segment coordinates, or None for none."""
    joints, points = implied_points(angles, lengths)
    if offsets is not None:
        points = points + np.einsum("tkij,kj->tki", segment_rotations(angles), offsets)
    return points, joints


def shoulder_drift(
    times: NDArray[np.float64], rng: np.random.Generator, m: Measurement
) -> NDArray[np.float64]:
    """Slow trunk drift (T, 3) in metres: per axis 3 sinusoids in ``m.drift_band_hz``."""
    t = np.asarray(times, dtype=np.float64)
    freqs = rng.uniform(*m.drift_band_hz, size=(3, 3))
    phases = rng.uniform(0.0, 2 * np.pi, size=(3, 3))
    weights = rng.uniform(0.3, 1.0, size=(3, 3))
    rms = m.drift_rms_m * rng.uniform(0.5, 1.5) * np.array([1.0, 1.0, 0.5])
    # sum of sinusoids with amplitudes a_i has RMS sqrt(sum a_i^2 / 2)
    amps = weights * (rms / np.sqrt(0.5 * np.sum(weights**2, axis=1)))[:, None]
    waves = np.sin(2 * np.pi * freqs[None] * t[:, None, None] + phases[None])
    return np.sum(amps[None] * waves, axis=2)


def vibration(
    times: NDArray[np.float64],
    speed: NDArray[np.float64],
    rng: np.random.Generator,
    m: Measurement,
) -> NDArray[np.float64]:
    """High-frequency sensor vibration (T, 4, 3) in metres; ``speed`` (T, 4) in m/s."""
    t = np.asarray(times, dtype=np.float64)
    direction = rng.normal(size=(4, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    freq = rng.uniform(*m.vibration_band_hz, size=4)
    phase = rng.uniform(0.0, 2 * np.pi, size=4)
    amp = m.vibration_amplitude_m * rng.uniform(0.6, 1.4, size=4)
    envelope = 0.35 + 0.65 * np.tanh(np.asarray(speed) / 0.8)
    wave = np.sin(2 * np.pi * freq[None] * t[:, None] + phase[None]) * envelope * amp[None]
    return wave[:, :, None] * direction[None]


@dataclass(frozen=True)
class DistortionField:
    """A smooth spatial error field of the tracker (one per session).

    ``error(p) = Σ_k amplitude[k] * sin(2π wavevector[k]·p + phase[k])`` with wave vectors
    in 1/m, amplitudes and the resulting error in metres.
    """

    wavevector: NDArray[np.float64]  # (K, 3), 1/m
    amplitude: NDArray[np.float64]  # (K, 3), m (one per error coordinate)
    phase: NDArray[np.float64]  # (K, 3), rad

    def __call__(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Error vectors (..., 3) in metres at ``points`` (..., 3) in metres."""
        arg = np.einsum("...j,kj->...k", points, self.wavevector)[..., None] * (2 * np.pi)
        return np.sum(self.amplitude * np.sin(arg + self.phase), axis=-2)


def sample_distortion(
    rng: np.random.Generator, m: Measurement, n_waves: int = 4
) -> DistortionField:
    """One session's field distortion (see the module docstring)."""
    direction = rng.normal(size=(n_waves, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    wavelength = rng.uniform(*m.distortion_wavelength_m, size=(n_waves, 1))
    weights = rng.uniform(0.3, 1.0, size=(n_waves, 3))
    # a sum of sinusoids with amplitudes a_k has RMS sqrt(sum a_k^2 / 2) over space
    amplitude = weights * (m.distortion_rms_m / np.sqrt(0.5 * np.sum(weights**2, axis=0)))
    phase = rng.uniform(0.0, 2 * np.pi, size=(n_waves, 3))
    return DistortionField(direction / wavelength, amplitude, phase)


def sensor_noise(
    shape: tuple[int, ...], rng: np.random.Generator, m: Measurement
) -> NDArray[np.float64]:
    """White Gaussian position jitter, SD ``m.noise_sd_m`` metres."""
    return rng.normal(0.0, m.noise_sd_m, size=shape)

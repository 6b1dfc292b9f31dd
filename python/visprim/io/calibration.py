"""Camera calibrations: Qualisys QCA and Pose2Sim/OpenCV TOML → pinhole cameras with lens
distortion.

A :class:`Camera` follows OpenCV's conventions: ``R``, ``t`` map world points (metres) to
camera coordinates (x right, y down, z forward), ``K`` is the pixel matrix and ``dist`` the
distortion ``(k1, k2, p1, p2, k3)`` of OpenCV's radial-tangential model.

Qualisys QCA (XML, ``<calibration><cameras><camera serial=...>``), converted as Pose2Sim's
reader does (``Pose2Sim/calibration.py``, ``read_qca``), validated here by the reprojection
error of the four-view triangulation of the shared Pose2Sim clip (``benches/video_accuracy.py``):

* ``<transform>``: position ``x, y, z`` of the camera in millimetres and a rotation
  ``r11 … r33``; the world-to-camera rotation is ``Rx(π) · M`` with ``M = [[r11, r12, r13],
  [r21, r22, r23], [r31, r32, r33]]`` and ``t = −Rx(π) · M · c`` (``c`` the position in
  metres; ``Rx(π)`` turns Qualisys' camera axes, y up and looking along −z, into OpenCV's);
* ``<intrinsic>``: focal lengths and principal point in 1/64 sub-pixel sensor units (÷ 64
  for pixels; the principal point relative to the ``fov_video`` corner), radial
  ``radialDistortion1–2`` and tangential ``tangentalDistortion1–2`` coefficients, also
  ÷ 64 as Pose2Sim reads them (its TOML → QCA writer multiplies them by 64, and the shared
  clip's file was written that way); ``radialDistortion3`` is ignored, as Pose2Sim does;
* ``<fov_video>``: the image size (``right − left + 1`` × ``bottom − top + 1``).

Pose2Sim/OpenCV TOML (what Pose2Sim's calibration writes, also anipose's layout): one table
per camera with ``name``, ``size = [width, height]`` px, ``matrix`` (3 × 3 ``K``),
``distortions = [k1, k2, p1, p2]`` (optionally ``k3``), ``rotation`` (a Rodrigues vector,
world → camera, rad), ``translation`` (m) and ``fisheye`` (only ``false`` is supported);
tables without ``matrix`` (``metadata``...) are skipped. Validated in the tests by reading
the QCA file converted with Pose2Sim's formulas (``calib_qca_fun``) and comparing the
projections of the same 3-D points through both readers.

**A video frame of another size than the calibrated image** (:meth:`Camera.fitted_to`,
applied by :func:`visprim.io.views.triangulate_poses` wherever a view's frame size differs
from its camera's ``size``): the calibrated image is taken to have been scaled uniformly to
fit inside the frame and centred, the rest padded (letterbox / pillarbox: what ffmpeg's
``scale=W:H:force_original_aspect_ratio=decrease,pad=W:H:(ow-iw)/2:(oh-ih)/2`` and most
editors' "fit" make). With ``s = min(W'/W, H'/H)`` and offsets ``o = ((W' − sW)/2,
(H' − sH)/2)``, a calibrated pixel ``p`` (pixel centres at integers) lands at
``s·(p + ½) − ½ + o``: ``K``'s focal lengths scale by ``s`` and its principal point maps
like a pixel; distortion, in normalised coordinates, is unchanged. A frame of the
calibration's aspect ratio is a plain scale (``o = 0``), e.g. a half-size copy.

The shared Pose2Sim clip needs it: its calibration is 1088 × 1920 px for every camera, and
cam01/cam02's videos are 1080 × 1920 with 7 black rows above and below the picture.
Registering their first frame to Pose2Sim's own 1088 × 1920 image of the same camera
(``calibration/extrinsics/cam0N_ext.png`` in Pose2Sim's ``Demo_SinglePerson``; SIFT matches,
affine fit, 0.4–0.5 px residual) gives ``u' = 0.9928 u − 0.02``, ``v' = 0.9926 v + 7.2``
(cam01) and ``0.9926 u + 0.09``, ``0.9926 v + 7.19`` (cam02), against the rule's
``0.9926 u − 0.004``, ``0.9926 v + 7.05``; cam03/cam04's 1088 × 1920 videos register to
their images as the identity (scale 1.0000, offsets < 0.1 px). Without the fit, cam01/02's
keypoints are off by up to 7 px (about 4 px at the person, near the image centre). It is
not a codec crop (H.264 stores 1080 as 1088 and crops 8): a crop leaves no black rows, and
chosen on half of the clip's frames, no crop hypothesis scores better on the other half
(``benches/video_frame_fit.py``).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from visprim.io.errors import MalformedFileError, ReadError

__all__ = ["Camera", "frame_fit", "read_calibration", "read_qca", "read_toml", "rodrigues"]

_RX_PI = np.diag([1.0, -1.0, -1.0])
#: QCA distortion coefficients are stored × 64 (Pose2Sim's convention, see the module docstring).
QCA_DISTORTION_SCALE = 64.0
#: Fixed-point iterations of :meth:`Camera.undistort` (converged to < 1e-9 px for the
#: distortions of ordinary lenses; checked against :meth:`Camera.project` in the tests).
UNDISTORT_ITERATIONS = 20


@dataclass(frozen=True)
class Camera:
    """One calibrated camera (see the module docstring); ``size`` = (width, height) px."""

    name: str
    size: tuple[int, int]
    K: NDArray[np.float64]
    dist: NDArray[np.float64]
    R: NDArray[np.float64]
    t: NDArray[np.float64]

    def fitted_to(self, size: tuple[int, int]) -> Camera:
        """This camera for a video frame of ``size`` (width, height) px into which its
        calibrated image was scaled uniformly and centred (see the module docstring);
        ``self`` when the sizes are equal."""
        w, h = int(size[0]), int(size[1])
        if w <= 0 or h <= 0:
            raise ValueError(f"frame size must be positive, got {size!r}")
        if (w, h) == tuple(self.size):
            return self
        s, ox, oy = frame_fit(self.size, (w, h))
        k = self.K.copy()
        k[0, 0] *= s
        k[1, 1] *= s
        k[0, 1] *= s
        k[0, 2] = s * (k[0, 2] + 0.5) - 0.5 + ox
        k[1, 2] = s * (k[1, 2] + 0.5) - 0.5 + oy
        return Camera(name=self.name, size=(w, h), K=k, dist=self.dist, R=self.R, t=self.t)

    @property
    def projection(self) -> NDArray[np.float64]:
        """``[R | t]`` (3 × 4): world points → normalised image coordinates."""
        return np.hstack([self.R, self.t[:, None]])

    @property
    def centre(self) -> NDArray[np.float64]:
        """The camera's position in the world (m)."""
        return -self.R.T @ self.t

    def _distort(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        k1, k2, p1, p2, k3 = self.dist
        x, y = xy[..., 0], xy[..., 1]
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return np.stack([xd, yd], axis=-1)

    def project(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """World points (…, 3) m → pixels (…, 2), lens distortion included."""
        c = points @ self.R.T + self.t
        with np.errstate(invalid="ignore", divide="ignore"):
            xy = c[..., :2] / c[..., 2:3]
        d = self._distort(xy)
        return np.stack(
            [self.K[0, 0] * d[..., 0] + self.K[0, 2], self.K[1, 1] * d[..., 1] + self.K[1, 2]],
            axis=-1,
        )

    def undistort(self, pixels: NDArray[np.float64]) -> NDArray[np.float64]:
        """Pixels (…, 2) → undistorted normalised image coordinates (…, 2) (the inverse of
        :meth:`project`'s last two steps, by fixed-point iteration; NaN stays NaN)."""
        xd = np.stack(
            [
                (pixels[..., 0] - self.K[0, 2]) / self.K[0, 0],
                (pixels[..., 1] - self.K[1, 2]) / self.K[1, 1],
            ],
            axis=-1,
        )
        k1, k2, p1, p2, k3 = self.dist
        xy = xd.copy()
        for _ in range(UNDISTORT_ITERATIONS):
            x, y = xy[..., 0], xy[..., 1]
            r2 = x * x + y * y
            radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
            dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
            dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
            xy = np.stack([(xd[..., 0] - dx) / radial, (xd[..., 1] - dy) / radial], axis=-1)
        return xy


def frame_fit(calibrated: tuple[int, int], frame: tuple[int, int]) -> tuple[float, float, float]:
    """Scale ``s`` and offsets ``(ox, oy)`` px of a calibrated image (width, height) fitted
    uniformly and centred into a frame (width, height) (see the module docstring)."""
    cw, ch = float(calibrated[0]), float(calibrated[1])
    fw, fh = float(frame[0]), float(frame[1])
    s = min(fw / cw, fh / ch)
    return s, (fw - s * cw) / 2, (fh - s * ch) / 2


def _float(path: Path, el: ET.Element, key: str) -> float:
    raw = el.get(key)
    if raw is None:
        raise MalformedFileError(path, f"<{el.tag}> has no {key}")
    try:
        value = float(raw)
    except ValueError:
        raise MalformedFileError(path, f"<{el.tag}> {key}={raw!r} is not a number") from None
    if not np.isfinite(value):
        raise MalformedFileError(path, f"<{el.tag}> {key} is not finite")
    return value


def read_qca(path: str | os.PathLike[str]) -> list[Camera]:
    """The cameras of a Qualisys QCA calibration, in file order (see the module docstring).

    Raises :class:`ReadError` naming the file and the problem.
    """
    p = Path(path)
    try:
        root = ET.parse(p).getroot()
    except OSError as exc:
        raise ReadError(p, f"cannot read: {exc.strerror or exc}") from None
    except ET.ParseError as exc:
        raise MalformedFileError(p, f"not XML ({exc})") from None
    cams = root.findall("cameras/camera")
    if not cams:
        raise MalformedFileError(p, "no <cameras><camera> elements (not a QCA calibration?)")
    out = []
    for i, cam in enumerate(cams):
        name = cam.get("serial") or f"camera{i + 1}"
        tr, intr, fov = cam.find("transform"), cam.find("intrinsic"), cam.find("fov_video")
        if tr is None or intr is None or fov is None:
            raise MalformedFileError(
                p, f"camera {name} lacks <transform>, <intrinsic> or <fov_video>"
            )
        m = np.array(
            [[_float(p, tr, f"r{r}{c}") for c in (1, 2, 3)] for r in (1, 2, 3)], dtype=np.float64
        )
        if not np.allclose(m @ m.T, np.eye(3), atol=1e-6) or np.linalg.det(m) < 0:
            raise MalformedFileError(p, f"camera {name}: the transform is not a rotation")
        centre = np.array([_float(p, tr, k) for k in ("x", "y", "z")]) / 1000.0
        left, top = _float(p, fov, "left"), _float(p, fov, "top")
        size = (
            int(_float(p, fov, "right") - left + 1),
            int(_float(p, fov, "bottom") - top + 1),
        )
        fu, fv = _float(p, intr, "focalLengthU") / 64, _float(p, intr, "focalLengthV") / 64
        if fu <= 0 or fv <= 0:
            raise MalformedFileError(p, f"camera {name}: focal lengths must be positive")
        cu = _float(p, intr, "centerPointU") / 64 - left
        cv = _float(p, intr, "centerPointV") / 64 - top
        k = np.array([[fu, 0.0, cu], [0.0, fv, cv], [0.0, 0.0, 1.0]])
        dist = np.array(
            [
                _float(p, intr, "radialDistortion1"),
                _float(p, intr, "radialDistortion2"),
                _float(p, intr, "tangentalDistortion1"),
                _float(p, intr, "tangentalDistortion2"),
                0.0,
            ]
        )
        dist[:4] /= QCA_DISTORTION_SCALE
        rot = _RX_PI @ m
        out.append(Camera(name=name, size=size, K=k, dist=dist, R=rot, t=-rot @ centre))
    return out


def rodrigues(vector: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrix (3 × 3) of a Rodrigues vector (axis × angle, rad), as OpenCV's
    ``cv2.Rodrigues``."""
    v = np.asarray(vector, dtype=np.float64)
    theta = float(np.linalg.norm(v))
    if theta < 1e-12:
        return np.eye(3)
    k = v / theta
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * (kx @ kx)


def _numbers(
    p: Path, cam: str, table: dict[str, object], key: str, shape: tuple[int, ...]
) -> NDArray[np.float64]:
    if key not in table:
        raise MalformedFileError(p, f"camera {cam} has no {key}")
    try:
        a = np.asarray(table[key], dtype=np.float64)
    except (TypeError, ValueError):
        raise MalformedFileError(p, f"camera {cam}: {key} is not numbers") from None
    if a.shape != shape or not np.isfinite(a).all():
        raise MalformedFileError(
            p, f"camera {cam}: {key} must be {shape} finite numbers, got shape {a.shape}"
        )
    return a


def read_toml(path: str | os.PathLike[str]) -> list[Camera]:
    """The cameras of a Pose2Sim/OpenCV TOML calibration, in file order (see the module
    docstring). Raises :class:`ReadError` naming the file and the problem."""
    import tomllib

    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ReadError(p, f"cannot read: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise MalformedFileError(p, f"not TOML ({exc})") from None
    out = []
    for key, table in data.items():
        if not isinstance(table, dict) or "matrix" not in table:
            continue
        name = str(table.get("name", key))
        if table.get("fisheye", False):
            raise MalformedFileError(p, f"camera {name}: fisheye lenses are not supported")
        size = _numbers(p, name, table, "size", (2,))
        k = _numbers(p, name, table, "matrix", (3, 3))
        if k[0, 0] <= 0 or k[1, 1] <= 0:
            raise MalformedFileError(p, f"camera {name}: focal lengths must be positive")
        raw = np.asarray(table.get("distortions", []), dtype=np.float64).ravel()
        if raw.size not in (4, 5) or not np.isfinite(raw).all():
            raise MalformedFileError(
                p, f"camera {name}: distortions must be 4 or 5 numbers (k1, k2, p1, p2[, k3])"
            )
        dist = np.zeros(5)
        dist[: raw.size] = raw
        rot = rodrigues(_numbers(p, name, table, "rotation", (3,)))
        t = _numbers(p, name, table, "translation", (3,))
        out.append(Camera(name=name, size=(int(size[0]), int(size[1])), K=k, dist=dist, R=rot, t=t))
    if not out:
        raise MalformedFileError(p, "no camera tables (with a matrix) in this TOML file")
    return out


def read_calibration(path: str | os.PathLike[str]) -> list[Camera]:
    """Cameras from a calibration file: Qualisys QCA (``.qca``, ``.qca.txt``) or
    Pose2Sim/OpenCV TOML (``.toml``)."""
    p = Path(path)
    name = p.name.lower()
    if name.endswith(".qca") or name.endswith(".qca.txt"):
        return read_qca(p)
    if name.endswith(".toml"):
        return read_toml(p)
    raise ReadError(p, "unknown calibration format; supported: Qualisys .qca / .qca.txt, .toml")

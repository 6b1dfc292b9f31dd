"""The report's figures (matplotlib, object API, no global state; PNG via the Agg canvas).

Every ``plot_*`` function draws one figure, writes it to ``path`` and returns the path; the
``*_figure`` functions it uses return the :class:`~matplotlib.figure.Figure` itself. Angles
are plotted in **degrees**, times in seconds; the data given to the functions are radians.

What a model's segment vectors are made of (:mod:`visprim.features`) decides how its
eigenvectors, primitives, eigenvalues and SEG-2 speed are drawn and labelled
(:class:`Channels`): Z-Y-Z angles in degrees, or the components of the unit upper-arm and
forearm vectors in the shoulder frame (x forward, y outward: right for the right arm, left
for the mirrored left arm, z down), dimensionless.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import ArrayLike, NDArray

from visprim.arm import ANGLE_NAMES
from visprim.features import n_channels

#: Axis labels of the four angles.
ANGLE_LABELS: tuple[str, ...] = (
    "γ shoulder azimuth",
    "β shoulder elevation",
    "α humeral rotation",
    "θ elbow flexion",
)
_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red")
_DPI = 110
_RAD2 = float(np.degrees(1.0)) ** 2

assert len(ANGLE_LABELS) == len(ANGLE_NAMES)


#: The shoulder frame's axes, as the direction components are labelled.
_AXES = ("x fwd", "y out", "z down")
_AXIS_COLORS = ("tab:blue", "tab:orange", "tab:green")
_LEFT_COLORS = ("tab:red", "tab:purple", "tab:brown", "tab:olive")


@dataclass(frozen=True)
class Channels:
    """What the channels of a model's segment vectors are, for drawing them.

    ``features`` ``"zyz"`` (4 angles per arm, radians, drawn in degrees) or
    ``"directions"`` (upper-arm and forearm unit vectors, 6 components per arm,
    dimensionless); ``arms`` the arms, channel blocks in that order; ``offsets`` ``"mean"``
    when each channel of a segment vector is taken relative to its mean over the segment
    (:mod:`visprim.vectors`), so that curves are changes from the segment's mean posture.
    """

    features: str = "zyz"
    arms: tuple[str, ...] = ("right",)
    offsets: str = "turns"

    @classmethod
    def of(cls, model: Any) -> Channels:
        """The channels of a fitted :class:`~visprim.model.PrimitiveModel`."""
        return cls(
            str(getattr(model, "features", "zyz")),
            tuple(getattr(model, "arms_", ("right",))),
            str(getattr(model, "offsets", "turns")),
        )

    @property
    def n(self) -> int:
        """Channels per frame."""
        return n_channels(self.features, len(self.arms))

    @property
    def is_angles(self) -> bool:
        return self.features == "zyz"

    @property
    def scale(self) -> float:
        """Factor from the stored values to the drawn ones (radians to degrees for angles)."""
        return float(np.degrees(1.0)) if self.is_angles else 1.0

    def styles(self) -> list[tuple[str, str, str]]:
        """``(label, colour, line style)`` of each channel."""
        out = []
        two = len(self.arms) > 1
        for a, arm in enumerate(self.arms):
            prefix = f"{arm} " if two else ""
            if self.is_angles:
                angle_colors = _COLORS if a == 0 else _LEFT_COLORS
                for j, label in enumerate(ANGLE_LABELS):
                    out.append((prefix + label, angle_colors[j], "-" if a == 0 else "--"))
                continue
            axis_colors = _AXIS_COLORS if a == 0 else _LEFT_COLORS[1:]
            for bone, ls in (("upper arm", "-"), ("forearm", "--" if a == 0 else ":")):
                for j, axis in enumerate(_AXES):
                    out.append((f"{prefix}{bone} {axis}", axis_colors[j], ls))
        return out

    @property
    def value_label(self) -> str:
        """Y label of channel curves (primitives)."""
        if self.is_angles:
            return "deg, from segment mean" if self.offsets == "mean" else "deg"
        if self.offsets == "mean":
            return "unit-vector component,\nfrom segment mean"
        return "unit-vector component"

    @property
    def what(self) -> str:
        """What the channels are, for titles and captions."""
        if self.is_angles:
            return "the four Z-Y-Z arm angles (degrees)"
        return (
            "the components of the unit upper-arm (solid) and forearm (dashed) vectors in the "
            "shoulder frame (x forward, y outward, z down; dimensionless)"
        )

    @property
    def variance_unit(self) -> str:
        """Unit of eigenvalues and squared errors of segment vectors."""
        return "deg²" if self.is_angles else "(unit-vector component)²"

    @property
    def variance_scale(self) -> float:
        return self.scale**2

    @property
    def z_label(self) -> str:
        """SEG-2's z(t): summed squared angular velocities of the angles, or of the bones."""
        if self.is_angles:
            return "z(t) = Σ θ̇ᵢ², squared angle velocities"
        return "z(t) = |u̇|² + |ḟ|², squared bone angular speeds"


def save_figure(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as a PNG to ``path`` (folder created) and return ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _wrap(title: str, width: int = 95) -> str:
    """Break a long title into lines so that it is never clipped at the figure's edge."""
    import textwrap

    return "\n".join(textwrap.wrap(title, width)) if len(title) > width else title


def _truth_ticks(ax, boundaries: NDArray[np.float64]) -> None:  # type: ignore[no-untyped-def]
    """True boundaries as small triangles under the axis: nothing like a cut line."""
    ax.plot(
        boundaries,
        np.zeros_like(boundaries),
        "^",
        ms=6,
        color="k",
        alpha=0.7,
        transform=ax.get_xaxis_transform(),
        clip_on=False,
    )


_SEGMENT_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def plot_segmentation(
    path: Path,
    times: ArrayLike,
    angles: ArrayLike,
    crossings_time: ArrayLike,
    crossings_dof: ArrayLike,
    segments: ArrayLike,
    *,
    truth_boundaries: ArrayLike | None = None,
    title: str = "",
) -> Path:
    """Paper Fig. 5: the four angles, one coloured curve per SEG-1 segment with its cut
    points (vertical bars), each angle's zero-velocity crossings (open dots), and the true
    stroke boundaries, when known, as triangles under each axis (not lines, so they are not
    taken for cuts). Between segments (SEG-1 does not partition) the angle is drawn grey."""
    t = np.asarray(times)
    a = np.degrees(np.asarray(angles))
    ct = np.asarray(crossings_time)
    cd = np.asarray(crossings_dof)
    seg = np.asarray(segments).reshape(-1, 2)
    tb = None if truth_boundaries is None else np.asarray(truth_boundaries, dtype=np.float64)
    fig = Figure(figsize=(10, 8), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    for j, ax in enumerate(axes):
        ax.plot(t, a[:, j], color="0.7", lw=1.0)
        for i, (s0, e0) in enumerate(seg):
            m = (t >= s0) & (t <= e0)
            color = _SEGMENT_COLORS[i % len(_SEGMENT_COLORS)]
            ax.plot(t[m], a[m, j], color=color, lw=1.8)
            for x in (s0, e0):
                y = float(np.interp(x, t, a[:, j]))
                ax.plot([x], [y], "|", ms=14, mew=2.0, color="k")
        m = cd == j
        if np.any(m):
            ax.plot(ct[m], np.interp(ct[m], t, a[:, j]), "o", ms=4, mfc="white", mec="0.3")
        if tb is not None:
            _truth_ticks(ax, tb)
        ax.set_ylabel(f"{ANGLE_LABELS[j]}\n(deg)", fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    handles = [
        axes[0].plot([], [], "o", mfc="white", mec="0.3", ms=4)[0],
        axes[0].plot([], [], color="0.7")[0],
    ]
    labels = ["zero-velocity crossing", "not in a segment"]
    if seg.size:
        handles[:0] = [
            axes[0].plot([], [], color="tab:blue", lw=1.8)[0],
            axes[0].plot([], [], "|", ms=12, mew=2.0, color="k")[0],
        ]
        labels[:0] = ["SEG-1 segment (one colour each)", "cut point"]
    else:
        labels[-1] = "no SEG-1 segment in this trial"
    if tb is not None:
        handles.append(axes[0].plot([], [], "^", color="k", alpha=0.7)[0])
        labels.append("true stroke boundary (generator)")
    fig.legend(handles, labels, loc="outside lower center", ncols=5, fontsize=8)
    fig.suptitle(
        _wrap(title or "Fig. 5: segmentation at zero-velocity crossings (SEG-1)"),
        x=0.02,
        ha="left",
        fontsize=11,
    )
    return save_figure(fig, path)


def seg2_figure(
    times: ArrayLike,
    z: ArrayLike,
    threshold: float,
    segments: ArrayLike,
    *,
    truth_boundaries: ArrayLike | None = None,
    edge_s: float = 0.0,
    title: str = "",
    channels: Channels | None = None,
) -> Figure:
    """Paper Fig. 6 (see :func:`plot_seg2`)."""
    ch = channels or Channels()
    t = np.asarray(times)
    zz = np.asarray(z) * _RAD2
    c = float(threshold) * _RAD2
    seg = np.asarray(segments).reshape(-1, 2)
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax = fig.subplots()
    floor = c * 1e-4
    ax.semilogy(t, np.maximum(zz, floor), color="tab:purple", lw=1.3, label=ch.z_label)
    ax.axhline(c, color="tab:red", lw=1.2, label=f"threshold c = {c:.4g} (deg/s)²")
    if edge_s > 0 and t.size > 1:
        inner = (t >= t[0] + edge_s) & (t <= t[-1] - edge_s)
        ax.axvspan(t[0], t[0] + edge_s, color="0.85", lw=0, label="filter edge transient")
        ax.axvspan(t[-1] - edge_s, t[-1], color="0.85", lw=0)
        if np.any(inner):
            top = float(np.max(zz[inner]))
            ax.set_ylim(floor, max(top, c) * 3.0)
    bounds = np.unique(seg.ravel()) if seg.size else np.zeros(0)
    for i, b in enumerate(bounds):
        ax.axvline(b, color="tab:green", lw=1.2, label="SEG-2 boundary" if i == 0 else None)
    if truth_boundaries is not None:
        tb = np.asarray(truth_boundaries, dtype=np.float64)
        _truth_ticks(ax, tb)
        ax.plot([], [], "^", color="k", alpha=0.7, label="true stroke boundary (generator)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("z (deg/s)²")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    speed = "angular velocity" if ch.is_angles else "bone angular speed"
    ax.set_title(
        _wrap(title or f"Fig. 6: SEG-2, summed squared {speed} and its threshold"),
        loc="left",
        fontsize=11,
    )
    return fig


def plot_seg2(
    path: Path,
    times: ArrayLike,
    z: ArrayLike,
    threshold: float,
    segments: ArrayLike,
    *,
    truth_boundaries: ArrayLike | None = None,
    edge_s: float = 0.0,
    title: str = "",
    channels: Channels | None = None,
) -> Path:
    """Paper Fig. 6: SEG-2's ``z(t)`` in (deg/s)² (log scale) — ``Σ θ̇ᵢ²`` of the angles, or
    ``|u̇|² + |ḟ|²``, the squared angular speeds of the two bones, for a direction model
    (``channels``) — with the threshold c in the same unit (as the command line prints it)
    and the boundaries it yields. ``z`` and ``threshold`` are in (rad/s)².

    ``edge_s`` seconds at each end of the trial are shaded: there the zero-phase filter's
    edge transients dominate z(t); the y range is set from the interior only."""
    fig = seg2_figure(
        times,
        z,
        threshold,
        segments,
        truth_boundaries=truth_boundaries,
        edge_s=edge_s,
        title=title,
        channels=channels,
    )
    return save_figure(fig, path)


def eigenvalues_figure(
    eigenvalues: ArrayLike, n_components: int, *, channels: Channels | None = None
) -> Figure:
    """Paper Fig. 7 (see :func:`plot_eigenvalues`)."""
    ch = channels or Channels()
    lam = np.clip(np.asarray(eigenvalues, dtype=np.float64), 0.0, None) * ch.variance_scale
    total = lam.sum()
    idx = np.arange(1, lam.size + 1)
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    pos = lam > 0
    ax1.semilogy(idx[pos], lam[pos], ".-", color="tab:blue", ms=3, lw=0.8)
    ax1.axvline(n_components, color="tab:red", ls="--", lw=1, label=f"f = {n_components}")
    ax1.set_xlabel("eigenvalue index")
    ax1.set_ylabel(f"eigenvalue {ch.variance_unit}")
    ax1.set_title("Eigenvalue spectrum", loc="left", fontsize=10)
    ax1.grid(alpha=0.3, which="both")
    ax1.legend()
    n_show = min(lam.size, max(4 * n_components, 100))
    residual = (total - np.cumsum(lam)) / total * 100 if total > 0 else np.zeros_like(lam)
    f_axis = idx[:n_show]
    res = residual[:n_show]
    keep = res > 0
    ax2.semilogy(f_axis[keep], res[keep], color="tab:green")
    ax2.axvline(n_components, color="tab:red", ls="--", lw=1)
    if 1 <= n_components <= residual.size and residual[n_components - 1] > 0:
        r = float(residual[n_components - 1])
        ax2.plot([n_components], [r], "o", color="tab:red")
        ax2.annotate(
            f"{r:.3g} % left at f = {n_components}",
            (n_components, r),
            xytext=(8, 8),
            textcoords="offset points",
            fontsize=9,
        )
    ax2.set_xlabel("number of eigenvectors f")
    ax2.set_ylabel("residual variance (% of total, log)")
    ax2.set_title("Variance not captured by the first f eigenvectors", loc="left", fontsize=10)
    ax2.grid(alpha=0.3, which="both")
    fig.suptitle("Fig. 7: eigenvalues of the segment covariance", x=0.02, ha="left")
    return fig


def plot_eigenvalues(
    path: Path, eigenvalues: ArrayLike, n_components: int, *, channels: Channels | None = None
) -> Path:
    """Paper Fig. 7: the eigenvalue spectrum of K (log scale; deg² for angle vectors,
    squared unit-vector components for direction vectors, ``channels``) and the residual
    variance left by the first f eigenvectors (% of the total, log scale: the projection
    error of Table 1 relative to the total variance). Eigenvalues are given in rad² (the
    vectors' own unit)."""
    return save_figure(eigenvalues_figure(eigenvalues, n_components, channels=channels), path)


def _curves_grid(
    curves: NDArray[np.float64],
    titles: Sequence[str],
    suptitle: str,
    ylabel: str,
    ncols: int,
    channels: Channels,
    *,
    durations: ArrayLike | None = None,
    scale: float = 1.0,
) -> Figure:
    """Panels of one curve per channel each (``(n, samples, C)`` values times ``scale``);
    x in % of the segment (or s if durations)."""
    n = curves.shape[0]
    styles = channels.styles()
    if curves.shape[2] != len(styles):
        raise ValueError(f"curves have {curves.shape[2]} channels, expected {len(styles)}")
    nrows = int(np.ceil(n / ncols))
    legend_rows = int(np.ceil(len(styles) / 6))
    width, height = 2.6 * ncols, 2.1 * nrows + 0.8 + 0.25 * legend_rows
    # A fixed layout (inches converted to figure fractions): constrained layout costs
    # seconds per figure with dozens of panels.
    fig = Figure(figsize=(width, height))
    fig.subplots_adjust(
        left=0.75 / width,
        right=1 - 0.1 / width,
        top=1 - 0.8 / height,
        bottom=(0.55 + 0.25 * legend_rows) / height,
        wspace=0.12,
        hspace=0.45,
    )
    axes = np.atleast_1d(fig.subplots(nrows, ncols, sharey=True, squeeze=False)).ravel()
    x_pct = np.linspace(0, 100, curves.shape[1])
    for i, ax in enumerate(axes):
        if i >= n:
            ax.set_axis_off()
            continue
        x = (
            x_pct
            if durations is None
            else np.linspace(0, float(np.asarray(durations)[i]), curves.shape[1])
        )
        for j, (label, color, ls) in enumerate(styles):
            ax.plot(x, curves[i, :, j] * scale, color=color, ls=ls, lw=1.2, label=label)
        ax.set_title(titles[i], fontsize=8)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_major_locator(MaxNLocator(3))
        ax.yaxis.set_major_locator(MaxNLocator(4))
        if i % ncols == 0:
            ax.set_ylabel(ylabel, fontsize=8)
        if i >= n - ncols:
            ax.set_xlabel("% of segment" if durations is None else "time (s)", fontsize=8)
    handles = [axes[0].plot([], [], color=c, ls=ls)[0] for _, c, ls in styles]
    fig.legend(
        handles,
        [label for label, _, _ in styles],
        loc="lower center",
        ncols=min(len(styles), 6 if ncols >= 4 else 3),
        fontsize=8 if len(styles) > 4 else 9,
        frameon=False,
    )
    fig.suptitle(_wrap(suptitle, int(11 * width)), x=0.02, ha="left", fontsize=11)
    return fig


def eigenvectors_figure(
    eigenvectors: ArrayLike,
    eigenvalues: ArrayLike,
    n: int = 4,
    *,
    channels: Channels | None = None,
) -> Figure:
    """Paper Fig. 8 (see :func:`plot_eigenvectors`)."""
    ch = channels or Channels()
    e = np.asarray(eigenvectors)[:, :n]
    n = e.shape[1]
    lam = np.clip(np.asarray(eigenvalues)[:n], 0.0, None)
    d = e.shape[0]
    if d % ch.n:
        raise ValueError(f"eigenvectors of {d} components do not split into {ch.n} channels")
    curves = e.T.reshape(n, ch.n, d // ch.n).transpose(0, 2, 1)
    share = lam / max(float(np.sum(np.clip(eigenvalues, 0, None))), 1e-300) * 100
    titles = [f"eigenvector {i + 1} ({share[i]:.1f} % of variance)" for i in range(n)]
    kind = "angle" if ch.is_angles else "direction component"
    return _curves_grid(
        curves,
        titles,
        f"Fig. 8: the first eigenvectors (unit length; each {kind}'s {d // ch.n} components "
        "over the segment)",
        "eigenvector component",
        ncols=min(n, 4),
        channels=ch,
    )


def plot_eigenvectors(
    path: Path,
    eigenvectors: ArrayLike,
    eigenvalues: ArrayLike,
    n: int = 4,
    *,
    channels: Channels | None = None,
) -> Path:
    """Paper Fig. 8: the first ``n`` unit eigenvectors, each drawn as one curve per channel
    of the segment vector (``channels``: 4 angles, or 6 bone-direction components per arm;
    ``n_samples`` components each; dimensionless, ‖e‖ = 1)."""
    return save_figure(eigenvectors_figure(eigenvectors, eigenvalues, n, channels=channels), path)


def primitives_figure(
    primitive_curves: NDArray[np.float64],
    counts: ArrayLike,
    durations: ArrayLike,
    *,
    channels: Channels | None = None,
) -> Figure:
    """Paper Fig. 9 (see :func:`plot_primitives`)."""
    ch = channels or Channels()
    curves = np.asarray(primitive_curves, dtype=np.float64)
    k = curves.shape[0]
    counts = np.asarray(counts)
    durations = np.asarray(durations)
    titles = [f"#{i}: {counts[i]} seg., {durations[i]:.2f} s" for i in range(k)]
    ncols = 6 if k > 12 else min(k, 4)
    what = "angles" if ch.is_angles else "bone directions"
    rel = ", relative to the segment's mean posture" if ch.offsets == "mean" else ""
    return _curves_grid(
        curves,
        titles,
        f"Fig. 9: the {k} primitives (cluster centres reconstructed as {what}{rel}; "
        "x: % of the segment)",
        ch.value_label,
        ncols,
        ch,
        scale=ch.scale,
    )


def plot_primitives(
    path: Path,
    primitive_curves: NDArray[np.float64],
    counts: ArrayLike,
    durations: ArrayLike,
    *,
    channels: Channels | None = None,
) -> Path:
    """Paper Fig. 9: the cluster centres (primitives) as curves ``(k, n_samples, C)`` of the
    model's own channels (``channels``): the four angles (radians, drawn in degrees), or the
    upper-arm and forearm unit-vector components (dimensionless) — never turned into angles,
    so there are no unwrapping steps. With ``offsets="mean"`` they are changes from the
    segment's mean posture."""
    return save_figure(
        primitives_figure(primitive_curves, counts, durations, channels=channels), path
    )


def plot_reconstruction(
    path: Path,
    times: ArrayLike,
    original: ArrayLike,
    from_projection: ArrayLike,
    from_cluster: ArrayLike | None,
    *,
    boundaries: ArrayLike | None = None,
    title: str,
    errors_deg: tuple[float, float | None] | None = None,
) -> Path:
    """Paper Figs. 10–11: original angles vs their reconstruction from the projection
    (``E_f p + s̄``) and from the primitive (``E_f c + s̄``), degrees."""
    t = np.asarray(times)
    o = np.degrees(np.asarray(original))
    p = np.degrees(np.asarray(from_projection))
    c = None if from_cluster is None else np.degrees(np.asarray(from_cluster))
    fig = Figure(figsize=(10, 7.5), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    for j, ax in enumerate(axes):
        ax.plot(t, o[:, j], color="k", lw=1.6)
        ax.plot(t, p[:, j], color=_COLORS[j], lw=1.3, ls="--")
        if c is not None:
            ax.plot(t, c[:, j], color="0.45", lw=1.1, ls=":")
        if boundaries is not None:
            for b in np.asarray(boundaries):
                ax.axvline(b, color="tab:green", lw=0.7, alpha=0.6)
        ax.set_ylabel(f"{ANGLE_LABELS[j]}\n(deg)", fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    handles = [
        axes[0].plot([], [], color="k", lw=1.6)[0],
        axes[0].plot([], [], color="tab:blue", ls="--")[0],
    ]
    labels = ["original (low-passed IK angles)", "from projection (E_f p + s̄)"]
    if c is not None:
        handles.append(axes[0].plot([], [], color="0.45", ls=":")[0])
        labels.append("from primitive (E_f c + s̄)")
    if boundaries is not None:
        handles.append(axes[0].plot([], [], color="tab:green", lw=0.7)[0])
        labels.append("SEG-2 boundary")
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=9)
    if errors_deg is not None:
        ep, ec = errors_deg
        title += f"  —  RMS error: projection {ep:.2f}°"
        if ec is not None:
            title += f", primitive {ec:.2f}°"
    fig.suptitle(_wrap(title), x=0.02, ha="left", fontsize=11)
    return save_figure(fig, path)


def confusion_figure(classes: Sequence[str], matrix: ArrayLike, title: str) -> Figure:
    """A confusion matrix (rows: true class, columns: predicted), counts in the cells and
    the colour the fraction of the row."""
    m = np.asarray(matrix, dtype=np.float64)
    n = len(classes)
    rows = m.sum(axis=1, keepdims=True)
    frac = np.divide(m, rows, out=np.zeros_like(m), where=rows > 0)
    side = max(4.0, 0.45 * n + 2.5)
    fig = Figure(figsize=(side + 1.0, side), layout="constrained")
    ax = fig.subplots()
    im = ax.imshow(frac, cmap="Blues", vmin=0.0, vmax=1.0)
    for i in range(n):
        for j in range(n):
            if m[i, j]:
                color = "white" if frac[i, j] > 0.6 else "black"
                ax.text(j, i, f"{int(m[i, j])}", ha="center", va="center", fontsize=8, color=color)
    ax.set_xticks(range(n), list(classes), rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(n), list(classes), fontsize=8)
    ax.set_xlabel("predicted class")
    ax.set_ylabel("true class")
    fig.colorbar(im, ax=ax, shrink=0.8, label="fraction of the true class")
    fig.suptitle(_wrap(title, int(10 * (side + 1.0))), x=0.02, ha="left", fontsize=10)
    return fig


def group_accuracy_figure(
    per_group: dict[str, tuple[float, float, int]], group_by: str, title: str
) -> Figure:
    """Accuracy on each held-out group: the MotionClassifier beside the DTW 1-NN baseline
    (``per_group``: group → (accuracy, baseline accuracy, trials))."""
    names = list(per_group)
    acc = np.array([per_group[g][0] for g in names])
    base = np.array([per_group[g][1] for g in names])
    counts = [per_group[g][2] for g in names]
    x = np.arange(len(names))
    fig = Figure(figsize=(max(5.0, 0.6 * len(names) + 2.5), 3.8), layout="constrained")
    ax = fig.subplots()
    ax.bar(x - 0.2, 100 * acc, 0.4, color="tab:blue", label="MotionClassifier")
    ax.bar(x + 0.2, 100 * base, 0.4, color="0.65", label="DTW 1-NN baseline")
    ax.set_xticks(x, [f"{g or '-'}\n({n})" for g, n in zip(names, counts, strict=True)], fontsize=8)
    ax.set_xlabel(f"held-out {group_by} (trials)")
    ax.set_ylabel("accuracy (%)")
    ax.set_ylim(0, 105)
    ax.grid(alpha=0.3, axis="y")
    fig.legend(loc="outside lower center", ncols=2, fontsize=8, frameon=False)
    fig.suptitle(_wrap(title, 80), x=0.02, ha="left", fontsize=10)
    return fig

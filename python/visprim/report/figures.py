"""The report's figures (matplotlib, object API, no global state; PNG via the Agg canvas).

Every function draws one figure, writes it to ``path`` and returns the path. Angles are
plotted in **degrees**, times in seconds; the data given to the functions are radians.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from visprim.arm import ANGLE_NAMES

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


def _save(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


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
    """Paper Fig. 5: the four angles with each angle's zero-velocity crossings (dots) and the
    SEG-1 segments (shaded); true stroke boundaries as dashed lines when known."""
    t = np.asarray(times)
    a = np.degrees(np.asarray(angles))
    ct = np.asarray(crossings_time)
    cd = np.asarray(crossings_dof)
    seg = np.asarray(segments).reshape(-1, 2)
    fig = Figure(figsize=(10, 7.5), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    for j, ax in enumerate(axes):
        for s, e in seg:
            ax.axvspan(s, e, color="0.88", lw=0)
        ax.plot(t, a[:, j], color=_COLORS[j], lw=1.4)
        m = cd == j
        if np.any(m):
            ax.plot(
                ct[m], np.interp(ct[m], t, a[:, j]), "o", ms=5, mfc="white", mec="k", label="ZVC"
            )
        if truth_boundaries is not None:
            for b in np.asarray(truth_boundaries):
                ax.axvline(b, color="k", ls="--", lw=0.8, alpha=0.6)
        ax.set_ylabel(f"{ANGLE_LABELS[j]}\n(deg)", fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    handles = [
        axes[0].plot([], [], "o", mfc="white", mec="k")[0],
        axes[0].fill([], [], color="0.88")[0],
    ]
    labels = ["zero-velocity crossing", "SEG-1 segment"]
    if truth_boundaries is not None:
        handles.append(axes[0].plot([], [], "k--", lw=0.8)[0])
        labels.append("true stroke boundary")
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize=9)
    fig.suptitle(title or "Segmentation at zero-velocity crossings (SEG-1)", x=0.02, ha="left")
    return _save(fig, path)


def plot_seg2(
    path: Path,
    times: ArrayLike,
    z: ArrayLike,
    threshold: float,
    segments: ArrayLike,
    *,
    truth_boundaries: ArrayLike | None = None,
    title: str = "",
) -> Path:
    """Paper Fig. 6: ``z(t) = Σ θ̇ᵢ²`` in (deg/s)² (log scale) with the SEG-2 threshold c and
    the boundaries it yields."""
    t = np.asarray(times)
    zz = np.asarray(z) * _RAD2
    c = float(threshold) * _RAD2
    seg = np.asarray(segments).reshape(-1, 2)
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax = fig.subplots()
    ax.semilogy(t, np.maximum(zz, c * 1e-4), color="tab:purple", lw=1.3, label="z(t) = Σ θ̇ᵢ²")
    ax.axhline(c, color="tab:red", lw=1.2, label=f"threshold c = {c:.4g} (deg/s)²")
    bounds = np.unique(seg.ravel()) if seg.size else np.zeros(0)
    for i, b in enumerate(bounds):
        ax.axvline(b, color="tab:green", lw=1.2, label="SEG-2 boundary" if i == 0 else None)
    if truth_boundaries is not None:
        for i, b in enumerate(np.asarray(truth_boundaries)):
            ax.axvline(
                b,
                color="k",
                ls="--",
                lw=0.8,
                alpha=0.6,
                label="true stroke boundary" if i == 0 else None,
            )
    ax.set_xlabel("time (s)")
    ax.set_ylabel("z (deg/s)²")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    ax.set_title(title or "SEG-2: summed squared angular velocity and its threshold", loc="left")
    return _save(fig, path)


def plot_eigenvalues(path: Path, eigenvalues: ArrayLike, n_components: int) -> Path:
    """Eigenvalue spectrum of K (deg², log scale) and the cumulative variance kept."""
    lam = np.clip(np.asarray(eigenvalues, dtype=np.float64), 0.0, None) * _RAD2
    total = lam.sum()
    idx = np.arange(1, lam.size + 1)
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    pos = lam > 0
    ax1.semilogy(idx[pos], lam[pos], ".-", color="tab:blue", ms=3, lw=0.8)
    ax1.axvline(n_components, color="tab:red", ls="--", lw=1, label=f"f = {n_components}")
    ax1.set_xlabel("eigenvalue index")
    ax1.set_ylabel("eigenvalue (deg²)")
    ax1.set_title("Eigenvalue spectrum", loc="left")
    ax1.grid(alpha=0.3, which="both")
    ax1.legend()
    n_show = min(lam.size, max(4 * n_components, 60))
    frac = np.cumsum(lam) / total * 100 if total > 0 else np.zeros_like(lam)
    ax2.plot(idx[:n_show], frac[:n_show], color="tab:green")
    ax2.axvline(n_components, color="tab:red", ls="--", lw=1)
    kept = frac[n_components - 1] if n_components <= frac.size else 100.0
    ax2.axhline(kept, color="0.5", lw=0.8)
    ax2.text(n_components + 1, kept - 6, f"{kept:.3f} % kept by f = {n_components}", fontsize=9)
    ax2.set_xlabel("number of eigenvectors f")
    ax2.set_ylabel("variance kept (%)")
    ax2.set_ylim(0, 101)
    ax2.set_title("Cumulative variance", loc="left")
    ax2.grid(alpha=0.3)
    return _save(fig, path)


def _curves_grid(
    path: Path,
    curves: NDArray[np.float64],
    titles: Sequence[str],
    suptitle: str,
    ylabel: str,
    ncols: int,
    *,
    durations: ArrayLike | None = None,
) -> Path:
    """Panels of 4 angle curves (degrees) each; x in % of the segment (or s if durations)."""
    n = curves.shape[0]
    nrows = int(np.ceil(n / ncols))
    fig = Figure(figsize=(2.6 * ncols, 2.1 * nrows + 0.8), layout="constrained")
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
        for j in range(4):
            ax.plot(x, np.degrees(curves[i, :, j]), color=_COLORS[j], lw=1.2)
        ax.set_title(titles[i], fontsize=8)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
        if i % ncols == 0:
            ax.set_ylabel(ylabel, fontsize=8)
        if i >= n - ncols:
            ax.set_xlabel("% of segment" if durations is None else "time (s)", fontsize=8)
    handles = [axes[0].plot([], [], color=c)[0] for c in _COLORS]
    fig.legend(handles, ANGLE_LABELS, loc="outside lower center", ncols=4, fontsize=9)
    fig.suptitle(suptitle, x=0.02, ha="left", fontsize=11)
    return _save(fig, path)


def plot_eigenvectors(
    path: Path, eigenvectors: ArrayLike, eigenvalues: ArrayLike, n: int = 4
) -> Path:
    """Paper Fig. 8: the first ``n`` eigenvectors, each as 4 angle curves, scaled by the
    square root of their eigenvalue (one standard deviation along the eigenvector, deg)."""
    e = np.asarray(eigenvectors)[:, :n]
    lam = np.clip(np.asarray(eigenvalues)[:n], 0.0, None)
    d = e.shape[0]
    curves = (e * np.sqrt(lam)).T.reshape(n, 4, d // 4).transpose(0, 2, 1)
    share = lam / max(float(np.sum(np.clip(eigenvalues, 0, None))), 1e-300) * 100
    titles = [f"eigenvector {i + 1} ({share[i]:.1f} % of variance)" for i in range(n)]
    return _curves_grid(
        path, curves, titles, "First eigenvectors (× √eigenvalue)", "deg", ncols=min(n, 4)
    )


def plot_primitives(
    path: Path,
    primitive_curves: NDArray[np.float64],
    counts: ArrayLike,
    durations: ArrayLike,
) -> Path:
    """Paper Fig. 9: the cluster centres (primitives) as 4 angle curves each (degrees)."""
    k = primitive_curves.shape[0]
    counts = np.asarray(counts)
    durations = np.asarray(durations)
    titles = [f"#{i}: {counts[i]} seg., {durations[i]:.2f} s" for i in range(k)]
    ncols = 6 if k > 12 else min(k, 4)
    return _curves_grid(
        path,
        primitive_curves,
        titles,
        f"The {k} primitives (cluster centres reconstructed; x: % of the segment)",
        "deg",
        ncols,
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
    fig.suptitle(title, x=0.02, ha="left", fontsize=11)
    return _save(fig, path)

"""The rate–distortion report: markdown tables, CSV and plot."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from visprim.rate.benchmark import RateResult

# ---------------------------------------------------------------------------- reports


#: Rates (numbers per second) of the "best within" table of :func:`rate_markdown`.
FRONTIER_RATES: tuple[float, ...] = (8, 10, 12, 16, 20)


def best_within(
    summary: Sequence[dict[str, Any]], rate: float, kinds: str
) -> dict[str, Any] | None:
    """The description of ``summary`` rows with the lowest median bone-direction error
    among those of at most ``rate`` numbers per second: of the primitives (``kinds``
    ``"visprim"``), the keyframes or the DCT baselines."""

    def kind(fam: str) -> str:
        return fam.split("-")[0] if fam.startswith(("keyframes", "dct")) else "visprim"

    rows = [s for s in summary if kind(s["family"]) == kinds and s["numbers_per_s"] <= rate]
    return min(rows, key=lambda s: s["bone_deg_median"]) if rows else None


def rate_markdown(results: Sequence[RateResult]) -> str:
    """The rate–distortion tables as markdown, one per benchmark: the best description of
    each kind within a few rates, then every description by rate."""
    out = ["# Rate–distortion (held-out groups)", ""]
    for r in results:
        opts = ", ".join(f"{k}={v}" for k, v in r.options.items())
        summary = r.summary()
        out += [
            f"## {r.benchmark} (leave one {r.group_by} out; {opts})",
            "",
            "| at most numbers / s | best primitive description | best keyframes | best DCT |",
            "|---:|---|---|---|",
        ]
        for rate in FRONTIER_RATES:
            cells = []
            for kinds in ("visprim", "keyframes", "dct"):
                b = best_within(summary, rate, kinds)
                cells.append(
                    "-"
                    if b is None
                    else f"{b['bone_deg_median']:.1f}° ({b['family']} {b['param']}, "
                    f"{b['numbers_per_s']:.1f}/s)"
                )
            out.append(f"| {rate:g} | " + " | ".join(cells) + " |")
        out += [
            "",
            "| description | parameter | numbers / s | bone-direction RMS median "
            "(group medians) | joint-space RMS median | movements |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for s in sorted(summary, key=lambda s: (s["family"], s["numbers_per_s"])):
            out.append(
                f"| {s['family']} | {s['param']} | {s['numbers_per_s']:.1f} | "
                f"{s['bone_deg_median']:.1f}° ({s['bone_deg_group_min']:.1f}–"
                f"{s['bone_deg_group_max']:.1f}°) | {s['joint_deg_median']:.1f}° | "
                f"{s['movements']} |"
            )
        out.append("")
    out.append(
        "numbers / s: everything a description stores (ids, durations, postures, gains, "
        "coefficients, start times) over the seconds of movement it covers. Bone-direction "
        "RMS: angle between the rebuilt and the held-out upper-arm and forearm directions; "
        "median over held-out one-arm movements (in brackets the lowest and highest median "
        "of one held-out group). Parameter: k primitives (nearest, warp), m coefficients "
        "(residual, projection), q DCT coefficients per channel (nearest+dct), target numbers "
        "/ s (keyframes, dct)."
    )
    return "\n".join(out) + "\n"


def _csv(results: Sequence[RateResult]) -> str:
    from visprim.csvfile import csv_text

    rows = [s for r in results for s in r.summary()]
    if not rows:
        return ""
    header = list(rows[0])
    cells = (
        [round(v, 4) if isinstance(v, float) else v for v in (s[k] for k in header)] for s in rows
    )
    return csv_text(header, cells)


#: Columns of ``rate_movements.csv``: one row per held-out movement and description.
MOVEMENT_COLUMNS: tuple[str, ...] = (
    "benchmark",
    "group",
    "movement",
    "family",
    "param",
    "code",
    "numbers",
    "seconds",
    "bone_deg",
    "joint_deg",
)


def _movements_csv(results: Sequence[RateResult]) -> str:
    """Every scored held-out movement: its description (``code``: which code an
    ``eigen/dct`` encoder used, else empty), numbers, seconds and errors (degrees)."""
    from visprim.csvfile import csv_text

    rows = (
        [
            round(v, 4) if isinstance(v, float) else v
            for v in ({**row, "benchmark": r.benchmark}.get(k, "") for k in MOVEMENT_COLUMNS)
        ]
        for r in results
        for row in r.rows
    )
    return csv_text(list(MOVEMENT_COLUMNS), rows)


def _plot(results: Sequence[RateResult], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(7 * len(results), 5), squeeze=False)
    for ax, r in zip(axes[0], results, strict=True):
        summary = r.summary()
        colours = plt.get_cmap("tab20")(np.arange(20))
        for i, fam in enumerate(dict.fromkeys(s["family"] for s in summary)):
            pts = sorted(
                (s["numbers_per_s"], s["bone_deg_median"]) for s in summary if s["family"] == fam
            )
            baseline = fam.startswith(("keyframes", "dct"))
            ax.plot(
                *zip(*pts, strict=True),
                "--" if baseline else "-",
                marker="s" if baseline else "o",
                ms=3,
                color=colours[(2 * i) % 20 + (2 * i) // 20],
                label=fam,
            )
        ax.set_xscale("log")
        ax.set_xlabel("numbers per second of movement")
        ax.set_ylabel("bone-direction RMS, degrees (median, held-out)")
        ax.set_title(f"{r.benchmark}: leave one {r.group_by} out")
        ax.set_ylim(bottom=0)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_rate_report(results: Sequence[RateResult], out_dir: str | os.PathLike[str]) -> dict:
    """Write ``rate.md``, ``rate.csv``, ``rate.png`` and ``rate_movements.csv`` into
    ``out_dir`` (each atomically). Returns the paths by kind."""
    from visprim.atomic import atomic_file, write_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "rate_markdown": out / "rate.md",
        "rate_csv": out / "rate.csv",
        "rate_plot": out / "rate.png",
        "rate_movements_csv": out / "rate_movements.csv",
    }
    write_text(paths["rate_markdown"], rate_markdown(results), newline="")
    write_text(paths["rate_csv"], _csv(results), newline="")
    write_text(paths["rate_movements_csv"], _movements_csv(results), newline="")
    with atomic_file(paths["rate_plot"]) as tmp:
        _plot(results, tmp)
    return paths

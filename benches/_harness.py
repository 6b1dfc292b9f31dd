"""Helpers for the Python benchmarks: medians of repeated runs, one table, and the CPU and
commit that stamp a result."""

from __future__ import annotations

import platform
import statistics
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


def median_time(fn: Callable[[], Any], repeat: int = 5, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` in seconds over ``repeat`` runs after ``warmup`` runs."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def blas_info() -> str:
    """Which BLAS the reference numpy uses (threadpoolctl), e.g. 'openblas Haswell, 2 threads'."""
    try:
        import numpy  # noqa: F401
        from threadpoolctl import threadpool_info
    except ImportError:
        return "unknown (threadpoolctl not installed)"
    infos = [i for i in threadpool_info() if i.get("user_api") == "blas"]
    return (
        "; ".join(
            f"{i.get('internal_api')} {i.get('architecture')}, {i.get('num_threads')} threads"
            for i in infos
        )
        or "none found"
    )


@dataclass
class Table:
    """Rows of (workload, implementation, median seconds, per-unit figure, note)."""

    rows: list[tuple[str, str, float, str, str]] = field(default_factory=list)
    ratios: list[tuple[str, str, float]] = field(default_factory=list)

    def add(self, workload: str, impl: str, seconds: float, unit: str = "", note: str = "") -> None:
        self.rows.append((workload, impl, seconds, unit, note))
        print(f"  {workload:<40} {impl:<34} {seconds * 1e3:10.2f} ms  {unit} {note}", flush=True)

    def ratio(self, workload: str, reference: str, ref_s: float, ours_s: float) -> None:
        """Record reference/visprim for ``workload`` (> 1: visprim faster)."""
        self.ratios.append((workload, reference, ref_s / ours_s))

    def print(self) -> None:
        print("\n| workload | implementation | median | per unit | note |")
        print("|---|---|---:|---|---|")
        for w, i, s, u, n in self.rows:
            print(f"| {w} | {i} | {s * 1e3:.2f} ms | {u} | {n} |")
        if self.ratios:
            print("\n| workload | reference | reference / visprim |")
            print("|---|---|---:|")
            for w, r, x in self.ratios:
                print(f"| {w} | {r} | {x:.2f}x |")


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), for the stamp of a result table."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def commit() -> str:
    """The short commit of this checkout, marked ``(modified)`` when tracked files differ
    from it, for the stamp of a result table; ``unknown`` outside git."""
    root = str(Path(__file__).resolve().parents[1])
    try:
        out = subprocess.run(
            ["git", "-C", root, "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        )
        dirty = subprocess.run(
            ["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=True,
        )
        return out.stdout.strip() + (" (modified)" if dirty.stdout.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"

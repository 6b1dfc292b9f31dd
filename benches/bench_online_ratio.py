"""Throughput of two versions of the online engine, measured alternately: the ratio new/old.

On a shared machine the load changes from minute to minute, so two versions are compared
run against run: ``bench_online.py --skip fidelity,memory`` of the old tree, then of the new
one, a few rounds in a row, each writing its JSON beside its ``--out``. For example, with the
old version's Python tree unpacked beside this one::

    git archive OLD python benches | tar -x -C /tmp/old   # + the compiled extension
    for r in 1 2 3; do
      (cd /tmp/old && PYTHONPATH=python python benches/bench_online.py --skip fidelity,memory \\
         --out /tmp/old_$r.md)
      PYTHONPATH=python python benches/bench_online.py --skip fidelity,memory --out /tmp/new_$r.md
    done
    python benches/bench_online_ratio.py --old /tmp/old_*.json --new /tmp/new_*.json [--cpu]

Prints a Markdown table: per classifier and chunk, the median over the rounds of the
frames/s (each run's own median) of both versions and of the ratio new/old of each round
(with its range), and the load averages the runs recorded.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path
from typing import Any


def _rates(path: Path, key: str) -> tuple[dict[tuple[str, int], float], dict[str, Any]]:
    blob = json.loads(path.read_text())
    rows = {(r["classifier"], int(r["chunk"])): float(r[key]) for r in blob["throughput"]}
    return rows, blob["stamp"]


def table(old: list[Path], new: list[Path], key: str = "median") -> str:
    """The ratio table of the rounds; ``key``: ``"median"`` (frames per wall second) or
    ``"cpu_median"`` (frames per CPU-second of the process)."""
    if len(old) != len(new) or not old:
        raise SystemExit("need as many --old as --new result files (one per round)")
    rounds = [
        (_rates(a, key), _rates(b, key)) for a, b in zip(sorted(old), sorted(new), strict=True)
    ]
    keys = list(rounds[0][0][0])
    lines = [
        f"rounds: {len(rounds)} (old then new each round); "
        + ("frames per CPU-second" if key == "cpu_median" else "frames per wall second"),
        "",
        "| classifier | chunk | old frames/s | new frames/s | new / old (range) |",
        "|---|---:|---:|---:|---|",
    ]
    for key in keys:
        o = [r[0][0][key] for r in rounds]
        n = [r[1][0][key] for r in rounds]
        ratio = [b / a for a, b in zip(o, n, strict=True)]
        lines.append(
            f"| {key[0]} | {key[1]} | {statistics.median(o):,.0f} | {statistics.median(n):,.0f} "
            f"| {statistics.median(ratio):.1f}× ({min(ratio):.1f}–{max(ratio):.1f}) |"
        )
    lines.append("")
    for side, name in ((0, "old"), (1, "new")):
        loads = [f"{r[side][1]['load_start']} → {r[side][1]['load_end']}" for r in rounds]
        lines.append(
            f"load averages (1/5/15 min) of the {name} runs, start → end: " + "; ".join(loads)
        )
    stamp = rounds[0][1][1]
    lines.append(
        f"new: commit {stamp['commit']} · CPU {stamp['cpu']} · instruction set "
        f"{stamp['instruction_set']} · {stamp['date']}"
    )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--old", type=Path, nargs="+", required=True, help="old version's JSON files")
    ap.add_argument("--new", type=Path, nargs="+", required=True, help="new version's JSON files")
    ap.add_argument(
        "--cpu", action="store_true", help="ratio of frames per CPU-second (process time)"
    )
    args = ap.parse_args(argv)
    print(table(args.old, args.new, "cpu_median" if args.cpu else "median"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

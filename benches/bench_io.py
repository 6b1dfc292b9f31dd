"""Parse time of the text readers against file size: is it linear?

For each case the file is generated at n/4, n/2 and n elements (joints, bones, columns) and
parsed ``--repeat`` times; the table gives the median and spread (min–max) per size and the
growth exponent ``log2(t(n) / t(n/2))`` (1 = linear, 2 = quadratic).

    python benches/bench_io.py            # n = 20,000 joints / 40,000 bones / 100,000 columns
    python benches/bench_io.py --quick    # n / 10

Cases (the sizes an adversarial file reached):

* ``bvh``: a BVH whose root has n joints (``parse_bvh``);
* ``asf``: an ASF skeleton with a chain of n bones (``parse_asf``);
* ``csv``: a marker CSV whose header has n columns (refused: unknown columns; the time to
  refuse is what is measured).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path


def bvh_text(n: int) -> str:
    joints = "".join(
        f"  JOINT j{i}\n  {{\n    OFFSET 0 1 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
        f"    End Site\n    {{\n      OFFSET 0 1 0\n    }}\n  }}\n"
        for i in range(n)
    )
    head = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n"
    row = " ".join(["0"] * (3 + 3 * n))
    return head + joints + "}\nMOTION\nFrames: 2\nFrame Time: 0.01\n" + row + "\n" + row + "\n"


def asf_text(n: int) -> str:
    bones = "".join(
        f"  begin\n    id {i + 1}\n    name b{i}\n    direction 0 1 0\n    length 1\n"
        f"    axis 0 0 0 XYZ\n    dof rx ry rz\n  end\n"
        for i in range(n)
    )
    chain = "    root b0\n" + "".join(f"    b{i} b{i + 1}\n" for i in range(n - 1))
    return (
        ":version 1.10\n:name big\n:units\n  length 1\n  angle deg\n:root\n"
        "  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n"
        f":bonedata\n{bones}:hierarchy\n  begin\n{chain}  end\n"
    )


def csv_text(n: int) -> str:
    cols = ["time_s"] + [f"s{i}_x_m" for i in range(n)]
    return ",".join(cols) + "\n" + ",".join(["0"] * len(cols)) + "\n"


def _cases() -> dict[str, tuple[int, str, Callable[[int], str], Callable[[Path], object]]]:
    from visprim.io.asfamc import parse_asf
    from visprim.io.bvh import parse_bvh

    try:
        from visprim.io.markers_csv import MarkerCSVError, read_marker_csv
    except ImportError:  # visprim before the marker CSV moved to io/ (for before/after runs)
        from visprim.io.markers_csv import MarkerCSVError, read_marker_csv  # type: ignore

    def csv(path: Path) -> object:
        try:
            return read_marker_csv(path)
        except MarkerCSVError:
            return None

    return {
        "bvh": (20_000, ".bvh", bvh_text, parse_bvh),
        "asf": (40_000, ".asf", asf_text, parse_asf),
        "csv": (100_000, ".csv", csv_text, csv),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="n / 10")
    parser.add_argument("--repeat", type=int, default=3, help="runs per size (default 3)")
    parser.add_argument("--only", nargs="*", choices=("bvh", "asf", "csv"))
    args = parser.parse_args()
    cases = _cases()
    print(f"{'case':5} {'n':>8} {'MB':>6} {'median s':>9} {'spread s':>15}  exponent")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.only or cases:
            full, ext, make, parse = cases[name]
            n_max = full // 10 if args.quick else full
            medians = []
            for n in (n_max // 4, n_max // 2, n_max):
                path = Path(tmp) / f"{name}_{n}{ext}"
                path.write_text(make(n))
                times = []
                for _ in range(args.repeat):
                    t0 = time.perf_counter()
                    parse(path)
                    times.append(time.perf_counter() - t0)
                med = statistics.median(times)
                medians.append(med)
                growth = (
                    f"{math.log2(med / medians[-2]):.2f}" if len(medians) > 1 and med > 0 else ""
                )
                print(
                    f"{name:5} {n:8d} {path.stat().st_size / 1e6:6.2f} {med:9.3f} "
                    f"{min(times):7.3f}–{max(times):7.3f}  {growth}"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""visprim against the reference stack (numpy / scipy / scikit-learn), same data, one run.

Run with ``make bench``. Prints one table of median wall times and ratios
(reference / visprim: > 1 means visprim is faster). Each section lives in its own module
(``bench_signal.py``, ``bench_linalg.py``, ``bench_pipeline.py``) exposing
``run(table, quick=False)``.
"""

from __future__ import annotations

import os

# Some machines set these as a workaround for old OpenBLAS builds; they slow a current
# numpy. Unset both before numpy is imported so the reference is measured at its best.
for _var in ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE"):
    os.environ.pop(_var, None)

import argparse  # noqa: E402
import importlib  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _harness import Table, blas_info  # noqa: E402

SECTIONS = ("bench_signal", "bench_linalg", "bench_pipeline", "bench_sim")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small workloads (smoke test)")
    parser.add_argument("--only", choices=SECTIONS, nargs="*", help="sections to run")
    args = parser.parse_args()
    from visprim.kernels import instruction_set

    print(f"BLAS: {blas_info()}; visprim kernels: {instruction_set()}")
    table = Table()
    for name in args.only or SECTIONS:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
            print(f"(section {name} not present)")
            continue
        module.run(table, quick=args.quick)
    table.print()
    return 0


if __name__ == "__main__":
    sys.exit(main())

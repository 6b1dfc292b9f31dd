"""The paper's Table 3 (total angular error, degrees, by k) under each SEG-2 boundary rule.

    PYTHONPATH=python python benches/seg2_boundary_table3.py

The demo's paper models (the generated experiment, as ``tests/test_params.py`` checks them)
with ``seg2_boundary`` "slowest" and "first_stop" (:mod:`visprim.segment.seg2`); prints
ours / the paper's for every row (the test holds the calibrated rows to 1/1.3–1.3).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _harness import commit, cpu_model  # noqa: E402
from test_params import CALIBRATED, PAPER_TABLE3, _args  # noqa: E402
from visprim import kernels  # noqa: E402
from visprim.cli import common  # noqa: E402
from visprim.cli.demo import paper_models  # noqa: E402
from visprim.params import SEG2_BOUNDARIES  # noqa: E402
from visprim.report.paper import total_error_by_k  # noqa: E402


def main() -> int:
    import os
    from datetime import UTC, datetime

    load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
    print(
        f"# Table 3 by SEG-2 boundary rule — {datetime.now(UTC):%Y-%m-%d %H:%M UTC}, commit "
        f"{commit()}, {cpu_model()}, instruction set {kernels.instruction_set()}, load "
        f"{load} (deterministic figures)\n"
    )
    print("| rule | method | k | ours (deg) | paper (deg) | ratio |")
    print("|---|---|---:|---:|---:|---:|")
    for rule in SEG2_BOUNDARIES:
        args = _args("demo", "--out", "d", "--no-sim", "--seg2-boundary", rule)
        source = common.generated_source(args)
        trials = common.load_source(source)
        for method, model in paper_models(args, trials, source):
            assert model.seg2_boundary == rule
            ours = total_error_by_k(model.error_table(k_values=tuple(PAPER_TABLE3[method])))
            for k, paper in PAPER_TABLE3[method].items():
                mark = "" if k in CALIBRATED[method] else " (not calibrated)"
                print(
                    f"| {rule} | {method} | {k}{mark} | {ours[k]:.2f} | {paper:.2f} | "
                    f"{ours[k] / paper:.3f} |",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

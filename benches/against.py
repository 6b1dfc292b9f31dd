"""visprim at an earlier commit against the working tree, on the same machine, in one run.

``python benches/against.py REV`` builds the extension of commit ``REV`` (a detached git
worktree and a wheel under ``target/against/<sha>``, built once and reused), then runs
``benches/compare.py --only SECTIONS`` of that commit and of the working tree one after the
other, ``--rounds`` times, and prints for every visprim row that both print:

* the median wall time of each side over the rounds, with its range;
* the earlier / current ratio (> 1: the working tree is faster), computed within each round
  (the two sides ran back to back) and given as its median and range.

Each side times its own workload with its own bench code: a row whose work changed between the
commits (the pipeline's segment count, say) is printed with both sides' per-unit column, so
the difference is visible. The reference stack (numpy / scipy / scikit-learn) is the one of
this environment for both.

Absolute timings differ between machines; this gives the speed of the current code relative to
an earlier one where both are measured together, e.g. against the commit at which a target
was measured elsewhere.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SECTIONS = ("bench_signal", "bench_linalg", "bench_pipeline")
#: A row of ``compare.py``'s final table: | workload | implementation | 12.34 ms | unit | note |
#: A per-unit text that is a count of work ("31726 segments"), not a rate.
COUNT = re.compile(r"^\d+ [a-z]+$")
ROW = re.compile(
    r"^\|\s*(?P<w>[^|]+?)\s*\|\s*(?P<i>[^|]+?)\s*\|\s*(?P<t>[\d.]+) ms\s*\|(?P<u>[^|]*)\|"
)


def _run(cmd: list[str], cwd: Path, env: dict[str, str] | None = None) -> str:
    """Run ``cmd`` and return its stdout; on failure exit with its stderr's last lines."""
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-15:])
        sys.exit(f"against.py: {' '.join(cmd[:3])} ... failed (exit {proc.returncode}):\n{tail}")
    return proc.stdout


def build(rev: str) -> tuple[Path, Path]:
    """The source tree and the installed package folder of commit ``rev`` (built if needed)."""
    sha = _run(["git", "rev-parse", "--verify", f"{rev}^{{commit}}"], ROOT).strip()
    base = ROOT / "target" / "against" / sha
    src, site, done = base / "src", base / "site", base / "built"
    if done.exists() and (src / "benches" / "compare.py").exists():
        return src, site
    print(f"building {rev} ({sha[:10]}) in {base} ...", flush=True)
    if src.exists():
        _run(["git", "worktree", "remove", "--force", str(src)], ROOT)
    _run(["git", "worktree", "prune"], ROOT)
    base.mkdir(parents=True, exist_ok=True)
    _run(["git", "worktree", "add", "--detach", "--force", str(src), sha], ROOT)
    wheels = base / "wheel"
    bin_dir = Path(sys.executable).parent
    maturin = bin_dir / "maturin"
    tool = str(maturin) if maturin.exists() else "maturin"
    _run([tool, "build", "--release", "-o", str(wheels)], src)
    (wheel,) = wheels.glob("visprim-*.whl")
    pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(site)]
    _run([*pip, str(wheel)], src)
    done.write_text(sha + "\n")
    return src, site


def timings(src: Path, sections: list[str], quick: bool, site: Path | None) -> dict:
    """``{(workload, implementation): (seconds, per-unit text)}`` of one ``compare.py`` run."""
    env = dict(os.environ)
    if site is not None:
        env["PYTHONPATH"] = str(site)
    cmd = [sys.executable, str(src / "benches" / "compare.py"), "--only", *sections]
    out = _run([*cmd, "--quick"] if quick else cmd, src, env)
    rows = {}
    for line in out.splitlines():
        m = ROW.match(line)
        if m and m["i"].startswith("visprim"):
            rows[(m["w"], m["i"])] = (float(m["t"]) / 1e3, m["u"].strip())
    return rows


def spread(values: list[float], fmt: str) -> str:
    """``median (min–max)`` of ``values`` formatted with ``fmt``."""
    med = statistics.median(values)
    return f"{med:{fmt}} ({min(values):{fmt}}–{max(values):{fmt}})"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rev", help="earlier commit (any git revision)")
    parser.add_argument("--rounds", type=int, default=3, help="back-to-back pairs of runs")
    parser.add_argument("--only", choices=SECTIONS, nargs="*", help="sections to run")
    parser.add_argument("--quick", action="store_true", help="small workloads (smoke test)")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")
    sections = list(args.only or SECTIONS)
    old_src, old_site = build(args.rev)
    runs: list[tuple[dict, dict]] = []
    for r in range(args.rounds):
        print(f"round {r + 1}/{args.rounds}: {args.rev}", flush=True)
        old = timings(old_src, sections, args.quick, old_site)
        print(f"round {r + 1}/{args.rounds}: working tree", flush=True)
        new = timings(ROOT, sections, args.quick, None)
        runs.append((old, new))
    keys = [k for k in runs[0][1] if all(k in o and k in n for o, n in runs)]
    print(f"\n{args.rev} against the working tree, {args.rounds} rounds (median (min–max)):\n")
    print(f"| workload | implementation | {args.rev} | working tree | {args.rev} / working tree |")
    print("|---|---|---|---|---|")
    for key in keys:
        old_t = [o[key][0] * 1e3 for o, _ in runs]
        new_t = [n[key][0] * 1e3 for _, n in runs]
        ratios = [o[key][0] / n[key][0] for o, n in runs]
        units = {runs[0][0][key][1], runs[0][1][key][1]}
        units = {u for u in units if COUNT.match(u)}
        unit = f" ({runs[0][0][key][1]} vs {runs[0][1][key][1]})" if len(units) > 1 else ""
        print(
            f"| {key[0]}{unit} | {key[1]} | {spread(old_t, '.1f')} ms | {spread(new_t, '.1f')} ms "
            f"| {spread(ratios, '.2f')}x |"
        )
    missing = sorted(set(runs[0][0]) ^ set(runs[0][1]))
    if missing:
        print(f"\n(rows printed by one side only: {', '.join(' / '.join(k) for k in missing)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

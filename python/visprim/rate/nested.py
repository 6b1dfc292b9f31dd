"""Settings chosen by nested leave-one-group-out, and scored only on the outer group.

For each held-out (outer) group, an inner leave-one-group-out over the *training* groups
scores every setting of :data:`SEARCH` (posture mode and maximum stroke) with every
primitive description of :data:`SEARCH_FAMILIES` (family and its k, m or q). For each
budget (numbers per second of movement) the choice is the setting and description with the
lowest inner median bone-direction error among those whose inner rate fits the budget. The
outer group is then rebuilt by that choice, learned from all the training groups, and only
scored. The keyframe and DCT baselines need no choice: they are run at the budget itself.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from visprim.params import RATE_OPTIONS
from visprim.rate.benchmark import (
    RateResult,
    _baseline,
    _fold,
    _prepare,
    held_out_movements,
    read_benchmarks,
    summarise_rows,
)
from visprim.rate.report import best_within
from visprim.trial import split_arms

#: Settings searched by the inner folds: (posture mode, max stroke in seconds or None), the
#: values :data:`visprim.params.RATE_OPTIONS` declares.
SEARCH: tuple[tuple[str, float | None], ...] = tuple(
    (p, s) for p in RATE_OPTIONS["posture"].searched for s in RATE_OPTIONS["max_stroke"].searched
)
#: Descriptions searched: the nearest primitive, with residual coefficients, with DCT
#: coefficients of its residual, the own projection, and the whole movement as a
#: superposition of eigen-movements learned from the training movements, alone or with the
#: encoder's choice of the DCT instead (the gain, the warp and the bridges are left out to
#: keep the nested run affordable on a shared 2-core machine; the full benchmark, ``visprim
#: evaluate --rate``, measures them beside).
SEARCH_FAMILIES: tuple[str, ...] = (
    "nearest",
    "residual",
    "nearest+dct",
    "projection",
    "eigen",
    "eigen/dct",
    "eigen/dct-fit1",
    "eigen/dct-fit2",
    "eigen/dct-fit3",
)
#: Budgets (numbers per second of movement) of the nested table.
BUDGETS: tuple[float, ...] = (10, 12, 16, 20)
#: Baselines scored at each budget.
BASELINES: tuple[str, ...] = ("keyframes-angles", "dct-angles")


@dataclass
class NestedResult:
    """Per budget and outer group: the choice of the inner folds and the outer rows."""

    benchmark: str
    group_by: str
    groups: list[str]
    choices: list[dict[str, Any]] = field(default_factory=list)
    rows: list[dict[str, Any]] = field(default_factory=list)

    def summary(self) -> list[dict[str, Any]]:
        """Per budget and description kind (``visprim`` for the nested choice, or a
        baseline): the outer rate, the median bone-direction and joint-space RMS over the
        outer movements and the lowest and highest per-group median."""
        out = []
        for budget in dict.fromkeys(r["budget"] for r in self.rows):
            for kind in dict.fromkeys(r["kind"] for r in self.rows if r["budget"] == budget):
                rs = [r for r in self.rows if r["budget"] == budget and r["kind"] == kind]
                head = {"benchmark": self.benchmark, "budget": budget, "kind": kind}
                out.append({**head, **summarise_rows(rs, self.groups)})
        return out


def _setting_label(posture: str, max_stroke: float | None) -> str:
    return f"posture={posture}, max_stroke={'none' if max_stroke is None else f'{max_stroke:g}'}"


def nested_rate(
    bench: Any,
    *,
    budgets: Sequence[float] = BUDGETS,
    search: Sequence[tuple[str, float | None]] = SEARCH,
    families: Sequence[str] = SEARCH_FAMILIES,
    model_params: dict[str, Any] | None = None,
    on_fold: Callable[[str], None] | None = None,
) -> NestedResult:
    """Nested leave-one-group-out of one :class:`visprim.evaluate.Benchmark` (module
    docstring). ``on_fold`` is called once per outer group."""
    params = dict(model_params or {})
    groups = bench.groups
    order = [str(g) for g in dict.fromkeys(groups.tolist())]
    if len(order) < 3:
        raise ValueError(
            f"{bench.name}: nested leave-one-{bench.group_by}-out needs at least 3 groups, "
            f"found {len(order)}"
        )
    result = NestedResult(bench.name, bench.group_by, order)

    def trials(keep: Sequence[str]) -> list[Any]:
        """The one-arm movements of the groups ``keep``."""
        return split_arms(
            [m for m, g in zip(bench.movements, groups, strict=True) if str(g) in keep]
        )

    for outer in order:
        if on_fold:
            on_fold(f"{bench.name}: {bench.group_by} {outer or '-'}")
        inner_groups = [g for g in order if g != outer]
        prepared: dict[str, Any] = {}
        inner = {}
        for posture, stroke in search:
            r = RateResult(bench.name, bench.group_by, inner_groups)
            for g in inner_groups:
                _fold(
                    trials([h for h in inner_groups if h != g]),
                    trials([g]),
                    g,
                    params,
                    families,
                    centres="projection",
                    max_stroke=stroke,
                    rows=r.rows,
                    posture_mode=posture,
                    prepared=prepared,
                    joint=False,
                )
            inner[(posture, stroke)] = r.summary()
        outer_rows: dict[tuple[str, float | None], list[dict[str, Any]]] = {}
        outer_prepared: dict[str, Any] = {}
        for budget in budgets:
            picks = [
                (b["bone_deg_median"], i, setting, b)
                for i, (setting, summary) in enumerate(inner.items())
                if (b := best_within(summary, float(budget), "visprim")) is not None
            ]
            if not picks:
                continue
            _, _, setting, b = min(picks, key=lambda p: (p[0], p[1]))
            if setting not in outer_rows:
                outer_rows[setting] = []
                _fold(
                    trials(inner_groups),
                    trials([outer]),
                    outer,
                    params,
                    families,
                    centres="projection",
                    max_stroke=setting[1],
                    rows=outer_rows[setting],
                    posture_mode=setting[0],
                    prepared=outer_prepared,
                )
            result.choices.append(
                {
                    "budget": float(budget),
                    "group": outer,
                    "setting": _setting_label(*setting),
                    "family": b["family"],
                    "param": b["param"],
                    "inner_numbers_per_s": b["numbers_per_s"],
                    "inner_bone_deg": b["bone_deg_median"],
                }
            )
            for row in outer_rows[setting]:
                if row["family"] == b["family"] and row["param"] == b["param"]:
                    result.rows.append({**row, "budget": float(budget), "kind": "visprim"})
        # The baselines at each budget, on the same outer movements (no choice to make).
        if outer not in outer_prepared:
            outer_prepared[outer] = _prepare(trials(inner_groups), trials([outer]), params)
        corpus = outer_prepared[outer][2]
        movements = held_out_movements(corpus, outer, list(corpus.segments))
        for budget in budgets:
            base_rows: list[dict[str, Any]] = []
            for family in BASELINES:
                for mv in movements:
                    _baseline(base_rows, mv, family, float(budget))
            for row in base_rows:
                result.rows.append({**row, "budget": float(budget), "kind": row["family"]})
    return result


def nested_rate_benchmark(
    sources: Iterable[str | os.PathLike[str]],
    *,
    labels: str | os.PathLike[str] | None = None,
    group_by: str | None = None,
    period: float = 0.034,
    budgets: Sequence[float] = BUDGETS,
    jobs: int | None = None,
    progress: bool | None = None,
) -> list[NestedResult]:
    """:func:`nested_rate` on every benchmark found under ``sources``."""
    from tqdm.auto import tqdm

    from visprim.progress import _disable

    disable = bool(_disable()) if progress is None else not progress
    benches = read_benchmarks(sources, labels, group_by, period, jobs, disable)
    n_folds = sum(len(set(b.groups.tolist())) for b in benches)
    out = []
    with tqdm(total=n_folds, desc="nested rate", unit="fold", disable=disable) as bar:

        def step(name: str) -> None:
            bar.set_postfix_str(name)
            bar.update(1)

        for b in benches:
            out.append(nested_rate(b, budgets=budgets, on_fold=step))
    return out


def nested_markdown(results: Sequence[NestedResult]) -> str:
    """The nested table as markdown: per budget, the outer error of the nested choice
    beside the baselines at that budget, then each outer group's choice."""
    out = ["# Rate–distortion, settings chosen by nested leave-one-group-out", ""]
    for r in results:
        summary = r.summary()
        out += [
            f"## {r.benchmark} (outer: leave one {r.group_by} out; inner: leave one of the "
            "other groups out)",
            "",
            "| budget, numbers / s | kind | outer numbers / s | bone-direction RMS median "
            "(group medians) | joint-space RMS median | movements |",
            "|---:|---|---:|---:|---:|---:|",
        ]
        for s in summary:
            out.append(
                f"| {s['budget']:g} | {s['kind']} | {s['numbers_per_s']:.1f} | "
                f"{s['bone_deg_median']:.1f}° ({s['bone_deg_group_min']:.1f}–"
                f"{s['bone_deg_group_max']:.1f}°) | {s['joint_deg_median']:.1f}° | "
                f"{s['movements']} |"
            )
        out += [
            "",
            "| budget | outer group | setting chosen by the inner folds | description | "
            "inner numbers / s | inner error |",
            "|---:|---|---|---|---:|---:|",
        ]
        for c in r.choices:
            out.append(
                f"| {c['budget']:g} | {c['group']} | {c['setting']} | {c['family']} "
                f"{c['param']} | {c['inner_numbers_per_s']:.1f} | {c['inner_bone_deg']:.1f}° |"
            )
        out.append("")
    out.append(
        "visprim: the setting (posture mode, max stroke) and description (family and its k, "
        "m or q) with the lowest inner median error within the budget, learned from every "
        "training group and scored on the outer group only. The outer rate can differ a "
        "little from the inner one. Baselines: each channel of the 4 arm angles, at the "
        "budget itself."
    )
    return "\n".join(out) + "\n"


def write_nested_report(
    results: Sequence[NestedResult], out_dir: str | os.PathLike[str]
) -> dict[str, Any]:
    """Write ``rate_nested.md`` and ``rate_nested.csv`` into ``out_dir`` (atomically)."""
    from pathlib import Path

    from visprim.atomic import write_text
    from visprim.csvfile import csv_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "rate_nested_markdown": out / "rate_nested.md",
        "rate_nested_csv": out / "rate_nested.csv",
    }
    write_text(paths["rate_nested_markdown"], nested_markdown(results), newline="")
    rows = [s for r in results for s in r.summary()]
    header = list(rows[0]) if rows else []
    cells = ([round(v, 4) if isinstance(v, float) else v for v in s.values()] for s in rows)
    write_text(paths["rate_nested_csv"], csv_text(header, cells) if rows else "", newline="")
    return paths

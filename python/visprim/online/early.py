"""Early recognition: accuracy against the fraction of the movement seen.

For every benchmark of labelled recordings (:mod:`visprim.evaluate`: same recordings,
benchmarks, groups and left-out classes as ``visprim evaluate``), each group is held out in
turn; the held-out movements are pushed frame by frame into an
:class:`~visprim.kernels.OnlineDtw` holding the training movements' bone directions
(:func:`visprim.classify.arm_directions`), and after each fraction ``p`` of a movement's
frames the running class is the label of the reference with the smallest **open-end** cost
(the movement so far against the best-matching beginning of each reference). At
``p = 1`` the **closed-end** cost, which is the DTW 1-NN baseline of ``visprim evaluate``,
is reported beside it. Nothing of the held-out group is used.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim import kernels
from visprim.classify import arm_directions

__all__ = ["DEFAULT_FRACTIONS", "EarlyResult", "early_recognition", "evaluate_early", "to_markdown"]

#: Fractions of the movement seen (10 % … 100 %).
DEFAULT_FRACTIONS: tuple[float, ...] = tuple(round(0.1 * i, 1) for i in range(1, 11))


@dataclass(frozen=True)
class EarlyResult:
    """Early recognition on one benchmark."""

    name: str
    group_by: str
    n_trials: int
    classes: list[str]
    fractions: list[float]
    accuracy: list[float]  #: open-end 1-NN accuracy at each fraction
    closed_end_accuracy: float  #: closed-end 1-NN on whole movements (the DTW baseline)
    per_group: dict[str, list[float]]  #: accuracy per held-out group at each fraction

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def early_recognition(
    name: str,
    movements: Sequence[Any],
    labels: NDArray[Any],
    groups: NDArray[Any],
    group_by: str = "group",
    fractions: Sequence[float] = DEFAULT_FRACTIONS,
) -> EarlyResult:
    """Leave-one-group-out early recognition of ``movements`` (module docstring)."""
    feats = [np.ascontiguousarray(arm_directions(t)) for t in movements]
    y = np.asarray(labels)
    g = np.asarray(groups)
    fr = [float(f) for f in fractions]
    hits = np.zeros((len(feats), len(fr)), dtype=bool)
    closed = np.zeros(len(feats), dtype=bool)
    order = list(dict.fromkeys(g.tolist()))
    for group in order:
        test = np.flatnonzero(g == group)
        train = np.flatnonzero(g != group)
        refs = [feats[i] for i in train]
        offsets = np.concatenate([[0], np.cumsum([r.shape[0] for r in refs])[:-1]]).astype(np.int64)
        dtw = kernels.OnlineDtw(np.concatenate(refs), offsets)
        for i in test:
            x = feats[i]
            n = x.shape[0]
            marks = [max(1, int(round(f * n))) for f in fr]
            dtw.reset()
            done = 0
            for k, m in enumerate(marks):
                if m > done:
                    dtw.push(x[done:m])
                    done = m
                costs, _ = dtw.open_end()
                hits[i, k] = y[train][int(np.argmin(costs))] == y[i]
            if done < n:
                dtw.push(x[done:])
            closed[i] = y[train][int(np.argmin(dtw.costs()))] == y[i]
    per_group = {str(grp): [float(v) for v in hits[g == grp].mean(axis=0)] for grp in order}
    return EarlyResult(
        name=name,
        group_by=group_by,
        n_trials=len(feats),
        classes=sorted(set(y.tolist())),
        fractions=fr,
        accuracy=[float(v) for v in hits.mean(axis=0)],
        closed_end_accuracy=float(closed.mean()),
        per_group=per_group,
    )


def evaluate_early(
    sources: Iterable[str | os.PathLike[str]],
    *,
    labels: str | os.PathLike[str] | None = None,
    group_by: str | None = None,
    classes: Sequence[str] | None = None,
    period: float = 0.034,
    arm: str = "both",
    jobs: int | None = None,
    fractions: Sequence[float] = DEFAULT_FRACTIONS,
) -> tuple[list[EarlyResult], list[str]]:
    """:func:`early_recognition` on every benchmark under ``sources``, read and split as
    :func:`visprim.evaluate.evaluate` does. Returns ``(results, notes)``."""
    from visprim.evaluate import find_recordings, make_benchmarks, read_movements

    recordings, unlabelled = find_recordings(sources, labels)
    notes = [f"{len(unlabelled)} recording(s) without a label left out"] if unlabelled else []
    if classes is not None:
        recordings = [r for r in recordings if r.label in set(classes)]
    if not recordings:
        raise ValueError("no labelled recordings found (labels.tsv beside the data, or --labels)")
    read_out, errors = read_movements(recordings, period=period, arm=arm, jobs=jobs)
    notes.extend(errors)
    recordings = [r for r, t in zip(recordings, read_out, strict=True) if t is not None]
    movements = [t for t in read_out if t is not None]
    benches, more = make_benchmarks(recordings, movements, group_by=group_by, classes=classes)
    notes.extend(more)
    results = [
        early_recognition(b.name, b.movements, b.labels, b.groups, b.group_by, fractions)
        for b in benches
    ]
    return results, notes


def to_markdown(results: Sequence[EarlyResult], notes: Sequence[str] = ()) -> str:
    """One table: accuracy per benchmark at each fraction seen."""
    if not results:
        return "no benchmark\n"
    fr = results[0].fractions
    lines = [
        "## Early recognition (open-end DTW 1-NN, leave one group out)",
        "",
        "| benchmark | groups | trials | " + " | ".join(f"{f:.0%}" for f in fr) + " | closed end |",
        "|---|---|---|" + "---|" * (len(fr) + 1),
    ]
    for r in results:
        lines.append(
            f"| {r.name} | {r.group_by} ({len(r.per_group)}) | {r.n_trials} | "
            + " | ".join(f"{a:.2f}" for a in r.accuracy)
            + f" | {r.closed_end_accuracy:.2f} |"
        )
    lines += [""] + [f"- {n}" for n in notes]
    return "\n".join(lines) + "\n"


def write(results: Sequence[EarlyResult], notes: Sequence[str], folder: Path) -> list[Path]:
    """``early_recognition.md`` and ``early_recognition.json`` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    md = folder / "early_recognition.md"
    js = folder / "early_recognition.json"
    md.write_text(to_markdown(results, notes), encoding="utf-8")
    js.write_text(
        json.dumps({"results": [r.to_dict() for r in results], "notes": list(notes)}, indent=1),
        encoding="utf-8",
    )
    return [md, js]

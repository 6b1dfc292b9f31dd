"""What the commands share: reading DATA or the generated experiment, model options.

Data: ``DATA...`` are recording files, folders or globs read with
:func:`visprim.io.read_many`; without DATA (or with ``--generated``) the default generated
imitation experiment (:func:`visprim.datasets.imitation_experiment`) is used. The model file
records where its trials came from, so ``visprim report MODEL`` can redraw the per-trial
figures from the same data without DATA.

Frame rate of recordings: the method's low-pass cutoff (``--cutoff``) is a fraction of the
Nyquist frequency and its SEG-1 window and SEG-2 constant were set for the original study's
34 ms frame period, so ``learn`` resamples DATA to ``--resample`` seconds (default 0.034, see
:func:`visprim.io.resample_trial`; ``--no-resample`` keeps each file's rate). The period is
recorded in the model file; ``report`` and ``classify`` resample their DATA the same way.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from visprim.trial import Trial

_DEFAULT_GENERATED = {"n_subjects": 11, "n_stimuli": 20, "seed": 0}
#: Frame period (s) recordings are resampled to by default: the original study's 34 ms.
DEFAULT_RESAMPLE_S = 0.034


# ---------------------------------------------------------------------------- data


def generated_source(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "kind": "generated",
        "n_subjects": int(getattr(args, "subjects", 11)),
        "n_stimuli": int(getattr(args, "stimuli", 20)),
        "seed": int(getattr(args, "data_seed", 0)),
    }


def load_source(source: dict[str, Any]) -> list[Trial]:
    """Trials described by a model's ``training_source_`` (see the module docstring)."""
    kind = source.get("kind")
    if kind == "generated":
        from visprim.datasets import imitation_experiment

        return imitation_experiment(
            int(source.get("n_subjects", 11)),
            int(source.get("n_stimuli", 20)),
            int(source.get("seed", 0)),
        )
    if kind == "files":
        return read_files(list(source.get("paths", [])), source.get("resample"))
    raise ValueError(f"unknown data source {source!r}")


def read_files(paths: Sequence[str], resample: float | None = None) -> list[Trial]:
    try:
        from visprim.io import read_many
    except ImportError as exc:  # pragma: no cover - the readers are part of visprim
        raise SystemExit(
            f"visprim: cannot read recordings, visprim.io unavailable ({exc})"
        ) from None
    try:
        trials = read_many(list(paths), resample=resample)
    except (ValueError, OSError) as exc:
        raise SystemExit(f"visprim: {exc}") from None
    if not trials:
        raise SystemExit(f"visprim: no trials found in {', '.join(paths)}")
    return list(trials)


def trials_and_source(
    args: argparse.Namespace, resample: float | None = None
) -> tuple[list[Trial], dict[str, Any]]:
    """DATA (resampled to ``resample`` s, None = file rate) or the generated experiment."""
    data = list(getattr(args, "data", []) or [])
    if data and getattr(args, "generated", False):
        raise SystemExit("visprim: give DATA files or --generated, not both")
    if data:
        trials = read_files(data, resample)
        paths = [str(Path(p).resolve()) for p in data]
        return trials, {"kind": "files", "paths": paths, "resample": resample}
    source = generated_source(args)
    return load_source(source), source


def model_period(model: Any) -> float | None:
    """The period DATA given to ``report``/``classify`` is resampled to: the model's own
    (recorded by ``learn``), else the default (models of generated data: 34 ms frames)."""
    period = (model.training_source_ or {}).get("resample", DEFAULT_RESAMPLE_S)
    return None if period is None else float(period)


def add_generated_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("generated data (used without DATA, or with --generated)")
    g.add_argument("--generated", action="store_true", help="use the generated experiment")
    g.add_argument("--subjects", type=int, default=11, help="subjects (default 11)")
    g.add_argument("--stimuli", type=int, default=20, help="stimuli (default 20)")
    g.add_argument("--data-seed", type=int, default=0, help="generator seed (default 0)")


def add_model_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("model parameters (visprim.PrimitiveModel)")
    g.add_argument(
        "--segmentation",
        choices=("seg2", "seg1"),
        default="seg2",
        help="segmentation of the training movements (default seg2)",
    )
    g.add_argument("--filter-order", type=int, default=10, help="Butterworth order (default 10)")
    g.add_argument(
        "--cutoff",
        type=float,
        default=0.25,
        help="normalised low-pass cutoff, fraction of Nyquist (default 0.25)",
    )
    g.add_argument(
        "--zvc-threshold",
        type=float,
        default=5.0,
        help="ZVC significant-movement threshold, degrees (default 5)",
    )
    g.add_argument("--window", type=float, default=0.3, help="SEG-1 window, s (default 0.3)")
    g.add_argument(
        "--features",
        choices=("directions", "zyz"),
        default=None,
        help="what segments are made of: bone directions (default) or the paper's Z-Y-Z angles",
    )
    g.add_argument(
        "--seg2-tuning",
        choices=("robust", "repetitions"),
        default=None,
        help="how SEG-2's c is tuned: to the corpus' speed (default) or the paper's rule "
        "from the repetitions",
    )
    g.add_argument(
        "--paper",
        action="store_true",
        help="the paper's exact method (Z-Y-Z angles, c from repetitions, fixed SEG-1 "
        "window) unless --features / --seg2-tuning say otherwise",
    )
    g.add_argument(
        "--seg2-threshold",
        type=float,
        default=None,
        help="SEG-2 constant c, (rad/s)^2 (default: tuned on the data)",
    )
    g.add_argument("--samples", type=int, default=100, help="samples per angle (default 100)")
    g.add_argument("--components", type=int, default=30, help="eigenvectors f (default 30)")
    g.add_argument("--clusters", type=int, default=30, help="primitives k (default 30)")
    g.add_argument("--n-init", type=int, default=10, help="k-means restarts (default 10)")
    g.add_argument("--seed", type=int, default=0, help="k-means seed (default 0)")


def model_from_args(args: argparse.Namespace, **overrides: Any) -> Any:
    from visprim.model import PrimitiveModel

    paper = bool(getattr(args, "paper", False))
    params = dict(
        features=getattr(args, "features", None) or ("zyz" if paper else "directions"),
        seg2_tuning=getattr(args, "seg2_tuning", None) or ("repetitions" if paper else "robust"),
        seg1_adaptive=not paper,
        segmentation=args.segmentation,
        filter_order=args.filter_order,
        cutoff=args.cutoff,
        zvc_threshold_deg=args.zvc_threshold,
        window=args.window,
        seg2_threshold=args.seg2_threshold,
        n_samples=args.samples,
        n_components=args.components,
        n_clusters=args.clusters,
        n_init=args.n_init,
        seed=args.seed,
    )
    params.update(overrides)
    return PrimitiveModel(**params)


def label(method: str) -> str:
    """Display name of a segmentation method ("SEG-1", "SEG-2")."""
    from visprim.report import method_label

    return method_label(method)


def summary(model: Any, n_trials: int) -> str:
    """One line on a fitted model: segments, SEG-2 c, f and k."""
    thr = model.seg2_threshold_
    c = f", SEG-2 c = {thr:.4g} (rad/s)^2" if thr is not None else ""
    empty = getattr(model, "n_trials_without_segments_", 0)
    short = getattr(model, "n_short_trials_", 0)
    notes = f"; {empty} trial(s) without a segment" if empty else ""
    notes += f"; {short} trial(s) shorter than the filter padding (padded less)" if short else ""
    return (
        f"{n_trials} trials -> {model.n_training_segments_} {label(model.segmentation)} "
        f"segments{c}; PCA f = {model.n_components} of {model.dim}; "
        f"k-means k = {model.n_primitives} (inertia {model.inertia_:.4g} rad^2){notes}"
    )

"""The pipeline's subcommands of the ``visprim`` CLI: ``demo``, ``learn``, ``report``, ``classify``.

Registered on the main parser by :func:`add_subcommands` (see :mod:`visprim.cli`).

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

Fewer segments than ``--clusters``: ``learn`` stops with an error naming the number of
segments found (it does not silently learn fewer primitives than asked); lower
``--clusters`` or give more recordings.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from visprim.trial import Trial

_DEFAULT_GENERATED = {"n_subjects": 11, "n_stimuli": 20, "seed": 0}
#: Frame period (s) recordings are resampled to by default: the original study's 34 ms.
DEFAULT_RESAMPLE_S = 0.034


# ---------------------------------------------------------------------------- data


def _generated_source(args: argparse.Namespace) -> dict[str, Any]:
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
        return _read_files(list(source.get("paths", [])), source.get("resample"))
    raise ValueError(f"unknown data source {source!r}")


def _read_files(paths: Sequence[str], resample: float | None = None) -> list[Trial]:
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


def _trials_and_source(
    args: argparse.Namespace, resample: float | None = None
) -> tuple[list[Trial], dict[str, Any]]:
    """DATA (resampled to ``resample`` s, None = file rate) or the generated experiment."""
    data = list(getattr(args, "data", []) or [])
    if data and getattr(args, "generated", False):
        raise SystemExit("visprim: give DATA files or --generated, not both")
    if data:
        trials = _read_files(data, resample)
        paths = [str(Path(p).resolve()) for p in data]
        return trials, {"kind": "files", "paths": paths, "resample": resample}
    source = _generated_source(args)
    return load_source(source), source


def _model_period(model: Any) -> float | None:
    """The period DATA given to ``report``/``classify`` is resampled to: the model's own
    (recorded by ``learn``), else the default (models of generated data: 34 ms frames)."""
    period = (model.training_source_ or {}).get("resample", DEFAULT_RESAMPLE_S)
    return None if period is None else float(period)


def _add_generated_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("generated data (used without DATA, or with --generated)")
    g.add_argument("--generated", action="store_true", help="use the generated experiment")
    g.add_argument("--subjects", type=int, default=11, help="subjects (default 11)")
    g.add_argument("--stimuli", type=int, default=20, help="stimuli (default 20)")
    g.add_argument("--data-seed", type=int, default=0, help="generator seed (default 0)")


def _add_model_options(p: argparse.ArgumentParser) -> None:
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


def _model_from_args(args: argparse.Namespace, **overrides: Any) -> Any:
    from visprim.model import PrimitiveModel

    params = dict(
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


# ---------------------------------------------------------------------------- learn


def _label(method: str) -> str:
    from visprim.report import method_label

    return method_label(method)


def _learn(args: argparse.Namespace) -> int:
    from visprim.modelfile import save_model
    from visprim.progress import stages

    with stages(3, "learn") as st:
        st.step("reading data")
        trials, source = _trials_and_source(args, args.resample)
        st.step(f"fitting {len(trials)} trials")
        model = _model_from_args(args)
        try:
            model.fit(trials, source=source)
        except ValueError as exc:
            hint = " (option --clusters)" if "n_clusters=" in str(exc) else ""
            raise SystemExit(f"visprim learn: {exc}{hint}") from None
        st.step("error tables")
        tables = model.error_table()
    path = save_model(model, args.out)
    print(_summary(model, len(trials)))
    print()
    print(tables.to_markdown())
    print(f"model written to {path}")
    return 0


def _summary(model: Any, n_trials: int) -> str:
    thr = model.seg2_threshold_
    c = f", SEG-2 c = {thr:.4g} (rad/s)^2" if thr is not None else ""
    return (
        f"{n_trials} trials -> {model.n_training_segments_} {_label(model.segmentation)} "
        f"segments{c}; PCA f = {model.n_components} of {model.dim}; "
        f"k-means k = {model.n_primitives} (inertia {model.inertia_:.4g} rad^2)"
    )


# ---------------------------------------------------------------------------- report


def _report(args: argparse.Namespace) -> int:
    from visprim.model import PrimitiveModel
    from visprim.report import write_report

    model = PrimitiveModel.load(args.model)
    trials: list[Trial] | None = None
    if args.data or args.generated:
        trials, _ = _trials_and_source(args, _model_period(model))
    elif model.training_source_:
        try:
            trials = load_source(model.training_source_)
        except (OSError, ValueError, SystemExit) as exc:
            print(
                f"visprim report: cannot read the training data again ({exc}); "
                "writing the model-only part",
                file=sys.stderr,
            )
    rep = write_report(model, args.out, trials, trial_name=args.trial)
    for msg in rep.skipped:
        print(f"note: {msg}")
    print(f"report written to {rep.index} ({len(rep.files)} files)")
    return 0


# ---------------------------------------------------------------------------- classify


def _classify(args: argparse.Namespace) -> int:
    import numpy as np

    from visprim.classify import classify_trials, score_against_truth
    from visprim.model import PrimitiveModel

    model = PrimitiveModel.load(args.model)
    trials, _ = _trials_and_source(args, _model_period(model))
    results = classify_trials(model, trials)
    lines = []
    for r in results:
        hist = r.histogram
        top = np.argsort(-hist, kind="stable")[: min(5, hist.size)]
        top_s = ", ".join(f"#{i}x{hist[i]}" for i in top if hist[i] > 0)
        lines.append(f"{r.name}: sequence {list(r.sequence)}; histogram {top_s or '-'}")
    print("\n".join(lines))
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        with out.open("w", encoding="utf-8") as fh:
            fh.write("trial,segment,start_s,end_s,primitive,distance_rad\n")
            for r in results:
                for j, ((s, e), lab, d) in enumerate(
                    zip(r.segments, r.labels, r.distances, strict=True)
                ):
                    fh.write(f"{r.name},{j},{s:.6f},{e:.6f},{int(lab)},{d:.6g}\n")
        print(f"segment primitives written to {out}")
    if all(t.truth is not None for t in trials):
        print(f"against the true strokes: {score_against_truth(model, trials, results)}")
    return 0


# ---------------------------------------------------------------------------- demo


def _demo(args: argparse.Namespace) -> int:
    from visprim.datasets import imitation_experiment
    from visprim.modelfile import save_model
    from visprim.progress import stages
    from visprim.report import format_segmentation_scores, segmentation_scores, write_report

    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    source = _generated_source(args)
    log: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        log.append(text)

    with stages(7, "demo") as st:
        st.step("generating the experiment")
        trials = imitation_experiment(source["n_subjects"], source["n_stimuli"], source["seed"])
        n_true = len({int(v) for t in trials for v in t.truth.labels})  # type: ignore[union-attr]
        say(
            f"Generated experiment: {len(trials)} trials ({source['n_subjects']} subjects x "
            f"{source['n_stimuli']} stimuli, seed {source['seed']}), {n_true} true stroke "
            "primitives."
        )

        st.step("segmentation scores")
        scores = segmentation_scores(_model_from_args(args), trials)
        say("\nSegmentation against the true stroke boundaries (±100 ms):")
        say(format_segmentation_scores(scores))

        models = {}
        for method in ("seg1", "seg2"):
            st.step(f"learning with {_label(method)}")
            model = _model_from_args(args, segmentation=method)
            model.fit(trials, source=source)
            models[method] = model
            path = save_model(model, out / f"model_{method}.npz")
            say(f"{_label(method)}: {_summary(model, len(trials))}; saved {path}")
            tables = model.error_table()
            say(f"\nTables 1-3 ({_label(method)} model):\n")
            say(tables.to_markdown())

        st.step("classification")
        from visprim.classify import score_against_truth

        k_model = _model_from_args(args, n_clusters=n_true)
        k_model.fit(trials, source=source)
        cls = score_against_truth(k_model, trials)
        say(
            f"Classification at k = {n_true} (number of true stroke primitives), SEG-2 "
            f"segments: {cls}"
        )

        st.step("report")
        rep = write_report(
            models["seg2"],
            out,
            trials,
            extra_sections=[("visprim demo output", "\n".join(log))],
            title="visprim demo: primitives of the generated imitation experiment (SEG-2)",
        )
    gifs = _demo_sim(models["seg2"], out / "primitives", args)
    elapsed = time.perf_counter() - t0
    print()
    print(f"Report:  {rep.index}  (figures, tables1-3 .md/.csv, index.html)")
    print(f"Models:  {out / 'model_seg2.npz'}, {out / 'model_seg1.npz'}")
    if gifs:
        print(f"Primitives on the simulated humanoid: {', '.join(str(g) for g in gifs)}")
    print(f"Done in {elapsed:.1f} s.")
    return 0


def _demo_sim(model: Any, out_dir: Path, args: argparse.Namespace) -> list[Path]:
    if args.no_sim:
        return []
    try:
        from visprim.sim.cli import demo_primitives
    except ImportError as exc:
        print(f"note: the humanoid simulation is not available ({exc}); no primitive GIFs")
        return []
    return list(demo_primitives(model, out_dir, n=args.sim_primitives))


# ---------------------------------------------------------------------------- parser


def add_subcommands(sub: Any) -> None:
    """Register ``demo``, ``learn``, ``report`` and ``classify`` on ``sub`` (the result of
    :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "demo",
        help="generate the default experiment, learn with SEG-1 and SEG-2, print scores and "
        "Tables 1-3, write the report",
        description="Generate the default imitation experiment, learn primitives with SEG-1 "
        "and SEG-2, print the segmentation scores and Tables 1-3, write the report (and "
        "primitive GIFs on the simulated humanoid) to --out.",
    )
    p.add_argument("--out", default="out/demo", help="output folder (default out/demo)")
    p.add_argument("--no-sim", action="store_true", help="skip the humanoid GIFs")
    p.add_argument(
        "--sim-primitives",
        type=int,
        default=3,
        help="primitives to render on the humanoid (default 3)",
    )
    _add_generated_options(p)
    _add_model_options(p)
    p.set_defaults(func=_demo)

    p = sub.add_parser(
        "learn",
        help="learn primitives from recordings (or the generated experiment)",
        description="Learn primitives (PCA + k-means of segment vectors) and write the model "
        "file; prints Tables 1-3.",
    )
    p.add_argument(
        "data",
        nargs="*",
        metavar="DATA",
        help="recording files, folders or globs (default: the generated experiment)",
    )
    p.add_argument("--out", required=True, metavar="MODEL", help="model file to write (.npz)")
    p.add_argument(
        "--resample",
        type=float,
        default=DEFAULT_RESAMPLE_S,
        metavar="SECONDS",
        help="resample DATA to this frame period before learning, so that --cutoff and the "
        "segmentation mean what they meant at the study's rate (default 0.034)",
    )
    p.add_argument(
        "--no-resample",
        dest="resample",
        action="store_const",
        const=None,
        help="keep each recording's own frame rate",
    )
    _add_generated_options(p)
    _add_model_options(p)
    p.set_defaults(func=_learn)

    p = sub.add_parser(
        "report",
        help="write the figures, Tables 1-3 and index.html of a model",
        description="Write the report of MODEL to --out. Per-trial figures use DATA, or "
        "--generated, or else the data the model was learned from (recorded in the model "
        "file).",
    )
    p.add_argument("model", metavar="MODEL", help="model file written by `visprim learn`")
    p.add_argument("data", nargs="*", metavar="DATA", help="recordings for the trial figures")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--trial", default=None, help="name of the trial to draw")
    _add_generated_options(p)
    p.set_defaults(func=_report)

    p = sub.add_parser(
        "classify",
        help="give each segment of new movements its nearest primitive",
        description="Segment DATA with the model's settings and print each trial's sequence "
        "and histogram of primitives (and ARI/purity on generated data).",
    )
    p.add_argument("model", metavar="MODEL", help="model file written by `visprim learn`")
    p.add_argument(
        "data", nargs="*", metavar="DATA", help="recordings (default: the generated experiment)"
    )
    p.add_argument("--out", default=None, help="also write the segment primitives as CSV")
    _add_generated_options(p)
    p.set_defaults(func=_classify)

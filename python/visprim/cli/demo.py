"""``visprim demo``: the default experiment end to end (scores, Tables 1-3, report).

Everything (models, report, primitive GIFs) is written into a hidden folder beside ``--out``
and swapped in at the end (:func:`visprim.cli.outputs.atomic_folder`)."""

from __future__ import annotations

import argparse
import logging
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from visprim.cli import common, logs, outputs

log = logging.getLogger(__name__)


def run(args: argparse.Namespace) -> int:
    from visprim.modelfile import save_model
    from visprim.progress import stages
    from visprim.report import format_segmentation_scores, segmentation_scores, write_report
    from visprim.report.paper import (
        comparison_markdown,
        eigenvectors_markdown,
        tables_in_degrees,
    )

    t0 = time.perf_counter()
    out = outputs.check_folder(args.out, force=args.force)
    source = common.generated_source(args)
    common.model_from_args(args)  # checks the options before the long work

    quiet = bool(getattr(args, "quiet", False))

    def say(text: str = "") -> None:
        """The tables and scores as they come (not with --quiet: the files hold them)."""
        if not quiet:
            print(text, flush=True)

    with (
        outputs.atomic_folder(out, "demo") as tmp,
        logs.paths_shown_as(tmp, out),
        stages(7, "demo") as st,
    ):
        st.step("generating the experiment")
        trials = common.load_source(source)
        n_true = len({int(v) for t in trials for v in t.truth.labels})  # type: ignore[union-attr]
        say(
            f"Generated experiment ({source.preset!r} preset): {len(trials)} trials "
            f"({source.n_subjects} subjects x {source.n_stimuli} stimuli, seed "
            f"{source.seed}), {n_true} true stroke kinds. Units: degrees, deg^2."
        )

        st.step("segmentation scores")
        scores = segmentation_scores(common.model_from_args(args), trials)
        say("\nSegmentation against the true stroke boundaries (±100 ms):")
        say(format_segmentation_scores(scores))

        models: dict[str, Any] = {}
        tables = {}
        for method, model in paper_models(args, trials, source, st.step):
            models[method] = model
            name = f"model_{method}.npz"
            save_model(model, tmp / name)
            say(f"{common.label(method)}: {common.summary(model, len(trials))}; saved {out / name}")
            tables[method] = model.error_table()
            say(f"\nTables 1-3 ({common.label(method)} model, deg^2 and deg):\n")
            say(tables_in_degrees(tables[method]).to_markdown())

        comparison = comparison_markdown(tables)
        say("Comparison with the paper (Table 3, total angular error):\n")
        say(comparison)
        eig = eigenvectors_markdown({m: models[m].eigenvalues_ for m in models})
        say("Eigenvectors needed for the same projection error (paper §7: SEG-2 more):\n")
        say(eig)
        comparison += "\nEigenvectors needed for the same projection error:\n\n" + eig
        (tmp / "paper_comparison.md").write_text(comparison, encoding="utf-8")

        st.step("classification")
        from visprim.classify import score_against_truth

        k_model = common.model_from_args(args, n_clusters=n_true)
        k_model.fit(trials, source=source)
        # The page and the console show the same two scores under the same names.
        cls = (
            f"SEG-2 model (k = {models['seg2'].n_primitives}): "
            f"{score_against_truth(models['seg2'], trials)}; at k = {n_true} (number of true "
            f"stroke kinds): {score_against_truth(k_model, trials)}"
        )
        say(f"Segment primitives vs true stroke labels: {cls}")

        st.step("primitives on the humanoid")
        tmp_gifs = _demo_sim(models["seg2"], tmp, args, trials)
        st.step("report")
        write_report(
            models["seg2"],
            tmp,
            trials,
            title="visprim demo: primitives of the generated imitation experiment (SEG-2)",
            comparison=comparison,
            gifs=tmp_gifs,
            seg_scores=scores,
            classification=cls,
        )
        gifs = [outputs.moved(g, tmp, out) for g in tmp_gifs]
    elapsed = time.perf_counter() - t0
    print()
    print(
        f"Report:  {out / 'index.html'}  (figures, tables1-3 .md/.csv, paper_comparison.md, "
        "index.html)"
    )
    print(f"Models:  {out / 'model_seg2.npz'}, {out / 'model_seg1.npz'}")
    if gifs:
        print(f"Primitives on the simulated humanoid: {', '.join(str(g) for g in gifs)}")
    print(f"Done in {elapsed:.1f} s.")
    return 0


def paper_models(
    args: argparse.Namespace,
    trials: list[Any],
    source: Any,
    step: Any = None,
) -> Iterator[tuple[str, Any]]:
    """``(method, fitted model)`` for SEG-1, then SEG-2: the models the demo learns from
    ``trials`` with the options ``args`` (the paper's preset unless they say otherwise);
    ``step(text)`` is told before each fit."""
    for method in ("seg1", "seg2"):
        if step is not None:
            step(f"learning with {common.label(method)}")
        model = common.model_from_args(args, segmentation=method)
        yield method, model.fit(trials, source=source)


def _demo_sim(model: Any, out_dir: Path, args: argparse.Namespace, trials: Any) -> list[Path]:
    if args.no_sim:
        return []
    try:
        from visprim.sim.showcase import demo_primitives, primitive_postures
    except ImportError as exc:
        log.warning("the humanoid simulation is not available (%s); no primitive GIFs", exc)
        return []
    # Posture-relative primitives are played where their segments were made.
    postures = primitive_postures(model, trials) if model.offsets == "mean" else None
    gifs = demo_primitives(model, out_dir / "primitives", n=args.sim_primitives, postures=postures)
    return list(gifs)


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "demo",
        help="generate the default experiment, learn with SEG-1 and SEG-2, print scores and "
        "Tables 1-3, write the report",
        description="Generate the default imitation experiment, learn primitives with SEG-1 "
        "and SEG-2, print the segmentation scores and Tables 1-3, write the report (and "
        "primitive GIFs on the simulated humanoid) to the folder --out.",
    )
    p.add_argument(
        "--out", default="out/demo", metavar="FOLDER", help="output folder (default out/demo)"
    )
    common.add_force_option(p)
    p.add_argument("--no-sim", action="store_true", help="skip the humanoid GIFs")
    p.add_argument(
        "--sim-primitives",
        type=common.seed_int,
        default=3,
        help="primitives to render on the humanoid (default 3)",
    )
    common.add_generated_options(p)
    common.add_model_options(p)
    p.set_defaults(func=run, paper=True)  # the demo reproduces the paper: its exact method

"""``visprim demo``: the default experiment end to end (scores, Tables 1-3, report)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from visprim.cli import common


def run(args: argparse.Namespace) -> int:
    from visprim.datasets import imitation_experiment
    from visprim.modelfile import save_model
    from visprim.progress import stages
    from visprim.report import format_segmentation_scores, segmentation_scores, write_report

    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    source = common.generated_source(args)
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
        scores = segmentation_scores(common.model_from_args(args), trials)
        say("\nSegmentation against the true stroke boundaries (±100 ms):")
        say(format_segmentation_scores(scores))

        models = {}
        for method in ("seg1", "seg2"):
            st.step(f"learning with {common.label(method)}")
            model = common.model_from_args(args, segmentation=method)
            model.fit(trials, source=source)
            models[method] = model
            path = save_model(model, out / f"model_{method}.npz")
            say(f"{common.label(method)}: {common.summary(model, len(trials))}; saved {path}")
            tables = model.error_table()
            say(f"\nTables 1-3 ({common.label(method)} model):\n")
            say(tables.to_markdown())

        st.step("classification")
        from visprim.classify import score_against_truth

        k_model = common.model_from_args(args, n_clusters=n_true)
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
        from visprim.sim.showcase import demo_primitives
    except ImportError as exc:
        print(f"note: the humanoid simulation is not available ({exc}); no primitive GIFs")
        return []
    return list(demo_primitives(model, out_dir, n=args.sim_primitives))


def _demo_sim(model: Any, out_dir: Path, args: argparse.Namespace) -> list[Path]:
    if args.no_sim:
        return []
    try:
        from visprim.sim.showcase import demo_primitives
    except ImportError as exc:
        print(f"note: the humanoid simulation is not available ({exc}); no primitive GIFs")
        return []
    return list(demo_primitives(model, out_dir, n=args.sim_primitives))


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
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
    common.add_generated_options(p)
    common.add_model_options(p)
    p.set_defaults(func=run, paper=True)  # the demo reproduces the paper: its exact method

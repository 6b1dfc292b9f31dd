"""``visprim learn``: learn primitives from recordings and write the model file.

The model file also holds the eigen-movements of the training movements, whole
(:func:`visprim.rate.budget.learn_eigen_movements`), which ``visprim imitate --budget``
considers beside the primitives; learning from a lazy corpus (``--stream``, ``--dask``)
stores none.

Fewer segments than ``--clusters``: ``learn`` stops with an error naming the number of
segments found (it does not silently learn fewer primitives than asked); lower
``--clusters`` or give more recordings."""

from __future__ import annotations

import argparse
import logging
from typing import Any

from visprim.cli import common, outputs

log = logging.getLogger(__name__)


def run(args: argparse.Namespace) -> int:
    out = outputs.check_file(args.out, (".npz",), force=args.force, what="model file")
    if args.dask is not None or args.stream:
        return _run_corpus(args, out)
    from visprim.modelfile import save_model
    from visprim.progress import stages

    model = common.model_from_args(args)
    with stages(3, "learn") as st:
        st.step("reading data")
        trials, source = common.trials_and_source(args, args.resample, common.model_lowpass(model))
        log.debug("learning from %d trials", len(trials))
        st.step(f"fitting {len(trials)} trials")
        try:
            model.fit(trials, source=source)
        except ValueError as exc:
            raise common.CLIError(_with_fix(str(exc))) from None
        # The whole training movements' principal components, for `imitate --budget`.
        from visprim.rate.budget import learn_eigen_movements

        model.eigen_movements_ = learn_eigen_movements(model, trials)
        st.step("error tables")
        tables = model.error_table()
    path = save_model(model, out)
    print(common.summary(model, len(trials)))
    book = model.eigen_movements_
    if book is not None:
        print(
            f"eigen-movements: {book.n_components} of the training movements, whole (one arm "
            f"each, {book.n_samples} instants), for imitate --budget"
        )
    print()
    from visprim.report.paper import tables_in_degrees

    print(tables_in_degrees(tables).to_markdown())
    print(f"model written to {path}")
    return 0


def _with_fix(message: str) -> str:
    message = message.removeprefix("fit: ")
    if "short='reduce'" in message:  # the filter's advice, in command-line terms
        head = message.split("; drop them")[0]
        return f"{head}; leave them out with --short drop"
    if "n_clusters=" in message:
        return message.replace("lower n_clusters", "lower --clusters")
    if "segment" in message and "found" in message:
        return f"{message}; give more or longer recordings, or try --segmentation seg1"
    return message


def _run_corpus(args: argparse.Namespace, out: Any) -> int:
    """Learn from a lazy corpus: streaming (``--stream``) or on Dask (``--dask``)."""
    from visprim.io.corpus import Corpus, GeneratedCorpus
    from visprim.modelfile import save_model

    data = list(args.data or [])
    if data and args.generated:
        raise common.UsageError("give DATA files or --generated, not both")
    try:
        corpus = (
            Corpus(data, resample=args.resample, **common.reader_options(args, allow_each=True))
            if data
            else GeneratedCorpus(
                args.subjects, args.stimuli, args.data_seed, preset=args.data_preset
            )
        )
    except ValueError as exc:
        raise common.CLIError(str(exc)) from None
    model = common.model_from_args(args)
    client: Any = None if args.dask is None else (args.dask or True)
    how = "streaming" if client is None else f"Dask ({args.dask or 'local cluster'})"
    try:
        model.fit(corpus, client=client)
    except ValueError as exc:
        hint = " (option --clusters)" if "n_clusters=" in str(exc) else ""
        raise common.CLIError(f"{exc}{hint}") from None
    except (ImportError, RuntimeError, OSError) as exc:
        raise common.CLIError(str(exc)) from None
    path = save_model(model, out)
    print(f"learned by {how} from {len(corpus)} items")
    print(common.summary(model, len(model.trial_names_)))
    print("(error tables need the training vectors: run learn without --dask/--stream)")
    print(f"model written to {path}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
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
    common.add_force_option(p)
    p.add_argument(
        "--resample",
        type=common.period_s,
        default=common.DEFAULT_RESAMPLE_S,
        metavar="SECONDS",
        help="resample DATA to this frame period before learning, so that --cutoff and the "
        f"segmentation mean what they meant at the study's rate (default "
        f"{common.DEFAULT_RESAMPLE_S:g})",
    )
    p.add_argument(
        "--no-resample",
        dest="resample",
        action="store_const",
        const=None,
        help="keep each recording's own frame rate",
    )
    common.add_reader_options(p)
    p.add_argument(
        "--dask",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="learn on a Dask cluster: the scheduler's ADDRESS (tcp://host:8786), or a local "
        "cluster without it (needs pip install 'visprim[dask]'); no error tables",
    )
    p.add_argument(
        "--stream",
        action="store_true",
        help="learn in bounded memory, reading DATA in chunks (no error tables)",
    )
    common.add_generated_options(p)
    common.add_model_options(p)
    p.set_defaults(func=run)

"""``visprim report``: figures, Tables 1-3 and index.html of a model.

The report is written into a hidden folder beside ``--out`` and swapped in once complete
(:func:`visprim.cli.outputs.atomic_folder`): an interrupted run leaves the previous complete
report, or none.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from visprim.cli import common, outputs
from visprim.trial import Trial

log = logging.getLogger(__name__)


def write_report_atomic(
    model: Any,
    out: str | Path,
    trials: list[Trial] | None,
    *,
    command: str = "report",
    **options: Any,
) -> Any:
    """:func:`visprim.report.write_report` into ``out`` atomically; the returned
    :class:`~visprim.report.Report` names the final paths."""
    from visprim.report import write_report

    target = Path(out)
    with outputs.atomic_folder(target, command) as tmp:
        rep = write_report(model, tmp, trials, **options)
    rep.out_dir = target
    rep.index = outputs.moved(Path(rep.index), tmp, target)
    rep.files = [outputs.moved(Path(f), tmp, target) for f in rep.files]
    return rep


def run(args: argparse.Namespace) -> int:
    from visprim.progress import stages

    inputs = [args.model, *args.data]
    out = outputs.check_folder(args.out, force=args.force, inputs=inputs)
    with stages(3, "report") as st:
        st.step("loading the model")
        model = common.load_model(args.model)
        lowpass = common.model_lowpass(model)
        trials: list[Trial] | None = None
        st.step("reading the data")
        if args.data or args.generated:
            trials, _ = common.trials_and_source(args, common.model_period(model), lowpass)
        elif model.provenance_.reproducible:
            try:
                trials = common.load_source(model.provenance_, lowpass)
            except (OSError, ValueError, ArithmeticError, TypeError, common.CLIError) as exc:
                log.warning(
                    "cannot read the training data again (%s); writing the model-only part "
                    "(give DATA for the trial figures)",
                    " ".join(str(exc).split()),
                )
        if args.trial is not None:
            names = [t.name for t in trials or []]
            if args.trial not in names:
                shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
                raise common.CLIError(
                    f"--trial {args.trial}: no trial of that name in the data ({shown or 'none'})"
                    "; give one of them, or leave --trial out"
                )
        st.step("writing the report")
        rep = write_report_atomic(model, out, trials, trial_name=args.trial)
    for msg in rep.skipped:
        log.info("note: %s", msg)
    print(f"report written to {rep.index} ({len(rep.files)} files)")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "report",
        help="write the figures, Tables 1-3 and index.html of a model",
        description="Write the report of MODEL to the folder --out. Per-trial figures use "
        "DATA, or --generated, or else the data the model was learned from (recorded in the "
        "model file).",
    )
    p.add_argument("model", metavar="MODEL", help="model file written by `visprim learn`")
    p.add_argument("data", nargs="*", metavar="DATA", help="recordings for the trial figures")
    p.add_argument("--out", required=True, metavar="FOLDER", help="output folder")
    common.add_force_option(p)
    p.add_argument("--trial", default=None, help="name of the trial to draw")
    common.add_reader_options(p)
    common.add_generated_options(p)
    p.set_defaults(func=run)

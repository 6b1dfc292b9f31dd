"""``visprim watch``: segment, recognise (and imitate) a movement stream as it arrives.

The stream goes through :class:`visprim.online.OnlinePipeline` chunk by chunk; each event
is printed on one line and written as one JSON object per line
(:func:`visprim.online.event_to_dict`). The events file is written under a hidden
temporary name beside ``--out`` (one whole line per event, flushed) and renamed over
``--out`` when the stream ends, at Ctrl-C or SIGTERM, or on an error: the file is complete
and valid JSON Lines wherever it is kept. An interruption ends the stream (the open
movement ends, as at the end of a recording) and exits with status 130 (Ctrl-C) or 143
(SIGTERM), the events so far kept.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

from visprim.cli import common, outputs

#: The prefix of a Lab Streaming Layer SOURCE.
LSL_PREFIX = "lsl:"
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


class _Stopped(BaseException):
    """Ctrl-C or SIGTERM while watching (``status`` is the exit status)."""

    def __init__(self, status: int, why: str) -> None:
        super().__init__(why)
        self.status = status
        self.why = why


@contextlib.contextmanager
def _stop_on_signals() -> Iterator[None]:
    """SIGINT and SIGTERM raise :class:`_Stopped` in the main thread while watching."""

    def handler(signum: int, frame: Any) -> None:
        if signum == signal.SIGTERM:
            raise _Stopped(EXIT_TERMINATED, "SIGTERM")
        raise _Stopped(EXIT_INTERRUPTED, "Ctrl-C")

    previous: dict[int, Any] = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, handler)
    except ValueError:  # not the main thread: leave the handlers alone
        pass
    try:
        yield
    finally:
        for signum, h in previous.items():
            signal.signal(signum, h)


class EventLog:
    """JSON Lines of events written to a hidden temporary file beside ``path`` and renamed
    over it by :meth:`keep` (module docstring)."""

    def __init__(self, path: Path) -> None:
        import secrets

        from visprim.atomic import remove_stale

        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale(path)
        # The hidden name visprim.atomic gives its temporaries (removed by remove_stale
        # once this process is gone, if it is killed).
        token = secrets.token_hex(4)
        self.tmp = path.parent / f".{path.name}.visprim-tmp-{os.getpid()}-{token}{path.suffix}"
        self._fh: TextIO | None = open(self.tmp, "x", encoding="utf-8", newline="\n")  # noqa: SIM115
        self.n = 0

    def write(self, record: dict[str, Any]) -> None:
        assert self._fh is not None
        self._fh.write(json.dumps(record, allow_nan=False) + "\n")
        self._fh.flush()
        self.n += 1

    def keep(self) -> None:
        """Flush the file to disk and rename it over the target."""
        from visprim.atomic import umask_mode

        if self._fh is None:
            return
        fh, self._fh = self._fh, None
        fh.flush()
        os.fsync(fh.fileno())
        fh.close()
        os.chmod(self.tmp, umask_mode())
        os.replace(self.tmp, self.path)

    def discard(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
        with contextlib.suppress(OSError):
            self.tmp.unlink()


def describe_event(record: dict[str, Any]) -> str:
    """One printed line for an event dict (:func:`visprim.online.event_to_dict`)."""
    kind = record["event"]
    at = f"{record['emitted']:9.3f} s"
    if kind == "segment":
        forced = " (cut at the longest segment)" if record["forced"] else ""
        return (
            f"{at}  segment    movement {record['movement']} #{record['index']}: "
            f"{record['start']:.3f}-{record['end']:.3f} s, primitive {record['primitive']}, "
            f"distance {record['distance']:.3f} rad, amplitude {record['amplitude']:.2f}{forced}"
        )
    if kind == "class":
        return (
            f"{at}  class      movement {record['movement']}: {record['label'] or '-'} "
            f"(confidence {record['confidence']:.2f}, {record['frames']} frames)"
        )
    span = (
        f"{record['start']:.3f}-{record['end']:.3f} s"
        if record["start"] is not None and record["end"] is not None
        else "no segment"
    )
    label = (
        f", class {record['label']} (confidence {record['confidence']:.2f})"
        if record["label"]
        else ""
    )
    return (
        f"{at}  movement   movement {record['movement']} ended: {span}, "
        f"{record['n_segments']} segments{label}"
    )


# ---------------------------------------------------------------------------- inputs


def _arm(args: argparse.Namespace, model: Any) -> tuple[str, dict[str, Any]]:
    """The arm to read (both for a two-arm model) and the other reader options."""
    opts = common.reader_options(args)
    arm = str(opts.pop("arm"))
    arms = tuple(getattr(model, "arms_", ("right",)))
    if len(arms) == 2:
        arm = "both"
    elif arm == "both":
        raise common.UsageError(
            f"--arm both: the model has one arm ({arms[0]}); give --arm right or left"
        )
    return arm, opts


def read_source(args: argparse.Namespace, model: Any) -> Any:
    """The recording SOURCE as a trial of the model's arms at the model's frame period."""
    from visprim.io import read

    path = Path(args.source)
    if path.is_dir():
        raise common.UsageError(
            f"SOURCE {args.source} is a folder; give one recording or video file, or lsl:NAME"
        )
    if not path.is_file():
        if args.source.isdigit():
            raise common.UsageError(
                f"SOURCE {args.source}: live cameras are not supported; record a video file "
                "and watch it, or stream poses over Lab Streaming Layer (lsl:NAME)"
            )
        raise common.UsageError(
            f"SOURCE {args.source} not found; give a recording file or lsl:NAME"
        )
    arm, opts = _arm(args, model)
    if hasattr(args, "max_gap"):  # one setting: the gaps the reader fills, the stream's split
        opts["max_gap"] = args.max_gap
    return read(path, arm, resample=common.model_period(model), **opts)


def fit_classifier(args: argparse.Namespace, model: Any) -> Any:
    """A :class:`~visprim.classify.DTWClassifier` fitted on the labelled recordings of
    ``--classifier`` (labels as ``visprim evaluate`` reads them), or None."""
    if not args.classifier:
        return None
    from visprim.classify import DTWClassifier
    from visprim.evaluate import find_recordings, read_movements

    recordings, _ = find_recordings(args.classifier, args.labels)
    if not recordings:
        raise common.UsageError(
            f"--classifier {' '.join(args.classifier)}: no labelled recording found (a "
            "labels.tsv beside them, --labels TSV, or Bandai-Namco file names)"
        )
    arm, _ = _arm(args, model)
    period = common.model_period(model)
    trials, errors = read_movements(
        recordings, period=period if period is not None else 0.034, arm=arm, jobs=1
    )
    for e in errors:
        print(f"visprim watch: warning: --classifier: {e}", file=sys.stderr)
    pairs = [(t, r.label) for t, r in zip(trials, recordings, strict=True) if t is not None]
    labels = {lab for _, lab in pairs}
    if len(labels) < 2:
        raise common.UsageError(
            f"--classifier: the readable recordings have {len(labels)} label(s); a classifier "
            "needs at least two"
        )
    return DTWClassifier().fit([t for t, _ in pairs], [lab for _, lab in pairs])


def open_source(args: argparse.Namespace, model: Any) -> tuple[Any, str]:
    """``(iterable of Frames chunks, description)`` for SOURCE."""
    from visprim.online.sources import LslSource, RecordingSource

    if args.source.startswith(LSL_PREFIX):
        name = args.source[len(LSL_PREFIX) :]
        source = LslSource(
            name,
            len(getattr(model, "arms_", ("right",))),
            resolve_timeout=args.lsl_timeout,
            idle=args.idle,
        )
        try:
            source.open()
        except ImportError as exc:
            if exc.name != "mne_lsl":
                raise
            raise common.CLIError(f"{args.source}: {exc}") from None
        return source, f"Lab Streaming Layer stream {name!r}"
    trial = read_source(args, model)
    src = RecordingSource(trial, chunk=args.chunk, fast=args.fast)
    pace = "as fast as possible" if args.fast else "on its own clock"
    return src, f"{args.source} ({trial.n_frames} frames, {trial.duration:.1f} s) {pace}"


# ---------------------------------------------------------------------------- run


def add_online_options(p: argparse.ArgumentParser) -> None:
    """One option per setting of :data:`visprim.params.ONLINE_OPTIONS` (not given: the
    declared default applies)."""
    from visprim.params import ONLINE_OPTIONS

    g = p.add_argument_group("online pipeline (visprim.online)")
    for o in ONLINE_OPTIONS.values():
        unit = f" {o.unit}" if o.unit else ""
        kw: dict[str, Any] = {
            "default": argparse.SUPPRESS,
            "help": f"{o.help} (default {o.default}{unit})",
        }
        if o.choices is not None:
            kw["choices"] = o.choices
        elif isinstance(o.default, int):
            kw["type"] = common.positive_int
            kw["metavar"] = "N"
        else:
            kw["type"] = common.positive_float
            kw["metavar"] = (o.unit or "X").upper()
        g.add_argument("--" + o.name.replace("_", "-"), **kw)


def online_options(args: argparse.Namespace) -> dict[str, Any]:
    """The online settings given on the command line, by name."""
    from visprim.params import ONLINE_OPTIONS

    return {name: getattr(args, name) for name in ONLINE_OPTIONS if hasattr(args, name)}


def run(args: argparse.Namespace) -> int:
    from visprim.online import OnlinePipeline, SegmentClosed, event_to_dict

    out = (
        outputs.check_file(args.out, (".jsonl",), force=args.force, what="events file")
        if args.out
        else None
    )
    model = common.load_model(args.model)
    classifier = fit_classifier(args, model)
    pipe = OnlinePipeline(model, classifier, **online_options(args))
    adonis = None
    if args.adonis:
        from visprim.online.adonis import LiveAdonis

        adonis = LiveAdonis(model, dt=args.dt)
    source, what = open_source(args, model)
    print(f"watching {what}; Ctrl-C ends", file=sys.stderr, flush=True)
    if getattr(model, "seg2_boundary", "slowest") != "first_stop":
        print(
            "note: this model cuts at the slowest frame of each pause, so a segment is "
            "reported only when the next stroke starts (or the rest timeout); a model "
            "learned with --seg2-boundary first_stop reports each one 4 frames after it ends",
            file=sys.stderr,
            flush=True,
        )
    log = EventLog(out) if out is not None else None
    status = 0
    stopped = ""
    frames = 0
    newest = math.nan

    def emit(events: list[Any]) -> None:
        for ev in events:
            record = event_to_dict(ev)
            if log is not None:
                log.write(record)
            print(describe_event(record), flush=True)
            if adonis is not None and isinstance(ev, SegmentClosed):
                adonis.add(ev)

    try:
        with _stop_on_signals():
            try:
                for chunk in source:
                    frames += len(chunk)
                    newest = float(chunk.times[-1])
                    if adonis is not None:
                        adonis.observe(chunk)
                    emit(pipe.push(chunk))
                    if adonis is not None:
                        adonis.advance(newest)
            except _Stopped as stop:
                status, stopped = stop.status, stop.why
            emit(pipe.flush())
            if adonis is not None and not stopped:
                adonis.drain(pace=not args.fast and not args.source.startswith(LSL_PREFIX))
    except _Stopped as stop:  # a second signal while the stream was being closed
        status, stopped = stop.status, stop.why
    except BaseException:
        if log is not None:
            log.keep()  # the events so far, complete
        raise
    finally:
        close = getattr(source, "close", None)
        if close is not None:
            close()
    if log is not None:
        log.keep()
    kept = f"; {log.n} events written to {out}" if log is not None else ""
    print(f"{frames} frames, stream time {newest:.2f} s{kept}", file=sys.stderr)
    missing = pipe.segmenter.missing_frames
    if missing:
        print(
            f"{missing} frames with a missing value (NaN) were left out, and the stream "
            "interpolated across them",
            file=sys.stderr,
        )
    late = getattr(source, "out_of_order", 0)
    if late:
        print(
            f"{late} samples whose timestamp did not come after the last one were left out",
            file=sys.stderr,
        )
    gaps = pipe.segmenter.gaps
    if gaps:
        print(
            f"{gaps} gap{'s' if gaps > 1 else ''} longer than {pipe.segmenter.max_gap:g} s "
            "split the stream: the movement in progress ended before each, and the frames "
            "after it were segmented afresh",
            file=sys.stderr,
        )
    if getattr(source, "max_late", 0.0) > 0.05:
        print(
            f"the replay fell behind its clock by up to {source.max_late:.2f} s",
            file=sys.stderr,
        )
    if adonis is not None:
        print(adonis.report().summary(), file=sys.stderr)
    if stopped:
        print(f"visprim watch: interrupted: stopped by {stopped}{kept}", file=sys.stderr)
    return status


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "watch",
        help="segment, recognise and imitate a movement stream as it arrives",
        description=(
            "Run SOURCE through the online pipeline of MODEL (visprim.online): print one "
            "line per event (a segment closed with its primitive, the running class of the "
            "movement, a movement ended with its final class) and write them as JSON Lines "
            "to --out. SOURCE is a recording or video file (any format visprim.io.read "
            "reads, resampled to the model's frame period and replayed on its own clock) "
            "or lsl:NAME, a Lab Streaming Layer stream of markers (and joints), which needs "
            "the extra visprim[lsl]. Ctrl-C or SIGTERM ends the stream: the open movement "
            "ends and the events so far are kept (exit status 130 or 143)."
        ),
    )
    p.add_argument(
        "source",
        metavar="SOURCE",
        help="a recording or video file, or lsl:NAME (a Lab Streaming Layer stream)",
    )
    p.add_argument("--model", required=True, help="model file written by `visprim learn`")
    p.add_argument(
        "--classifier",
        action="append",
        default=None,
        metavar="DATA",
        help="labelled recordings, a file or a folder (repeat the option for more; labels "
        "from labels.tsv beside them, --labels, or Bandai-Namco file names, as `visprim "
        "evaluate` reads them): a DTW 1-NN classifier of whole movements is fitted on them "
        "for the running and final class (default: no class events)",
    )
    p.add_argument(
        "--labels", default=None, metavar="TSV", help="a labels table for the --classifier data"
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="JSONL",
        help="also write the events, one JSON object per line (.jsonl); complete and "
        "valid when kept, also after Ctrl-C",
    )
    common.add_force_option(p)
    p.add_argument(
        "--fast",
        action="store_true",
        help="replay a recording as fast as possible (default: on its own clock)",
    )
    p.add_argument(
        "--chunk",
        type=common.positive_int,
        default=1,
        metavar="N",
        help="frames of a recording pushed at a time (default 1)",
    )
    p.add_argument(
        "--adonis",
        action="store_true",
        help="drive Adonis (DART) with each closed segment's primitive while the stream "
        "runs, stepped on the stream's clock; reports whether it kept up",
    )
    p.add_argument(
        "--dt",
        type=common.positive_float,
        default=0.002,
        metavar="SECONDS",
        help="--adonis: simulation step (default 0.002)",
    )
    p.add_argument(
        "--idle",
        type=common.positive_float,
        default=None,
        metavar="SECONDS",
        help="lsl:NAME: end the stream after this long without a sample (default: run "
        "until Ctrl-C)",
    )
    p.add_argument(
        "--lsl-timeout",
        type=common.positive_float,
        default=10.0,
        metavar="SECONDS",
        help="lsl:NAME: how long to look for the stream (default 10)",
    )
    add_online_options(p)
    common.add_reader_options(p, many=False)
    p.set_defaults(func=run)

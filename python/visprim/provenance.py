"""What a model was fitted on: :class:`Provenance`, a typed record saved in the model file.

One record per fit, written by the path that fitted it (:meth:`Provenance.generated` for the
generated experiment, in memory or lazily; :meth:`Provenance.recordings` for files, in
memory, streamed or on Dask; :meth:`Provenance.arrays` for bare segment vectors;
:meth:`Provenance.trials` for trials given in memory) and read back by one reader,
:meth:`Provenance.from_dict`, which also reads the ``training_source`` dicts of older model
files.

A model file is data, not instructions: :meth:`Provenance.from_dict` checks every field's
type and range, and :meth:`Provenance.check_reproducible` bounds what ``visprim report``
may regenerate or read again (generated sizes, existing regular files or folders outside
``/proc``, ``/sys`` and ``/dev``, known reader options only).

Units: seconds (``frame_period``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from visprim.params import SHORT_POLICIES, SHORT_POLICY, STUDY_FRAME_PERIOD_S

__all__ = ["KINDS", "Provenance", "ProvenanceError"]

#: Source kinds: the generated experiment, recording files, bare segment vectors, or
#: trials handed to ``fit`` in memory (not reproducible from the record).
KINDS: tuple[str, ...] = ("generated", "recordings", "arrays", "trials")
#: Generator presets (:func:`visprim.datasets.imitation_experiment`).
PRESETS: tuple[str, ...] = ("paper", "strokes")
#: Keyword options of the generator a record may carry.
GENERATOR_OPTIONS: tuple[str, ...] = ("noise", "skin_offsets", "drift", "timing_jitter")
#: Largest generated experiment a record may ask to regenerate (subjects, stimuli, trials).
MAX_SUBJECTS = 1000
MAX_STIMULI = 1000
MAX_GENERATED_TRIALS = 20000
#: Most files a record may name.
MAX_FILES = 1_000_000
#: Frame periods a record may hold (s), as the readers accept.
FRAME_PERIOD_RANGE = (1e-5, 10.0)
#: Folders whose contents are never read again from a record.
_SYSTEM = ("/proc", "/sys", "/dev")


class ProvenanceError(ValueError):
    """A provenance record that is malformed, or that cannot (or may not) be reproduced."""


def _reader_option_names() -> frozenset[str]:
    from visprim.io import read_option_names

    return frozenset(read_option_names())


@dataclass(frozen=True)
class Provenance:
    """What a model was fitted on.

    Attributes
    ----------
    kind : one of :data:`KINDS`.
    frame_period : seconds the training trials were sampled (or resampled) at; None when
        they kept their own rates or the model was fitted on bare vectors.
    preset, n_subjects, n_stimuli, seed, generator_options : the generated experiment
        (``kind="generated"``).
    files : the recording files, folders or globs, absolute (``kind="recordings"``).
    reader_options : reader keyword arguments (:func:`visprim.io.read_many`; ``arm`` may be
        ``"each"``).
    short : what was done with recordings shorter than the filter padding
        (:data:`visprim.params.SHORT_POLICIES`).
    """

    kind: str
    frame_period: float | None = None
    preset: str | None = None
    n_subjects: int | None = None
    n_stimuli: int | None = None
    seed: int | None = None
    generator_options: Mapping[str, Any] = field(default_factory=dict)
    files: tuple[str, ...] = ()
    reader_options: Mapping[str, Any] = field(default_factory=dict)
    short: str = SHORT_POLICY

    # ------------------------------------------------------------------ writers

    @classmethod
    def generated(
        cls, n_subjects: int, n_stimuli: int, seed: int, preset: str, **options: Any
    ) -> Provenance:
        """The generated imitation experiment (sampled every 34 ms)."""
        return cls(
            kind="generated",
            frame_period=STUDY_FRAME_PERIOD_S,
            preset=str(preset),
            n_subjects=int(n_subjects),
            n_stimuli=int(n_stimuli),
            seed=int(seed),
            generator_options=dict(options),
        )

    @classmethod
    def recordings(
        cls,
        files: Sequence[str | Path],
        frame_period: float | None,
        reader_options: Mapping[str, Any] | None = None,
        short: str = SHORT_POLICY,
    ) -> Provenance:
        """Recording files (resampled to ``frame_period`` s; None: their own rates)."""
        return cls(
            kind="recordings",
            frame_period=None if frame_period is None else float(frame_period),
            files=tuple(str(Path(f).resolve()) for f in files),
            reader_options=dict(reader_options or {}),
            short=str(short),
        )

    @classmethod
    def arrays(cls) -> Provenance:
        """Bare segment vectors (nothing to redraw trials from)."""
        return cls(kind="arrays")

    @classmethod
    def trials(cls, trials: Sequence[Any]) -> Provenance:
        """Trials handed to ``fit`` in memory: their common frame period, if they share one."""
        nominal = {t.meta.get("frame_period_s") for t in trials}  # the generator's clock
        if len(nominal) == 1 and _is_number(next(iter(nominal))):
            return cls(kind="trials", frame_period=float(nominal.pop()))
        periods = sorted(float(t.frame_period) for t in trials if t.n_frames > 1)
        common = bool(periods) and periods[-1] <= periods[0] * 1.01  # jittered clocks agree
        return cls(kind="trials", frame_period=periods[len(periods) // 2] if common else None)

    # ------------------------------------------------------------------ (de)serialising

    def to_dict(self) -> dict[str, Any]:
        """The record as JSON types (for the model file)."""
        out: dict[str, Any] = {"kind": self.kind, "frame_period": self.frame_period}
        if self.kind == "generated":
            out.update(
                preset=self.preset,
                n_subjects=self.n_subjects,
                n_stimuli=self.n_stimuli,
                seed=self.seed,
                generator_options=dict(self.generator_options),
            )
        if self.kind == "recordings":
            out.update(
                files=list(self.files), reader_options=dict(self.reader_options), short=self.short
            )
        return out

    @classmethod
    def from_dict(cls, data: Any) -> Provenance:
        """The record of :meth:`to_dict`, or of an older file's ``training_source`` dict,
        checked (:class:`ProvenanceError` names the field)."""
        if not isinstance(data, Mapping):
            raise ProvenanceError("provenance is not an object")
        d = dict(data)
        kind = d.get("kind")
        if "frame_period" not in d:  # an older file's ``training_source``
            d = _from_training_source(d)
            kind = d["kind"]
        if kind not in KINDS:
            raise ProvenanceError(f"provenance kind {kind!r} is not one of {list(KINDS)}")
        period: Any = d.get("frame_period")
        if period is not None and not (
            _is_number(period) and FRAME_PERIOD_RANGE[0] <= period <= FRAME_PERIOD_RANGE[1]
        ):
            raise ProvenanceError(
                f"provenance frame_period {period!r} is not a number of seconds in "
                f"[{FRAME_PERIOD_RANGE[0]:g}, {FRAME_PERIOD_RANGE[1]:g}] or null"
            )
        period = None if period is None else float(period)
        if kind == "generated":
            preset = d.get("preset")
            if preset not in PRESETS:
                raise ProvenanceError(f"provenance preset {preset!r} is not one of {list(PRESETS)}")
            counts = {}
            for name, top in (("n_subjects", MAX_SUBJECTS), ("n_stimuli", MAX_STIMULI)):
                v: Any = d.get(name)
                if not (_is_int(v) and 1 <= v <= top):
                    raise ProvenanceError(
                        f"provenance {name} {v!r} is not an integer in [1, {top}]"
                    )
                counts[name] = int(v)
            if counts["n_subjects"] * counts["n_stimuli"] > MAX_GENERATED_TRIALS:
                raise ProvenanceError(
                    f"provenance asks for {counts['n_subjects'] * counts['n_stimuli']} generated "
                    f"trials (at most {MAX_GENERATED_TRIALS})"
                )
            seed: Any = d.get("seed")
            if not (_is_int(seed) and 0 <= seed < 2**63):
                raise ProvenanceError(f"provenance seed {seed!r} is not an integer >= 0")
            options = d.get("generator_options") or {}
            if not isinstance(options, Mapping) or any(
                k not in GENERATOR_OPTIONS or not isinstance(v, bool) for k, v in options.items()
            ):
                raise ProvenanceError(
                    f"provenance generator_options {options!r}: only {list(GENERATOR_OPTIONS)} "
                    "(true/false) are allowed"
                )
            return cls(
                kind="generated",
                frame_period=period,
                preset=str(preset),
                n_subjects=counts["n_subjects"],
                n_stimuli=counts["n_stimuli"],
                seed=int(seed),
                generator_options=dict(options),
            )
        if kind == "recordings":
            files = d.get("files")
            if (
                not isinstance(files, list)
                or len(files) > MAX_FILES
                or not all(isinstance(f, str) and f and "\x00" not in f for f in files)
            ):
                raise ProvenanceError("provenance files is not a list of paths")
            options = d.get("reader_options") or {}
            if not isinstance(options, Mapping):
                raise ProvenanceError("provenance reader_options is not an object")
            unknown = sorted(set(options) - _reader_option_names())
            if unknown:
                raise ProvenanceError(
                    f"provenance reader_options has unknown option(s) {', '.join(unknown)}"
                )
            short = d.get("short", SHORT_POLICY)
            if short not in SHORT_POLICIES:
                raise ProvenanceError(
                    f"provenance short {short!r} is not one of {list(SHORT_POLICIES)}"
                )
            return cls(
                kind="recordings",
                frame_period=period,
                files=tuple(files),
                reader_options=dict(options),
                short=str(short),
            )
        return cls(kind=str(kind), frame_period=period)

    # ------------------------------------------------------------------ reading back

    @property
    def reproducible(self) -> bool:
        """Whether the trials can be had again from the record (generated or recordings)."""
        return self.kind in ("generated", "recordings")

    def check_reproducible(self) -> None:
        """Raise :class:`ProvenanceError` unless the trials may be had again: generated
        within :data:`MAX_GENERATED_TRIALS`, or recordings that are existing regular files
        or folders (a glob's folder must exist) outside ``/proc``, ``/sys`` and ``/dev``."""
        if self.kind == "generated":
            return  # bounded by from_dict / the writers
        if self.kind != "recordings":
            raise ProvenanceError(f"a model fitted on {self.kind} has no trials to read again")
        if not self.files:
            raise ProvenanceError("the record names no recordings")
        for f in self.files:
            path = Path(f)
            probe = path
            while any(ch in str(probe) for ch in "*?["):  # a glob: its fixed folder
                probe = probe.parent
            try:
                resolved = probe.resolve(strict=True)
            except (OSError, RuntimeError):
                raise ProvenanceError(f"{f}: no such file or folder") from None
            if any(resolved == Path(s) or Path(s) in resolved.parents for s in _SYSTEM):
                raise ProvenanceError(f"{f}: a system folder, not recordings")
            if not (resolved.is_file() or resolved.is_dir()):
                raise ProvenanceError(f"{f}: not a regular file or folder")

    def describe(self) -> str:
        """One sentence for reports."""
        if self.kind == "generated":
            return (
                f"Generated imitation experiment (visprim.datasets, preset {self.preset!r}): "
                f"{self.n_subjects} subjects × {self.n_stimuli} stimuli, seed {self.seed}; "
                f"four sensors every {1000 * (self.frame_period or STUDY_FRAME_PERIOD_S):.0f} ms."
            )
        if self.kind == "recordings":
            rs = (
                f"resampled to {1000 * self.frame_period:.0f} ms frames"
                if self.frame_period
                else "file rates"
            )
            paths = list(self.files)
            more = f" and {len(paths) - 5} more" if len(paths) > 5 else ""
            return f"Recordings: {', '.join(paths[:5])}{more} ({rs})."
        if self.kind == "arrays":
            return "Fitted on bare segment vectors (no trials)."
        return "Fitted on trials given in memory (not recorded)."


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _from_training_source(d: dict[str, Any]) -> dict[str, Any]:
    """An older model file's ``training_source`` dict in this record's fields."""
    kind = d.get("kind")
    if kind == "generated":
        # Sources written before the presets existed describe the "strokes" generator.
        return {
            "kind": "generated",
            "frame_period": STUDY_FRAME_PERIOD_S,
            "preset": d.get("preset", "strokes"),
            "n_subjects": d.get("n_subjects", 11),
            "n_stimuli": d.get("n_stimuli", 20),
            "seed": d.get("seed", 0),
            "generator_options": d.get("options") or {},
        }
    if kind == "files":
        return {
            "kind": "recordings",
            "frame_period": d.get("resample"),
            "files": d.get("paths", []),
            "reader_options": d.get("options") or {},
            "short": d.get("short", SHORT_POLICY),
        }
    if not d:  # fitted in memory without a source: the study's period was assumed
        return {"kind": "trials", "frame_period": STUDY_FRAME_PERIOD_S}
    raise ProvenanceError(f"unknown training source {d!r}")

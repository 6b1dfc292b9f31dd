"""Real motion capture in: BVH, ASF/AMC, C3D and the marker CSV → :class:`visprim.Trial`.

>>> from visprim.io import read, read_many
>>> trial = read("wave.bvh")                      # right arm, format from the extension
>>> trial = read("05_02.amc", skeleton="05.asf", rate=120)
>>> trials = read_many(["../shared/data"], resample=0.034)  # every recording, subfolders too

Every trial is in the common frame of :mod:`visprim.trial` — metres, +z up, the subject facing
+x at the first frame (when the torso is known), +y to the subject's left — with

* ``times`` in seconds from the first frame (or the file's own timestamps for CSV);
* ``joints``: shoulder, elbow and wrist joint centres (skeleton joints, or centres estimated
  from anatomical landmarks; see :mod:`visprim.io.c3d`);
* ``markers``: the method's four sensors. By default (``markers="virtual"``) they are placed
  as inverse kinematics assumes: mid upper arm = (shoulder + elbow) / 2, mid forearm =
  (elbow + wrist) / 2, wrist = wrist centre, finger = middle-finger knuckle (or the hand end
  extrapolated from the hand joint, see :mod:`visprim.io.assemble`). C3D files with their own
  sensors can keep them with ``markers="file"``;
* ``body_frame``: the torso's orientation (BVH/AMC: rigidly attached to the chest joint;
  C3D: thorax or shoulder markers), ``None`` when the source has no torso;
* ``name`` (file stem, ``_part2`` etc. when long gaps split a recording), ``source`` (path),
  ``subject`` (C3D subject prefix), ``stimulus`` (Bandai content label), ``meta`` (rate,
  units and up axis in the file and how they were decided, joint/marker names used, gaps
  filled, style/take labels...).

Errors are :class:`ReadError` subclasses (``ValueError``) naming the file and the problem;
bad arguments raise ``ValueError`` naming the argument.
"""

from __future__ import annotations

import fnmatch
import glob
import os
import re
import warnings
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from visprim.io.assemble import ArmRecording, align_heading, check_up_axis
from visprim.io.corpus import Corpus
from visprim.io.errors import (
    FrameCountError,
    GapError,
    MalformedFileError,
    MissingPointError,
    ReadError,
    TruncatedFileError,
    UnknownFormatError,
)
from visprim.io.gaps import check_gap_options
from visprim.io.presets import MARKER_PRESETS, RIG_PRESETS, check_arm
from visprim.io.resample import check_resample_period, resample_trial
from visprim.io.views import read_views, read_views_pieces
from visprim.params import MARKER_SOURCES, READ_OPTIONS
from visprim.trial import Trial, TrialError

__all__ = [
    "BANDAI_NAME",
    "FORMATS",
    "MARKER_PRESETS",
    "RIG_PRESETS",
    "Corpus",
    "FrameCountError",
    "GapError",
    "MalformedFileError",
    "MissingPointError",
    "ReadError",
    "TruncatedFileError",
    "UnknownFormatError",
    "labels_from_name",
    "read",
    "read_many",
    "read_pieces",
    "read_views",
    "read_views_pieces",
    "resample_trial",
]

#: Supported extensions (lower case) → format name.
FORMATS: dict[str, str] = {
    ".bvh": "bvh",
    ".amc": "amc",
    ".c3d": "c3d",
    ".csv": "csv",
    ".npz": "amass",
    ".trc": "trc",
    **dict.fromkeys((".mp4", ".avi", ".mov", ".webm", ".mkv"), "video"),
}
#: Options that only apply to some formats (the marker CSV is already an arm trial in the
#: common frame; declared in :data:`visprim.params.READ_OPTIONS`). read() refuses them for
#: other files; read_many() passes them only there.
_FORMAT_OPTIONS: dict[str, tuple[str, ...]] = {
    o.name: o.formats for o in READ_OPTIONS.values() if o.formats is not None
}

#: Bandai-Namco file names: ``dataset-<n>_<content>_<style>_<take>`` (the stem).
BANDAI_NAME = re.compile(
    r"^dataset-(?P<dataset>\d+)_(?P<content>[a-z0-9-]+)_(?P<style>[a-z]+)_(?P<take>\d+)$"
)


def labels_from_name(stem: str) -> dict[str, Any]:
    """Labels encoded in a file name. Bandai-Namco: ``dataset-2_wave-right-hand_normal_001`` →
    ``{"dataset": 2, "content": "wave-right-hand", "style": "normal", "take": 1}``; other
    names → ``{}``."""
    m = BANDAI_NAME.match(stem)
    if m is None:
        return {}
    return {
        "dataset": int(m["dataset"]),
        "content": m["content"],
        "style": m["style"],
        "take": int(m["take"]),
    }


def _format_of(path: Path) -> str:
    ext = path.suffix.lower()
    if ext == ".asf":
        raise UnknownFormatError(
            path,
            "an .asf file is a skeleton without motion; read the .amc file "
            "(its skeleton is found next to it, or pass skeleton=...)",
        )
    if ext not in FORMATS:
        raise UnknownFormatError(
            path,
            f"unknown extension {path.suffix or '(none)'!r}; supported: "
            + ", ".join(sorted(FORMATS)),
        )
    return FORMATS[ext]


#: The readers' defaults (:data:`visprim.params.READ_OPTIONS`).
_D: dict[str, Any] = {o.name: o.default for o in READ_OPTIONS.values()}


def read_pieces(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    skeleton: str | os.PathLike[str] | None = _D["skeleton"],
    rate: float | None = _D["rate"],
    mapping: Mapping[str, str | Sequence[str]] | None = _D["mapping"],
    preset: str | None = _D["preset"],
    up_axis: str | None = _D["up_axis"],
    units: str | float | None = _D["units"],
    markers: str = _D["markers"],
    max_gap: float = _D["max_gap"],
    on_gap: str = _D["on_gap"],
    gap_method: str = _D["gap_method"],
    min_duration: float = _D["min_duration"],
    resample: float | None = _D["resample"],
    repetitions: int | None = _D["repetitions"],
    mirror: bool = _D["mirror"],
    person: int | None = _D["person"],
) -> list[Trial]:
    """Read one recording as a list of trials (several when long gaps split it).

    Parameters
    ----------
    path : path of a .bvh, .amc, .c3d or .csv file
    arm : 'right' (default), 'left' or 'both' (a two-arm trial, see
        :attr:`visprim.trial.Trial.arms`)
    skeleton : AMC only: the .asf (default: same stem, else the only .asf in the folder,
        else the .asf whose stem starts the AMC's stem)
    rate : AMC only: frames per second (default 120, CMU; AMC does not store it)
    mapping : dict, optional
        Explicit names per role, e.g. ``{"shoulder": "RightArm", "elbow":
        "RightForeArm", "wrist": "RightHand"}`` (BVH/ASF) or ``{"acromion": "RSHO",
        "elbow": ["EPL", "EPM"], "wrist": ["WRA", "WRB"], "finger": "FIN"}`` (C3D); roles are
        listed in :mod:`visprim.io.presets`. Overrides the preset's names.
    preset : a name from :data:`RIG_PRESETS` (BVH/AMC) or :data:`MARKER_PRESETS` (C3D);
        default: the first preset whose arm joints/markers are all in the file
    up_axis : the file's vertical axis ('+y', '+z', '-x', ...). Default: +Y for BVH/AMC,
        ``POINT:Y_SCREEN`` or anatomy for C3D (see :mod:`visprim.io.c3d`)
    units : BVH only: the length unit ('m', 'cm', 'mm', 'in' or metres per unit); default
        detected from the upper-arm length
    markers : 'virtual' (default) or 'file' (C3D: the file's own sensor markers)
    max_gap : seconds; C3D gaps up to this long are filled (``gap_method``: 'cubic',
        'pchip' or 'linear'), longer ones handled by ``on_gap``: 'split' (cut into pieces),
        'longest' (keep the longest piece) or 'raise' (:class:`GapError`); pieces shorter
        than ``min_duration`` seconds are dropped with a warning. See :mod:`visprim.io.gaps`
    resample : new frame period in seconds (e.g. 0.034), or None to keep the file's
    repetitions : ``Trial.repetitions`` (default 1; CSV: the file's value)
    mirror : reflect left ↔ right so that a left arm looks like a right arm (for the
        right-arm angle convention); default False
    person : video only: which person to follow when several are in view, numbered from 0,
        largest first (default: the largest; see :mod:`visprim.io.video`)
    """
    p = Path(path)
    fmt = _format_of(p)
    arm = check_arm(arm)
    check_gap_options(max_gap, on_gap, gap_method)
    if not p.is_file():
        raise ReadError(p, "no such file" if not p.exists() else "not a regular file")
    if up_axis is not None:
        check_up_axis(up_axis)
    given = {
        "skeleton": skeleton,
        "rate": rate,
        "units": units,
        "mapping": mapping,
        "preset": preset,
        "up_axis": up_axis,
        "mirror": mirror or None,
        "person": person,
    }
    for name, value in given.items():
        formats = _FORMAT_OPTIONS[name]
        if value is not None and fmt not in formats:
            raise ValueError(f"{name}= applies to {'/'.join(formats)} files, not {p.name}")
    if markers not in ("virtual", "file"):
        raise ValueError(f"markers must be 'virtual' or 'file', got {markers!r}")
    if markers == "file" and fmt != "c3d":
        raise ValueError(f"markers='file' applies to C3D files, not {p.name}")
    if repetitions is not None and int(repetitions) < 1:
        raise ValueError(f"repetitions must be >= 1, got {repetitions!r}")
    check_person(person)
    if resample is not None:
        check_resample_period(resample)

    if fmt == "csv":
        trials = [_read_csv(p, arm, repetitions)]
    elif fmt in ("trc", "video"):  # keypoints: visprim.io.trc, visprim.io.video
        from visprim.io.keypoints import read_keypoint_file

        gaps = {"max_gap": max_gap, "on_gap": on_gap, "gap_method": gap_method}
        gaps["min_duration"] = min_duration
        trials = read_keypoint_file(
            p, fmt, arm, mapping, up_axis, mirror, repetitions, gaps, person=person
        )
    else:
        if arm == "both" and mirror:
            raise ValueError(
                "mirror= does not apply to arm='both' (the left arm is mirrored by IK)"
            )
        sides = ("right", "left") if arm == "both" else (arm,)
        per_side = [
            _read_arm(
                p,
                fmt,
                side,
                skeleton=skeleton,
                rate=rate,
                mapping=mapping,
                preset=preset,
                up_axis=up_axis,
                units=units,
                markers=markers,
                max_gap=max_gap,
                on_gap=on_gap,
                gap_method=gap_method,
                min_duration=min_duration,
            )
            for side in sides
        ]
        recs = per_side[0]
        heading = align_heading([r for side in per_side for r in side])
        if len(per_side) > 1 and [r.times.shape for r in per_side[1]] != [
            r.times.shape for r in recs
        ]:
            raise MalformedFileError(
                p, "the right and left arms have different gaps; read each arm on its own"
            )
        if mirror:
            for r in recs:
                r.mirror()
        labels = labels_from_name(p.stem)
        trials = []
        for i, rec in enumerate(recs):
            meta = {
                **rec.meta,
                **labels,
                "arm": arm,
                "mirrored": bool(mirror),
                "heading_deg": heading,
                "piece": [i + 1, len(recs)],
            }
            arm_recs = [side[i] for side in per_side]
            try:
                trial = Trial(
                    times=rec.times,
                    markers=np.concatenate([r.markers(markers) for r in arm_recs], axis=1),
                    joints=np.concatenate([r.joints for r in arm_recs], axis=1),
                    body_frame=rec.body_frame,
                    name=p.stem if len(recs) == 1 else f"{p.stem}_part{i + 1}",
                    subject=rec.meta.get("subject"),
                    stimulus=labels.get("content"),
                    repetitions=1 if repetitions is None else int(repetitions),
                    source=str(p),
                    meta=meta,
                    arms=("right", "left") if arm == "both" else ("right",),
                )
            except TrialError as exc:
                raise MalformedFileError(
                    p, f"the arm's points are degenerate ({_without_path(str(exc), p)})"
                ) from None
            trials.append(trial)
    if resample is not None:
        try:
            trials = [resample_trial(t, resample) for t in trials]
        except (TrialError, ValueError) as exc:
            raise ReadError(p, _without_path(str(exc), p)) from None
    return trials


def _without_path(message: str, p: Path) -> str:
    """``message`` without a leading ``"<path>: "`` (ReadError adds the path itself)."""
    return message[len(str(p)) :].lstrip(":, ") if message.startswith(str(p)) else message


def read(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    skeleton: str | os.PathLike[str] | None = _D["skeleton"],
    rate: float | None = _D["rate"],
    mapping: Mapping[str, str | Sequence[str]] | None = _D["mapping"],
    preset: str | None = _D["preset"],
    up_axis: str | None = _D["up_axis"],
    units: str | float | None = _D["units"],
    markers: str = _D["markers"],
    max_gap: float = _D["max_gap"],
    on_gap: str = _D["on_gap"],
    gap_method: str = _D["gap_method"],
    min_duration: float = _D["min_duration"],
    resample: float | None = _D["resample"],
    repetitions: int | None = _D["repetitions"],
    mirror: bool = _D["mirror"],
    person: int | None = _D["person"],
) -> Trial:
    """Read one recording as one :class:`~visprim.trial.Trial`.

    The options are those of :func:`read_pieces`. If long gaps split the recording into
    several pieces, raises :class:`GapError` (use :func:`read_pieces` / :func:`read_many`
    for all pieces, or ``on_gap="longest"``).
    """
    given = locals()
    options: dict[str, Any] = {name: given[name] for name in READ_OPTIONS}
    trials = read_pieces(path, arm, **options)
    if len(trials) > 1:
        spans = ", ".join(f"{t.times[0]:.2f}–{t.times[-1]:.2f} s" for t in trials)
        raise GapError(
            path,
            f"long gaps split the recording into {len(trials)} pieces ({spans}); use "
            "read_pieces() or read_many() to get them all, or on_gap='longest'",
        )
    return trials[0]


def _walk_files(root: Path) -> list[Path]:
    """Files under ``root``, subfolders included; symbolic links to folders are followed
    once each (a link back to a parent is not walked again)."""
    found: list[Path] = []
    seen: set[tuple[int, int]] = set()
    stack = [root]
    while stack:
        folder = stack.pop()
        try:
            st = folder.stat()
            key = (st.st_dev, st.st_ino)
            if key in seen:
                continue
            seen.add(key)
            entries = list(os.scandir(folder))
        except OSError:
            continue  # unreadable or dangling: nothing to read there
        for entry in entries:
            try:
                if entry.is_dir():
                    stack.append(Path(entry.path))
                elif entry.is_file():
                    found.append(Path(entry.path))
            except OSError:
                continue
    return found


def _glob(pattern: str, recursive: bool) -> list[Path]:
    """:func:`glob.glob`, but ``**`` walks folders with :func:`_walk_files` (safe against
    symbolic-link loops, which make ``glob`` recurse without end)."""
    if not (recursive and "**" in pattern):
        return [Path(h) for h in glob.glob(pattern)]
    parts = Path(pattern).parts
    k = next(i for i, part in enumerate(parts) if any(ch in part for ch in "*?["))
    root = Path(*parts[:k]) if k else Path(".")
    flat = pattern.replace("**" + os.sep, "")
    hits = []
    for f in _walk_files(root):
        name = str(f) if k else os.path.relpath(f)
        if fnmatch.fnmatchcase(name, pattern) or fnmatch.fnmatchcase(name, flat):
            hits.append(f)
    return hits


def _expand(
    sources: str | os.PathLike[str] | Iterable[str | os.PathLike[str]], recursive: bool
) -> list[Path]:
    items = [sources] if isinstance(sources, (str, os.PathLike)) else list(sources)
    out: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            walk = _walk_files(p) if recursive else [f for f in p.iterdir() if f.is_file()]
            found = sorted(f for f in walk if f.suffix.lower() in FORMATS)
            if not found:
                raise ReadError(
                    p,
                    f"no recordings ({', '.join(sorted(FORMATS))}) in this folder"
                    + ("" if recursive else " (recursive=True searches subfolders)"),
                )
            out.extend(found)
        elif p.exists():
            out.append(p)
        elif any(ch in str(item) for ch in "*?["):
            hits = sorted(_glob(str(item), recursive))
            files = [h for h in hits if h.is_file() and h.suffix.lower() in FORMATS]
            if not files:
                raise ReadError(str(item), "the pattern matches no recording")
            out.extend(files)
        else:
            raise ReadError(p, "no such file or folder")
    seen: set[Path] = set()
    unique = []
    for f in out:
        key = f.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(f)
    return unique


def read_many(
    sources: str | os.PathLike[str] | Iterable[str | os.PathLike[str]],
    arm: str = "right",
    *,
    recursive: bool = True,
    on_error: str = "raise",
    **options: Any,
) -> list[Trial]:
    """Read files, folders and glob patterns into one flat list of trials.

    Folders contribute their .bvh/.amc/.c3d/.csv files, subfolders included unless
    ``recursive=False`` (sorted; other files such as README.md, .asf skeletons and licences
    are skipped);
    patterns are expanded with :func:`glob.glob`. Recordings split by long gaps contribute
    every piece. Options are those of :func:`read_pieces`; format-specific ones (``skeleton``
    and ``rate`` for AMC, ``units`` for BVH, ``mapping``, ``preset``, ``up_axis`` and
    ``mirror`` for the motion-capture formats, not the marker CSV) are only passed to files of
    those formats.
    ``on_error="warn"`` skips unreadable files (other formats named explicitly included)
    with a warning instead of raising; every problem of a file is a :class:`ReadError`, so
    nothing else escapes. Bad arguments (an unknown preset, ``resample=1e-9``) raise
    ``ValueError`` before any file is read, whatever ``on_error``. Folders and ``**``
    patterns follow symbolic links to folders once each (link loops are not walked again).
    """
    if on_error not in ("raise", "warn"):
        raise ValueError(f"on_error must be 'raise' or 'warn', got {on_error!r}")
    unknown = set(options) - set(_READ_OPTIONS)
    if unknown:
        raise TypeError(f"read_many() got unexpected option(s) {', '.join(sorted(unknown))}")
    arm = check_arm(arm)
    _check_options(options)
    trials: list[Trial] = []
    for path in _expand(sources, recursive):
        try:
            fmt = _format_of(path)
            opts = {
                k: v
                for k, v in options.items()
                if k not in _FORMAT_OPTIONS or fmt in _FORMAT_OPTIONS[k]
            }
            trials.extend(read_pieces(path, arm, **opts))
        except ReadError as exc:
            if on_error == "raise":
                raise
            warnings.warn(f"skipped: {exc}", stacklevel=2)
        except Exception as exc:
            # Data that got past a reader's checks (a reader bug): still one file's problem.
            err = ReadError(path, f"unexpected {type(exc).__name__}: {exc}")
            if on_error == "raise":
                raise err from exc
            warnings.warn(f"skipped: {err}", stacklevel=2)
    return trials


#: Keyword options of :func:`read_pieces` (and so of :func:`read_many`).
_READ_OPTIONS = tuple(READ_OPTIONS)


def read_option_names() -> tuple[str, ...]:
    """Every keyword option of :func:`read_many` (``arm`` and those of :func:`read_pieces`)."""
    return ("arm", *_READ_OPTIONS)


def _check_options(options: Mapping[str, Any]) -> None:
    """Argument checks that do not depend on the file (ValueError naming the argument)."""

    def get(name: str) -> Any:
        return options.get(name, READ_OPTIONS[name].default)

    check_gap_options(get("max_gap"), get("on_gap"), get("gap_method"))
    if options.get("up_axis") is not None:
        check_up_axis(options["up_axis"])
    if get("markers") not in MARKER_SOURCES:
        raise ValueError(f"markers must be 'virtual' or 'file', got {options['markers']!r}")
    preset = options.get("preset")
    if preset is not None and preset not in RIG_PRESETS and preset not in MARKER_PRESETS:
        raise ValueError(
            f"unknown preset {preset!r}; rig presets: {', '.join(RIG_PRESETS)}; marker "
            f"presets: {', '.join(MARKER_PRESETS)}"
        )
    if options.get("resample") is not None:
        check_resample_period(options["resample"])
    reps = options.get("repetitions")
    if reps is not None and int(reps) < 1:
        raise ValueError(f"repetitions must be >= 1, got {reps!r}")
    check_person(options.get("person"))


def check_person(person: Any) -> None:
    """``person=`` is None or a person number >= 0 (ValueError otherwise)."""
    if person is not None and (
        isinstance(person, bool) or not isinstance(person, (int, np.integer)) or person < 0
    ):
        raise ValueError(f"person must be None or an integer >= 0, got {person!r}")


def _read_arm(p: Path, fmt: str, arm: str, **kw: Any) -> list[ArmRecording]:
    """The format's reader on ``p``; whatever goes wrong in it is a :class:`ReadError`
    naming the file (the arguments were checked before)."""
    try:
        return _read_arm_of(p, fmt, arm, **kw)
    except ReadError:
        raise
    except MemoryError:
        raise MalformedFileError(p, "too large to read in the memory available") from None
    except ValueError as exc:
        raise MalformedFileError(p, _without_path(str(exc), p) or "unreadable") from exc
    except Exception as exc:
        reason = _without_path(str(exc), p) or "no details"
        raise MalformedFileError(p, f"unreadable ({type(exc).__name__}: {reason})") from exc


def _read_arm_of(p: Path, fmt: str, arm: str, **kw: Any) -> list[ArmRecording]:
    if fmt == "bvh":
        from visprim.io.bvh import read_bvh_arm

        return [
            read_bvh_arm(
                p,
                arm,
                preset=kw["preset"],
                mapping=kw["mapping"],
                up_axis=kw["up_axis"],
                units=kw["units"],
            )
        ]
    if fmt == "amass":
        from visprim.io.amass import read_amass_arm

        return [read_amass_arm(p, arm, up_axis=kw["up_axis"])]
    if fmt == "amc":
        from visprim.io.asfamc import read_amc_arm

        return [
            read_amc_arm(
                p,
                arm,
                skeleton=kw["skeleton"],
                rate=kw["rate"],
                preset=kw["preset"],
                mapping=kw["mapping"],
                up_axis=kw["up_axis"],
            )
        ]
    from visprim.io.c3d import read_c3d_arm

    return read_c3d_arm(
        p,
        arm,
        preset=kw["preset"],
        mapping=kw["mapping"],
        up_axis=kw["up_axis"],
        markers=kw["markers"],
        max_gap=kw["max_gap"],
        on_gap=kw["on_gap"],
        gap_method=kw["gap_method"],
        min_duration=kw["min_duration"],
    )


def _read_csv(p: Path, arm: str, repetitions: int | None) -> Trial:
    if arm != "right":
        raise ValueError(f"{p}: the marker CSV holds one (right) arm; arm={arm!r} is not available")
    try:
        from visprim.io.markers_csv import read_marker_csv
    except ImportError as exc:  # pragma: no cover - the module ships with visprim
        raise ReadError(p, f"marker CSV support is unavailable ({exc})") from None
    try:
        return read_marker_csv(p, repetitions=repetitions)
    except ReadError:
        raise
    except ValueError as exc:  # MarkerCSVError: "<path>: ..." or "<path>, line N: ..."
        raise MalformedFileError(p, _without_path(str(exc), p)) from exc

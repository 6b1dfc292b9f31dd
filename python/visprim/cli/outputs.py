"""Where the commands write: checked ``--out`` paths and atomic writes.

* :func:`check_file` / :func:`check_folder` refuse, before any work is done, an output that
  cannot be written (a parent that is a file, a folder where a file is wanted, an extension
  whose format the command does not write) or that exists (unless ``--force``).
* :func:`atomic_file` writes a file to a hidden temporary name in the target's folder and
  renames it over the target once complete; :func:`atomic_folder` does the same for a whole
  folder (the report, the demo, the generated experiment). An interrupted run leaves the
  previous complete output or none (plus a hidden temporary that the next run removes),
  never a mix of old and half-written files.

A folder written by :func:`atomic_folder` holds a marker file :data:`MARKER`; ``--force``
replaces only such folders (or empty ones), never a folder of other files.

Concurrent runs: :func:`check_file` and :func:`check_folder` also claim the output for this
process (:func:`claim`): a lock file created with ``O_EXCL`` in the temporary folder, named
after the output's absolute path and holding the process id. A second run to the same
output stops at once with an error naming the first run's process; the lock is released by
:func:`release_claims` (the command line calls it when the command ends) or at exit, and a
lock whose process is gone (a killed run) is taken over.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import os
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from visprim.atomic import atomic_file, pid_alive, remove_stale
from visprim.atomic import atomic_folder as _atomic_folder
from visprim.cli.common import UsageError

__all__ = [
    "MARKER",
    "atomic_file",
    "atomic_folder",
    "check_file",
    "check_folder",
    "moved",
    "remove_stale",
]

#: File naming the command that wrote an output folder.
MARKER = ".visprim-output"
#: Extensions that make a new ``--out`` folder look like a file name (a likely mistake).
_FILE_SUFFIXES = {".html", ".htm", ".png", ".gif", ".pdf", ".csv", ".md", ".npz", ".txt"}


def _first_existing_parent(path: Path) -> Path:
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    return parent


def _check_parent(path: Path, option: str) -> None:
    parent = _first_existing_parent(path.absolute())
    if not parent.is_dir():
        raise UsageError(
            f"{option} {path}: {parent} is a file, not a folder; choose an --out in a folder"
        )
    if not os.access(parent, os.W_OK):
        raise UsageError(f"{option} {path}: cannot write in {parent}; choose another --out")


def check_file(
    path: str | os.PathLike[str],
    suffixes: Sequence[str],
    *,
    force: bool,
    option: str = "--out",
    what: str = "file",
) -> Path:
    """``path`` as an output file with one of ``suffixes`` (e.g. ``(".npz",)``)."""
    p = Path(path)
    if p.is_dir() or str(path).endswith(("/", os.sep)) or p.name in ("", ".", ".."):
        example = p / f"{what.split()[0]}{suffixes[0]}"
        raise UsageError(f"{option} {path} is a folder; give a {what} name such as {example}")
    if p.suffix.lower() not in suffixes:
        raise UsageError(
            f"{option} {path}: the {what} is written as {' or '.join(suffixes)}, not "
            f"{p.suffix or '(no extension)'}; name it {p.with_suffix(suffixes[0]).name}"
        )
    _check_parent(p, option)
    if p.exists() and not force:
        raise UsageError(f"{option} {path} exists; pass --force to replace it")
    claim(p, option)
    return p


def check_folder(
    path: str | os.PathLike[str],
    *,
    force: bool,
    inputs: Sequence[str | os.PathLike[str]] = (),
    option: str = "--out",
) -> Path:
    """``path`` as an output folder (see the module docstring); ``inputs`` are files the
    command reads, which must not be inside it (replacing the folder would delete them)."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UsageError(f"{option} {path} is a file; give a folder (new, or a previous output)")
    if not p.exists() and p.suffix.lower() in _FILE_SUFFIXES:
        raise UsageError(
            f"{option} {path} names a file, but the output is a folder (index.html and the "
            f"other files go inside); give a folder name such as {p.with_suffix('')}"
        )
    _check_parent(p, option)
    if p.is_dir() and any(p.iterdir()):
        if not (p / MARKER).is_file() and not (p / "index.html").is_file():
            raise UsageError(
                f"{option} {path} is a folder of other files; give a new or empty folder"
            )
        if not force:
            raise UsageError(
                f"{option} {path} holds a previous visprim output; pass --force to replace it"
            )
        target = p.resolve()
        for item in inputs:
            if target in Path(item).resolve().parents:
                raise UsageError(
                    f"{option} {path} holds the input {item}, which replacing it would "
                    "delete; choose another --out"
                )
    claim(p, option)
    return p


#: Lock files held by this process (path → the output they claim).
_claims: dict[Path, Path] = {}


def _lock_path(target: Path) -> Path:
    key = os.path.realpath(os.path.abspath(target))
    digest = hashlib.sha256(key.encode("utf-8", "surrogateescape")).hexdigest()[:24]
    return Path(tempfile.gettempdir()) / f"visprim-out-{digest}.lock"


def claim(target: str | os.PathLike[str], option: str = "--out") -> None:
    """Claim the output ``target`` for this process (see the module docstring); a
    :class:`UsageError` if another live visprim process holds it."""
    lock = _lock_path(Path(target))
    if lock in _claims:
        return
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            try:
                text = lock.read_text(encoding="ascii").strip()
                owner = int(text) if text else None
            except (OSError, ValueError):
                owner = None
            if owner is None:  # being written this instant, or garbage
                with contextlib.suppress(OSError):
                    if time.time() - lock.stat().st_mtime < 10.0:
                        owner = -1
            if owner is not None and owner != os.getpid() and (owner == -1 or pid_alive(owner)):
                who = "another run" if owner == -1 else f"another run (process {owner})"
                raise UsageError(
                    f"{option} {target} is being written by {who}; wait for it to finish "
                    "or choose another output"
                ) from None
            with contextlib.suppress(OSError):
                lock.unlink()  # the run that held it is gone
            continue
        except OSError:
            return  # no usable temporary folder: no lock (the checks above still hold)
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(f"{os.getpid()}\n")
        _claims[lock] = Path(target)
        return
    raise UsageError(f"{option} {target}: cannot take its lock file {lock}; try again")


def release_claims() -> None:
    """Release every output claimed by this process (:func:`claim`)."""
    for lock in list(_claims):
        with contextlib.suppress(OSError):
            if lock.read_text(encoding="ascii").strip() == str(os.getpid()):
                lock.unlink()
        del _claims[lock]


atexit.register(release_claims)


@contextlib.contextmanager
def atomic_folder(path: str | os.PathLike[str], command: str) -> Iterator[Path]:
    """:func:`visprim.atomic.atomic_folder` marked as written by visprim ``command``
    (:data:`MARKER`)."""
    with _atomic_folder(path, (MARKER, f"written by visprim {command}\n")) as tmp:
        yield tmp


def moved(path: Path, tmp: Path, target: Path) -> Path:
    """Where ``path`` (written under the temporary folder ``tmp``) is once ``tmp`` became
    ``target``."""
    try:
        return target / path.relative_to(tmp)
    except ValueError:
        return path

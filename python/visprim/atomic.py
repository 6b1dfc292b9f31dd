"""Atomic files and folders: written under a hidden temporary name beside the target, then
renamed over it once complete.

* :func:`atomic_file` yields a temporary path to write; on success the file is flushed to
  disk, given the mode a new file gets under the umask (0644 typically, as ``open`` would
  give it; ``tempfile.mkstemp``'s 0600 is not kept) and renamed over the target
  (:func:`os.replace`). :func:`write_text` and :func:`write_bytes` write one string or
  buffer that way.
* :func:`atomic_folder` yields a new hidden folder to fill; on success it replaces the
  target folder in two renames (old → hidden, new → target), then the old one is removed.

An interrupted writer leaves the previous complete output, or none, plus a hidden temporary
``.<name>.visprim-tmp-<pid>-<hex>[suffix]`` that the next write to the same target removes
once its process is gone (:func:`remove_stale`).
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
from collections.abc import Iterator
from pathlib import Path

__all__ = [
    "atomic_file",
    "atomic_folder",
    "remove_stale",
    "umask_mode",
    "write_bytes",
    "write_text",
]

_TEMP = re.compile(r"^\.(?P<name>.+)\.visprim-(?:tmp|old)-(?P<pid>\d+)-[0-9a-f]+(?:\..*)?$")


def umask_mode() -> int:
    """The mode a new regular file gets here (0o666 minus the process umask)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def _hidden(target: Path, kind: str, suffix: str = "") -> Path:
    token = secrets.token_hex(4)
    return target.parent / f".{target.name}.visprim-{kind}-{os.getpid()}-{token}{suffix}"


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale(target: Path) -> None:
    """Remove hidden temporaries of ``target`` left by killed writers (whose process is
    gone)."""
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        return
    for entry in parent.iterdir():
        m = _TEMP.match(entry.name)
        if m is None or m["name"] != target.name:
            continue
        pid = int(m["pid"])
        if pid != os.getpid() and pid_alive(pid):
            continue
        _remove(entry)


@contextlib.contextmanager
def atomic_file(path: str | os.PathLike[str], *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path (not yet created) to write; on success it replaces ``path``
    in one rename, with the umask's mode. ``suffix`` of the temporary name: the target's
    own by default (writers that pick the format from the extension see the right one).
    Parent folders are created."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(target)
    tmp = _hidden(target, "tmp", target.suffix if suffix is None else suffix)
    try:
        yield tmp
        if not tmp.is_file():
            raise RuntimeError(f"nothing was written for {target}")
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, umask_mode())
        os.replace(tmp, target)
    finally:
        _remove(tmp)


def write_text(path: str | os.PathLike[str], text: str, *, newline: str | None = None) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    with atomic_file(path) as tmp, open(tmp, "x", encoding="utf-8", newline=newline) as fh:
        fh.write(text)
    return Path(path)


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_file(path) as tmp, open(tmp, "xb") as fh:
        fh.write(data)
    return Path(path)


@contextlib.contextmanager
def atomic_folder(
    path: str | os.PathLike[str], marker: tuple[str, str] | None = None
) -> Iterator[Path]:
    """Yield a new hidden folder to fill; on success it replaces the folder ``path``
    (``marker`` = (file name, text): a file written into it last, naming the writer).

    The swap is two renames (old folder → hidden, new → ``path``) and then the removal of
    the old one: an interruption leaves the previous complete output, or none.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(target)
    tmp = _hidden(target, "tmp")
    tmp.mkdir()
    try:
        yield tmp
        if marker is not None:
            (tmp / marker[0]).write_text(marker[1], encoding="utf-8")
        old = None
        if target.exists():
            old = _hidden(target, "old")
            os.rename(target, old)
        os.rename(tmp, target)
        if old is not None:
            _remove(old)
    finally:
        _remove(tmp)

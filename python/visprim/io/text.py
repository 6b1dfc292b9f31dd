"""Reading the text formats (BVH, ASF, AMC, marker CSV): bytes → text, whatever the encoding.

Files are UTF-8 (a byte-order mark is dropped). Files that are not valid UTF-8 are decoded
as Latin-1: exporters write names and comments in the local 8-bit code page (unmodified
HDM05 files have one Latin-1 byte in their first comment), and the numbers and keywords
the readers need are ASCII either way. A NUL byte means the file is binary, not text.
"""

from __future__ import annotations

import os
from pathlib import Path

from visprim.io.errors import MalformedFileError, ReadError, TruncatedFileError


def read_text(path: str | os.PathLike[str]) -> tuple[str, str]:
    """``(text, encoding)`` of a text recording; ``encoding`` is ``"utf-8"`` or
    ``"latin-1"`` (the fallback for bytes that are not UTF-8).

    Raises
    ------
    ReadError
        The file cannot be read.
    TruncatedFileError
        The file is empty (or holds only whitespace).
    MalformedFileError
        The file holds NUL bytes (a binary file).
    """
    path = os.fspath(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise ReadError(path, f"cannot read: {exc.strerror or exc}") from None
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise MalformedFileError(path, f"not a text file (NUL byte at byte {nul})")
    try:
        text, encoding = raw.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError:
        text, encoding = raw.decode("latin-1"), "latin-1"
    if not text.strip():
        raise TruncatedFileError(path, "the file is empty")
    return text, encoding


def file_stamp(*paths: str | os.PathLike[str]) -> tuple[int, ...]:
    """Size and modification time (ns) of each file, a cache key that changes when a file
    does; a file that cannot be examined contributes ``-1, -1`` (its reader reports why)."""
    out: list[int] = []
    for p in paths:
        try:
            st = os.stat(p)
        except OSError:
            out.extend((-1, -1))
        else:
            out.extend((st.st_size, st.st_mtime_ns))
    return tuple(out)

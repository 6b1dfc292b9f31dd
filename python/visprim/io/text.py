"""Reading the text formats (BVH, ASF, AMC, marker CSV): bytes → text, whatever the encoding.

Files are UTF-8 (a byte-order mark is dropped). Files that are not valid UTF-8 are decoded
as Latin-1: exporters write names and comments in the local 8-bit code page (unmodified
HDM05 files have one Latin-1 byte in their first comment), and the numbers and keywords
the readers need are ASCII either way. A NUL byte means the file is binary, not text.

Sizes are bounded before anything is read (:func:`check_file_size`): a recording may have up
to :data:`MAX_RECORDING_BYTES`, a skeleton file :data:`MAX_SKELETON_BYTES`; character
devices, pipes and other files that are not regular files are refused (``/dev/zero`` would
be read until memory runs out).
"""

from __future__ import annotations

import os
import stat

from visprim.io.errors import MalformedFileError, ReadError, TruncatedFileError

#: Largest recording file read (bytes): 1 GiB, about 5 h of a 60-channel BVH at 120 Hz.
MAX_RECORDING_BYTES = 1 << 30
#: Largest skeleton file (.asf) read (bytes): real ones are a few kilobytes.
MAX_SKELETON_BYTES = 16 << 20


def check_file_size(path: str | os.PathLike[str], limit: int, what: str = "recording") -> int:
    """Size in bytes of the regular file ``path``; a :class:`ReadError` if it is not a
    regular file (a folder, a device, a pipe) or is larger than ``limit`` bytes."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise ReadError(path, f"cannot read: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a folder" if stat.S_ISDIR(st.st_mode) else "a device or pipe"
        raise ReadError(path, f"not a regular file ({kind}); give a {what} file")
    if st.st_size > limit:
        raise ReadError(
            path,
            f"{st.st_size / 2**20:.0f} MiB is larger than a {what} file can be "
            f"({limit / 2**20:.0f} MiB); is it the right file?",
        )
    return int(st.st_size)


def read_text(
    path: str | os.PathLike[str], *, limit: int = MAX_RECORDING_BYTES, what: str = "recording"
) -> tuple[str, str]:
    """``(text, encoding)`` of a text recording; ``encoding`` is ``"utf-8"`` or
    ``"latin-1"`` (the fallback for bytes that are not UTF-8). ``limit``: largest size in
    bytes (``what`` names the kind of file in the error).

    Raises
    ------
    ReadError
        The file cannot be read, is not a regular file, or is larger than ``limit``.
    TruncatedFileError
        The file is empty (or holds only whitespace).
    MalformedFileError
        The file holds NUL bytes (a binary file).
    """
    path = os.fspath(path)
    size = check_file_size(path, limit, what)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(size + 1)
    except OSError as exc:
        raise ReadError(path, f"cannot read: {exc.strerror or exc}") from None
    if len(raw) > limit:
        raise ReadError(path, f"grew past {limit / 2**20:.0f} MiB while being read")
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

"""Errors raised by :mod:`visprim.io`.

Every reader raises a subclass of :class:`ReadError` (itself a :class:`ValueError`) whose
message starts with the file it was reading and says what is wrong with it.
"""

from __future__ import annotations

import os


class ReadError(ValueError):
    """A recording cannot be turned into a trial.

    Attributes
    ----------
    path : str
        The file being read (or the argument that named it).
    reason : str
        What is wrong, without the path.
    """

    def __init__(self, path: str | os.PathLike[str], reason: str) -> None:
        self.path = os.fspath(path)
        self.reason = reason
        super().__init__(f"{self.path}: {reason}")


class UnknownFormatError(ReadError):
    """The file's extension is not one of the supported formats."""


class MalformedFileError(ReadError):
    """The file does not follow its format (bad token, non-numeric value, missing section)."""


class TruncatedFileError(MalformedFileError):
    """The file ends before the data it declares (frames, rows, values)."""


class FrameCountError(MalformedFileError):
    """Frame counts disagree (declared vs present, or between channels / files)."""


class MissingPointError(ReadError):
    """A joint or marker needed for the requested arm is not in the file."""


class GapError(ReadError):
    """A gap (run of missing samples) is longer than allowed, or splits a trial that the
    caller asked to read as one piece."""

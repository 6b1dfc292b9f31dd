"""Lazy corpora: recordings (or generated trials) read on demand, in chunks.

A corpus is a sequence of *items* — one recording file, or one generated trial — that are
only read when asked for:

>>> from visprim.io import Corpus
>>> corpus = Corpus(["mocap/", "extra/*.bvh"], resample=0.034)
>>> len(corpus)                      # recordings, not yet read
>>> for trials in corpus.chunks(64):  # lists of Trial, 64 recordings at a time
...     ...
>>> from visprim.io.corpus import GeneratedCorpus
>>> big = GeneratedCorpus(n_subjects=500, n_stimuli=400)  # 200,000 trials, none in memory

``len(corpus)`` counts items. An item is normally one trial; a C3D recording split by long
gaps contributes all its pieces to the chunk that reads it (so the number of trials is only
known once read). Items are read in order and the same item always gives the same trials:
a corpus can be read several times, in any order (:meth:`LazyCorpus.read`), by several
processes (corpora pickle as their description, not their data).

Both kinds describe themselves as a :class:`~visprim.provenance.Provenance`
(:attr:`LazyCorpus.provenance`), the record :class:`~visprim.model.PrimitiveModel` keeps in
``provenance_``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from visprim.provenance import Provenance
from visprim.trial import EACH_ARM, Trial, split_arms

__all__ = ["DEFAULT_CHUNK", "Corpus", "GeneratedCorpus", "LazyCorpus", "sample_items"]

#: Items per chunk when none is given: small enough that a chunk of typical recordings
#: (a few seconds each) takes a few MB, large enough that the kernels run on long arrays.
DEFAULT_CHUNK = 256


class LazyCorpus:
    """Base of the lazy corpora: ``len``, :meth:`read` of any items, :meth:`chunks`.

    Subclasses implement ``__len__``, :meth:`read_item` and :attr:`source`.
    """

    def __len__(self) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def read_item(self, index: int) -> list[Trial]:  # pragma: no cover - abstract
        """The trial(s) of item ``index`` (one, or the pieces of a split recording)."""
        raise NotImplementedError

    @property
    def provenance(self) -> Provenance:  # pragma: no cover - abstract
        """How to get these trials again (``provenance_`` of a model)."""
        raise NotImplementedError

    def _index(self, index: int) -> int:
        n = len(self)
        i = int(index)
        if not -n <= i < n:
            raise IndexError(f"item {index} out of range for a corpus of {n} item(s)")
        return i % n

    def read(self, indices: Iterable[int]) -> list[Trial]:
        """The trials of the items ``indices``, in that order (pieces of an item together)."""
        out: list[Trial] = []
        for i in indices:
            out.extend(self.read_item(self._index(i)))
        return out

    def subset(self, indices: Sequence[int]) -> LazyCorpus:
        """The items ``indices`` as a corpus of their own (item ``j`` = item
        ``indices[j]``), small to send to another process."""
        return _Subset(self, [self._index(i) for i in indices])

    def chunk_ranges(self, size: int | None = None) -> list[range]:
        """Consecutive item ranges of ``size`` items (default :data:`DEFAULT_CHUNK`)."""
        size = _check_size(size)
        n = len(self)
        return [range(a, min(a + size, n)) for a in range(0, n, size)]

    def chunks(self, size: int | None = None) -> Iterator[list[Trial]]:
        """The trials, ``size`` items at a time (a chunk of a split recording may hold more
        trials than items; a chunk whose items all failed to read is skipped)."""
        for r in self.chunk_ranges(size):
            trials = self.read(r)
            if trials:
                yield trials

    def __iter__(self) -> Iterator[Trial]:
        for chunk in self.chunks():
            yield from chunk


class _Subset(LazyCorpus):
    def __init__(self, parent: LazyCorpus, indices: list[int]) -> None:
        self.parent, self.indices = parent, indices

    def __len__(self) -> int:
        return len(self.indices)

    def read_item(self, index: int) -> list[Trial]:
        return self.parent.read_item(self.indices[self._index(index)])

    @property
    def provenance(self) -> Provenance:
        return self.parent.provenance


def _check_size(size: int | None) -> int:
    if size is None:
        return DEFAULT_CHUNK
    if isinstance(size, bool) or not isinstance(size, int | np.integer) or size < 1:
        raise ValueError(f"chunk size must be a positive integer, got {size!r}")
    return int(size)


def sample_items(n: int, max_items: int) -> np.ndarray:
    """Deterministic sample of at most ``max_items`` of ``n`` item indices, spread evenly
    (the sample SEG-2's threshold is tuned on, :mod:`visprim.segment.seg2`)."""
    if n <= max_items:
        return np.arange(n, dtype=np.int64)
    return np.unique(np.linspace(0, n - 1, int(max_items)).round().astype(np.int64))


class Corpus(LazyCorpus):
    """Recording files, folders and glob patterns, read on demand.

    Parameters
    ----------
    sources : a path, folder or glob pattern, or several
        Expanded as :func:`visprim.io.read_many` does (folders: every recording inside,
        subfolders too unless ``recursive=False``; duplicates dropped). Expansion happens
        here, once: ``len`` is known without reading anything.
    arm : 'right' (default), 'left', 'both', or 'each': both arms as two one-arm trials, the
        left mirrored into a right arm (:func:`visprim.trial.split_arms`)
    recursive : search subfolders of folders
    on_error : 'raise' (default) or 'warn' — skip an unreadable file with a warning (as
        :func:`~visprim.io.read_many`: reader errors and unexpected errors on a file's data)
    **options : those of :func:`visprim.io.read_pieces` (``resample``, ``rate``, ``mirror``,
        ...), passed only to the formats they apply to, as in :func:`~visprim.io.read_many`.

    Raises
    ------
    visprim.io.ReadError
        A source that does not exist, a folder without recordings, a pattern that matches
        none (at construction; errors of a file's content come when it is read).
    """

    def __init__(
        self,
        sources: str | os.PathLike[str] | Iterable[str | os.PathLike[str]],
        arm: str = "right",
        *,
        recursive: bool = True,
        on_error: str = "raise",
        **options: Any,
    ) -> None:
        from visprim.io import _READ_OPTIONS, _check_options, _expand, check_arm

        if on_error not in ("raise", "warn"):
            raise ValueError(f"on_error must be 'raise' or 'warn', got {on_error!r}")
        unknown = set(options) - set(_READ_OPTIONS)
        if unknown:
            raise TypeError(f"Corpus() got unexpected option(s) {', '.join(sorted(unknown))}")
        arm = EACH_ARM if str(arm).lower() == EACH_ARM else check_arm(arm)
        _check_options(options)
        self.paths: list[Path] = _expand(sources, recursive)
        self.arm = arm
        self.on_error = on_error
        self.options = dict(options)

    def __len__(self) -> int:
        return len(self.paths)

    def __repr__(self) -> str:
        return f"Corpus({len(self)} recordings)"

    def subset(self, indices: Sequence[int]) -> Corpus:
        out = object.__new__(Corpus)
        out.paths = [self.paths[self._index(i)] for i in indices]
        out.arm, out.on_error, out.options = self.arm, self.on_error, dict(self.options)
        return out

    def read_item(self, index: int) -> list[Trial]:
        from visprim import io

        path = self.paths[self._index(index)]
        try:
            fmt = io._format_of(path)
            opts = {
                k: v
                for k, v in self.options.items()
                if k not in io._FORMAT_OPTIONS or fmt in io._FORMAT_OPTIONS[k]
            }
            if self.arm == EACH_ARM:
                return split_arms(io.read_pieces(path, "both", **opts))
            return io.read_pieces(path, self.arm, **opts)
        except io.ReadError as exc:
            err = exc
        except (ValueError, ArithmeticError, LookupError, TypeError) as exc:
            # As read_many: data that got past a reader's checks is still one file's problem.
            err = io.ReadError(path, f"unexpected {type(exc).__name__}: {exc}")
            err.__cause__ = exc
        if self.on_error == "raise":
            raise err
        warnings.warn(f"skipped: {err}", stacklevel=2)
        return []

    @property
    def provenance(self) -> Provenance:
        options = {k: v for k, v in self.options.items() if k != "resample"}
        if self.arm != "right":
            options["arm"] = self.arm
        return Provenance.recordings(self.paths, self.options.get("resample"), options)


class GeneratedCorpus(LazyCorpus):
    """The generated imitation experiment (:func:`visprim.datasets.imitation_experiment`)
    with each trial generated when read.

    Item ``i`` is subject ``i // n_stimuli`` imitating stimulus ``i % n_stimuli``: the same
    order and the same trials as ``imitation_experiment(n_subjects, n_stimuli, seed,
    **options)``, without holding them. ``options`` are that function's keyword arguments
    (``noise``, ``drift``, ...).
    """

    def __init__(
        self,
        n_subjects: int = 11,
        n_stimuli: int = 20,
        seed: int = 0,
        *,
        preset: str = "paper",
        **options: Any,
    ) -> None:
        from visprim.datasets import stimuli, subjects

        # Validate as the generator does (and fail now rather than in a worker).
        self._subjects = subjects(n_subjects, seed, preset)
        self._stimuli = stimuli(n_stimuli, seed, preset)
        self.preset = str(preset)
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        self.n_subjects = int(n_subjects)
        self.n_stimuli = int(n_stimuli)
        self.seed = int(seed)
        self.options = dict(options)

    def __len__(self) -> int:
        return self.n_subjects * self.n_stimuli

    def __repr__(self) -> str:
        return (
            f"GeneratedCorpus({self.n_subjects} subjects x {self.n_stimuli} stimuli, "
            f"seed {self.seed}, preset {self.preset!r})"
        )

    def read_item(self, index: int) -> list[Trial]:
        from visprim.datasets import generate_trial

        s, m = divmod(self._index(index), self.n_stimuli)
        return [generate_trial(self._subjects[s], self._stimuli[m], m, self.seed, **self.options)]

    @property
    def provenance(self) -> Provenance:
        return Provenance.generated(
            self.n_subjects, self.n_stimuli, self.seed, self.preset, **self.options
        )

    def __getstate__(self) -> dict[str, Any]:
        # Ship the description, not the sampled subjects and stimuli.
        return {
            "n_subjects": self.n_subjects,
            "n_stimuli": self.n_stimuli,
            "seed": self.seed,
            "preset": self.preset,
            "options": self.options,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        GeneratedCorpus.__init__(
            self,
            state["n_subjects"],
            state["n_stimuli"],
            state["seed"],
            preset=state["preset"],
            **state["options"],
        )


def as_lazy(data: Any) -> LazyCorpus | None:
    """``data`` as a :class:`LazyCorpus` if it is one, else None (lists of trials stay)."""
    return data if isinstance(data, LazyCorpus) else None


def trial_names(trials: Sequence[Trial], first: int) -> list[str]:
    """Names of trials as :func:`visprim.preprocess.prepare_corpus` gives them, with unnamed
    trials numbered by their position ``first + i`` in the whole corpus."""
    return [t.name or (t.source or f"#{first + i}") for i, t in enumerate(trials)]

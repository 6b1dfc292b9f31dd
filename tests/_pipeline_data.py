"""Shared, cached data for the pipeline tests (a plain helper module, not a test file).

Fits are cached per process so that the model, error, classification, report and CLI tests
share them instead of refitting.
"""

from __future__ import annotations

from functools import cache

from visprim.datasets import imitation_experiment
from visprim.model import PrimitiveModel
from visprim.trial import Trial

#: Where the cached generated trials come from (recorded in models for `visprim report`).
SOURCE = {"kind": "generated", "n_subjects": 11, "n_stimuli": 20, "seed": 0}


@cache
def default_trials() -> tuple[Trial, ...]:
    """The default generated experiment (11 subjects x 20 stimuli, seed 0)."""
    return tuple(imitation_experiment())


@cache
def fitted(segmentation: str = "seg2", n_clusters: int = 30) -> PrimitiveModel:
    """A model of the paper's method fitted on :func:`default_trials` (do not mutate it)."""
    model = PrimitiveModel.paper(segmentation=segmentation, n_clusters=n_clusters)
    return model.fit(list(default_trials()), source=dict(SOURCE))


def n_true_strokes() -> int:
    """Number of distinct true stroke primitives in the default experiment."""
    return len({int(v) for t in default_trials() for v in t.truth.labels})

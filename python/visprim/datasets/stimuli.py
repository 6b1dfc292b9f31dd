"""The stimuli: the short demonstration "videos" the subjects imitate.

A stimulus is a fixed chain of 2–6 strokes (consecutive strokes share a key posture)
made of a prefix, a sub-sequence repeated ``repetitions`` times and a suffix. The
:data:`STIMULI` table holds the 20 stimuli of the experiment; 9 of them repeat a
sub-sequence 2 or 3 times. Their nominal length (strokes at the stimulus's tempo plus a
0.4 s hold before and after) is 3–5 s, like the original videos.

More than 20 stimuli can be requested: the extra ones are random valid chains drawn by
:func:`random_stimulus` (deterministic for its generator).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visprim.datasets.vocabulary import PRIMITIVE_NAMES, VOCABULARY, primitive_index

#: Nominal stillness before the first and after the last stroke of a stimulus, seconds.
STIMULUS_HOLD_S = 0.4


@dataclass(frozen=True)
class Stimulus:
    """One stimulus.

    Attributes
    ----------
    name : str
        Short description.
    prefix, repeat, suffix : tuple of int
        Stroke labels (indices into :data:`~visprim.datasets.vocabulary.VOCABULARY`);
        the stroke sequence is ``prefix + repeat * repetitions + suffix``.
    repetitions : int
        How many times ``repeat`` is performed (1 when nothing repeats).
    tempo : float
        Duration scale of the demonstration's strokes (1 = the vocabulary's durations).
    """

    name: str
    prefix: tuple[int, ...]
    repeat: tuple[int, ...]
    repetitions: int
    suffix: tuple[int, ...]
    tempo: float = 1.0

    @property
    def strokes(self) -> tuple[int, ...]:
        """Stroke labels in order."""
        return self.prefix + self.repeat * self.repetitions + self.suffix

    @property
    def nominal_duration(self) -> float:
        """Length of the demonstration in seconds (strokes plus the holds)."""
        return 2 * STIMULUS_HOLD_S + self.tempo * sum(VOCABULARY[k].duration for k in self.strokes)

    def validate(self) -> None:
        """Raise ValueError unless the strokes chain (each starts where the last ended)."""
        strokes = self.strokes
        if not 2 <= len(strokes) <= 6:
            raise ValueError(f"stimulus {self.name!r}: needs 2-6 strokes, has {len(strokes)}")
        if self.repetitions < 1 or (self.repetitions > 1 and not self.repeat):
            raise ValueError(f"stimulus {self.name!r}: bad repetitions {self.repetitions}")
        for a, b in zip(strokes[:-1], strokes[1:], strict=True):
            if VOCABULARY[a].end != VOCABULARY[b].start:
                raise ValueError(
                    f"stimulus {self.name!r}: {VOCABULARY[a].name} ends at "
                    f"{VOCABULARY[a].end!r} but {VOCABULARY[b].name} starts at "
                    f"{VOCABULARY[b].start!r}"
                )


def _s(name: str, prefix: str, repeat: str, reps: int, suffix: str, tempo: float) -> Stimulus:
    def labels(text: str) -> tuple[int, ...]:
        return tuple(primitive_index(w) for w in text.split())

    return Stimulus(name, labels(prefix), labels(repeat), reps, labels(suffix), tempo)


#: The 20 stimuli of the experiment.
STIMULI: tuple[Stimulus, ...] = (
    _s("reach forward and back", "reach_forward", "", 1, "return_from_front", 1.3),
    _s("side raise and lower", "reach_side", "", 1, "return_from_side", 1.2),
    _s("two forward reaches", "", "reach_forward return_from_front", 2, "", 1.0),
    _s("two elbow curls", "reach_forward", "elbow_flex elbow_extend", 2, "return_from_front", 0.9),
    _s("wave twice", "raise_forearm", "wave_out wave_in", 2, "lower_forearm", 1.0),
    _s("wave three times", "", "wave_out wave_in", 3, "", 1.1),
    _s("circle in front", "reach_forward", "circle", 1, "return_from_front", 1.0),
    _s("two circles", "", "circle", 2, "", 1.0),
    _s("sweep across", "reach_forward sweep_across sweep_back return_from_front", "", 1, "", 1.0),
    _s("sweep twice", "reach_forward", "sweep_across sweep_back", 2, "return_from_front", 0.85),
    _s("raise overhead", "reach_forward raise_up lower_from_up return_from_front", "", 1, "", 1.0),
    _s("overhead twice", "", "raise_up lower_from_up", 2, "", 1.0),
    _s(
        "front then side",
        "reach_forward return_from_front reach_side return_from_side",
        "",
        1,
        "",
        1.0,
    ),
    _s("curl and sweep", "elbow_flex elbow_extend sweep_across sweep_back", "", 1, "", 1.1),
    _s("three curls", "", "elbow_flex elbow_extend", 3, "", 1.0),
    _s(
        "side wave",
        "reach_side raise_forearm wave_out wave_in lower_forearm return_from_side",
        "",
        1,
        "",
        1.0,
    ),
    _s("circle then raise", "circle raise_up lower_from_up", "", 1, "", 1.0),
    _s(
        "reach, curl, return",
        "reach_forward elbow_flex elbow_extend return_from_front",
        "",
        1,
        "",
        1.0,
    ),
    _s("sweep three times", "", "sweep_across sweep_back", 3, "", 0.9),
    _s(
        "side then front",
        "reach_side return_from_side reach_forward return_from_front",
        "",
        1,
        "",
        1.0,
    ),
)


def random_stimulus(rng: np.random.Generator, index: int) -> Stimulus:
    """A random valid stimulus (2–6 chained strokes, 3–5 s, maybe a repeated pair)."""
    by_start: dict[str, list[int]] = {}
    for k, p in enumerate(VOCABULARY):
        by_start.setdefault(p.start, []).append(k)
    returns = {  # strokes that come straight back: (a, b) with b undoing a
        a: b
        for a, pa in enumerate(VOCABULARY)
        for b, pb in enumerate(VOCABULARY)
        if pa.start == pb.end and pa.end == pb.start and a != b
    }
    for _ in range(1000):
        if rng.random() < 0.45:  # a repeated out-and-back pair
            first = int(rng.choice(sorted(returns)))
            pair = (first, returns[first])
            reps = int(rng.integers(2, 4))
            stim = Stimulus(f"random {index}", (), pair, reps, (), 1.0)
        else:
            n = int(rng.integers(2, 7))
            seq = [int(rng.integers(len(VOCABULARY)))]
            while len(seq) < n:
                seq.append(int(rng.choice(by_start[VOCABULARY[seq[-1]].end])))
            stim = Stimulus(f"random {index}", tuple(seq), (), 1, (), 1.0)
        strokes_s = stim.nominal_duration - 2 * STIMULUS_HOLD_S
        lo, hi = 3.0 - 2 * STIMULUS_HOLD_S, 5.0 - 2 * STIMULUS_HOLD_S
        tempo = float(np.clip(rng.uniform(lo, hi) / strokes_s, 0.8, 1.25))
        stim = Stimulus(stim.name, stim.prefix, stim.repeat, stim.repetitions, stim.suffix, tempo)
        if len(stim.strokes) <= 6 and 3.0 <= stim.nominal_duration <= 5.0:
            stim.validate()
            return stim
    raise RuntimeError("could not draw a valid random stimulus")  # pragma: no cover


def describe(stimulus: Stimulus) -> str:
    """One line: name, stroke names with the repeated part in brackets, repetitions."""
    pre = " ".join(PRIMITIVE_NAMES[k] for k in stimulus.prefix)
    rep = " ".join(PRIMITIVE_NAMES[k] for k in stimulus.repeat)
    suf = " ".join(PRIMITIVE_NAMES[k] for k in stimulus.suffix)
    middle = f"[{rep}] x{stimulus.repetitions}" if rep else ""
    return f"{stimulus.name}: " + " ".join(x for x in (pre, middle, suf) if x)

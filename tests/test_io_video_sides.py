"""Single-view left/right exchanges: found by the image continuity of the limbs and put back
(labels, confidences, world landmarks with their depth reflected)."""

from __future__ import annotations

import numpy as np
from visprim.io.video_pose import VideoPoses
from visprim.io.video_sides import CONTINUITY_PAIRS, repair_side_exchanges, side_exchanges
from visprim.io.views import SIDE_PAIRS

PAIRS = SIDE_PAIRS["blazepose33"]


def _body(t: int, seed: int = 0, turn: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A walking-in-place figure (T, 33) in the image (px) and in hip-centred, camera-aligned
    world coordinates (m); ``turn``: the person turns half round (left and right cross in
    the image, continuously)."""
    rng = np.random.default_rng(seed)
    base = rng.normal(0.0, 0.05, (33, 3))
    for a, b in PAIRS:  # left at +x, right at -x, 0.1-0.2 m apart
        half = rng.uniform(0.1, 0.2)
        base[a, 0], base[b, 0] = half, -half
        base[b, 1:] = base[a, 1:] + rng.normal(0.0, 0.02, 2)
    base[:, 1] += np.linspace(-0.8, 0.8, 33)
    base[[23, 24], 2] = 0.0
    world = np.empty((t, 33, 3))
    for i in range(t):
        ang = np.pi * i / (t - 1) if turn else 0.15 * np.sin(i / 6)
        c, s = np.cos(ang), np.sin(ang)
        rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        world[i] = base @ rot.T
        world[i, :, 1] += 0.02 * np.sin(i / 3)
    image = 540 + 500 * world[..., :2] / (3.0 + world[..., 2:3])
    return image + rng.normal(0.0, 1.0, image.shape), world


def _poses(image: np.ndarray, world: np.ndarray) -> VideoPoses:
    t = image.shape[0]
    return VideoPoses(
        times=np.arange(t) / 30.0,
        world=world,
        image=image,
        confidence=np.ones((t, 33)),
        found=np.ones(t, dtype=bool),
        size=(1080, 1920),
        meta={"layout": "blazepose33"},
    )


def _mirror(image: np.ndarray, world: np.ndarray, frames: np.ndarray) -> None:
    """What the estimator does: labels exchanged, depth reflected about the hips."""
    for a, b in PAIRS:
        for arr in (image, world):
            arr[frames, a], arr[frames, b] = arr[frames, b].copy(), arr[frames, a].copy()
    world[frames, :, 2] = -world[frames, :, 2]


def test_exchanged_runs_are_found_and_put_back():
    image, world = _body(90)
    truth_image, truth_world = image.copy(), world.copy()
    flipped = np.zeros(90, dtype=bool)
    flipped[20:35] = True
    flipped[50] = True
    flipped[60:72] = True
    _mirror(image, world, flipped)
    found = side_exchanges(
        image, np.ones((90, 33)), np.ones(90, bool), CONTINUITY_PAIRS["blazepose33"]
    )
    np.testing.assert_array_equal(found, flipped)
    fixed, frames = repair_side_exchanges(_poses(image, world))
    np.testing.assert_array_equal(frames, flipped)
    np.testing.assert_allclose(fixed.image, truth_image)
    np.testing.assert_allclose(fixed.world, truth_world, atol=1e-12)
    assert fixed.meta["side_exchanges"] == flipped.sum()
    labels_only, _ = repair_side_exchanges(_poses(image, world), reflect_depth=False)
    np.testing.assert_allclose(labels_only.image, truth_image)
    assert not np.allclose(labels_only.world[flipped, :, 2], truth_world[flipped, :, 2])


def test_the_majority_labelling_is_kept_and_a_turn_is_not_an_exchange():
    # Exchanged from the first frame for less than half the clip: the later labelling wins.
    image, world = _body(60, seed=1)
    truth = image.copy()
    flipped = np.arange(60) < 25
    _mirror(image, world, flipped)
    fixed, frames = repair_side_exchanges(_poses(image, world))
    np.testing.assert_array_equal(frames, flipped)
    np.testing.assert_allclose(fixed.image, truth)
    # A person turning half round: left and right cross over smoothly, labels stay right.
    image, world = _body(80, seed=2, turn=True)
    _, frames = repair_side_exchanges(_poses(image, world))
    assert not frames.any()


def test_an_exchange_back_while_the_sides_overlap_is_seen_after_it():
    """Left and right overlap in the image (seen side-on) for a few frames, and the labels
    switch back in between: compared with the last decisive frame, the switch is still
    found, and the overlapping frames keep the labelling before them."""
    image, world = _body(60, seed=3)
    # Frames 38-42: the figure seen edge-on, each left/right pair at the same place (their
    # mean), with 6 px of independent noise: no frame there tells the labels apart.
    rng = np.random.default_rng(30)
    for a, b in PAIRS:
        mid = (image[38:43, a] + image[38:43, b]) / 2
        image[38:43, a] = mid + rng.normal(0.0, 6.0, mid.shape)
        image[38:43, b] = mid + rng.normal(0.0, 6.0, mid.shape)
    flipped = np.zeros(60, dtype=bool)
    flipped[20:40] = True  # back to the right labels at frame 40, inside the overlap
    _mirror(image, world, flipped)
    found = side_exchanges(
        image, np.ones((60, 33)), np.ones(60, bool), CONTINUITY_PAIRS["blazepose33"]
    )
    np.testing.assert_array_equal(found[:38], flipped[:38])
    np.testing.assert_array_equal(found[43:], flipped[43:])  # the switch back was seen


def test_frames_without_a_person_start_a_new_run_and_low_confidence_is_ignored():
    image, world = _body(40, seed=4)
    flipped = np.zeros(40, dtype=bool)
    flipped[25:40] = True  # after the gap: 15 of that run's 19 frames, its majority
    _mirror(image, world, flipped)
    found_mask = np.ones(40, dtype=bool)
    found_mask[20] = False
    conf = np.ones((40, 33))
    found = side_exchanges(image, conf, found_mask, CONTINUITY_PAIRS["blazepose33"])
    # Two runs, each decided alone: the first is all one labelling; in the second, the
    # majority (frames 25-39) is kept and frames 21-24 are put back to it.
    assert not found[:20].any()
    assert found[21:25].all() and not found[25:].any()
    conf[:, [11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]] = 0.1
    assert not side_exchanges(image, conf, np.ones(40, bool), CONTINUITY_PAIRS["blazepose33"]).any()

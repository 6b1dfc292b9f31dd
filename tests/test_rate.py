"""Rate–distortion of movement descriptions (visprim.rate, `visprim evaluate --rate`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _motion_data import movements
from visprim.arm import rot_z
from visprim.evaluate import Recording, make_benchmarks
from visprim.features import from_angles
from visprim.imitate import joint_space_errors
from visprim.rate import (
    best_within,
    bone_rms_deg,
    dct_rebuild,
    evaluate_rate,
    fit_codebook,
    joint_rms_deg,
    keyframe_rebuild,
    movement_numbers,
    rate_markdown,
    rebuild_segments,
    segment_numbers,
    split_long,
    unit_bones,
    unit_posture,
    warp_curves,
    write_rate_report,
)

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def _book(centres: str, seed: int = 0):
    rng = np.random.default_rng(seed)
    train = rng.normal(size=(60, 60))
    test = rng.normal(size=(12, 60))
    return fit_codebook(train, [5, 30], n_components=8, centres=centres), test


def test_numbers_per_segment_are_counted() -> None:
    # id + duration + 6 posture numbers; + a gain; + m coefficients; + gain and warp.
    assert segment_numbers("nearest", 6) == 8
    assert segment_numbers("nearest+gain", 6) == 9
    assert segment_numbers("residual", 6, 5) == 13
    assert segment_numbers("warp", 6) == 10
    # The projection needs no primitive id.
    assert segment_numbers("projection", 6, 30) == 37
    with pytest.raises(ValueError, match="unknown family"):
        segment_numbers("paper", 6)
    # Bridges: start, id and duration per segment, two unit directions per boundary.
    assert movement_numbers("bridge", 3, 6) == 1 + 3 * 2 + 4 * 4
    assert movement_numbers("bridge+residual", 2, 6, 5) == 1 + 2 * 7 + 3 * 4
    assert movement_numbers("nearest", 3, 4) == 1 + 3 * 6


def test_unit_posture_restores_unit_bones() -> None:
    """A curve of unit bones is rebuilt from its shape and the unit directions of its mean:
    the rebuilt offset has the right length on average (exact for a constant-length
    shape, here a bone turning on a cone)."""
    u = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    cone = np.stack([0.6 * np.cos(u), 0.6 * np.sin(u), np.full_like(u, 0.8)], axis=1)
    curve = np.concatenate([cone, cone[:, [1, 0, 2]]], axis=1)[None]  # (1, 50, 6)
    mean = curve.mean(axis=1)
    shape = curve - mean[:, None, :]
    offset = unit_posture(unit_bones(mean), shape)
    np.testing.assert_allclose(offset, mean, atol=1e-12)


def test_all_residual_coefficients_rebuild_the_projection() -> None:
    book, test = _book("projection")
    f = book.n_components
    full = rebuild_segments(book, test, 6, "residual", f)
    projection = rebuild_segments(book, test, 6, "projection", f)
    np.testing.assert_allclose(full, projection, atol=1e-10)
    # Members' centres keep what lies outside the eigen-primitives: the residual then
    # differs from the projection by exactly that part of its centre.
    book, test = _book("members")
    full = rebuild_segments(book, test, 6, "residual", f)
    centre = book.centers[30][book.nearest(test, 30)[:, 0]]
    outside = (centre - book.mean) - ((centre - book.mean) @ book.components) @ book.components.T
    projection = rebuild_segments(book, test, 6, "projection", f)
    np.testing.assert_allclose(full, projection + outside, atol=1e-10)
    # Fewer coefficients rebuild worse, more rebuild better, than the centre alone.
    centre = rebuild_segments(book, test, 6, "nearest", 30)
    err = [
        np.sum((test - r) ** 2)
        for r in (centre, rebuild_segments(book, test, 6, "residual", 2), full)
    ]
    assert err[0] > err[1] > err[2]


def test_members_centres_rebuild_training_members_closer() -> None:
    rng = np.random.default_rng(3)
    train = rng.normal(size=(80, 40))
    members = fit_codebook(train, [10], n_components=4, centres="members")
    paper = fit_codebook(train, [10], n_components=4, centres="projection")
    # Means of the members' whole vectors are the least-squares centres of those members.
    e_members = np.sum((train - rebuild_segments(members, train, 4, "nearest", 10)) ** 2)
    e_paper = np.sum((train - rebuild_segments(paper, train, 4, "nearest", 10)) ** 2)
    assert e_members < e_paper
    with pytest.raises(ValueError, match="centres must be one of"):
        fit_codebook(train, [10], centres="mean")


def test_dct_and_keyframes_with_every_sample_are_exact() -> None:
    rng = np.random.default_rng(1)
    v = np.cumsum(rng.normal(size=(57, 4)), axis=0)
    np.testing.assert_allclose(dct_rebuild(v, 57), v, atol=1e-10)
    np.testing.assert_allclose(keyframe_rebuild(v, 57), v, atol=1e-9)
    # A straight line is kept exactly by two keys, and a cubic by four.
    t = np.linspace(0, 1, 40)[:, None]
    np.testing.assert_allclose(keyframe_rebuild(2 * t - 1, 2), 2 * t - 1, atol=1e-12)
    cubic = t**3 - t
    np.testing.assert_allclose(keyframe_rebuild(cubic, 4), cubic, atol=1e-9)
    # One DCT coefficient keeps the mean.
    np.testing.assert_allclose(dct_rebuild(v, 1), np.broadcast_to(v.mean(0), v.shape))


def test_bone_and_joint_errors_of_known_rotations() -> None:
    rng = np.random.default_rng(2)
    angles = rng.uniform([-2, 0.3, -2, 0.2], [2, 2.5, 2, 2.0], size=(50, 4))
    dirs = from_angles(angles, "directions").reshape(50, 2, 3)
    dirs[:, :, 2] = 0.0  # horizontal bones: a turn about z turns each by its full angle
    dirs /= np.linalg.norm(dirs, axis=2, keepdims=True)
    turned = dirs @ rot_z(np.radians(10.0)).T
    assert bone_rms_deg(turned.reshape(50, 6), dirs.reshape(50, 6)) == pytest.approx(10.0)
    # Scaling a direction changes nothing.
    assert bone_rms_deg(3 * dirs.reshape(50, 6), dirs.reshape(50, 6)) == pytest.approx(0, abs=1e-6)
    other = angles + rng.normal(scale=0.1, size=angles.shape)
    shoulder, elbow = joint_space_errors(other, angles)
    expected = np.degrees(np.sqrt(np.mean(np.concatenate([shoulder, elbow]) ** 2)))
    assert joint_rms_deg(other, angles) == pytest.approx(expected, rel=1e-6)


def test_split_long_and_warp() -> None:
    segs = np.array([[0.0, 0.5], [0.5, 2.0], [2.0, 2.3]])
    cut = split_long(segs, 0.6)
    assert cut.shape == (5, 2) and np.all(np.diff(cut, axis=1) <= 0.6 + 1e-12)
    np.testing.assert_allclose(cut[1:, 0], cut[:-1, 1])
    assert (cut[0, 0], cut[-1, 1]) == (0.0, 2.3)
    assert split_long(segs, None) is segs
    curves = np.linspace(0, 1, 11)[:, None] * np.ones((1, 2))
    np.testing.assert_allclose(warp_curves(curves, 0.0), curves)
    warped = warp_curves(curves, 0.5)
    assert warped[0, 0] == 0.0 and warped[-1, 0] == 1.0 and np.all(np.diff(warped[:, 0]) > 0)
    assert warped[5, 0] == pytest.approx(0.5 + 0.5 * 0.25)


def test_rate_benchmark_counts_and_report(tmp_path: Path) -> None:
    data, labels = movements(3, seed=0)
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    bench = make_benchmarks(recs, data)[0][0]
    res = evaluate_rate(
        bench,
        families=["nearest", "projection", "dct-angles", "keyframes-directions"],
        model_params=SMALL_MODEL,
        posture="mean",
        max_stroke=None,
    )
    assert res.groups == ["g0", "g1", "g2"]
    rows = res.rows
    assert rows and {r["family"] for r in rows} == {
        "nearest",
        "projection",
        "dct-angles",
        "keyframes-directions",
    }
    near = [r for r in rows if r["family"] == "nearest" and r["param"] == 10]
    proj = [r for r in rows if r["family"] == "projection" and r["param"] == 4]
    for a, b in zip(near, proj, strict=True):
        # Same movement, same segments: 1 start + 8 per segment, and 1 + (1 + 6 + 4).
        assert a["movement"] == b["movement"] and a["seconds"] == b["seconds"]
        n_seg = (a["numbers"] - 1) // 8
        assert a["numbers"] == 1 + 8 * n_seg and b["numbers"] == 1 + 11 * n_seg
    for r in rows:
        if r["family"] == "dct-angles":
            # Start and duration + 4 channels x coefficients, near the asked rate.
            assert (r["numbers"] - 2) % 4 == 0
            assert abs(r["numbers"] / r["seconds"] - r["param"]) <= 4 / r["seconds"] + 1e-9 or (
                r["numbers"] == 10
            )
        assert np.isfinite(r["bone_deg"]) and r["bone_deg"] >= 0
    summary = {(s["family"], s["param"]): s for s in res.summary()}
    # More projection coefficients rebuild the held-out movements closer.
    assert (
        summary[("projection", 5)]["bone_deg_median"]
        < summary[("projection", 1)]["bone_deg_median"]
    )
    assert (
        summary[("dct-angles", 60)]["bone_deg_median"]
        < summary[("dct-angles", 4)]["bone_deg_median"]
    )
    md = rate_markdown([res])
    assert "| nearest | 10 |" in md and "numbers / s" in md
    paths = write_rate_report([res], tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "rate.csv",
        "rate.md",
        "rate.png",
        "rate_movements.csv",
    ]
    per_movement = paths["rate_movements_csv"].read_text().splitlines()
    assert (
        per_movement[0]
        == "benchmark,group,movement,family,param,code,numbers,seconds,bone_deg,joint_deg"
    )
    assert len(per_movement) == 1 + len(res.rows)
    lines = paths["rate_csv"].read_text().splitlines()
    assert lines[0].startswith("benchmark,family,param,numbers_per_s,bone_deg_median")
    assert len(lines) == 1 + len(summary)
    with pytest.raises(ValueError, match="unknown description"):
        evaluate_rate(bench, families=["mean"])
    # Unit postures store 4 numbers a segment instead of 6; bridges their boundaries.
    unit = evaluate_rate(
        bench,
        families=["nearest", "bridge"],
        model_params=SMALL_MODEL,
        posture="unit",
        max_stroke=None,
    )
    for a, b in zip(
        [r for r in unit.rows if r["family"] == "nearest" and r["param"] == 10], near, strict=True
    ):
        n_seg = (b["numbers"] - 1) // 8
        assert a["numbers"] == 1 + 6 * n_seg
    for r in unit.rows:
        if r["family"] == "bridge":
            n_seg = (r["numbers"] - 5) // 6
            assert r["numbers"] == 1 + 2 * n_seg + 4 * (n_seg + 1)


def test_best_within_a_rate() -> None:
    rows = [
        {"family": "nearest", "param": 30, "numbers_per_s": 8.0, "bone_deg_median": 12.0},
        {"family": "residual", "param": 4, "numbers_per_s": 11.5, "bone_deg_median": 9.5},
        {"family": "residual", "param": 6, "numbers_per_s": 13.0, "bone_deg_median": 8.0},
        {"family": "dct-angles", "param": 12, "numbers_per_s": 12.0, "bone_deg_median": 7.0},
        {"family": "keyframes-angles", "param": 12, "numbers_per_s": 12.1, "bone_deg_median": 9},
    ]
    assert best_within(rows, 12, "visprim")["param"] == 4
    assert best_within(rows, 12, "dct")["bone_deg_median"] == 7.0
    assert best_within(rows, 12, "keyframes") is None
    assert best_within(rows, 7, "visprim") is None

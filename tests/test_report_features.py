"""The report's model figures follow the model's features: a bone-direction model is drawn
as direction components (dimensionless, no angle labels, no unwrapping steps), a Z-Y-Z
model as angles in degrees."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.report import figures, model_figures, primitive_curves, write_report


@cache
def _trials():
    return tuple(imitation_experiment(n_subjects=2, n_stimuli=4, seed=0))


@cache
def _model(features: str) -> PrimitiveModel:
    model = PrimitiveModel(features=features, n_components=8, n_clusters=6, n_init=2)
    return model.fit(list(_trials()))


def _lines_range(ax) -> tuple[float, float]:
    ys = [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()]
    ys = np.concatenate([y[np.isfinite(y)] for y in ys if y.size])
    return float(ys.min()), float(ys.max())


def _panels(fig):
    return [ax for ax in fig.axes if ax.get_visible() and ax.axison]


def test_direction_model_primitives_are_direction_components():
    model = _model("directions")
    fig = model_figures(model)["primitives.png"]
    panels = _panels(fig)
    assert len(panels) == model.n_primitives
    assert "unit-vector component" in panels[0].get_ylabel()
    assert "deg" not in panels[0].get_ylabel()
    for ax in panels:
        lines = [ln for ln in ax.get_lines() if len(ln.get_ydata())]
        assert len(lines) == 6  # upper arm and forearm, x y z
        lo, hi = _lines_range(ax)
        # Changes of unit-vector components from the segment's mean: within ±2.
        assert -2.0 <= lo and hi <= 2.0, (lo, hi)
        for ln in lines:
            y = np.asarray(ln.get_ydata(), dtype=float)
            # Smooth curves: no step near a whole turn (or any step of 0.5) between samples.
            assert np.max(np.abs(np.diff(y))) < 0.5
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[0].startswith("upper arm") and legend[3].startswith("forearm")
    assert not any("γ" in t or "elbow" in t for t in legend)
    assert "bone directions" in fig.get_suptitle()


def test_direction_model_eigenvectors_one_curve_per_component():
    model = _model("directions")
    fig = model_figures(model)["eigenvectors.png"]
    ax = _panels(fig)[0]
    lines = [ln for ln in ax.get_lines() if len(ln.get_ydata())]
    assert len(lines) == 6
    assert all(len(ln.get_ydata()) == model.n_samples for ln in lines)
    # The curves are the eigenvector itself, channel by channel.
    e = model.eigenvectors_[:, 0]
    got = np.concatenate([np.asarray(ln.get_ydata(), dtype=float) for ln in lines])
    np.testing.assert_allclose(got, e, atol=1e-12)
    eig = _panels(model_figures(model)["eigenvalues.png"])[0]
    assert "deg" not in eig.get_ylabel() and "component" in eig.get_ylabel()


def test_zyz_model_drawn_as_angles_in_degrees():
    model = _model("zyz")
    drawn = model_figures(model)
    panels = _panels(drawn["primitives.png"])
    assert panels[0].get_ylabel().startswith("deg")
    legend = [t.get_text() for t in drawn["primitives.png"].legends[0].get_texts()]
    assert legend == list(figures.ANGLE_LABELS)
    curves = primitive_curves(model)
    for i, ax in enumerate(panels):
        lines = [ln for ln in ax.get_lines() if len(ln.get_ydata())]
        assert len(lines) == 4
        y = np.asarray(lines[1].get_ydata(), dtype=float)  # β, degrees
        np.testing.assert_allclose(y, np.degrees(curves[i, :, 1]), atol=1e-9)
        lo, hi = _lines_range(ax)
        assert -400 < lo and hi < 400, (lo, hi)
    assert "deg²" in _panels(drawn["eigenvalues.png"])[0].get_ylabel()


@pytest.mark.parametrize(
    ("features", "label"), [("directions", "bone angular speeds"), ("zyz", "θ̇")]
)
def test_seg2_figure_names_what_is_summed(features, label):
    fig = figures.seg2_figure(
        np.linspace(0, 1, 50),
        np.full(50, 1.0),
        0.5,
        np.array([[0.2, 0.8]]),
        channels=figures.Channels(features),
    )
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert label in texts[0]
    other = "θ̇" if features == "directions" else "bone angular speeds"
    assert other not in " ".join(texts)


def test_direction_report_page_captions(tmp_path):
    model = _model("directions")
    rep = write_report(model, tmp_path, list(_trials()))
    html = rep.index.read_text(encoding="utf-8")
    assert "upper-arm" in html and "forearm" in html
    assert "|u̇|² + |ḟ|²" in html
    assert "unit-vector component" in html
    assert "four angle blocks" not in html

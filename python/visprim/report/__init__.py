"""The report of a fitted model: PNG figures, Tables 1–3 (Markdown + CSV) and ``index.html``.

:func:`write_report` writes into one folder:

* ``tables.md`` and ``table1.md/.csv``, ``table2.md/.csv``, ``table3.md/.csv`` — projection,
  clustering and total error (:mod:`visprim.accuracy`);
* ``eigenvalues.png`` (spectrum), ``eigenvectors.png`` (paper Fig. 8), ``primitives.png``
  (Fig. 9) — from the model alone;
* with trials (the model does not store trials; pass them, e.g. read again from the files
  the model was learned from): ``segmentation.png`` (Fig. 5, ZVCs and SEG-1),
  ``seg2_threshold.png`` (Fig. 6, z(t) and the SEG-2 threshold), ``segment_reconstruction.png``
  (Fig. 10) and ``movement_reconstruction.png`` (Fig. 11) for one example trial, and, when the
  trials carry ground truth, the segmentation scores and classification scores;
* ``index.html`` showing all of it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from visprim.accuracy import ErrorTables
from visprim.classify import score_against_truth
from visprim.model import PrimitiveModel
from visprim.report import figures
from visprim.report.html import (
    Page,
    figure,
    markdown_table,
    markdown_to_html,
    paragraph,
    pre,
    table,
)
from visprim.report.paper import tables_in_degrees
from visprim.segment import corpus_boundary_scores, truth_pause_halfwidths, zvc
from visprim.trial import Trial
from visprim.vectors import to_curves

__all__ = [
    "Report",
    "model_figures",
    "primitive_curves",
    "repetitions_text",
    "segmentation_scores",
    "write_report",
]

#: Frames flagged at each end of a trial in Fig. 6: the zero-phase filter's edge transients
#: (a 10th-order Butterworth at 0.25 of Nyquist has a group delay of about 12 frames).
EDGE_FRAMES = 12

UNITS_NOTE = (
    "Units: angles in degrees, squared errors in deg², angular velocities in deg/s and "
    "z(t) in (deg/s)² throughout this page (the Python API works in radians)."
)


def repetitions_text(trial: Trial) -> str:
    """A trial's repetitions for display: the number when known (generated trials, or a
    reader that found it: ``meta["repetitions"]``), else "unknown" (``Trial.repetitions``
    defaults to 1 for real recordings)."""
    if trial.truth is not None or "repetitions" in trial.meta:
        return str(trial.repetitions)
    return "unknown"


@dataclass
class Report:
    """What :func:`write_report` wrote: the folder, ``index.html`` and every file."""

    out_dir: Path
    index: Path
    files: list[Path] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)


def segmentation_scores(
    model: PrimitiveModel, trials: Sequence[Trial], tolerance: float = 0.1
) -> dict[str, tuple[float, float, float]]:
    """Boundary precision / recall / F1 (±``tolerance`` s) of SEG-1 and SEG-2 against the
    trials' true stroke boundaries, with the model's filter and segmentation settings
    (SEG-2's constant tuned on ``trials``)."""
    out = {}
    truth = [t.truth.boundaries for t in trials if t.truth is not None]
    if len(truth) != len(trials):
        raise ValueError("segmentation_scores needs trials with truth (generated data)")
    halves = [truth_pause_halfwidths(t) for t in trials]
    for method in ("seg1", "seg2"):
        corpus = model.prepare(trials, tune_seg2=True, segmentation=method)
        s = corpus_boundary_scores(corpus.segments, truth, tolerance)
        out[method] = (float(s.precision), float(s.recall), float(s.f1))
        # A boundary the generator puts in the middle of a pause is matched anywhere in
        # that pause (± tolerance): the subject is at rest throughout, so any instant of it
        # separates the two strokes.
        s = corpus_boundary_scores(corpus.segments, truth, tolerance, truth_halfwidth=halves)
        out[f"{method} (pause-aware)"] = (float(s.precision), float(s.recall), float(s.f1))
    return out


def method_label(method: str) -> str:
    """ "seg2" → "SEG-2", "seg1 (pause-aware)" → "SEG-1 (pause-aware)"."""
    return method.replace("seg", "SEG-")


def format_segmentation_scores(scores: dict[str, tuple[float, float, float]]) -> str:
    """Scores as a small Markdown table."""
    lines = ["| method | precision | recall | F1 |", "|---|---:|---:|---:|"]
    for method, (p, r, f) in scores.items():
        lines.append(f"| {method_label(method)} | {p:.3f} | {r:.3f} | {f:.3f} |")
    return "\n".join(lines) + "\n"


def _pick_trial(
    corpus_names: list[str],
    counts: np.ndarray,
    name: str | None,
    mixed: np.ndarray | None = None,
) -> int:
    if name is not None:
        if name not in corpus_names:
            raise ValueError(f"report: no trial named {name!r} among the {len(corpus_names)} given")
        return corpus_names.index(name)
    # An example with several segments (deterministic): the first trial with 4 to 8 SEG-2
    # segments whose Fig. 5 shows both SEG-1 segments and frames outside them (``mixed``),
    # else the first with 4 to 8 SEG-2 segments, else the one with the most.
    good = (counts >= 4) & (counts <= 8)
    if mixed is not None and np.any(good & mixed):
        return int(np.flatnonzero(good & mixed)[0])
    if np.any(good):
        return int(np.flatnonzero(good)[0])
    return int(np.argmax(counts))


#: Fig. 5 shows "both kinds" when SEG-1 segments cover at least one frame and at most this
#: share of the trial.
MIXED_MAX_COVER = 0.9


def _seg1_mixed(model: PrimitiveModel, trials: list[Trial]) -> np.ndarray:
    """Per trial: whether SEG-1 (with the model's settings) finds a segment and leaves part
    of the trial outside its segments, so that Fig. 5 has coloured and grey parts."""
    corpus = model.prepare(trials, segmentation="seg1")
    out = np.zeros(len(trials), dtype=bool)
    for i, (t, segs) in enumerate(zip(corpus.times, corpus.segments, strict=True)):
        span = float(t[-1] - t[0]) if t.size > 1 else 0.0
        if segs.shape[0] and span > 0:
            out[i] = float(np.sum(segs[:, 1] - segs[:, 0])) <= MIXED_MAX_COVER * span
    return out


def write_report(
    model: PrimitiveModel,
    out_dir: str | Path,
    trials: Sequence[Trial] | None = None,
    *,
    trial_name: str | None = None,
    extra_sections: Sequence[tuple[str, str]] = (),
    title: str = "visprim report",
    provenance: str | None = None,
    comparison: str | None = None,
    gifs: Sequence[str | Path] = (),
    seg_scores: dict[str, tuple[float, float, float]] | None = None,
    classification: str | None = None,
) -> Report:
    """Write the report of ``model`` into ``out_dir`` (see the module docstring).

    Parameters
    ----------
    model : PrimitiveModel
        A fitted (or loaded) model.
    out_dir : path
        Folder to write (created if needed; files of the same names are replaced).
    trials : list of Trial, optional
        Trials for the per-trial figures (Figs. 5, 6, 10, 11) and, if they have truth, the
        segmentation and classification scores. Without them those parts are skipped
        (listed in ``Report.skipped`` and on the page).
    trial_name : str, optional
        Which trial to draw (default: the first with 4–8 SEG-2 segments, else the one with most).
    extra_sections : sequence of (heading, preformatted text)
        Added to the page after the tables.
    provenance : str, optional
        Where the data came from (source, files, frame period, resampling); shown first.
    comparison : str, optional
        A Markdown table comparing Table 3 with the paper
        (:func:`visprim.report.paper.comparison_markdown`).
    gifs : sequence of paths
        Animations (e.g. primitives on the simulated humanoid) embedded in the page; paths
        relative to ``out_dir`` or absolute.
    seg_scores, classification : optional
        Already computed :func:`segmentation_scores` of ``trials`` and the text of
        :func:`visprim.classify.score_against_truth` (computed here when None).
    """
    model._check_fitted()
    if trials and trial_name is not None and trial_name not in {t.name for t in trials}:
        raise ValueError(f"report: no trial named {trial_name!r} among the {len(trials)} given")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rep = Report(out_dir=out, index=out / "index.html")
    page = Page(title=title)
    params = model.get_params()
    page.intro = (
        paragraph(
            f"Model: {model.n_primitives} primitives (k-means clusters) in the space of the first "
            f"{model.n_components} eigenvectors of {model.n_training_segments_} training segments "
            f"({method_label(params['segmentation'])}), each resampled to {model.n_samples} "
            f"samples per channel ({model.dim}-D vectors of "
            f"{figures.Channels.of(model).what})."
        )
        + f'<p class="note">{html_escape(UNITS_NOTE)}</p>'
    )
    page.add("Data", paragraph(provenance or _provenance(model, trials)))
    if comparison:
        page.add("Comparison with the paper (Table 3)", _markdown_blocks(comparison))

    # Tables 1-3 ------------------------------------------------------------------
    tables = _tables_in_degrees(model)
    if tables is None:
        rep.skipped.append("error tables: the model keeps no training vectors")
        page.add(
            "Error analysis (Tables 1–3)",
            paragraph(
                "Error tables are not available: this model keeps no training vectors (it "
                "was learned with --stream or --dask, or saved without them). Learn it in "
                "memory for Tables 1–3; the other figures are drawn below."
            ),
        )
    else:
        md_all = []
        table_html = []
        for i, t in enumerate(tables, start=1):
            md = out / f"table{i}.md"
            csv = out / f"table{i}.csv"
            md.write_text(t.to_markdown(), encoding="utf-8")
            csv.write_text(t.to_csv(), encoding="utf-8")
            rep.files += [md, csv]
            md_all.append(t.to_markdown())
            table_html.append(table(t, [("Markdown", md.name), ("CSV", csv.name)]))
        all_md = out / "tables.md"
        all_md.write_text("\n".join(md_all), encoding="utf-8")
        rep.files.append(all_md)
        page.add(
            "Error analysis (Tables 1–3)",
            paragraph(
                "Mean squared error per segment vector (deg²) and the RMS angle error "
                "sqrt(MSE / d) in degrees, as the paper reports it. Projection error = sum of the "
                "dropped eigenvalues; total = projection + clustering (the residuals are "
                "orthogonal)."
            )
            + (
                ""
                if model.features == "zyz"
                else '<p class="note">'
                + html_escape(
                    "This model's vectors hold unit-vector components of the upper arm and "
                    "forearm, not angles. A component that changes by δ turns its bone by "
                    "about δ radians, so the tables give the squared component errors as deg² "
                    f"of bone direction: (component × 180/π)², {math.degrees(1.0) ** 2:.0f} "
                    "times the squared components of Fig. 7."
                )
                + "</p>"
            )
            + "".join(table_html),
        )
    for heading, text in extra_sections:
        page.add(heading, pre(text))

    # Scores (trials with truth) ------------------------------------------------------
    if trials and all(t.truth is not None for t in trials):
        if seg_scores is None:
            seg_scores = segmentation_scores(model, trials)
        cls = classification if classification is not None else score_against_truth(model, trials)
        text = format_segmentation_scores(seg_scores)
        (out / "segmentation_scores.md").write_text(text, encoding="utf-8")
        rep.files.append(out / "segmentation_scores.md")
        page.add(
            "Scores against the ground truth",
            paragraph(f"Boundary precision / recall / F1 at ±100 ms over {len(trials)} trials:")
            + markdown_table(text)
            + paragraph(f"Segment primitives vs true stroke labels: {cls}."),
        )

    # Model figures -------------------------------------------------------------------
    ch = figures.Channels.of(model)
    drawn = model_figures(model)
    for name, fig in drawn.items():
        rep.files.append(figures.save_figure(fig, out / name))
    f_eig, f_vec, f_prim = (out / name for name in drawn)
    page.add(
        "Principal components",
        figure(
            f_eig.name,
            "Fig. 7: eigenvalues of the covariance of the segment vectors "
            f"({ch.variance_unit}, log scale) and the variance left out by the first f "
            "eigenvectors (log scale).",
        )
        + figure(
            f_vec.name,
            f"Fig. 8: the first four unit eigenvectors, each drawn as {ch.n} curves of "
            f"{model.n_samples} components, one per channel of the segment vectors: "
            f"{ch.what}.",
        ),
    )
    rel = (
        ", as changes from the segment's mean posture (the vectors hold shapes)"
        if ch.offsets == "mean"
        else ""
    )
    page.add(
        "Primitives",
        figure(
            f_prim.name,
            f"Fig. 9: cluster centres reconstructed as curves of {ch.what}{rel}: the "
            "primitives; titles give the number of member segments and their mean duration.",
        ),
    )

    # Trial figures -------------------------------------------------------------------
    if trials:
        rep.files += _trial_figures(model, list(trials), out, page, trial_name)
    else:
        msg = (
            "No trials given: the segmentation (Figs. 5, 6) and reconstruction (Figs. 10, 11) "
            "figures need them (visprim report MODEL DATA... or --generated)."
        )
        rep.skipped.append(msg)
        page.add("Segmentation and reconstruction", paragraph(msg))

    if gifs:
        imgs = "".join(
            f'<img src="{html_escape(_relative(g, out))}" alt="{html_escape(Path(g).stem)}">'
            for g in gifs
        )
        page.add(
            "Primitives on the simulated humanoid",
            paragraph(
                "Primitives played back on Adonis (DART simulation): by default the ones "
                "whose upper arm and forearm travel furthest (the bones' path length, in "
                "the titles), not the most populated, which are near rest; `visprim demo` "
                "plays primitives of posture-relative vectors at their segments' mean posture."
            )
            + f'<div class="gifs">{imgs}</div>',
        )

    page.add(
        "Model parameters",
        pre("\n".join(f"{k} = {v!r}" for k, v in sorted(params.items()))),
    )
    page.write(rep.index)
    rep.files.append(rep.index)
    return rep


def primitive_curves(model: PrimitiveModel) -> np.ndarray:
    """The primitives ``E_f c + s̄`` as curves of the model's own channels,
    ``(k, n_samples, C)`` (radians, or unit-vector components for a direction model): what
    Fig. 9 draws. Not turned into angles: inverse kinematics of a direction primitive held
    relative to its mean posture has no meaning, and unwrapping would add whole turns."""
    rebuilt = model.cluster_centers_ @ model.components_.T + model.mean_
    return to_curves(rebuilt, model.n_channels)


def model_figures(model: PrimitiveModel) -> dict[str, Figure]:
    """Figs. 7–9 of a fitted model, by file name (``eigenvalues.png``,
    ``eigenvectors.png``, ``primitives.png``), drawn for the model's features."""
    ch = figures.Channels.of(model)
    counts = np.bincount(model.labels_, minlength=model.n_primitives)
    return {
        "eigenvalues.png": figures.eigenvalues_figure(
            model.eigenvalues_, model.n_components, channels=ch
        ),
        "eigenvectors.png": figures.eigenvectors_figure(
            model.eigenvectors_, model.eigenvalues_, channels=ch
        ),
        "primitives.png": figures.primitives_figure(
            primitive_curves(model), counts, model.primitive_durations_, channels=ch
        ),
    }


def _trial_figures(
    model: PrimitiveModel, trials: list[Trial], out: Path, page: Page, trial_name: str | None
) -> list[Path]:
    corpus = model.prepare(trials)
    counts = corpus.segmentation.counts() if corpus.segmentation.method == "seg2" else None
    if counts is None:
        # Count SEG-2 segments for the choice of the example trial.
        counts = model.prepare(trials, segmentation="seg2").segmentation.counts()
    mixed = _seg1_mixed(model, trials) if trial_name is None else None
    i = _pick_trial(corpus.names, counts, trial_name, mixed)
    trial = trials[i]
    times = corpus.times[i]
    angles = corpus.angles[i]
    truth_b = trial.truth.boundaries if trial.truth is not None else None
    name = corpus.names[i]
    files = []

    # Fig. 5: ZVCs + SEG-1 (with the model's ZVC settings).
    seg1_corpus = model.prepare([trial], segmentation="seg1")
    c = zvc(times, angles, min_change_deg=float(model.zvc_threshold_deg))
    files.append(
        figures.plot_segmentation(
            out / "segmentation.png",
            times,
            angles,
            c.time,
            c.dof,
            seg1_corpus.segments[0],
            truth_boundaries=truth_b,
            title=f"Fig. 5: trial {name}, zero-velocity crossings (moves ≥ "
            f"{model.zvc_threshold_deg:g}°) and the SEG-1 segments",
        )
    )
    # Fig. 6: z(t) and the SEG-2 threshold.
    seg2_corpus = model.prepare([trial], segmentation="seg2")
    seg = seg2_corpus.segmentation
    z = seg.z if seg.z is not None else np.zeros_like(times)
    c_trial = seg.trial_thresholds[0] if seg.trial_thresholds is not None else seg.threshold
    c_used = float("nan") if c_trial is None else float(c_trial)
    segs = seg2_corpus.segments[0]
    files.append(
        figures.plot_seg2(
            out / "seg2_threshold.png",
            times,
            z,
            c_used,
            segs,
            truth_boundaries=truth_b,
            edge_s=EDGE_FRAMES * float(np.median(np.diff(times))),
            title=f"Fig. 6: trial {name}, SEG-2 (z(t) below c delimits the segments)",
            channels=figures.Channels.of(model),
        )
    )
    # Fig. 11: the whole movement.
    t_m, rec_p, orig = model.reconstruct_movement(trial, source="projection", return_original=True)
    _, rec_c = model.reconstruct_movement(trial, source="cluster")
    ep = _rms_deg(rec_p, orig)
    ec = _rms_deg(rec_c, orig)
    # The whole trial: the original everywhere, the reconstruction where segments cover it.
    full_p = np.full_like(angles, np.nan)
    full_c = np.full_like(angles, np.nan)
    where = np.searchsorted(times, t_m)
    full_p[where] = rec_p
    full_c[where] = rec_c
    files.append(
        figures.plot_reconstruction(
            out / "movement_reconstruction.png",
            times,
            angles,
            full_p,
            full_c,
            boundaries=np.unique(segs.ravel()),
            title=f"Fig. 11: trial {name}, the whole movement rebuilt from its consecutive "
            "SEG-2 segments",
            errors_deg=(ep, ec),
        )
    )
    # Fig. 10: one segment (the middle SEG-2 segment of the example trial).
    j = len(segs) // 2
    s, e = segs[j]
    mask = (times >= s) & (times <= e)
    # reconstruct_segment adds the segment's whole-turn offsets of γ/α back.
    tt, rp = model.reconstruct_segment(times, angles, s, e, source="projection")
    _, rc = model.reconstruct_segment(times, angles, s, e, source="cluster")
    label = int(model.predict(model.vectorize(seg2_corpus).vectors[j : j + 1])[0])
    files.append(
        figures.plot_reconstruction(
            out / "segment_reconstruction.png",
            tt,
            angles[mask],
            rp,
            rc,
            title=f"Fig. 10: trial {name}, segment {j} ({s:.2f}–{e:.2f} s, primitive #{label})",
            errors_deg=(_rms_deg(rp, angles[mask]), _rms_deg(rc, angles[mask])),
        )
    )
    z_text = (
        "z(t) = sum of the squared angular velocities of the four angles"
        if model.features == "zyz"
        else "z(t) = |u̇|² + |ḟ|², the summed squared angular speeds of the upper arm and "
        "forearm directions (the channels SEG-2 runs on)"
    )
    page.add(
        "Segmentation",
        paragraph(
            f"Example trial: {name} ({trial.duration:.2f} s, repetitions "
            f"{repetitions_text(trial)})."
        )
        + figure(
            "segmentation.png",
            "Fig. 5: the four low-passed angles, one coloured curve per SEG-1 segment with "
            "its cut points (bars), each angle's zero-velocity crossings (open dots); "
            "triangles under the axes: true stroke boundaries where known.",
        )
        + figure(
            "seg2_threshold.png",
            f"Fig. 6: {z_text}, (deg/s)², with the SEG-2 "
            "threshold c in the same unit; the movement is cut inside each dip below c. "
            "Shaded: the trial's ends, where the zero-phase filter's edge transients "
            "dominate z(t).",
        ),
    )
    page.add(
        "Reconstruction",
        figure(
            "segment_reconstruction.png",
            "Fig. 10: one segment and its reconstructions from its "
            "projection on the first f eigenvectors and from its primitive (cluster "
            "centre), stretched back to the segment's duration.",
        )
        + figure(
            "movement_reconstruction.png",
            "Fig. 11: the whole trial and its reconstruction from its consecutive SEG-2 "
            "segments (none before the first and after the last boundary); RMS errors over "
            "the segments.",
        ),
    )
    return files


def _markdown_blocks(text: str) -> str:
    """Blank-line separated blocks: pipe tables as HTML tables, anything else as text."""
    return markdown_to_html(text)


def html_escape(text: str) -> str:
    import html

    return html.escape(text)


def _relative(path: str | Path, out: Path) -> str:
    p = Path(path)
    try:
        return p.resolve().relative_to(out.resolve()).as_posix()
    except ValueError:
        return p.as_posix()


def _tables_in_degrees(model: PrimitiveModel) -> ErrorTables | None:
    """Tables 1-3 of ``model`` in degrees, or None when it has no training vectors and no
    saved tables."""
    if getattr(model, "training_vectors_", None) is None and not getattr(
        model, "error_tables_", None
    ):
        return None
    return tables_in_degrees(model.error_table())


def _provenance(model: PrimitiveModel, trials: Sequence[Trial] | None) -> str:
    text = model.provenance_.describe()
    if trials:
        periods = [float(np.median(np.diff(t.times))) for t in trials if t.times.size > 1]
        text += (
            f" {len(trials)} trials; median frame period {1000 * float(np.median(periods)):.1f} ms."
        )
    return text


def _rms_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2))))

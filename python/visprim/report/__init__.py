"""The report of a fitted model: PNG figures, Tables 1–3 (Markdown + CSV) and ``index.html``.

:func:`write_report` writes into one folder:

* ``tables.md`` and ``table1.md/.csv``, ``table2.md/.csv``, ``table3.md/.csv`` — projection,
  clustering and total error (:mod:`visprim.errors`);
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

from visprim.classify import score_against_truth
from visprim.model import PrimitiveModel
from visprim.report import figures
from visprim.report.html import Page, figure, paragraph, pre, table
from visprim.segment import corpus_boundary_scores, truth_pause_halfwidths, zvc
from visprim.trial import Trial

__all__ = ["Report", "segmentation_scores", "write_report"]


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


def _pick_trial(corpus_names: list[str], counts: np.ndarray, name: str | None) -> int:
    if name is not None:
        if name not in corpus_names:
            raise ValueError(f"report: no trial named {name!r} among the {len(corpus_names)} given")
        return corpus_names.index(name)
    # An example with several segments (deterministic): the first trial with 4 to 8 SEG-2
    # segments, else the one with the most.
    good = np.flatnonzero((counts >= 4) & (counts <= 8))
    return int(good[0]) if good.size else int(np.argmax(counts))


def write_report(
    model: PrimitiveModel,
    out_dir: str | Path,
    trials: Sequence[Trial] | None = None,
    *,
    trial_name: str | None = None,
    extra_sections: Sequence[tuple[str, str]] = (),
    title: str = "visprim report",
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
        Added to the page before the figures (e.g. the demo's console output).
    """
    model._check_fitted()
    if trials and trial_name is not None and trial_name not in {t.name for t in trials}:
        raise ValueError(f"report: no trial named {trial_name!r} among the {len(trials)} given")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rep = Report(out_dir=out, index=out / "index.html")
    page = Page(title=title)
    params = model.get_params()
    page.intro = paragraph(
        f"Model: {model.n_primitives} primitives (k-means clusters) in the space of the first "
        f"{model.n_components} eigenvectors of {model.n_training_segments_} training segments "
        f"({method_label(params['segmentation'])}), each resampled to {model.n_samples} "
        f"samples per angle ({model.dim}-D vectors). Angles in degrees on all axes."
    ) + pre("\n".join(f"{k} = {v!r}" for k, v in sorted(params.items())))

    for heading, text in extra_sections:
        page.add(heading, pre(text))

    # Tables 1-3 ------------------------------------------------------------------
    tables = model.error_table()
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
            "Mean squared error per segment vector (rad²) and the RMS angle error "
            "sqrt(MSE / d) in degrees. Projection error = sum of the dropped eigenvalues; "
            "total = projection + clustering (the residuals are orthogonal)."
        )
        + "".join(table_html),
    )

    # Scores (trials with truth) ------------------------------------------------------
    if trials and all(t.truth is not None for t in trials):
        seg_scores = segmentation_scores(model, trials)
        cls = score_against_truth(model, trials)
        text = format_segmentation_scores(seg_scores)
        (out / "segmentation_scores.md").write_text(text, encoding="utf-8")
        rep.files.append(out / "segmentation_scores.md")
        page.add(
            "Scores against the ground truth",
            paragraph(f"Boundary precision / recall / F1 at ±100 ms over {len(trials)} trials:")
            + pre(text)
            + paragraph(f"Segment primitives vs true stroke labels: {cls}."),
        )

    # Model figures -------------------------------------------------------------------
    f_eig = figures.plot_eigenvalues(
        out / "eigenvalues.png", model.eigenvalues_, model.n_components
    )
    f_vec = figures.plot_eigenvectors(
        out / "eigenvectors.png", model.eigenvectors_, model.eigenvalues_
    )
    k = model.n_primitives
    prim = np.stack([model.primitive_angles(i) for i in range(k)])
    counts = np.bincount(model.labels_, minlength=k)
    f_prim = figures.plot_primitives(
        out / "primitives.png", prim, counts, model.primitive_durations_
    )
    rep.files += [f_eig, f_vec, f_prim]
    page.add(
        "Principal components",
        figure(
            f_eig.name,
            "Eigenvalues of the covariance of the segment vectors (deg², log "
            "scale) and the variance kept by the first f eigenvectors.",
        )
        + figure(
            f_vec.name,
            "The first four eigenvectors as four angle curves each, scaled "
            "by the square root of their eigenvalue (cf. the paper's Fig. 8).",
        ),
    )
    page.add(
        "Primitives",
        figure(
            f_prim.name,
            "Cluster centres reconstructed as angle curves: the primitives "
            "(cf. Fig. 9); titles give the number of member segments and their mean "
            "duration.",
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

    page.write(rep.index)
    rep.files.append(rep.index)
    return rep


def _trial_figures(
    model: PrimitiveModel, trials: list[Trial], out: Path, page: Page, trial_name: str | None
) -> list[Path]:
    corpus = model.prepare(trials)
    counts = corpus.segmentation.counts() if corpus.segmentation.method == "seg2" else None
    if counts is None:
        # Count SEG-2 segments for the choice of the example trial.
        counts = model.prepare(trials, segmentation="seg2").segmentation.counts()
    i = _pick_trial(corpus.names, counts, trial_name)
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
            title=f"Trial {name}: zero-velocity crossings (≥ {model.zvc_threshold_deg:g}° moves) "
            f"and SEG-1 segments",
        )
    )
    # Fig. 6: z(t) and the SEG-2 threshold.
    seg2_corpus = model.prepare([trial], segmentation="seg2")
    seg = seg2_corpus.segmentation
    z = seg.z if seg.z is not None else np.zeros_like(times)
    c_used = float(seg.trial_thresholds[0] if seg.trial_thresholds is not None else seg.threshold)
    segs = seg2_corpus.segments[0]
    files.append(
        figures.plot_seg2(
            out / "seg2_threshold.png",
            times,
            z,
            c_used,
            segs,
            truth_boundaries=truth_b,
            title=f"Trial {name}: SEG-2 (z(t) below c delimits the segments)",
        )
    )
    # Fig. 11: the whole movement.
    t_m, rec_p, orig = model.reconstruct_movement(trial, source="projection", return_original=True)
    _, rec_c = model.reconstruct_movement(trial, source="cluster")
    ep = _rms_deg(rec_p, orig)
    ec = _rms_deg(rec_c, orig)
    files.append(
        figures.plot_reconstruction(
            out / "movement_reconstruction.png",
            t_m,
            orig,
            rec_p,
            rec_c,
            boundaries=np.unique(segs.ravel()),
            title=f"Trial {name}: whole movement from consecutive SEG-2 segments",
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
            title=f"Trial {name}, segment {j} ({s:.2f}–{e:.2f} s, primitive #{label})",
            errors_deg=(_rms_deg(rp, angles[mask]), _rms_deg(rc, angles[mask])),
        )
    )
    page.add(
        "Segmentation",
        paragraph(
            f"Example trial: {name} ({trial.duration:.2f} s, repetitions {trial.repetitions})."
        )
        + figure(
            "segmentation.png",
            "The four low-passed angles with each angle's "
            "zero-velocity crossings (dots) and the SEG-1 segments (shaded); dashed: true "
            "stroke boundaries where known (cf. the paper's Fig. 5).",
        )
        + figure(
            "seg2_threshold.png",
            "z(t) = sum of squared angular velocities with the "
            "SEG-2 threshold c; the movement is cut inside each dip below c (cf. Fig. 6).",
        ),
    )
    page.add(
        "Reconstruction",
        figure(
            "segment_reconstruction.png",
            "One segment and its reconstructions from its "
            "projection on the first f eigenvectors and from its primitive (cluster "
            "centre), stretched back to the segment's duration (cf. Fig. 10).",
        )
        + figure(
            "movement_reconstruction.png",
            "A whole movement rebuilt from its consecutive SEG-2 segments (cf. Fig. 11).",
        ),
    )
    return files


def _rms_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2))))

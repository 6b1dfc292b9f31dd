"""Plot one generated trial: the four markers over time and the true angles with strokes.

Usage (from the repository root)::

    .venv/bin/python docs/plot_generated_trial.py [--subject 3] [--stimulus 7] \
        [--seed 0] [--preset paper] [--out docs/generated_trial.png]

The trial is the one of the experiment ``imitation_experiment(seed=seed, preset=preset)``
(default: the paper-like default experiment), so the figure shows exactly what the pipeline
receives.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from visprim.arm import ANGLE_NAMES  # noqa: E402
from visprim.datasets import (  # noqa: E402
    PRIMITIVE_NAMES,
    STROKE_KINDS,
    generate_trial,
    stimuli,
    subjects,
)
from visprim.trial import MARKER_NAMES, Trial  # noqa: E402

ANGLE_LABELS = {
    "gamma": "γ (plane)",
    "beta": "β (elevation)",
    "alpha": "α (humeral rot.)",
    "elbow": "elbow flexion",
}


def plot_trial(trial: Trial, out: str | Path) -> Path:
    """Write a PNG of ``trial`` (markers in m and truth angles in degrees) to ``out``."""
    if trial.truth is None:
        raise ValueError(f"{trial.name}: the trial has no ground truth to plot")
    t = trial.times
    truth = trial.truth
    fig, axes = plt.subplots(
        4, 1, figsize=(11.5, 10), sharex=True, gridspec_kw={"height_ratios": [1, 1, 1, 1.4]}
    )
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for a, axis in enumerate("xyz"):
        ax = axes[a]
        for k, name in enumerate(MARKER_NAMES):
            ax.plot(
                t,
                trial.markers[:, k, a],
                ".-",
                ms=2.5,
                lw=0.8,
                color=colors[k],
                label=name.replace("_", " "),
            )
        ax.set_ylabel(f"{axis} (m)")
        ax.grid(alpha=0.3)
    axes[1].legend(
        fontsize=8, loc="center left", bbox_to_anchor=(1.005, 0.5), title="sensor", title_fontsize=8
    )
    axes[0].set_title(
        f"{trial.name}: subject {trial.subject}, stimulus {trial.stimulus} "
        f"({trial.meta.get('stimulus_name', '')}), repetitions {trial.repetitions}\n"
        "markers (world frame: +x forward, +y left, +z up; sampled every 34 ms, noise on)",
        fontsize=10,
    )
    ax = axes[3]
    for j, name in enumerate(ANGLE_NAMES):
        ax.plot(
            t, np.degrees(truth.angles[:, j]), lw=1.5, color=colors[4 + j], label=ANGLE_LABELS[name]
        )
    ax.set_ylabel("true angle (deg)")
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)
    ax.legend(
        fontsize=8, loc="center left", bbox_to_anchor=(1.005, 0.5), title="angle", title_fontsize=8
    )
    ymax = ax.get_ylim()[1]
    names = STROKE_KINDS if trial.meta.get("preset") == "paper" else PRIMITIVE_NAMES
    for b in truth.boundaries:
        for a_ in axes:
            a_.axvline(b, color="k", ls="--", lw=0.8, alpha=0.6)
    for k, label in enumerate(truth.labels):
        mid = 0.5 * (truth.boundaries[k] + truth.boundaries[k + 1])
        ax.text(
            mid,
            ymax,
            names[int(label)].replace("_", " "),
            ha="center",
            va="bottom",
            fontsize=8,
            rotation=20,
        )
    ax.set_title(
        "ground truth: angles (visprim.arm convention) and stroke boundaries (dashed)",
        fontsize=10,
        pad=26,
    )
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subject", type=int, default=3)
    parser.add_argument("--stimulus", type=int, default=7)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--preset", choices=("paper", "strokes"), default="paper")
    parser.add_argument("--out", default=str(Path(__file__).with_name("generated_trial.png")))
    args = parser.parse_args()
    subject = subjects(args.subject + 1, args.seed, args.preset)[args.subject]
    stimulus = stimuli(args.stimulus + 1, args.seed, args.preset)[args.stimulus]
    trial = generate_trial(subject, stimulus, args.stimulus, args.seed)
    print(plot_trial(trial, args.out))


if __name__ == "__main__":
    main()

"""Video trials downstream: ``visprim learn`` and ``visprim classify`` take folders of
videos and single video files, and :func:`visprim.evaluate.evaluate` runs leave-one-group-
out on labelled videos. The clips are the first frames of the four shared Pose2Sim views,
downsized and written to a temporary folder (one pose cache for the module, so MediaPipe
runs once per clip)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.cli import main
from visprim.io import Corpus, read

HAS_MEDIAPIPE = importlib.util.find_spec("mediapipe") is not None
pytestmark = pytest.mark.skipif(
    not HAS_MEDIAPIPE, reason="the video extra is not installed (pip install 'visprim[video]')"
)
FRAMES = 60
SMALL = ["--arm", "both", "--clusters", "2", "--components", "2"]


@pytest.fixture(scope="module")
def videos(shared_data: Path, tmp_path_factory) -> Path:
    """cam01..cam04: the first :data:`FRAMES` frames at half size (540 × 960, 60 fps) in a
    folder with a labels table (two labels, two subjects) and a file that is not a video."""
    import cv2

    src = shared_data / "video" / "pose2sim_single_person"
    if not (src / "cam04.mp4").is_file():
        pytest.skip(f"shared video clip not found in {src}")
    root = tmp_path_factory.mktemp("videos")
    folder = root / "clips"
    folder.mkdir()
    for cam in ("cam01", "cam02", "cam03", "cam04"):
        cap = cv2.VideoCapture(str(src / f"{cam}.mp4"))
        out = cv2.VideoWriter(
            str(folder / f"{cam}.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 60.0, (540, 960)
        )
        for _ in range(FRAMES):
            ok, frame = cap.read()
            assert ok
            out.write(cv2.resize(frame, (540, 960), interpolation=cv2.INTER_AREA))
        out.release()
        cap.release()
    (folder / "labels.tsv").write_text(
        "file\tlabel\tsubject\n"
        "cam01.mp4\ta\ts1\ncam02.mp4\tb\ts1\ncam03.mp4\ta\ts2\ncam04.mp4\tb\ts2\n"
    )
    (folder / "notes.txt").write_text("not a recording\n")
    return folder


@pytest.fixture(autouse=True)
def _shared_cache(videos, monkeypatch):
    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(videos.parent / "cache"))


def test_a_folder_of_videos_is_a_corpus_of_video_trials(videos):
    corpus = Corpus(videos)
    assert [p.name for p in corpus.paths] == ["cam01.mp4", "cam02.mp4", "cam03.mp4", "cam04.mp4"]
    trial = read(videos / "cam02.mp4", arm="both")
    assert trial.meta["format"] == "video"
    assert trial.times.shape == (FRAMES,)
    np.testing.assert_allclose(trial.times[-1], (FRAMES - 1) / 60, atol=1e-6)


def test_learn_and_classify_take_video_folders_and_files(videos, tmp_path, capsys):
    model = tmp_path / "model.npz"
    assert main(["learn", str(videos), "--out", str(model), *SMALL]) == 0
    fitted = PrimitiveModel.load(model)
    assert fitted.arms_ == ("right", "left")
    capsys.readouterr()
    assert main(["classify", str(model), str(videos / "cam03.mp4"), "--arm", "both"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("cam03: sequence [") and "histogram" in out


def test_evaluate_runs_leave_one_group_out_on_labelled_videos(videos):
    from visprim.classify import MotionClassifier
    from visprim.evaluate import evaluate

    clf = MotionClassifier(model_params={"n_clusters": 2, "n_components": 2})
    results, notes = evaluate([videos], classifier=clf, jobs=1, progress=False)
    assert len(results) == 1
    result = results[0]
    assert result.n_trials == 4 and result.classes == ["a", "b"]
    assert sorted(result.groups) == ["s1", "s2"]
    assert result.confusion.sum() == 4 and result.baseline_confusion.sum() == 4
    assert 0.0 <= result.accuracy <= 1.0

"""``visprim imitate MODEL clip.mp4``: the real estimator on the shared clip, and the side-by-side
video checked frame by frame against the source video decoded on its own."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.cli.main import main
from visprim.datasets import imitation_experiment

MISSING = [m for m in ("cv2", "mediapipe", "imageio_ffmpeg") if importlib.util.find_spec(m) is None]
pytestmark = pytest.mark.skipif(
    bool(MISSING),
    reason=f"the video extra is not installed (missing {', '.join(MISSING)}): "
    "pip install 'visprim[video]'",
)
SIZE = 320


@pytest.fixture(scope="module")
def run(shared_data: Path, tmp_path_factory):
    """One imitation of the shared clip (its pose cache private to this module)."""
    clip = shared_data / "video" / "pose2sim_single_person" / "cam01.mp4"
    if not clip.is_file():
        pytest.skip(f"shared video clip not found at {clip}")
    tmp = tmp_path_factory.mktemp("imitate_video")
    mp = pytest.MonkeyPatch()
    mp.setenv("VISPRIM_CACHE_DIR", str(tmp / "cache"))
    model = PrimitiveModel(n_clusters=5, n_init=2, seed=0).fit(imitation_experiment(2, 4, seed=4))
    model.save(tmp / "model.npz")
    out = tmp / "out"
    argv = ["imitate", str(tmp / "model.npz"), str(clip), "--out", str(out), "--size", str(SIZE)]
    assert main(argv) == 0
    yield clip, out
    mp.undo()


def _decode(path: Path) -> tuple[list[np.ndarray], list[float], float]:
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames, stamps = [], []
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        stamps.append(cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0)
        frames.append(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
    cap.release()
    return frames, stamps, fps


def test_the_video_is_the_source_frames_with_the_arm_beside_adonis(run) -> None:
    import cv2
    from visprim.io.video_pose import video_poses

    clip, out = run
    video = out / "imitation.mp4"
    assert video.is_file()
    source, stamps, src_fps = _decode(clip)
    frames, _, fps = _decode(video)
    # One output frame per source frame (60 fps is kept), at the source's rate.
    assert len(frames) == len(source) == 100 and fps == pytest.approx(src_fps)
    h_src, w_src = source[0].shape[:2]
    vw = int(round(w_src * SIZE / h_src / 2)) * 2
    assert frames[0].shape == (SIZE, vw + SIZE, 3)
    left = [f[:, :vw].astype(np.int16) for f in frames]
    scaled = [
        cv2.resize(s, (vw, SIZE), interpolation=cv2.INTER_AREA).astype(np.int16) for s in source
    ]
    # Away from the labels (top and bottom bands) and the drawn arm, the left part is the
    # source frame itself (up to H.264), and frame i is the source's frame i, not another.
    poses = video_poses(clip)
    scale = vw / w_src
    yy, xx = np.mgrid[0:SIZE, 0:vw]
    band = (yy > 28) & (yy < SIZE - 24)
    for i in (0, 33, 66, 99):
        arm = poses.image[i, [12, 14, 16, 18, 20]] * scale
        near = np.zeros_like(band)
        for a, b in zip(arm[:-1], arm[1:], strict=True):
            for s in np.linspace(0, 1, 20):
                x, y = a + s * (b - a)
                near |= (xx - x) ** 2 + (yy - y) ** 2 < 12**2
        keep = band & ~near
        diffs = [np.abs(left[i] - scaled[j])[keep].mean() for j in range(len(scaled))]
        assert diffs[i] < 6.0, (i, diffs[i])
        assert abs(int(np.argmin(diffs)) - i) <= 1, (i, int(np.argmin(diffs)))
        # The right upper arm is drawn: along it the output is the drawing's orange-red,
        # not the video.
        mid = ((arm[0] + arm[1]) / 2).round().astype(int)
        px = left[i][mid[1] - 1 : mid[1] + 2, mid[0] - 1 : mid[0] + 2].reshape(-1, 3).mean(0)
        assert px[0] - px[2] > 90 and np.abs(px - scaled[i][mid[1], mid[0]]).max() > 40, px
    # The right part is Adonis, moving with the clip.
    right = [f[:, vw:].astype(np.int16) for f in frames]
    assert np.abs(right[0] - right[-1]).mean() > 0.5
    assert stamps[-1] > stamps[0]


def test_adonis_is_on_the_videos_own_clock(run, tmp_path) -> None:
    """Right half of output frame i = Adonis at source frame i's own timestamp."""
    from visprim.imitate import imitate
    from visprim.io import read
    from visprim.sim.sidebyside_video import VideoSideBySide

    clip, out = run
    frames, _, _ = _decode(out / "imitation.mp4")
    _, stamps, _ = _decode(clip)
    model = PrimitiveModel.load(out.parent / "model.npz")
    res = imitate(model, read(str(clip)))
    view = VideoSideBySide(res, (SIZE, SIZE))
    vw = view.video_size[0]
    for i in (10, 50, 90):
        t = stamps[i] - stamps[0]
        want = np.asarray(view.adonis_at(t)).astype(np.int16)
        got = frames[i][:, vw:].astype(np.int16)
        assert np.abs(got - want).mean() < 3.0
        off = np.asarray(view.adonis_at(t + 0.3)).astype(np.int16)
        assert np.abs(got - off).mean() > np.abs(got - want).mean()

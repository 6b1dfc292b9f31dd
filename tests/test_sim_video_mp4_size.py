"""An MP4 whose frames change size stops with a clear error and writes nothing."""

from __future__ import annotations

import pytest
from PIL import Image
from visprim.sim.video import write_video


def test_mp4_frame_of_another_size_is_refused(tmp_path) -> None:
    pytest.importorskip("imageio_ffmpeg")
    frames = [Image.new("RGB", (40, 30), (200, 10, 10)), Image.new("RGB", (42, 30))]
    with pytest.raises(ValueError, match=r"frame 1 is \(42, 30\), the first \(40, 30\)"):
        write_video(tmp_path / "v.mp4", iter(frames), 25.0)
    assert list(tmp_path.iterdir()) == []

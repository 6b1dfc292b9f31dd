"""GIF frames as changed rectangles (the Rust encoder): Pillow decodes exactly the frames
Pillow's own palette reduction makes of the input, and each frame covers just the pixels
whose palette index changed."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from visprim import _visprim
from visprim.sim.video import palette_lut, write_video


def _frames(seed: int, n: int = 40, size: tuple[int, int] = (83, 61)) -> list[np.ndarray]:
    """Random frames: a noisy first frame (a full 255-colour palette), then changes of
    random rectangles to random colours, small perturbations (often within one colour cell),
    repeated frames and returns to an earlier frame."""
    rng = np.random.default_rng(seed)
    w, h = size
    a = rng.integers(0, 256, size=(h, w, 3), dtype=np.uint8)
    out = [a.copy()]
    for k in range(1, n):
        kind = k % 5
        if kind == 0:
            a = a.copy()  # the same frame again
        elif kind == 1:
            a = out[max(0, k - 3)].copy()  # back to an earlier frame
        elif kind == 2:
            a = a.copy()
            x0, y0 = rng.integers(0, w), rng.integers(0, h)
            x1, y1 = rng.integers(x0 + 1, w + 1), rng.integers(y0 + 1, h + 1)
            a[y0:y1, x0:x1] = rng.integers(0, 256, size=3, dtype=np.uint8)
        elif kind == 3:
            a = a.copy()
            m = rng.random((h, w)) < 0.02
            a[m] = np.clip(a[m].astype(int) + rng.integers(-2, 3, size=(int(m.sum()), 3)), 0, 255)
        else:
            a = a.copy()
            y, x = rng.integers(0, h), rng.integers(0, w)
            a[y, x] = rng.integers(0, 256, size=3, dtype=np.uint8)  # one pixel
        out.append(a)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pillow_decodes_exactly_the_quantised_frames(tmp_path, seed):
    frames = _frames(seed)
    images = [Image.fromarray(f) for f in frames]
    path = write_video(tmp_path / "v.gif", iter(images), 20.0)
    # The reference: Pillow's nearest-colour reduction of every frame to the first frame's
    # median-cut palette (Pillow alone, not the encoder's colour table).
    palette = images[0].quantize(
        colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
    )
    indices = [np.asarray(im.quantize(palette=palette, dither=Image.Dither.NONE)) for im in images]
    expected = [
        np.asarray(im.quantize(palette=palette, dither=Image.Dither.NONE).convert("RGB"))
        for im in images
    ]
    assert len(np.unique(indices[0])) > 200, "the palette should be nearly full"
    with Image.open(path) as gif:
        assert gif.n_frames == len(frames) and gif.info["duration"] == 50
        for k, want in enumerate(expected):
            gif.seek(k)
            np.testing.assert_array_equal(np.asarray(gif.convert("RGB")), want, err_msg=f"{k}")
            # The frame's rectangle: the whole first frame, then the bounding box of the
            # pixels whose index changed (one pixel when none did).
            if k == 0:
                box = (0, 0, want.shape[1], want.shape[0])
            else:
                ys, xs = np.nonzero(indices[k] != indices[k - 1])
                box = (
                    (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
                    if ys.size
                    else (0, 0, 1, 1)
                )
            assert gif.dispose_extent == box, k


def test_colour_table_reproduces_pillow_on_every_colour_of_a_cell():
    rng = np.random.default_rng(5)
    palette = Image.fromarray(rng.integers(0, 256, (40, 40, 3), dtype=np.uint8)).quantize(
        colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
    )
    lut = np.frombuffer(palette_lut(palette), dtype=np.uint8)
    assert lut.size == 64**3 and lut.max() < _visprim.GifFrames.TRANSPARENT
    colours = rng.integers(0, 256, (256, 1024, 3), dtype=np.uint8)  # not cell corners
    want = np.asarray(Image.fromarray(colours).quantize(palette=palette, dither=Image.Dither.NONE))
    c = colours.astype(np.int64) >> 2
    np.testing.assert_array_equal(lut[c[..., 0] | c[..., 1] << 6 | c[..., 2] << 12], want)


def test_encoder_refuses_frames_of_another_size():
    lut = bytes(64**3)
    enc = _visprim.GifFrames(4, 3, lut)
    blocks, rect = enc.frame(bytes(4 * 3 * 3), 4)
    assert rect == (0, 0, 4, 3) and blocks[:4] == b"\x21\xf9\x04\x04"
    with pytest.raises(ValueError, match="bytes"):
        enc.frame(bytes(5), 4)
    with pytest.raises(ValueError, match="colour table"):
        _visprim.GifFrames(4, 3, lut[:-1])
    with pytest.raises(ValueError, match="reserved"):
        _visprim.GifFrames(4, 3, b"\xff" * 64**3)
    with pytest.raises(ValueError, match="65535"):
        _visprim.GifFrames(0, 3, lut)


def test_write_video_refuses_frames_of_another_size(tmp_path):
    frames = [Image.new("RGB", (8, 6)), Image.new("RGB", (8, 7))]
    with pytest.raises(ValueError, match="frame 1"):
        write_video(tmp_path / "v.gif", iter(frames), 10.0)
    assert not list(tmp_path.iterdir())


def test_the_image_memory_and_bytes_give_the_same_blocks():
    images = [Image.fromarray(f) for f in _frames(3, n=12)]
    lut = palette_lut(images[0].quantize(colors=255, dither=Image.Dither.NONE))
    direct, copied = (_visprim.GifFrames(83, 61, lut) for _ in range(2))
    for im in images:
        a = direct.frame_arrow(*im.__arrow_c_array__(), 5)
        b = copied.frame(im.tobytes("raw", "RGBX"), 5)
        assert a == b
    grey = Image.new("L", (83, 61)).__arrow_c_array__()
    with pytest.raises(ValueError, match="4 bytes a pixel"):
        direct.frame_arrow(*grey, 5)
    with pytest.raises(ValueError):
        direct.frame_arrow(grey[1], grey[0], 5)  # the capsules swapped

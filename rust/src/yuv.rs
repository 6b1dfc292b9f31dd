//! RGB pixels to the planar YUV 4:2:0 frames an H.264 encoder takes (BT.601, limited range).
//!
//! A frame of `width × height` pixels, row-major, of 3 (`r g b`) or 4 (`r g b x`, the fourth
//! ignored) bytes each, becomes three planes one after the other: Y of `w × h` values, then
//! U and V of `w/2 × h/2` each, where `w` and `h` are the width and height rounded up to even
//! numbers by repeating the last column and row (4:2:0 needs even sizes). The layout is
//! ffmpeg's `yuv420p`.
//!
//! The coefficients are the 8-bit integer form of ITU-R BT.601 for the studio range (Y in
//! 16…235, U and V in 16…240), as in ffmpeg's and Microsoft's references:
//!
//! ```text
//! Y = ((  66 R + 129 G +  25 B + 128) >> 8) +  16
//! U = (( -38 R -  74 G + 112 B + 128) >> 8) + 128
//! V = (( 112 R -  94 G -  18 B + 128) >> 8) + 128
//! ```
//!
//! U and V are those of the mean colour of each 2 × 2 block: the same sums over the block's
//! four pixels, shifted by 10 instead of 8, so the mean is rounded once.

use crate::buffer;
use crate::{Error, Result};

/// Sizes of the planes of a `width × height` frame: `(w, h)`, the even width and height of
/// the Y plane, and the bytes of the whole frame (`w·h + 2·(w/2)·(h/2)`).
pub fn yuv420_layout(width: usize, height: usize) -> Result<(usize, usize, usize)> {
    if width == 0 || height == 0 {
        return Err(Error::Shape(format!(
            "a YUV frame needs at least one pixel, got {width} x {height}"
        )));
    }
    let even = |n: usize| n.saturating_add(n % 2); // usize::MAX: refused just below
    let (w, h) = (even(width), even(height));
    let luma = buffer::elements::<u8>(&[w, h], "YUV 4:2:0 frame")?;
    Ok((w, h, luma + luma / 2))
}

#[inline]
fn luma(r: i32, g: i32, b: i32) -> u8 {
    (((66 * r + 129 * g + 25 * b + 128) >> 8) + 16) as u8
}

/// U and V of a 2 × 2 block from the sums of its four pixels' channels.
#[inline]
fn chroma(r4: i32, g4: i32, b4: i32) -> (u8, u8) {
    let u = ((-38 * r4 - 74 * g4 + 112 * b4 + 512) >> 10) + 128;
    let v = ((112 * r4 - 94 * g4 - 18 * b4 + 512) >> 10) + 128;
    (u as u8, v as u8)
}

/// Converts one frame (see the module docs) into `out`, which must hold exactly the frame's
/// bytes ([`yuv420_layout`]). `pixels` must hold `width · height` pixels of 3 or 4 bytes.
pub fn rgb_to_yuv420(pixels: &[u8], width: usize, height: usize, out: &mut [u8]) -> Result<()> {
    let (_, _, total) = yuv420_layout(width, height)?;
    let n = width * height; // ≤ w · h, checked above
    let bpp = match pixels.len() {
        l if l == n * 3 => 3,
        l if l / 4 == n && l % 4 == 0 => 4,
        l => {
            return Err(Error::Shape(format!(
                "a {width} x {height} frame has {} (RGB) or {} (RGBX) bytes, got {l}",
                n * 3,
                n * 4
            )))
        }
    };
    if out.len() != total {
        return Err(Error::Shape(format!(
            "the YUV 4:2:0 frame of {width} x {height} pixels has {total} bytes, got a buffer of {}",
            out.len()
        )));
    }
    if bpp == 3 {
        planes::<3>(pixels, width, height, out);
    } else {
        planes::<4>(pixels, width, height, out);
    }
    Ok(())
}

/// The conversion proper, for `BPP` bytes a pixel (sizes checked by the caller).
fn planes<const BPP: usize>(pixels: &[u8], width: usize, height: usize, out: &mut [u8]) {
    let (w, h) = (width + width % 2, height + height % 2);
    let stride = width * BPP;
    let row = |y: usize| &pixels[y.min(height - 1) * stride..][..stride];
    let (y_plane, uv) = out.split_at_mut(w * h);
    let (u_plane, v_plane) = uv.split_at_mut(w * h / 4);
    for (y, out_row) in y_plane.chunks_exact_mut(w).enumerate() {
        for (o, p) in out_row.iter_mut().zip(row(y).chunks_exact(BPP)) {
            *o = luma(p[0] as i32, p[1] as i32, p[2] as i32);
        }
        if w > width {
            out_row[width] = out_row[width - 1];
        }
    }
    for (by, (u_row, v_row)) in u_plane
        .chunks_exact_mut(w / 2)
        .zip(v_plane.chunks_exact_mut(w / 2))
        .enumerate()
    {
        let (r0, r1) = (row(2 * by), row(2 * by + 1));
        let blocks = r0.chunks_exact(2 * BPP).zip(r1.chunks_exact(2 * BPP));
        for ((u, v), (a, b)) in u_row.iter_mut().zip(v_row.iter_mut()).zip(blocks) {
            let (r4, g4, b4) = (
                a[0] as i32 + a[BPP] as i32 + b[0] as i32 + b[BPP] as i32,
                a[1] as i32 + a[BPP + 1] as i32 + b[1] as i32 + b[BPP + 1] as i32,
                a[2] as i32 + a[BPP + 2] as i32 + b[2] as i32 + b[BPP + 2] as i32,
            );
            (*u, *v) = chroma(r4, g4, b4);
        }
        if w > width {
            // The last block: the last column twice.
            let (a, b) = (&r0[stride - BPP..], &r1[stride - BPP..]);
            let c = |k: usize| 2 * (a[k] as i32 + b[k] as i32);
            (u_row[w / 2 - 1], v_row[w / 2 - 1]) = chroma(c(0), c(1), c(2));
        }
    }
}

/// As [`rgb_to_yuv420`], into a new buffer (allocated fallibly).
pub fn rgb_to_yuv420_vec(pixels: &[u8], width: usize, height: usize) -> Result<Vec<u8>> {
    let (_, _, total) = yuv420_layout(width, height)?;
    let mut out = buffer::try_filled(total, 0u8, "YUV 4:2:0 frame")?;
    rgb_to_yuv420(pixels, width, height, &mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BT.601 studio range in floating point (the standard's definition), rounded.
    fn reference(r: f64, g: f64, b: f64) -> (f64, f64, f64) {
        let (r, g, b) = (r / 255.0, g / 255.0, b / 255.0);
        let y = 0.299 * r + 0.587 * g + 0.114 * b;
        (
            16.0 + 219.0 * y,
            128.0 + 224.0 * (b - y) / 1.772,
            128.0 + 224.0 * (r - y) / 1.402,
        )
    }

    #[test]
    fn primaries_and_greys_match_the_standard_within_one_level() {
        let colours = [
            [0u8, 0, 0],
            [255, 255, 255],
            [255, 0, 0],
            [0, 255, 0],
            [0, 0, 255],
            [128, 128, 128],
            [200, 60, 30],
            [17, 230, 99],
        ];
        for c in colours {
            let px: Vec<u8> = c.iter().copied().cycle().take(12).collect(); // 2 x 2 of c
            let out = rgb_to_yuv420_vec(&px, 2, 2).unwrap();
            let (y, u, v) = reference(c[0] as f64, c[1] as f64, c[2] as f64);
            assert!(
                out[..4].iter().all(|&l| (l as f64 - y).abs() <= 1.0),
                "{c:?} {out:?}"
            );
            assert!(
                (out[4] as f64 - u).abs() <= 1.0,
                "{c:?} U {} vs {u}",
                out[4]
            );
            assert!(
                (out[5] as f64 - v).abs() <= 1.0,
                "{c:?} V {} vs {v}",
                out[5]
            );
        }
        let black = rgb_to_yuv420_vec(&[0; 12], 2, 2).unwrap();
        assert_eq!(black, [16, 16, 16, 16, 128, 128]);
        let white = rgb_to_yuv420_vec(&[255; 12], 2, 2).unwrap();
        assert_eq!(white, [235, 235, 235, 235, 128, 128]);
    }

    #[test]
    fn chroma_is_that_of_the_block_mean_and_planes_are_in_order() {
        // 4 x 2: left block red and blue, right block green.
        let mut px = Vec::new();
        for row in [[[255, 0, 0], [0, 0, 255], [0, 255, 0], [0, 255, 0]]; 2] {
            for p in row {
                px.extend_from_slice(&p);
            }
        }
        let out = rgb_to_yuv420_vec(&px, 4, 2).unwrap();
        assert_eq!(out.len(), 8 + 2 + 2);
        let (_, u_left, v_left) = reference(127.5, 0.0, 127.5);
        let (_, u_right, v_right) = reference(0.0, 255.0, 0.0);
        assert!((out[8] as f64 - u_left).abs() <= 1.0);
        assert!((out[9] as f64 - u_right).abs() <= 1.0);
        assert!((out[10] as f64 - v_left).abs() <= 1.0);
        assert!((out[11] as f64 - v_right).abs() <= 1.0);
        assert_eq!(out[0], out[4]); // both rows alike
    }

    #[test]
    fn odd_sizes_repeat_the_last_column_and_row_and_rgbx_equals_rgb() {
        let (width, height) = (3, 3);
        let rgb: Vec<u8> = (0..27).map(|i| (i * 37 % 251) as u8).collect();
        let rgbx: Vec<u8> = rgb.chunks(3).flat_map(|p| [p[0], p[1], p[2], 7]).collect();
        let a = rgb_to_yuv420_vec(&rgb, width, height).unwrap();
        assert_eq!(a, rgb_to_yuv420_vec(&rgbx, width, height).unwrap());
        // The same frame padded by hand to 4 x 4.
        let mut padded = Vec::new();
        for y in 0..4usize {
            for x in 0..4usize {
                let p = (y.min(2) * 3 + x.min(2)) * 3;
                padded.extend_from_slice(&rgb[p..p + 3]);
            }
        }
        assert_eq!(a, rgb_to_yuv420_vec(&padded, 4, 4).unwrap());
        assert_eq!(a.len(), 16 + 4 + 4);
    }

    #[test]
    fn sizes_are_checked() {
        assert!(matches!(yuv420_layout(0, 4), Err(Error::Shape(_))));
        assert!(matches!(
            yuv420_layout(usize::MAX, 3),
            Err(Error::Memory(_))
        ));
        assert!(matches!(
            rgb_to_yuv420_vec(&[0; 10], 2, 2),
            Err(Error::Shape(_))
        ));
        let mut small = [0u8; 5];
        assert!(matches!(
            rgb_to_yuv420(&[0; 12], 2, 2, &mut small),
            Err(Error::Shape(_))
        ));
    }
}

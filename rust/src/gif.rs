//! GIF frames from RGB pixels: palette lookup, the changed rectangle, LZW.
//!
//! A [`GifFrames`] encoder turns a stream of frames of one size (row-major pixels of packed
//! `r g b` or `r g b x` bytes) into GIF89a frame blocks (graphic control extension, image
//! descriptor, LZW image data). Whatever the length of the stream it holds one frame of
//! pixels and one of palette indices (the last frame), and the rectangle being encoded.
//!
//! * **Palette.** A pixel `(r, g, b)` becomes `lut[(r >> 2) | (g >> 2) << 6 | (b >> 2) << 12]`:
//!   one index per cell of 4 × 4 × 4 colour values, the table the caller built (Pillow's
//!   `quantize(palette=…)` looks colours up in cells of exactly this size, so a table filled
//!   from it reproduces Pillow's indices). Index [`TRANSPARENT`] is reserved.
//! * **Changed rectangle.** The first frame is written whole. Every later frame is the
//!   smallest rectangle holding every pixel whose index differs from the previous frame's
//!   (only pixels whose bytes changed are looked up again);
//!   inside it, pixels that did not change are [`TRANSPARENT`], and the frame's disposal is
//!   "do not dispose", so a decoder shows exactly the current frame's indices. A frame equal
//!   to the last one is a single transparent pixel.
//! * **LZW.** Variable-width codes (9 to 12 bits) with the minimum code size 8 and a clear
//!   code when the table is full, as giflib's encoder writes them, in data sub-blocks of at
//!   most 255 bytes.

use crate::buffer;
use crate::{Error, Result};

/// The palette index of pixels that keep the previous frame's colour (never in the table).
pub const TRANSPARENT: u8 = 255;

/// Entries of the colour lookup table: 64 cells per channel.
pub const LUT_LEN: usize = 64 * 64 * 64;

/// LZW minimum code size: 8-bit palette indices.
const MIN_CODE_SIZE: u32 = 8;
const CLEAR: u16 = 1 << MIN_CODE_SIZE;
const END: u16 = CLEAR + 1;
/// The largest code of the table (GIF's codes have at most 12 bits).
const MAX_CODE: u16 = 4095;
/// Slots of the open-addressing table of (prefix code, index) → code: a power of two, about
/// twice the number of codes.
const HASH_SLOTS: usize = 8192;
const EMPTY: u32 = u32::MAX;

/// Index of the lookup-table cell of a colour.
#[inline]
fn cell(r: u8, g: u8, b: u8) -> usize {
    (r as usize >> 2) | (g as usize >> 2) << 6 | (b as usize >> 2) << 12
}

/// LZW encoder state (reused across frames: the table is cleared, not reallocated).
struct Lzw {
    /// `key << 12 | code` per slot, [`EMPTY`] when free; key = `prefix << 8 | index`.
    slots: Vec<u32>,
    /// Packed code bits of the frame being encoded.
    bytes: Vec<u8>,
    acc: u64,
    n_bits: u32,
    width: u32,
    next: u16,
}

impl Lzw {
    fn new() -> Result<Self> {
        Ok(Self {
            slots: buffer::try_filled(HASH_SLOTS, EMPTY, "LZW table")?,
            bytes: Vec::new(),
            acc: 0,
            n_bits: 0,
            width: MIN_CODE_SIZE + 1,
            next: END + 1,
        })
    }

    fn reset_table(&mut self) {
        self.slots.fill(EMPTY);
        self.width = MIN_CODE_SIZE + 1;
        self.next = END + 1;
    }

    /// Writes `code` at the current width; widens the codes once the next code to assign
    /// needs one more bit (giflib's rule, which decoders follow).
    #[inline]
    fn emit(&mut self, code: u16) {
        self.acc |= (code as u64) << self.n_bits;
        self.n_bits += self.width;
        while self.n_bits >= 8 {
            self.bytes.push(self.acc as u8);
            self.acc >>= 8;
            self.n_bits -= 8;
        }
        if u32::from(self.next) >= 1 << self.width && self.width < 12 {
            self.width += 1;
        }
    }

    /// Slot of `key`: the one holding it, or the free one where it belongs.
    #[inline]
    fn find(&self, key: u32) -> usize {
        let mut h = (key.wrapping_mul(0x9E37_79B1) >> 19) as usize & (HASH_SLOTS - 1);
        loop {
            let s = self.slots[h];
            if s == EMPTY || s >> 12 == key {
                return h;
            }
            h = (h + 1) & (HASH_SLOTS - 1);
        }
    }

    /// Encodes `indices` (at least one) and appends the image data (minimum code size, data
    /// sub-blocks, terminator) to `out`.
    fn encode(&mut self, indices: impl Iterator<Item = u8>, out: &mut Vec<u8>) -> Result<()> {
        self.bytes.clear();
        self.acc = 0;
        self.n_bits = 0;
        self.reset_table();
        self.emit(CLEAR);
        let mut indices = indices;
        let Some(first) = indices.next() else {
            return Err(Error::Shape("LZW: no pixels to encode".into()));
        };
        let mut current = u16::from(first);
        for k in indices {
            let key = u32::from(current) << 8 | u32::from(k);
            let h = self.find(key);
            let s = self.slots[h];
            if s != EMPTY {
                current = (s & 0xFFF) as u16;
                continue;
            }
            self.emit(current);
            current = u16::from(k);
            if self.next >= MAX_CODE {
                self.emit(CLEAR);
                self.reset_table();
            } else {
                self.slots[h] = key << 12 | u32::from(self.next);
                self.next += 1;
            }
        }
        self.emit(current);
        self.emit(END);
        if self.n_bits > 0 {
            self.bytes.push(self.acc as u8);
        }
        let blocks = self.bytes.len().div_ceil(255);
        let size = self
            .bytes
            .len()
            .checked_add(blocks + 2)
            .ok_or_else(|| Error::Memory("LZW: image data too large".into()))?;
        out.try_reserve(size)
            .map_err(|e| Error::Memory(format!("LZW: {size} bytes of image data: {e}")))?;
        out.push(MIN_CODE_SIZE as u8);
        for chunk in self.bytes.chunks(255) {
            out.push(chunk.len() as u8);
            out.extend_from_slice(chunk);
        }
        out.push(0);
        Ok(())
    }
}

/// The encoder of a stream of frames (see the module documentation).
pub struct GifFrames {
    width: usize,
    height: usize,
    lut: Vec<u8>,
    /// Bytes per pixel of the frames (3: RGB, 4: RGBX), fixed by the first frame.
    bpp: usize,
    /// The previous frame's pixels (`width * height * bpp` bytes, after the first frame).
    pixels: Vec<u8>,
    /// Palette indices a decoder shows after the last frame (`width * height`).
    shown: Vec<u8>,
    /// Indices of the changed pixel rectangle of the frame being encoded.
    scratch: Vec<u8>,
    started: bool,
    lzw: Lzw,
}

/// An inclusive-exclusive rectangle `x0..x1, y0..y1` of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl Rect {
    fn width(&self) -> usize {
        self.x1 - self.x0
    }
}

/// Grows `rect` (None: empty) by the columns `first..last` of row `y`.
fn grow(rect: &mut Option<Rect>, y: usize, first: usize, last: usize) {
    *rect = Some(match *rect {
        None => Rect {
            x0: first,
            y0: y,
            x1: last,
            y1: y + 1,
        },
        Some(r) => Rect {
            x0: r.x0.min(first),
            y0: r.y0,
            x1: r.x1.max(last),
            y1: y + 1,
        },
    });
}

/// The first and one past the last position where `a` and `b` (equal lengths) differ.
fn differing(a: &[u8], b: &[u8]) -> Option<(usize, usize)> {
    if a == b {
        return None;
    }
    let first = a.iter().zip(b).position(|(p, q)| p != q)?;
    let last = a.len()
        - a.iter()
            .rev()
            .zip(b.iter().rev())
            .position(|(p, q)| p != q)?;
    Some((first, last))
}

impl GifFrames {
    /// An encoder for `width × height` frames (1 to 65,535 pixels each way) with the colour
    /// table `lut` ([`LUT_LEN`] indices, none equal to [`TRANSPARENT`]).
    pub fn new(width: usize, height: usize, lut: &[u8]) -> Result<Self> {
        if !(1..=65535).contains(&width) || !(1..=65535).contains(&height) {
            return Err(Error::InvalidArgument(format!(
                "GIF frames must be 1 to 65535 pixels wide and high, got {width} x {height}"
            )));
        }
        if lut.len() != LUT_LEN {
            return Err(Error::Shape(format!(
                "the colour table must have {LUT_LEN} entries, got {}",
                lut.len()
            )));
        }
        if lut.contains(&TRANSPARENT) {
            return Err(Error::InvalidArgument(format!(
                "the colour table uses index {TRANSPARENT}, reserved for transparency"
            )));
        }
        let n = buffer::elements::<u8>(&[height, width], "GIF frame indices")?;
        Ok(Self {
            width,
            height,
            lut: buffer::try_copy(lut, "colour table")?,
            bpp: 0,
            pixels: Vec::new(),
            shown: buffer::try_filled(n, 0u8, "GIF frame indices")?,
            scratch: Vec::new(),
            started: false,
            lzw: Lzw::new()?,
        })
    }

    /// Bytes held by the encoder (tables, the last frame's pixels and indices, buffers).
    pub fn memory_bytes(&self) -> usize {
        self.lut.len()
            + self.pixels.capacity()
            + self.shown.len()
            + self.scratch.capacity()
            + self.lzw.slots.len() * 4
            + self.lzw.bytes.capacity()
    }

    /// The rectangle of pixels whose bytes differ from the previous frame's, if any.
    fn changed_pixels(&self, px: &[u8]) -> Option<Rect> {
        let (stride, bpp) = (self.width * self.bpp, self.bpp);
        let mut rect = None;
        for (y, (a, b)) in self
            .pixels
            .chunks_exact(stride)
            .zip(px.chunks_exact(stride))
            .enumerate()
        {
            if let Some((first, last)) = differing(a, b) {
                grow(&mut rect, y, first / bpp, last.div_ceil(bpp));
            }
        }
        rect
    }

    /// Encodes the next frame, `px` (`width * height` pixels of 3 bytes, RGB, or 4, RGBX: the
    /// fourth is ignored; every frame of a stream alike), shown for `delay` centiseconds, and
    /// appends its blocks to `out`. Returns the rectangle written.
    pub fn frame(&mut self, px: &[u8], delay: u16, out: &mut Vec<u8>) -> Result<Rect> {
        let n = self.shown.len();
        let bpp = if px.len() == n * 3 { 3 } else { 4 };
        if px.len() != n * bpp || (self.started && bpp != self.bpp) {
            return Err(Error::Shape(format!(
                "a {} x {} frame has {} (RGB) or {} (RGBX) bytes{}, got {}",
                self.width,
                self.height,
                n * 3,
                n * 4,
                if self.started {
                    ", as many as the first"
                } else {
                    ""
                },
                px.len()
            )));
        }
        let first = !self.started;
        let lut = &self.lut;
        let index = |p: &[u8]| lut[cell(p[0], p[1], p[2])];
        let rect = if first {
            self.bpp = bpp;
            self.pixels = buffer::try_copy(px, "GIF frame pixels")?;
            for (dst, p) in self.shown.iter_mut().zip(px.chunks_exact(bpp)) {
                *dst = index(p);
            }
            Rect {
                x0: 0,
                y0: 0,
                x1: self.width,
                y1: self.height,
            }
        } else {
            self.changed_indices(px)?.unwrap_or(Rect {
                x0: 0,
                y0: 0,
                x1: 1,
                y1: 1,
            })
        };
        // Graphic control extension: disposal 1 (keep), transparency after the first frame.
        let flags = 0b0000_0100 | u8::from(!first);
        out.try_reserve(18)
            .map_err(|e| Error::Memory(format!("GIF frame header: {e}")))?;
        out.extend_from_slice(&[0x21, 0xF9, 0x04, flags]);
        out.extend_from_slice(&delay.to_le_bytes());
        out.extend_from_slice(&[TRANSPARENT, 0x00]);
        // Image descriptor, no local colour table, not interlaced.
        out.push(0x2C);
        for v in [rect.x0, rect.y0, rect.width(), rect.y1 - rect.y0] {
            out.extend_from_slice(&(v as u16).to_le_bytes());
        }
        out.push(0x00);
        if first {
            self.lzw.encode(self.shown.iter().copied(), out)?;
        } else {
            // ``scratch`` holds the rectangle's pixels: an index, or transparent (unchanged).
            if self.scratch.is_empty() {
                self.scratch.push(TRANSPARENT); // no change: one transparent pixel
            }
            self.lzw.encode(self.scratch.iter().copied(), out)?;
        }
        self.started = true;
        Ok(rect)
    }

    /// Finds the pixels of `px` whose index differs from the one shown, updates ``shown``
    /// and ``pixels``, and leaves in ``scratch`` the smallest rectangle holding them (the
    /// new index, or [`TRANSPARENT`] for a pixel that keeps its index). None: no change.
    fn changed_indices(&mut self, px: &[u8]) -> Result<Option<Rect>> {
        self.scratch.clear();
        let Some(outer) = self.changed_pixels(px) else {
            return Ok(None);
        };
        let (w, bpp) = (self.width, self.bpp);
        let lut = &self.lut;
        // The new indices of the changed pixel rectangle, then the rectangle where they differ.
        self.scratch.clear();
        let area = outer.width() * (outer.y1 - outer.y0);
        self.scratch.try_reserve(area).map_err(|e| {
            Error::Memory(format!("GIF: {area} indices of a changed rectangle: {e}"))
        })?;
        let mut inner: Option<Rect> = None;
        for y in outer.y0..outer.y1 {
            let row = &px[(y * w + outer.x0) * bpp..(y * w + outer.x1) * bpp];
            let start = self.scratch.len();
            self.scratch
                .extend(row.chunks_exact(bpp).map(|p| lut[cell(p[0], p[1], p[2])]));
            let shown = &self.shown[y * w + outer.x0..y * w + outer.x1];
            if let Some((a, b)) = differing(&self.scratch[start..], shown) {
                grow(&mut inner, y, outer.x0 + a, outer.x0 + b);
            }
            let span = (y * w + outer.x0) * bpp..(y * w + outer.x1) * bpp;
            self.pixels[span.clone()].copy_from_slice(&px[span]);
        }
        let Some(inner) = inner else {
            self.scratch.clear();
            return Ok(None);
        };
        // Transparent where the index is kept; the shown indices become the new ones.
        let ow = outer.width();
        let mut k = 0;
        for y in inner.y0..inner.y1 {
            let new = (y - outer.y0) * ow + (inner.x0 - outer.x0);
            for (j, x) in (inner.x0..inner.x1).enumerate() {
                let v = self.scratch[new + j];
                let s = &mut self.shown[y * w + x];
                self.scratch[k] = if *s == v { TRANSPARENT } else { v };
                *s = v;
                k += 1;
            }
        }
        self.scratch.truncate(k);
        Ok(Some(inner))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plain GIF LZW decoder (as a decoder reads the stream), for the round trips.
    fn decode(data: &[u8]) -> Vec<u8> {
        assert_eq!(data[0], 8);
        let mut bytes = Vec::new();
        let mut p = 1;
        while data[p] != 0 {
            let len = data[p] as usize;
            bytes.extend_from_slice(&data[p + 1..p + 1 + len]);
            p += 1 + len;
        }
        assert_eq!(p, data.len() - 1, "data after the terminator");
        let mut table: Vec<Vec<u8>> = Vec::new();
        let reset = |t: &mut Vec<Vec<u8>>| {
            t.clear();
            t.extend((0..=255u8).map(|i| vec![i]));
            t.push(vec![]);
            t.push(vec![]);
        };
        reset(&mut table);
        let (mut width, mut acc, mut n_bits, mut pos) = (9u32, 0u64, 0u32, 0usize);
        let mut out = Vec::new();
        let mut prev: Option<Vec<u8>> = None;
        loop {
            while n_bits < width {
                acc |= u64::from(bytes[pos]) << n_bits;
                pos += 1;
                n_bits += 8;
            }
            let code = (acc & ((1 << width) - 1)) as usize;
            acc >>= width;
            n_bits -= width;
            if code == 256 {
                reset(&mut table);
                width = 9;
                prev = None;
                continue;
            }
            if code == 257 {
                break;
            }
            let entry = if code < table.len() {
                table[code].clone()
            } else {
                let p = prev.clone().expect("a new code right after a clear");
                assert_eq!(code, table.len(), "code beyond the table");
                let mut e = p.clone();
                e.push(p[0]);
                e
            };
            if let Some(p) = prev {
                if table.len() < 4096 {
                    let mut e = p;
                    e.push(entry[0]);
                    table.push(e);
                }
            }
            if table.len() == 1 << width && width < 12 {
                width += 1;
            }
            out.extend_from_slice(&entry);
            prev = Some(entry);
        }
        out
    }

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    #[test]
    fn lzw_round_trips_runs_noise_and_table_resets() {
        let mut lzw = Lzw::new().unwrap();
        let mut seed = 7;
        let cases: Vec<Vec<u8>> = vec![
            vec![3],
            vec![0; 100_000],
            (0..200_000).map(|_| lcg(&mut seed) as u8).collect(),
            (0..300_000).map(|_| (lcg(&mut seed) % 5) as u8).collect(),
            (0..50_000).map(|i| (i / 37 % 256) as u8).collect(),
        ];
        for case in cases {
            let mut out = Vec::new();
            lzw.encode(case.iter().copied(), &mut out).unwrap();
            assert_eq!(decode(&out), case);
        }
    }

    fn grey_lut() -> Vec<u8> {
        // The index is the red cell (0..63): colours differ by their red channel only.
        (0..LUT_LEN).map(|k| (k & 63) as u8).collect()
    }

    #[test]
    fn frames_keep_only_the_changed_rectangle() {
        let (w, h) = (7, 5);
        let lut = grey_lut();
        let mut enc = GifFrames::new(w, h, &lut).unwrap();
        let mut rgb = vec![0u8; w * h * 3];
        let mut out = Vec::new();
        let full = enc.frame(&rgb, 4, &mut out).unwrap();
        assert_eq!(
            full,
            Rect {
                x0: 0,
                y0: 0,
                x1: 7,
                y1: 5
            }
        );
        assert_eq!(&out[..8], &[0x21, 0xF9, 0x04, 0x04, 4, 0, TRANSPARENT, 0]);
        // Two pixels change: (2, 1) and (4, 3); a change within one colour cell does not count.
        rgb[(w + 2) * 3] = 40;
        rgb[(3 * w + 4) * 3] = 80;
        rgb[(4 * w + 6) * 3] = 2;
        out.clear();
        let r = enc.frame(&rgb, 4, &mut out).unwrap();
        assert_eq!(
            r,
            Rect {
                x0: 2,
                y0: 1,
                x1: 5,
                y1: 4
            }
        );
        assert_eq!(out[3], 0x05, "keep the frame, transparency on");
        let t = TRANSPARENT;
        let expected = [10, t, t, t, t, t, t, t, 20];
        assert_eq!(decode(&out[18..]), expected);
        out.clear();
        let same = enc.frame(&rgb, 4, &mut out).unwrap();
        assert_eq!(
            same,
            Rect {
                x0: 0,
                y0: 0,
                x1: 1,
                y1: 1
            }
        );
        assert_eq!(decode(&out[18..]), [t]);
    }

    #[test]
    fn rgbx_frames_ignore_the_fourth_byte_and_a_pixel_change_of_one_cell() {
        let (w, h) = (4, 3);
        let mut enc = GifFrames::new(w, h, &grey_lut()).unwrap();
        let mut px = vec![0u8; w * h * 4];
        let mut out = Vec::new();
        enc.frame(&px, 1, &mut out).unwrap();
        px[(w + 1) * 4 + 3] = 9; // the fourth byte
        px[(2 * w + 3) * 4] = 3; // red 3: still cell 0
        out.clear();
        assert_eq!(
            enc.frame(&px, 1, &mut out).unwrap(),
            Rect {
                x0: 0,
                y0: 0,
                x1: 1,
                y1: 1
            }
        );
        assert_eq!(decode(&out[18..]), [TRANSPARENT]);
        px[3 * 4] = 255; // pixel (3, 0) -> cell 63
        out.clear();
        assert_eq!(
            enc.frame(&px, 1, &mut out).unwrap(),
            Rect {
                x0: 3,
                y0: 0,
                x1: 4,
                y1: 1
            }
        );
        assert_eq!(decode(&out[18..]), [63]);
        assert!(
            enc.frame(&px[..w * h * 3], 1, &mut Vec::new()).is_err(),
            "RGB after RGBX"
        );
    }

    #[test]
    fn bad_arguments_are_refused() {
        let lut = grey_lut();
        assert!(GifFrames::new(0, 5, &lut).is_err());
        assert!(GifFrames::new(65536, 5, &lut).is_err());
        assert!(GifFrames::new(5, 5, &lut[1..]).is_err());
        let mut bad = lut.clone();
        bad[9] = TRANSPARENT;
        assert!(GifFrames::new(5, 5, &bad).is_err());
        let mut enc = GifFrames::new(5, 5, &lut).unwrap();
        assert!(enc.frame(&[0; 74], 1, &mut Vec::new()).is_err());
    }
}

//! GIF frames from RGB pixels: palette lookup, the changed rectangle, LZW.
//!
//! A [`GifFrames`] encoder turns a stream of RGB frames (packed `r g b` bytes, row-major) of
//! one size into GIF89a frame blocks (graphic control extension, image descriptor, LZW image
//! data). It holds two frames of palette indices (the last and the current one) whatever the
//! length of the stream.
//!
//! * **Palette.** A pixel `(r, g, b)` becomes `lut[(r >> 2) | (g >> 2) << 6 | (b >> 2) << 12]`:
//!   one index per cell of 4 × 4 × 4 colour values, the table the caller built (Pillow's
//!   `quantize(palette=…)` looks colours up in cells of exactly this size, so a table filled
//!   from it reproduces Pillow's indices). Index [`TRANSPARENT`] is reserved.
//! * **Changed rectangle.** The first frame is written whole. Every later frame is the
//!   smallest rectangle holding every pixel whose index differs from the previous frame's;
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
    /// Palette indices of the previous frame and of the current one (`width * height` each).
    prev: Vec<u8>,
    cur: Vec<u8>,
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
        let table = buffer::try_copy(lut, "colour table")?;
        Ok(Self {
            width,
            height,
            lut: table,
            prev: buffer::try_filled(n, 0u8, "GIF frame indices")?,
            cur: buffer::try_filled(n, 0u8, "GIF frame indices")?,
            started: false,
            lzw: Lzw::new()?,
        })
    }

    /// Bytes held by the encoder (tables and two frames of indices).
    pub fn memory_bytes(&self) -> usize {
        self.lut.len()
            + self.prev.len()
            + self.cur.len()
            + self.lzw.slots.len() * 4
            + self.lzw.bytes.capacity()
    }

    /// The rectangle of pixels whose index differs between `prev` and `cur`, if any.
    fn changed(&self) -> Option<Rect> {
        let w = self.width;
        let rows = self.prev.chunks_exact(w).zip(self.cur.chunks_exact(w));
        let (mut y0, mut y1, mut x0, mut x1) = (usize::MAX, 0, w, 0);
        for (y, (a, b)) in rows.enumerate() {
            if a == b {
                continue;
            }
            let first = a.iter().zip(b).position(|(p, q)| p != q).unwrap_or(0);
            let last = w - a.iter().rev().zip(b.iter().rev()).position(|(p, q)| p != q).unwrap_or(0);
            y0 = y0.min(y);
            y1 = y + 1;
            x0 = x0.min(first);
            x1 = x1.max(last);
        }
        (y0 != usize::MAX).then_some(Rect { x0, y0, x1, y1 })
    }

    /// Encodes the next frame, `rgb` (`width * height * 3` bytes), shown for `delay`
    /// centiseconds, and appends its blocks to `out`. Returns the rectangle written.
    pub fn frame(&mut self, rgb: &[u8], delay: u16, out: &mut Vec<u8>) -> Result<Rect> {
        let n = self.prev.len();
        if rgb.len() != n * 3 {
            return Err(Error::Shape(format!(
                "a {} x {} RGB frame has {} bytes, got {}",
                self.width,
                self.height,
                n * 3,
                rgb.len()
            )));
        }
        for (dst, px) in self.cur.iter_mut().zip(rgb.chunks_exact(3)) {
            *dst = self.lut[cell(px[0], px[1], px[2])];
        }
        let first = !self.started;
        let rect = if first {
            Rect { x0: 0, y0: 0, x1: self.width, y1: self.height }
        } else {
            self.changed().unwrap_or(Rect { x0: 0, y0: 0, x1: 1, y1: 1 })
        };
        // Graphic control extension: disposal 1 (keep), transparency after the first frame.
        let flags = 0b0000_0100 | u8::from(!first);
        out.try_reserve(10 + 8)
            .map_err(|e| Error::Memory(format!("GIF frame header: {e}")))?;
        out.extend_from_slice(&[0x21, 0xF9, 0x04, flags]);
        out.extend_from_slice(&delay.to_le_bytes());
        out.extend_from_slice(&[TRANSPARENT, 0x00]);
        // Image descriptor, no local colour table, not interlaced.
        out.push(0x2C);
        for v in [rect.x0, rect.y0, rect.x1 - rect.x0, rect.y1 - rect.y0] {
            out.extend_from_slice(&(v as u16).to_le_bytes());
        }
        out.push(0x00);
        let w = self.width;
        let (prev, cur) = (&self.prev, &self.cur);
        let pixels = (rect.y0..rect.y1).flat_map(move |y| {
            let row = y * w;
            (row + rect.x0..row + rect.x1).map(move |i| {
                if !first && prev[i] == cur[i] {
                    TRANSPARENT
                } else {
                    cur[i]
                }
            })
        });
        self.lzw.encode(pixels, out)?;
        std::mem::swap(&mut self.prev, &mut self.cur);
        self.started = true;
        Ok(rect)
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
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
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
        assert_eq!(full, Rect { x0: 0, y0: 0, x1: 7, y1: 5 });
        assert_eq!(&out[..8], &[0x21, 0xF9, 0x04, 0x04, 4, 0, TRANSPARENT, 0]);
        // Two pixels change: (2, 1) and (4, 3); a change within one colour cell does not count.
        rgb[(w + 2) * 3] = 40;
        rgb[(3 * w + 4) * 3] = 80;
        rgb[(4 * w + 6) * 3] = 2;
        out.clear();
        let r = enc.frame(&rgb, 4, &mut out).unwrap();
        assert_eq!(r, Rect { x0: 2, y0: 1, x1: 5, y1: 4 });
        assert_eq!(out[3], 0x05, "keep the frame, transparency on");
        let t = TRANSPARENT;
        let expected = [10, t, t, t, t, t, t, t, 20];
        assert_eq!(decode(&out[18..]), expected);
        out.clear();
        let same = enc.frame(&rgb, 4, &mut out).unwrap();
        assert_eq!(same, Rect { x0: 0, y0: 0, x1: 1, y1: 1 });
        assert_eq!(decode(&out[18..]), [t]);
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

//! Squared Euclidean distances between rows and a small set of centres (k-means kernels).
//!
//! The centres are stored transposed in a [`Panel`] (`data[j * kpad + c]` is coordinate `j` of
//! centre `c`, columns padded with zeros to a multiple of [`PAD`]) so that one SIMD register
//! holds one coordinate of 4 or 8 centres. [`sq_dists`] computes, for every row `x`,
//! `Σ_j (x_j - c_j)²` for all centres with the *direct* formula (no `‖x‖² - 2x·c + ‖c‖²`
//! cancellation), accumulating over `j = 0..d` in order with fused multiply-adds. Every
//! instruction set (AVX-512F, AVX2+FMA, portable `f64::mul_add`) therefore returns the same
//! bits, and the choice is made at run time (the crate is built for baseline x86-64).

use crate::simd::{self, Level};

/// Panel columns are padded to a multiple of this.
pub const PAD: usize = 8;

/// `k` centres of dimension `d`, transposed and zero-padded to `kpad` columns.
#[derive(Clone, Debug)]
pub struct Panel {
    d: usize,
    k: usize,
    kpad: usize,
    data: Vec<f64>,
}

impl Panel {
    /// Panel of the row-major `k × d` matrix `centers`.
    pub fn from_centers(centers: &[f64], k: usize, d: usize) -> Self {
        let mut p = Self {
            d,
            k: 0,
            kpad: 0,
            data: Vec::new(),
        };
        p.set(centers, k);
        p
    }

    /// Panel of the rows `idx` of the row-major `n × d` matrix `x`.
    pub fn from_rows(x: &[f64], d: usize, idx: &[usize]) -> Self {
        let k = idx.len();
        let kpad = k.div_ceil(PAD).max(1) * PAD;
        let mut data = vec![0.0; d * kpad];
        for (c, &i) in idx.iter().enumerate() {
            for j in 0..d {
                data[j * kpad + c] = x[i * d + j];
            }
        }
        Self { d, k, kpad, data }
    }

    /// Replace the centres (row-major `k × d`), reusing the buffer.
    pub fn set(&mut self, centers: &[f64], k: usize) {
        let d = self.d;
        assert_eq!(centers.len(), k * d, "centres must be k x d");
        self.k = k;
        self.kpad = k.div_ceil(PAD).max(1) * PAD;
        self.data.clear();
        self.data.resize(d * self.kpad, 0.0);
        for c in 0..k {
            for j in 0..d {
                self.data[j * self.kpad + c] = centers[c * d + j];
            }
        }
    }

    /// Number of centres.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Row length of the output of [`sq_dists`] (≥ k, a multiple of [`PAD`]).
    pub fn kpad(&self) -> usize {
        self.kpad
    }

    /// Dimension of the centres.
    pub fn dim(&self) -> usize {
        self.d
    }
}

/// `out[r * kpad + c] = ‖rows[r] - centre c‖²` for every row `r` and centre `c < k`
/// (columns `k..kpad` hold distances to the zero padding). Each row must have `d` values.
pub fn sq_dists(rows: &[&[f64]], panel: &Panel, out: &mut [f64]) {
    sq_dists_at(simd::active(), rows, panel, out)
}

/// [`sq_dists`] with an explicit instruction set (one this CPU runs; see [`simd::levels`]).
pub fn sq_dists_at(level: Level, rows: &[&[f64]], panel: &Panel, out: &mut [f64]) {
    let (d, kpad) = (panel.d, panel.kpad);
    assert!(out.len() >= rows.len() * kpad, "output buffer too small");
    assert!(
        rows.iter().all(|r| r.len() >= d),
        "row shorter than the panel dimension"
    );
    assert!(
        simd::cpu_runs(level),
        "instruction set {level:?} not available on this CPU"
    );
    match level {
        Level::Portable => scalar_dists(rows, panel, out),
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => {
            if kpad == PAD {
                // One register of 8 centres: 8 rows at a time keep 8 FMA chains in flight.
                blocked::<8>(rows, kpad, out, |ptrs, o| unsafe {
                    x86::tile512::<8, 1>(ptrs, d, panel.data.as_ptr(), kpad, 0, o)
                });
            } else {
                blocked::<4>(rows, kpad, out, |ptrs, o| unsafe {
                    let mut col = 0;
                    while col + 16 <= kpad {
                        x86::tile512::<4, 2>(ptrs, d, panel.data.as_ptr(), kpad, col, o);
                        col += 16;
                    }
                    if col < kpad {
                        x86::tile512::<4, 1>(ptrs, d, panel.data.as_ptr(), kpad, col, o);
                    }
                });
            }
        }
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => {
            blocked::<4>(rows, kpad, out, |ptrs, o| unsafe {
                let mut col = 0;
                while col < kpad {
                    x86::tile256::<4, 2>(ptrs, d, panel.data.as_ptr(), kpad, col, o);
                    col += 8;
                }
            });
        }
        #[cfg(not(target_arch = "x86_64"))]
        _ => scalar_dists(rows, panel, out),
    }
}

/// `‖a - b‖²` over the first `d` values, any summation order (used for bounds only).
pub fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    let d = a.len().min(b.len());
    #[cfg(target_arch = "x86_64")]
    if d >= 8 {
        match simd::active() {
            Level::Avx512 => return unsafe { x86::one512(a.as_ptr(), b.as_ptr(), d) },
            Level::Avx2Fma => return unsafe { x86::one256(a.as_ptr(), b.as_ptr(), d) },
            Level::Portable => {}
        }
    }
    let mut acc = [0.0f64; 4];
    let mut j = 0;
    while j + 4 <= d {
        for l in 0..4 {
            let t = a[j + l] - b[j + l];
            acc[l] += t * t;
        }
        j += 4;
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    while j < d {
        let t = a[j] - b[j];
        s += t * t;
        j += 1;
    }
    s
}

/// Index of the smallest value of `v` (the first one on ties), that value, and the smallest of
/// the other values (`+inf` when `v` has one value). `v` must not be empty; NaN is not
/// expected (distances of finite data).
pub fn two_nearest(v: &[f64]) -> (usize, f64, f64) {
    assert!(!v.is_empty());
    #[cfg(target_arch = "x86_64")]
    if v.len() >= 8 && simd::active() == Level::Avx512 {
        return unsafe { x86::two_nearest512(v) };
    }
    #[cfg(target_arch = "x86_64")]
    if v.len() >= 4 && simd::active() == Level::Avx2Fma {
        // SAFETY: AVX2 detected; `v.len() ≥ 4`.
        return unsafe { x86::two_nearest256(v) };
    }
    let (mut best, mut b, mut second) = (0, v[0], f64::INFINITY);
    for (j, &x) in v.iter().enumerate().skip(1) {
        if x < b {
            second = b;
            b = x;
            best = j;
        } else if x < second {
            second = x;
        }
    }
    (best, b, second)
}

/// Run `tile` on blocks of `P` row pointers; a short last block repeats its first row and
/// writes through a scratch buffer.
fn blocked<const P: usize>(
    rows: &[&[f64]],
    kpad: usize,
    out: &mut [f64],
    tile: impl Fn(&[*const f64; P], *mut f64),
) {
    let full = rows.len() / P;
    // Rows are often gathered from scattered places: prefetch a few blocks ahead.
    const AHEAD: usize = 4;
    for r in rows.iter().take(AHEAD * P) {
        prefetch_row(r);
    }
    for b in 0..full {
        for r in rows.iter().skip((b + AHEAD) * P).take(P) {
            prefetch_row(r);
        }
        let ptrs: [*const f64; P] = std::array::from_fn(|p| rows[b * P + p].as_ptr());
        tile(&ptrs, out[b * P * kpad..(b + 1) * P * kpad].as_mut_ptr());
    }
    let rest = rows.len() - full * P;
    if rest > 0 {
        let base = full * P;
        let ptrs: [*const f64; P] =
            std::array::from_fn(|p| rows[base + if p < rest { p } else { 0 }].as_ptr());
        let mut scratch = vec![0.0; P * kpad];
        tile(&ptrs, scratch.as_mut_ptr());
        out[base * kpad..(base + rest) * kpad].copy_from_slice(&scratch[..rest * kpad]);
    }
}

/// Hint the CPU to load a row into cache.
#[inline(always)]
pub fn prefetch_row(row: &[f64]) {
    prefetch_bytes(row.as_ptr().cast(), std::mem::size_of_val(row));
}

/// [`prefetch_row`] for a single-precision row.
#[inline(always)]
pub fn prefetch_row32(row: &[f32]) {
    prefetch_bytes(row.as_ptr().cast(), std::mem::size_of_val(row));
}

/// Prefetch the cache lines of `bytes` bytes from `p` (the memory of a slice).
#[inline(always)]
fn prefetch_bytes(p: *const i8, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let mut off = 0;
        while off < bytes {
            // SAFETY: prefetching is a hint and never faults; the address is inside the slice
            // the caller took `p` and `bytes` from.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off)) };
            off += 64;
        }
        // The last line, when the row is not 64-byte aligned.
        if bytes > 0 {
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(bytes - 1)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, bytes);
}

fn scalar_dists(rows: &[&[f64]], panel: &Panel, out: &mut [f64]) {
    let (d, kpad) = (panel.d, panel.kpad);
    for (r, row) in rows.iter().enumerate() {
        let o = &mut out[r * kpad..(r + 1) * kpad];
        o.fill(0.0);
        for (j, &xj) in row[..d].iter().enumerate() {
            let col = &panel.data[j * kpad..(j + 1) * kpad];
            for (acc, &c) in o.iter_mut().zip(col) {
                let t = xj - c;
                *acc = t.mul_add(t, *acc);
            }
        }
    }
}

/// Candidates in single precision for the k-means++ seeding: `data[j * kpad + c]` is
/// coordinate `j` of candidate `c`, zero-padded to a multiple of 8 columns.
#[derive(Clone, Debug)]
pub struct Panel32 {
    d: usize,
    k: usize,
    kpad: usize,
    data: Vec<f32>,
}

impl Panel32 {
    /// Panel of the rows `idx` of the row-major `n × d` f32 matrix `x`.
    pub fn from_rows(x: &[f32], d: usize, idx: &[usize]) -> Self {
        let k = idx.len();
        let kpad = k.div_ceil(PAD).max(1) * PAD;
        let mut data = vec![0.0; d * kpad];
        for (c, &i) in idx.iter().enumerate() {
            for j in 0..d {
                data[j * kpad + c] = x[i * d + j];
            }
        }
        Self { d, k, kpad, data }
    }

    /// Number of candidates.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Row length of the outputs (a multiple of 8).
    pub fn kpad(&self) -> usize {
        self.kpad
    }
}

/// Single-precision [`sq_dists`]: `out[r * kpad + c]` is the squared distance of row `r` to
/// candidate `c`, accumulated over `j = 0..d` in order with f32 fused multiply-adds and
/// widened to f64 (same bits with AVX2+FMA or portable code).
pub fn sq_dists32(rows: &[&[f32]], panel: &Panel32, out: &mut [f64]) {
    let (d, kpad) = (panel.d, panel.kpad);
    assert!(out.len() >= rows.len() * kpad);
    assert!(rows.iter().all(|r| r.len() >= d));
    #[cfg(target_arch = "x86_64")]
    if simd::active() != Level::Portable {
        for col in (0..kpad).step_by(8) {
            // SAFETY: AVX2 and FMA detected; rows hold d values; out holds rows × kpad.
            unsafe { x86::tile32(rows, d, panel.data.as_ptr().add(col), kpad, col, out) };
        }
        return;
    }
    for (r, row) in rows.iter().enumerate() {
        for c in 0..kpad {
            let mut acc = 0.0f32;
            for j in 0..d {
                let t = row[j] - panel.data[j * kpad + c];
                acc = t.mul_add(t, acc);
            }
            out[r * kpad + c] = acc as f64;
        }
    }
}

/// One k-means++ step on a block of rows against a panel of at most 8 candidates
/// (`kpad == 8`): `out[r * 8 + t]` is the squared distance of row `r` to candidate `t` (as
/// [`sq_dists32`]) and, for every candidate `t`, `pots[t] += min(out[r * 8 + t], closest[r])`
/// when `4·closest[r] > lim[t]` (the candidate may bring the row closer), else
/// `+= closest[r]`; rows are added in order in f64, so every instruction set gives the same
/// bits.
pub fn seed_block32(
    rows: &[&[f32]],
    closest: &[f64],
    panel: &Panel32,
    lim: &[f64; 8],
    out: &mut [f64],
    pots: &mut [f64; 8],
) {
    assert_eq!(
        panel.kpad, 8,
        "seed_block32 needs a panel of at most 8 candidates"
    );
    assert!(closest.len() == rows.len() && out.len() >= rows.len() * 8);
    assert!(rows.iter().all(|r| r.len() >= panel.d));
    #[cfg(target_arch = "x86_64")]
    if simd::active() != Level::Portable {
        // SAFETY: AVX2 and FMA detected; rows hold d values; out holds rows × 8.
        unsafe { x86::seed32(rows, closest, panel.d, panel.data.as_ptr(), lim, out, pots) };
        return;
    }
    sq_dists32(rows, panel, out);
    for (r, &di) in closest.iter().enumerate() {
        for t in 0..8 {
            let v = out[r * 8 + t];
            let m = if v < di { v } else { di };
            pots[t] += if 4.0 * di > lim[t] { m } else { di };
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// [`super::seed_block32`]: the [`tile32`] loop with the potential update fused in the
    /// epilogue (f64, lane-wise in row order like the portable code).
    ///
    /// # Safety
    /// AVX2 and FMA available; rows readable for `d` values; `panel` is `d × 8` f32; `out`
    /// holds `rows.len() × 8` values.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn seed32(
        rows: &[&[f32]],
        closest: &[f64],
        d: usize,
        panel: *const f32,
        lim: &[f64; 8],
        out: &mut [f64],
        pots: &mut [f64; 8],
    ) {
        const P: usize = 8;
        const AHEAD: usize = 4;
        let n = rows.len();
        let lim_lo = _mm256_loadu_pd(lim.as_ptr());
        let lim_hi = _mm256_loadu_pd(lim.as_ptr().add(4));
        let mut p_lo = _mm256_loadu_pd(pots.as_ptr());
        let mut p_hi = _mm256_loadu_pd(pots.as_ptr().add(4));
        let four = _mm256_set1_pd(4.0);
        for r in rows.iter().take(AHEAD * P) {
            super::prefetch_row32(r);
        }
        let mut b = 0;
        while b < n {
            for r in rows.iter().skip(b + AHEAD * P).take(P) {
                super::prefetch_row32(r);
            }
            let valid = (n - b).min(P);
            let ptrs: [*const f32; P] =
                std::array::from_fn(|p| rows[b + if p < valid { p } else { 0 }].as_ptr());
            let mut acc = [_mm256_setzero_ps(); P];
            for j in 0..d {
                let c = _mm256_loadu_ps(panel.add(j * 8));
                for p in 0..P {
                    let t = _mm256_sub_ps(_mm256_set1_ps(*ptrs[p].add(j)), c);
                    acc[p] = _mm256_fmadd_ps(t, t, acc[p]);
                }
            }
            for p in 0..valid {
                let lo = _mm256_cvtps_pd(_mm256_castps256_ps128(acc[p]));
                let hi = _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(acc[p]));
                let o = out.as_mut_ptr().add((b + p) * 8);
                _mm256_storeu_pd(o, lo);
                _mm256_storeu_pd(o.add(4), hi);
                let di = _mm256_set1_pd(closest[b + p]);
                let fd = _mm256_mul_pd(four, di);
                let u_lo = _mm256_cmp_pd::<_CMP_GT_OQ>(fd, lim_lo);
                let u_hi = _mm256_cmp_pd::<_CMP_GT_OQ>(fd, lim_hi);
                p_lo = _mm256_add_pd(p_lo, _mm256_blendv_pd(di, _mm256_min_pd(lo, di), u_lo));
                p_hi = _mm256_add_pd(p_hi, _mm256_blendv_pd(di, _mm256_min_pd(hi, di), u_hi));
            }
            b += P;
        }
        _mm256_storeu_pd(pots.as_mut_ptr(), p_lo);
        _mm256_storeu_pd(pots.as_mut_ptr().add(4), p_hi);
    }

    /// Single-precision tile: 8 rows × 8 candidates (one ymm), rows in blocks of 8 with
    /// prefetching; results widened to f64 into `out[r * kpad + col..+8]`.
    ///
    /// # Safety
    /// AVX2 and FMA available; rows readable for `d` values; `panel` points at column `col`
    /// of a `d × kpad` f32 panel; `out` holds `rows.len() × kpad` values.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn tile32(
        rows: &[&[f32]],
        d: usize,
        panel: *const f32,
        kpad: usize,
        col: usize,
        out: &mut [f64],
    ) {
        const P: usize = 8;
        const AHEAD: usize = 4;
        let n = rows.len();
        for r in rows.iter().take(AHEAD * P) {
            super::prefetch_row32(r);
        }
        let mut b = 0;
        while b < n {
            for r in rows.iter().skip(b + AHEAD * P).take(P) {
                super::prefetch_row32(r);
            }
            let valid = (n - b).min(P);
            let ptrs: [*const f32; P] =
                std::array::from_fn(|p| rows[b + if p < valid { p } else { 0 }].as_ptr());
            let mut acc = [_mm256_setzero_ps(); P];
            for j in 0..d {
                let c = _mm256_loadu_ps(panel.add(j * kpad));
                for p in 0..P {
                    let t = _mm256_sub_ps(_mm256_set1_ps(*ptrs[p].add(j)), c);
                    acc[p] = _mm256_fmadd_ps(t, t, acc[p]);
                }
            }
            for (p, a) in acc.iter().enumerate().take(valid) {
                let o = out.as_mut_ptr().add((b + p) * kpad + col);
                _mm256_storeu_pd(o, _mm256_cvtps_pd(_mm256_castps256_ps128(*a)));
                _mm256_storeu_pd(o.add(4), _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(*a)));
            }
            b += P;
        }
    }

    /// Register tile: `P` rows × `G` vectors of centres starting at column `col`.
    macro_rules! tile {
        ($name:ident, $feat:literal, $w:expr, $zero:ident, $set1:ident, $load:ident,
         $store:ident, $sub:ident, $fmadd:ident) => {
            /// # Safety
            /// CPU support for the feature; `rows[p]` readable for `d` values; panel and
            /// `out` readable/writable at the accessed offsets.
            #[target_feature(enable = $feat)]
            pub(super) unsafe fn $name<const P: usize, const G: usize>(
                rows: &[*const f64; P],
                d: usize,
                panel: *const f64,
                kpad: usize,
                col: usize,
                out: *mut f64,
            ) {
                let mut acc = [[$zero(); G]; P];
                for j in 0..d {
                    let cp = panel.add(j * kpad + col);
                    let mut c = [$zero(); G];
                    for g in 0..G {
                        c[g] = $load(cp.add(g * $w));
                    }
                    for p in 0..P {
                        let xv = $set1(*rows[p].add(j));
                        for g in 0..G {
                            let t = $sub(xv, c[g]);
                            acc[p][g] = $fmadd(t, t, acc[p][g]);
                        }
                    }
                }
                for p in 0..P {
                    for g in 0..G {
                        $store(out.add(p * kpad + col + g * $w), acc[p][g]);
                    }
                }
            }
        };
    }

    tile!(
        tile512,
        "avx512f",
        8,
        _mm512_setzero_pd,
        _mm512_set1_pd,
        _mm512_loadu_pd,
        _mm512_storeu_pd,
        _mm512_sub_pd,
        _mm512_fmadd_pd
    );
    tile!(
        tile256,
        "avx2,fma",
        4,
        _mm256_setzero_pd,
        _mm256_set1_pd,
        _mm256_loadu_pd,
        _mm256_storeu_pd,
        _mm256_sub_pd,
        _mm256_fmadd_pd
    );

    /// Lane-wise best/second/index over full vectors, then a cross-lane merge and a scalar
    /// tail; same result as the sequential scan.
    ///
    /// [`super::two_nearest`] with AVX2, branch-free: the minimum of all values, the first
    /// index holding it, then the minimum of the others (the sequential scan's result; its
    /// data-dependent branches mispredict on distances).
    ///
    /// # Safety
    /// AVX2 available; `v.len() ≥ 4`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn two_nearest256(v: &[f64]) -> (usize, f64, f64) {
        let len = v.len();
        let p = v.as_ptr();
        let inf = _mm256_set1_pd(f64::INFINITY);
        // Horizontal minimum of one register (a macro, so that it is compiled with AVX2).
        macro_rules! hmin {
            ($m:expr) => {{
                let m: __m256d = $m;
                let h = _mm_min_pd(_mm256_castpd256_pd128(m), _mm256_extractf128_pd(m, 1));
                _mm_cvtsd_f64(_mm_min_sd(h, _mm_unpackhi_pd(h, h)))
            }};
        }
        let body = len & !3;
        let mut m = _mm256_loadu_pd(p);
        let mut j = 4;
        while j < body {
            m = _mm256_min_pd(m, _mm256_loadu_pd(p.add(j)));
            j += 4;
        }
        let mut b = hmin!(m);
        for t in body..len {
            b = b.min(*p.add(t));
        }
        // First index holding the minimum.
        let bv = _mm256_set1_pd(b);
        let mut best = usize::MAX;
        let mut j = 0;
        while j < body {
            let hit =
                _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_loadu_pd(p.add(j)), bv));
            if hit != 0 {
                best = j + hit.trailing_zeros() as usize;
                break;
            }
            j += 4;
        }
        if best == usize::MAX {
            best = (body..len).find(|&t| *p.add(t) == b).unwrap_or(0);
        }
        // Smallest of the others.
        let lanes = _mm256_setr_epi64x(0, 1, 2, 3);
        let skip = _mm256_set1_epi64x(best as i64);
        let mut s = inf;
        let mut j = 0;
        while j < body {
            let idx = _mm256_add_epi64(lanes, _mm256_set1_epi64x(j as i64));
            let own = _mm256_castsi256_pd(_mm256_cmpeq_epi64(idx, skip));
            s = _mm256_min_pd(s, _mm256_blendv_pd(_mm256_loadu_pd(p.add(j)), inf, own));
            j += 4;
        }
        let mut second = hmin!(s);
        for t in body..len {
            if t != best {
                second = second.min(*p.add(t));
            }
        }
        (best, b, second)
    }

    /// # Safety
    /// AVX-512F available; `v.len() ≥ 8`.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn two_nearest512(v: &[f64]) -> (usize, f64, f64) {
        let len = v.len();
        let p = v.as_ptr();
        let inf = _mm512_set1_pd(f64::INFINITY);
        let mut best = _mm512_loadu_pd(p);
        let mut second = inf;
        let mut idx = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
        let step = _mm512_set1_epi64(8);
        let mut cur = idx;
        let mut j = 8;
        while j < len {
            cur = _mm512_add_epi64(cur, step);
            let x = if j + 8 <= len {
                _mm512_loadu_pd(p.add(j))
            } else {
                // Tail: missing lanes read as +inf.
                let m: __mmask8 = (1u8 << (len - j)) - 1;
                _mm512_mask_loadu_pd(inf, m, p.add(j))
            };
            let lt = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(x, best);
            second = _mm512_min_pd(second, _mm512_max_pd(x, best));
            best = _mm512_min_pd(best, x);
            idx = _mm512_mask_mov_epi64(idx, lt, cur);
            j += 8;
        }
        // Cross-lane: smallest value, lowest index among the lanes holding it; the second
        // value is the smallest of the lanes' seconds and of the other lanes' bests.
        let bmin = _mm512_reduce_min_pd(best);
        let at_min = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(best, _mm512_set1_pd(bmin));
        let imin = _mm512_reduce_min_epi64(_mm512_mask_mov_epi64(
            _mm512_set1_epi64(i64::MAX),
            at_min,
            idx,
        ));
        let lane = _mm512_cmpeq_epi64_mask(idx, _mm512_set1_epi64(imin)) & at_min;
        let others = _mm512_mask_mov_pd(best, lane, inf);
        let sec = _mm512_reduce_min_pd(_mm512_min_pd(second, others));
        (imin as usize, bmin, sec)
    }

    /// # Safety
    /// AVX-512F available; `a`, `b` readable for `d` values.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn one512(a: *const f64, b: *const f64, d: usize) -> f64 {
        let mut acc = _mm512_setzero_pd();
        let mut j = 0;
        while j + 8 <= d {
            let t = _mm512_sub_pd(_mm512_loadu_pd(a.add(j)), _mm512_loadu_pd(b.add(j)));
            acc = _mm512_fmadd_pd(t, t, acc);
            j += 8;
        }
        if j < d {
            let m: __mmask8 = (1u8 << (d - j)) - 1;
            let t = _mm512_sub_pd(
                _mm512_maskz_loadu_pd(m, a.add(j)),
                _mm512_maskz_loadu_pd(m, b.add(j)),
            );
            acc = _mm512_fmadd_pd(t, t, acc);
        }
        _mm512_reduce_add_pd(acc)
    }

    /// # Safety
    /// AVX2 and FMA available; `a`, `b` readable for `d` values.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn one256(a: *const f64, b: *const f64, d: usize) -> f64 {
        let mut acc0 = _mm256_setzero_pd();
        let mut acc1 = _mm256_setzero_pd();
        let mut j = 0;
        while j + 8 <= d {
            let t0 = _mm256_sub_pd(_mm256_loadu_pd(a.add(j)), _mm256_loadu_pd(b.add(j)));
            let t1 = _mm256_sub_pd(_mm256_loadu_pd(a.add(j + 4)), _mm256_loadu_pd(b.add(j + 4)));
            acc0 = _mm256_fmadd_pd(t0, t0, acc0);
            acc1 = _mm256_fmadd_pd(t1, t1, acc1);
            j += 8;
        }
        let mut buf = [0.0f64; 4];
        _mm256_storeu_pd(buf.as_mut_ptr(), _mm256_add_pd(acc0, acc1));
        let mut s = (buf[0] + buf[1]) + (buf[2] + buf[3]);
        while j < d {
            let t = *a.add(j) - *b.add(j);
            s += t * t;
            j += 1;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
            })
            .collect()
    }

    #[test]
    fn known_answer() {
        let centers = [0.0, 0.0, 3.0, 4.0];
        let panel = Panel::from_centers(&centers, 2, 2);
        let rows: Vec<&[f64]> = vec![&[0.0, 0.0], &[3.0, 0.0]];
        for level in simd::levels() {
            let mut out = vec![f64::NAN; 2 * panel.kpad()];
            sq_dists_at(level, &rows, &panel, &mut out);
            let k = panel.kpad();
            assert_eq!([out[0], out[1], out[k], out[k + 1]], [0.0, 25.0, 9.0, 16.0]);
        }
    }

    #[test]
    fn every_level_gives_the_same_bits_as_a_sequential_fma_chain() {
        for &(n, k, d) in &[
            (1usize, 1usize, 1usize),
            (7, 8, 3),
            (13, 17, 30),
            (9, 40, 5),
            (6, 5, 64),
        ] {
            let x = values(n * d, 1 + n as u64);
            let c = values(k * d, 99 + k as u64);
            let panel = Panel::from_centers(&c, k, d);
            let rows: Vec<&[f64]> = x.chunks_exact(d).collect();
            let kp = panel.kpad();
            for level in simd::levels() {
                let mut out = vec![f64::NAN; n * kp];
                sq_dists_at(level, &rows, &panel, &mut out);
                for i in 0..n {
                    for j in 0..k {
                        let mut acc = 0.0f64;
                        for t in 0..d {
                            let diff = x[i * d + t] - c[j * d + t];
                            acc = diff.mul_add(diff, acc);
                        }
                        assert_eq!(
                            out[i * kp + j].to_bits(),
                            acc.to_bits(),
                            "{level:?} {i} {j}"
                        );
                    }
                    let direct = sq_dist(&x[i * d..(i + 1) * d], &c[..d]);
                    assert!((direct - out[i * kp]).abs() <= 1e-12 * direct.max(1.0));
                }
            }
        }
    }

    #[test]
    fn two_nearest_matches_a_sequential_scan() {
        let reference = |v: &[f64]| {
            let mut best = 0;
            for j in 1..v.len() {
                if v[j] < v[best] {
                    best = j;
                }
            }
            let second = (0..v.len())
                .filter(|&j| j != best)
                .map(|j| v[j])
                .fold(f64::INFINITY, f64::min);
            (best, v[best], second)
        };
        for len in [1usize, 2, 3, 4, 5, 7, 8, 9, 16, 17, 30, 33, 176] {
            for seed in 0..20u64 {
                // Few distinct values: many ties, including ties for the minimum.
                let v: Vec<f64> = values(len, seed * 31 + len as u64)
                    .iter()
                    .map(|x| (x * 3.0).round())
                    .collect();
                assert_eq!(two_nearest(&v), reference(&v), "{v:?}");
                #[cfg(target_arch = "x86_64")]
                if len >= 4 && simd::levels().contains(&Level::Avx2Fma) {
                    // SAFETY: AVX2 detected, `len ≥ 4`.
                    let got = unsafe { x86::two_nearest256(&v) };
                    assert_eq!(got, reference(&v), "{v:?}");
                }
            }
        }
    }

    #[test]
    fn single_precision_kernels_match_their_definition() {
        let (n, d, k) = (29, 11, 13);
        let x: Vec<f32> = values(n * d, 8).iter().map(|&v| v as f32).collect();
        let idx: Vec<usize> = (0..k).map(|c| (c * 7) % n).collect();
        let panel = Panel32::from_rows(&x, d, &idx);
        let rows: Vec<&[f32]> = x.chunks_exact(d).collect();
        let kp = panel.kpad();
        let mut out = vec![f64::NAN; n * kp];
        sq_dists32(&rows, &panel, &mut out);
        for r in 0..n {
            for (c, &i) in idx.iter().enumerate() {
                let mut acc = 0.0f32;
                for j in 0..d {
                    let t = x[r * d + j] - x[i * d + j];
                    acc = t.mul_add(t, acc);
                }
                assert_eq!(out[r * kp + c].to_bits(), (acc as f64).to_bits());
            }
        }
        let p8 = Panel32::from_rows(&x, d, &idx[..5]);
        let closest: Vec<f64> = values(n, 9).iter().map(|v| v.abs() * 20.0).collect();
        let lim = [
            1.0,
            30.0,
            0.5,
            1e9,
            2.0,
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
        ];
        let mut out8 = vec![0.0; n * 8];
        let mut pots = [0.5; 8];
        seed_block32(&rows, &closest, &p8, &lim, &mut out8, &mut pots);
        let mut want = [0.5; 8];
        for r in 0..n {
            for t in 0..8 {
                let v = out8[r * 8 + t];
                let m = if v < closest[r] { v } else { closest[r] };
                want[t] += if 4.0 * closest[r] > lim[t] {
                    m
                } else {
                    closest[r]
                };
            }
        }
        assert_eq!(pots, want);
    }

    #[test]
    fn panel_from_rows_picks_rows() {
        let x = values(5 * 3, 4);
        let p = Panel::from_rows(&x, 3, &[4, 1]);
        assert_eq!(p.k(), 2);
        assert_eq!(p.kpad(), PAD);
        let rows: Vec<&[f64]> = vec![&x[12..15]];
        let mut out = vec![0.0; PAD];
        sq_dists(&rows, &p, &mut out);
        assert_eq!(out[0], 0.0);
        assert!(out[1] > 0.0);
    }
}

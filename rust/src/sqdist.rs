//! Squared Euclidean distances between rows and a small set of centres (k-means kernels).
//!
//! The centres are stored transposed in a [`Panel`] (`data[j * kpad + c]` is coordinate `j` of
//! centre `c`, columns padded with zeros to a multiple of [`PAD`]) so that one SIMD register
//! holds one coordinate of 4 or 8 centres. [`sq_dists`] computes, for every row `x`,
//! `Σ_j (x_j - c_j)²` for all centres with the *direct* formula (no `‖x‖² - 2x·c + ‖c‖²`
//! cancellation), accumulating over `j = 0..d` in order with fused multiply-adds. Every
//! instruction set (AVX-512F, AVX2+FMA, portable `f64::mul_add`) therefore returns the same
//! bits, and the choice is made at run time (the crate is built for baseline x86-64).

use std::sync::OnceLock;

/// Panel columns are padded to a multiple of this.
pub const PAD: usize = 8;

/// Instruction set used by the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Portable code (`f64::mul_add`).
    Scalar,
    /// AVX2 with FMA, 4 lanes.
    Avx2,
    /// AVX-512F, 8 lanes.
    Avx512,
}

/// The best level this CPU supports (detected once).
pub fn detected_level() -> Level {
    static LEVEL: OnceLock<Level> = OnceLock::new();
    *LEVEL.get_or_init(|| {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Level::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Level::Avx2;
            }
        }
        Level::Scalar
    })
}

/// Levels usable on this CPU (for tests comparing them).
pub fn available_levels() -> Vec<Level> {
    match detected_level() {
        Level::Scalar => vec![Level::Scalar],
        Level::Avx2 => vec![Level::Scalar, Level::Avx2],
        Level::Avx512 => vec![Level::Scalar, Level::Avx2, Level::Avx512],
    }
}

fn supported(level: Level) -> bool {
    matches!(
        (level, detected_level()),
        (Level::Scalar, _) | (_, Level::Avx512) | (Level::Avx2, Level::Avx2)
    )
}

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
    sq_dists_at(detected_level(), rows, panel, out)
}

/// [`sq_dists`] with an explicit instruction set (must be supported by this CPU; see
/// [`available_levels`]).
pub fn sq_dists_at(level: Level, rows: &[&[f64]], panel: &Panel, out: &mut [f64]) {
    let (d, kpad) = (panel.d, panel.kpad);
    assert!(out.len() >= rows.len() * kpad, "output buffer too small");
    assert!(
        rows.iter().all(|r| r.len() >= d),
        "row shorter than the panel dimension"
    );
    assert!(
        supported(level),
        "instruction set {level:?} not available on this CPU"
    );
    match level {
        Level::Scalar => scalar_dists(rows, panel, out),
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
        Level::Avx2 => {
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

/// One k-means++ step on a block of rows against a panel of at most 8 candidates
/// (`kpad == 8`): `out[r * 8 + t] = ‖rows[r] - t‖²` (as [`sq_dists`]) and, for every
/// candidate `t`, `pots[t] += min(out[r * 8 + t], closest[r])` when `4·closest[r] > lim[t]`
/// (the candidate may bring the row closer), else `+= closest[r]`; rows are added in order, so
/// every instruction set gives the same bits.
pub fn seed_block(
    rows: &[&[f64]],
    closest: &[f64],
    panel: &Panel,
    lim: &[f64; 8],
    out: &mut [f64],
    pots: &mut [f64; 8],
) {
    assert_eq!(
        panel.kpad, 8,
        "seed_block needs a panel of at most 8 candidates"
    );
    assert!(closest.len() == rows.len() && out.len() >= rows.len() * 8);
    assert!(rows.iter().all(|r| r.len() >= panel.d));
    #[cfg(target_arch = "x86_64")]
    if detected_level() == Level::Avx512 {
        // SAFETY: AVX-512F detected; rows hold d values; out holds rows.len() × 8.
        unsafe { x86::seed512(rows, closest, panel.d, panel.data.as_ptr(), lim, out, pots) };
        return;
    }
    sq_dists(rows, panel, out);
    for (r, &di) in closest.iter().enumerate() {
        for t in 0..8 {
            let v = out[r * 8 + t];
            let m = if v < di { v } else { di };
            pots[t] += if 4.0 * di > lim[t] { m } else { di };
        }
    }
}

/// `‖a - b‖²` over the first `d` values, any summation order (used for bounds only).
pub fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    let d = a.len().min(b.len());
    #[cfg(target_arch = "x86_64")]
    if d >= 8 {
        match detected_level() {
            Level::Avx512 => return unsafe { x86::one512(a.as_ptr(), b.as_ptr(), d) },
            Level::Avx2 => return unsafe { x86::one256(a.as_ptr(), b.as_ptr(), d) },
            Level::Scalar => {}
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
    if v.len() >= 8 && detected_level() == Level::Avx512 {
        return unsafe { x86::two_nearest512(v) };
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
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = row.as_ptr() as *const i8;
        let bytes = std::mem::size_of_val(row);
        let mut off = 0;
        while off < bytes {
            // SAFETY: prefetching is a hint and never faults; the address is inside `row`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.add(off)) };
            off += 64;
        }
        // The last line, when the row is not 64-byte aligned.
        if bytes > 0 {
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.add(bytes - 1)) };
        }
    }
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

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

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

    /// [`super::seed_block`] with AVX-512: 8 rows × 8 candidates per register tile, the
    /// potential update fused in the epilogue.
    ///
    /// # Safety
    /// AVX-512F available; every row readable for `d` values; `panel` is `d × 8`; `out` holds
    /// `rows.len() × 8` values.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn seed512(
        rows: &[&[f64]],
        closest: &[f64],
        d: usize,
        panel: *const f64,
        lim: &[f64; 8],
        out: &mut [f64],
        pots: &mut [f64; 8],
    ) {
        const P: usize = 8;
        const AHEAD: usize = 4;
        let limv = _mm512_loadu_pd(lim.as_ptr());
        let four = _mm512_set1_pd(4.0);
        let mut pacc = _mm512_loadu_pd(pots.as_ptr());
        for r in rows.iter().take(AHEAD * P) {
            super::prefetch_row(r);
        }
        let n = rows.len();
        let mut b = 0;
        while b < n {
            for r in rows.iter().skip(b + AHEAD * P).take(P) {
                super::prefetch_row(r);
            }
            let valid = (n - b).min(P);
            let ptrs: [*const f64; P] =
                std::array::from_fn(|p| rows[b + if p < valid { p } else { 0 }].as_ptr());
            let mut acc = [_mm512_setzero_pd(); P];
            for j in 0..d {
                let c = _mm512_loadu_pd(panel.add(j * 8));
                for p in 0..P {
                    let t = _mm512_sub_pd(_mm512_set1_pd(*ptrs[p].add(j)), c);
                    acc[p] = _mm512_fmadd_pd(t, t, acc[p]);
                }
            }
            for p in 0..valid {
                let di = _mm512_set1_pd(closest[b + p]);
                let m = _mm512_min_pd(acc[p], di);
                let useful = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(_mm512_mul_pd(four, di), limv);
                pacc = _mm512_add_pd(pacc, _mm512_mask_blend_pd(useful, di, m));
                _mm512_storeu_pd(out.as_mut_ptr().add((b + p) * 8), acc[p]);
            }
            b += P;
        }
        _mm512_storeu_pd(pots.as_mut_ptr(), pacc);
    }

    /// Lane-wise best/second/index over full vectors, then a cross-lane merge and a scalar
    /// tail; same result as the sequential scan.
    ///
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
        for level in available_levels() {
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
            for level in available_levels() {
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
        for len in [1usize, 2, 7, 8, 9, 16, 17, 33, 176] {
            for seed in 0..20u64 {
                // Few distinct values: many ties, including ties for the minimum.
                let v: Vec<f64> = values(len, seed * 31 + len as u64)
                    .iter()
                    .map(|x| (x * 3.0).round())
                    .collect();
                assert_eq!(two_nearest(&v), reference(&v), "{v:?}");
            }
        }
    }

    #[test]
    fn seed_block_matches_its_definition() {
        let d = 7;
        let x = values(37 * d, 5);
        let cands = values(6 * d, 6);
        let panel = Panel::from_centers(&cands, 6, d);
        let rows: Vec<&[f64]> = x.chunks_exact(d).collect();
        let closest: Vec<f64> = values(37, 7).iter().map(|v| v.abs() * 30.0).collect();
        let lim = [1.0, 50.0, 0.0, 1e9, 20.0, 3.0, f64::INFINITY, f64::INFINITY];
        let mut out = vec![0.0; 37 * 8];
        let mut pots = [1.0; 8];
        seed_block(&rows, &closest, &panel, &lim, &mut out, &mut pots);
        let mut want = vec![0.0; 37 * 8];
        sq_dists_at(Level::Scalar, &rows, &panel, &mut want);
        let mut want_pots = [1.0; 8];
        for r in 0..37 {
            for t in 0..8 {
                assert_eq!(out[r * 8 + t].to_bits(), want[r * 8 + t].to_bits());
                let v = want[r * 8 + t];
                want_pots[t] += if 4.0 * closest[r] > lim[t] {
                    v.min(closest[r])
                } else {
                    closest[r]
                };
            }
        }
        assert_eq!(pots, want_pots);
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

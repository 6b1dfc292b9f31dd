//! Lower triangle of the Gram matrix `Σ yᵀy` of a tall row-major block of shifted rows
//! `y = x - shift`, with the column sums `Σ y`: the inner product of the covariance.
//!
//! A register-blocked SIMD kernel for the tall-skinny product (`n ≫ d`): the shifted rows are
//! packed, `KC` rows at a time, twice: into panels of `mr` columns (`a[panel][row][mr]`) and of
//! `nr` columns (`b[panel][row][nr]`), zero beyond `d`. Each `mr × nr` tile of the lower
//! triangle of the (padded) result accumulates `Σ_row a ⊗ b` in vector registers, from `mr`
//! contiguous values and `nr` broadcasts per row. The packed blocks stay in L2 (the tile's two
//! panels in L1) and the result, stored tile after tile, is a sequential stream; the next
//! block's input rows are prefetched during the product. The packing is also where the shift
//! is subtracted, the column sums are formed and non-finite values are noticed (no separate
//! pass over the input).
//!
//! Two tiles, chosen by the SIMD level ([`crate::simd`]): 8 × 6 with AVX2 and FMA (12 of the 16
//! vector registers hold the tile), 16 × 12 where the CPU has AVX-512F (24 of its 32). Every
//! element of the result is the sum over the rows in row order (blocks in order, rows within a
//! block in order, each block's partial sum formed by fused multiply-adds from zero, then added
//! to the total), whatever the tile: the result depends on nothing but the input, and the two
//! kernels give the same bits. Only used at the AVX2+FMA level or above ([`available`]);
//! callers fall back to faer's triangular product elsewhere.

use crate::buffer;
use crate::simd::Level;
use crate::Result;

/// Rows per packed block: the two packings (`2 · KC · dp` values, 408–432 KiB for d = 400)
/// stay in L2.
const KC: usize = 64;

/// Whether the kernel runs at `level` (AVX2 and FMA, or AVX-512).
pub fn available(level: Level) -> bool {
    cfg!(target_arch = "x86_64") && level >= Level::Avx2Fma
}

/// One block's products added to one tile: `c[i + j · mr] += Σ_k a[mr · k + i] · b[nr · k + j]`
/// for `k < kc`.
type TileFn = unsafe fn(kc: usize, a: *const f64, b: *const f64, c: *mut f64);

/// A register tile (`mr × nr`), the panel width of the packing (a multiple of both) and the
/// function computing one tile.
#[derive(Clone, Copy)]
pub(crate) struct Kernel {
    mr: usize,
    nr: usize,
    pw: usize,
    tile: TileFn,
}

impl Kernel {
    /// The kernel of `level` (one this CPU runs): 16 × 12 with AVX-512F, 8 × 6 with AVX2
    /// and FMA.
    ///
    /// Panics if [`available`] is false at `level` or the CPU does not run `level`.
    pub(crate) fn at(level: Level) -> Self {
        assert!(
            available(level) && crate::simd::cpu_runs(level),
            "the Gram kernel needs AVX2 and FMA"
        );
        #[cfg(target_arch = "x86_64")]
        if level == Level::Avx512 {
            return Self::AVX512;
        }
        Self::AVX2
    }

    #[cfg(target_arch = "x86_64")]
    const AVX2: Self = Self {
        mr: 8,
        nr: 6,
        pw: 24,
        tile: x86::tile_8x6_avx2,
    };
    #[cfg(target_arch = "x86_64")]
    const AVX512: Self = Self {
        mr: 16,
        nr: 12,
        pw: 48,
        tile: x86::tile_16x12_avx512,
    };
    /// The AVX-512 tile's shape computed with AVX2 (4 vectors per column instead of 2): the
    /// packing and blocking of the wide tile, checked on any AVX2 machine.
    #[cfg(all(test, target_arch = "x86_64"))]
    const WIDE_AVX2: Self = Self {
        mr: 16,
        nr: 12,
        pw: 48,
        tile: x86::tile_16x12_avx2,
    };
    #[cfg(not(target_arch = "x86_64"))]
    const AVX2: Self = Self {
        mr: 0,
        nr: 0,
        pw: 0,
        tile: unreachable_tile,
    };

    /// Number of column tiles meeting the lower triangle in the row tile starting at `i0`:
    /// those starting before its last row.
    fn tiles_in_row(&self, i0: usize) -> usize {
        (i0 + self.mr).div_ceil(self.nr)
    }
}

#[cfg(not(target_arch = "x86_64"))]
unsafe fn unreachable_tile(_: usize, _: *const f64, _: *const f64, _: *mut f64) {
    unreachable!("the Gram kernel needs AVX2 and FMA")
}

/// A zeroed buffer of `len` values whose first element is 64-byte aligned, as
/// `(storage, offset of the aligned start)`.
fn aligned_zeroed(len: usize, what: &str) -> Result<(Vec<f64>, usize)> {
    let total = len
        .checked_add(8)
        .ok_or_else(|| crate::Error::Memory(format!("{what} is too large")))?;
    let v = buffer::try_zeroed_f64(total, what)?;
    let off = v.as_ptr().align_offset(64);
    debug_assert!(off < 8);
    Ok((v, off))
}

/// Writes the lower triangle of `Σ (x_r - shift)(x_r - shift)ᵀ` over the `n` rows of the
/// row-major `n × d` block `x` into `gram` (column-major `d × d`: element `(i, j)`, `i ≥ j`,
/// at `j * d + i`; the strict upper triangle is left as it was), and `Σ (x_r - shift)` into
/// `colsum`. Returns false if a sum is not finite (a NaN or infinite input, or an overflow):
/// the caller then locates the culprit.
///
/// Errors: the workspace cannot be allocated (Memory).
///
/// Panics if [`available`] is false at `level`, the CPU does not run `level`, or the lengths
/// do not match.
pub fn shifted_gram_lower(
    level: Level,
    x: &[f64],
    n: usize,
    d: usize,
    shift: &[f64],
    gram: &mut [f64],
    colsum: &mut [f64],
) -> Result<bool> {
    gram_lower_with(Kernel::at(level), x, n, d, shift, gram, colsum)
}

/// [`shifted_gram_lower`] with a given kernel.
fn gram_lower_with(
    kernel: Kernel,
    x: &[f64],
    n: usize,
    d: usize,
    shift: &[f64],
    gram: &mut [f64],
    colsum: &mut [f64],
) -> Result<bool> {
    assert!(d > 0 && Some(x.len()) == n.checked_mul(d) && Some(gram.len()) == d.checked_mul(d));
    assert!(shift.len() == d && colsum.len() == d);
    let Kernel { mr, nr, pw, .. } = kernel;
    // (`dp < d + pw`: `gram` of `d²` values exists, so `d` is far below `usize::MAX`.)
    let dp = d.div_ceil(pw) * pw;
    // The tiles meeting the lower triangle, each `mr × nr` column-major, one after the other
    // in the order `block_product` visits them (a sequential stream for the prefetcher).
    let tiles: usize = (0..dp / mr).map(|p| kernel.tiles_in_row(p * mr)).sum();
    let acc_len = buffer::elements::<f64>(&[tiles, mr * nr], "the Gram accumulator")?;
    let (mut acc_buf, acc_off) = aligned_zeroed(acc_len, "the Gram accumulator")?;
    let pack_len = buffer::elements::<f64>(&[2, KC, dp], "a packed block of rows")?;
    let (mut pack_buf, pack_off) = aligned_zeroed(pack_len, "a packed block of rows")?;
    let acc = &mut acc_buf[acc_off..acc_off + acc_len];
    let pack = &mut pack_buf[pack_off..pack_off + pack_len];
    let mut y = buffer::try_zeroed_f64(KC.min(n) * d, "a block of shifted rows")?;
    colsum.fill(0.0);
    for (b, rows) in x.chunks(KC * d).enumerate() {
        let kc = rows.len() / d;
        // The rows of the next block (empty after the last one).
        let rest = &x[((b + 1) * KC * d).min(x.len())..];
        let next = &rest[..rest.len().min(KC * d)];
        pack_rows(&kernel, rows, kc, d, shift, &mut y, pack, colsum);
        // SAFETY: the kernel's instruction set was detected; `pack` holds `2 · KC · dp`
        // values and `acc` every tile (checked inside).
        unsafe { block_product(&kernel, pack, kc, dp, acc, next) };
    }
    let mut t = 0;
    for p in 0..dp / mr {
        let i0 = p * mr;
        for q in 0..kernel.tiles_in_row(i0) {
            let tile = &acc[t * mr * nr..(t + 1) * mr * nr];
            for (jj, col) in tile.chunks_exact(mr).enumerate() {
                let j = q * nr + jj;
                if j >= d {
                    break;
                }
                for (ii, &v) in col.iter().enumerate() {
                    let i = i0 + ii;
                    if i >= j && i < d {
                        gram[j * d + i] = v;
                    }
                }
            }
            t += 1;
        }
    }
    Ok(colsum.iter().all(|c| c.is_finite()) && acc.iter().all(|c| c.is_finite()))
}

/// Packs `kc` rows of `x` minus `shift` into the `mr`-column panels (first `KC · dp` values of
/// `pack`) and the `nr`-column panels (the next `KC · dp`), and adds them to `colsum`; `y` is
/// scratch for `KC · d` values. The rows are first shifted into `y` (contiguous reads and
/// writes), then each panel is written contiguously from `y` (in L2).
#[allow(clippy::too_many_arguments)]
fn pack_rows(
    kernel: &Kernel,
    rows: &[f64],
    kc: usize,
    d: usize,
    shift: &[f64],
    y: &mut [f64],
    pack: &mut [f64],
    colsum: &mut [f64],
) {
    let y = &mut y[..kc * d];
    for (yrow, xrow) in y.chunks_exact_mut(d).zip(rows.chunks_exact(d)) {
        for ((yv, &xv), (&s, c)) in yrow
            .iter_mut()
            .zip(xrow)
            .zip(shift.iter().zip(colsum.iter_mut()))
        {
            *yv = xv - s;
            *c += *yv;
        }
    }
    let (a, b) = pack.split_at_mut(pack.len() / 2);
    panels(y, kc, d, kernel.mr, a);
    panels(y, kc, d, kernel.nr, b);
}

/// Copies the `kc` rows of the row-major `kc × d` matrix `y` into panels of `w` columns:
/// column `c` of row `r` to `dst[((c / w) · KC + r) · w + c % w]` (entries beyond `d` are left
/// as they are: zero). The widths of the tiles are compiled as constants (fixed-size copies).
fn panels(y: &[f64], kc: usize, d: usize, w: usize, dst: &mut [f64]) {
    match w {
        6 => panels_of::<6>(y, kc, d, dst),
        8 => panels_of::<8>(y, kc, d, dst),
        12 => panels_of::<12>(y, kc, d, dst),
        16 => panels_of::<16>(y, kc, d, dst),
        _ => unreachable!("no tile is {w} wide"),
    }
}

fn panels_of<const W: usize>(y: &[f64], kc: usize, d: usize, dst: &mut [f64]) {
    for p in 0..d.div_ceil(W) {
        let c0 = p * W;
        let width = W.min(d - c0);
        let panel = &mut dst[p * KC * W..(p * KC + kc) * W];
        for (r, out) in panel.chunks_exact_mut(W).enumerate() {
            let src = &y[r * d + c0..r * d + c0 + width];
            if width == W {
                out.copy_from_slice(src);
            } else {
                out[..width].copy_from_slice(src);
            }
        }
    }
}

/// Adds the products of one packed block (`kc` rows) to every tile of the padded `dp × dp`
/// result that meets the lower triangle; `acc` holds these tiles one after the other (see
/// `gram_lower_with`). Meanwhile the input rows `next` (of the next block) are prefetched.
///
/// SAFETY (caller): the CPU runs `kernel`.
unsafe fn block_product(
    kernel: &Kernel,
    pack: &[f64],
    kc: usize,
    dp: usize,
    acc: &mut [f64],
    next: &[f64],
) {
    let Kernel { mr, nr, tile, .. } = *kernel;
    assert!(pack.len() >= 2 * KC * dp && kc <= KC);
    let (a, b) = pack.split_at(KC * dp);
    // Cache lines of the next block of rows, requested a share per row tile so that they
    // arrive (from memory) while this block is multiplied.
    let lines = next.len().div_ceil(8);
    let per_tile = lines.div_ceil(dp / mr);
    let mut t = 0;
    for p in 0..dp / mr {
        for l in p * per_tile..((p + 1) * per_tile).min(lines) {
            prefetch(&next[l * 8]);
        }
        let count = kernel.tiles_in_row(p * mr);
        assert!((t + count) * mr * nr <= acc.len() && count * nr <= dp);
        for q in 0..count {
            // SAFETY: the tile reads `kc ≤ KC` rows of panel `p` of `a` and panel `q` of `b`
            // (`q · nr < dp`) and updates tile `t + q` of `acc` (checked above); the caller
            // guarantees the instruction set.
            unsafe {
                tile(
                    kc,
                    a.as_ptr().add(p * KC * mr),
                    b.as_ptr().add(q * KC * nr),
                    acc.as_mut_ptr().add((t + q) * mr * nr),
                )
            };
        }
        t += count;
    }
}

/// Asks for the cache line holding `v` (no effect on the program's meaning).
#[inline(always)]
fn prefetch(v: &f64) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86_64; a prefetch does not access memory architecturally.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
            (v as *const f64).cast(),
        )
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// A tile kernel of `$mv` vectors of `$w` lanes per column (`mr = $w · $mv` rows) and `$nr`
    /// columns: `$mv · $nr` accumulators, `$mv` loads and `$nr` broadcasts per packed row.
    macro_rules! tile {
        ($name:ident, $feat:literal, $v:ty, $w:literal, $mv:literal, $nr:literal,
         $zero:ident, $set1:ident, $load:ident, $store:ident, $add:ident, $fma:ident) => {
            /// SAFETY (caller): the CPU has the instruction set; `a` covers `kc` packed rows of
            #[doc = concat!(stringify!($w), " × ", stringify!($mv), " values, `b` of ", stringify!($nr), ", `c` one tile.")]
            #[target_feature(enable = $feat)]
            pub(super) unsafe fn $name(kc: usize, a: *const f64, b: *const f64, c: *mut f64) {
                const MR: usize = $w * $mv;
                let z = $zero();
                let mut acc: [[$v; $mv]; $nr] = [[z; $mv]; $nr];
                // SAFETY: every offset is inside the ranges guaranteed by the caller.
                unsafe {
                    for k in 0..kc {
                        let ak = a.add(k * MR);
                        let bk = b.add(k * $nr);
                        let mut av = [z; $mv];
                        for (v, slot) in av.iter_mut().enumerate() {
                            *slot = $load(ak.add(v * $w));
                        }
                        for (j, col) in acc.iter_mut().enumerate() {
                            let bj = $set1(*bk.add(j));
                            for (r, &x) in col.iter_mut().zip(&av) {
                                *r = $fma(x, bj, *r);
                            }
                        }
                    }
                    for (j, col) in acc.iter().enumerate() {
                        for (v, &r) in col.iter().enumerate() {
                            let p = c.add(j * MR + v * $w);
                            $store(p, $add($load(p), r));
                        }
                    }
                }
            }
        };
    }

    tile!(
        tile_8x6_avx2,
        "avx2,fma",
        __m256d,
        4,
        2,
        6,
        _mm256_setzero_pd,
        _mm256_set1_pd,
        _mm256_loadu_pd,
        _mm256_storeu_pd,
        _mm256_add_pd,
        _mm256_fmadd_pd
    );
    tile!(
        tile_16x12_avx512,
        "avx512f",
        __m512d,
        8,
        2,
        12,
        _mm512_setzero_pd,
        _mm512_set1_pd,
        _mm512_loadu_pd,
        _mm512_storeu_pd,
        _mm512_add_pd,
        _mm512_fmadd_pd
    );
    #[cfg(test)]
    tile!(
        tile_16x12_avx2,
        "avx2,fma",
        __m256d,
        4,
        4,
        12,
        _mm256_setzero_pd,
        _mm256_set1_pd,
        _mm256_loadu_pd,
        _mm256_storeu_pd,
        _mm256_add_pd,
        _mm256_fmadd_pd
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    /// The kernels this CPU runs, the wide tile computed with AVX2 included.
    fn kernels() -> Vec<(&'static str, Kernel)> {
        #[cfg(target_arch = "x86_64")]
        if available(crate::simd::active()) {
            let mut all = vec![
                ("8x6 avx2", Kernel::AVX2),
                ("16x12 avx2", Kernel::WIDE_AVX2),
            ];
            if crate::simd::active() == Level::Avx512 {
                all.push(("16x12 avx512", Kernel::AVX512));
            }
            return all;
        }
        Vec::new()
    }

    #[test]
    fn matches_the_plain_sums_for_awkward_sizes() {
        // d below, at and above a panel of either kernel; n below, at and above a packed block.
        let sizes = [
            (1usize, 1usize),
            (5, 11),
            (130, 12),
            (257, 13),
            (300, 37),
            (70, 49),
        ];
        for (name, kernel) in kernels() {
            for &(n, d) in &sizes {
                let x = values(n * d, (n * 7 + d) as u64);
                let shift: Vec<f64> = (0..d).map(|j| 0.01 * j as f64).collect();
                let mut gram = vec![-1.0; d * d];
                let mut colsum = vec![0.0; d];
                let ok = gram_lower_with(kernel, &x, n, d, &shift, &mut gram, &mut colsum);
                assert!(ok.unwrap(), "{name}");
                for j in 0..d {
                    let want: f64 = (0..n).map(|r| x[r * d + j] - shift[j]).sum();
                    assert!((colsum[j] - want).abs() < 1e-12 * n as f64);
                    for i in 0..d {
                        let got = gram[j * d + i];
                        if i < j {
                            assert_eq!(got, -1.0, "{name}: upper triangle untouched");
                            continue;
                        }
                        let want: f64 = (0..n)
                            .map(|r| (x[r * d + i] - shift[i]) * (x[r * d + j] - shift[j]))
                            .sum();
                        assert!((got - want).abs() < 1e-12 * n as f64, "{name} ({i}, {j})");
                    }
                }
            }
        }
    }

    #[test]
    fn every_tile_gives_the_same_bits() {
        let (n, d) = (1000usize, 101usize);
        let x = values(n * d, 11);
        let shift = vec![0.1; d];
        let mut first: Option<Vec<f64>> = None;
        for (name, kernel) in kernels() {
            let mut gram = vec![0.0; d * d];
            let mut colsum = vec![0.0; d];
            assert!(gram_lower_with(kernel, &x, n, d, &shift, &mut gram, &mut colsum).unwrap());
            match &first {
                None => first = Some(gram),
                Some(want) => assert!(want == &gram, "{name} differs from the 8x6 tile"),
            }
        }
    }

    #[test]
    fn non_finite_input_is_reported() {
        let (n, d) = (200, 14);
        for (name, kernel) in kernels() {
            for bad in [f64::NAN, f64::INFINITY] {
                let mut x = values(n * d, 3);
                x[150 * d + 13] = bad;
                let mut gram = vec![0.0; d * d];
                let mut colsum = vec![0.0; d];
                let shift = vec![0.0; d];
                let ok = gram_lower_with(kernel, &x, n, d, &shift, &mut gram, &mut colsum);
                assert!(!ok.unwrap(), "{name}");
            }
        }
    }
}

//! Lower triangle of the Gram matrix `Σ yᵀy` of a tall row-major block of shifted rows
//! `y = x - shift`, with the column sums `Σ y`: the inner product of the covariance.
//!
//! A register-blocked AVX2+FMA kernel for the tall-skinny product (`n ≫ d`): the shifted rows
//! are packed, `KC` rows at a time, twice: into panels of 8 columns (`a[panel][row][8]`) and of
//! 6 columns (`b[panel][row][6]`), zero beyond `d`. Each 8 × 6 tile of the lower triangle of
//! the (padded) result accumulates `Σ_row a ⊗ b` in 12 vector registers, from 2 vector loads
//! and 6 broadcasts per row, both read contiguously. The packed blocks stay in L2 (the tile's
//! two panels in L1) and the result, stored tile after tile, is a sequential stream; the next
//! block's input rows are prefetched during the product. The packing is also where the shift
//! is subtracted, the column sums are formed and non-finite values are noticed (no separate
//! pass over the input).
//!
//! Each element of the result is the sum over the rows in row order (blocks in order, then
//! rows within a block), so the result does not depend on anything but the input. Only used
//! where the CPU has AVX2 and FMA ([`available`]); callers fall back to faer's triangular
//! product elsewhere.

use crate::buffer;
use crate::Result;

/// Rows per packed block: the two packings (`2 · KC · d` values, ≈ 400 KiB for d = 400)
/// stay in L2.
const KC: usize = 64;
/// Panel width (columns per packed panel), tile rows (2 vectors of 4) and tile columns
/// (6 broadcasts); the panel width is a multiple of both.
const PW: usize = 24;
const MR: usize = 8;
const NR: usize = 6;

/// Whether this CPU runs the kernel (AVX2 and FMA).
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// A zeroed buffer of `len` values whose first element is 32-byte aligned, as
/// `(storage, offset of the aligned start)`.
fn aligned_zeroed(len: usize, what: &str) -> Result<(Vec<f64>, usize)> {
    let total = len
        .checked_add(4)
        .ok_or_else(|| crate::Error::Memory(format!("{what} is too large")))?;
    let v = buffer::try_zeroed_f64(total, what)?;
    let off = v.as_ptr().align_offset(32);
    debug_assert!(off < 4);
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
/// Panics if [`available`] is false or the lengths do not match.
pub fn shifted_gram_lower(
    x: &[f64],
    n: usize,
    d: usize,
    shift: &[f64],
    gram: &mut [f64],
    colsum: &mut [f64],
) -> Result<bool> {
    assert!(available(), "the Gram kernel needs AVX2 and FMA");
    assert!(d > 0 && Some(x.len()) == n.checked_mul(d) && Some(gram.len()) == d.checked_mul(d));
    assert!(shift.len() == d && colsum.len() == d);
    let panels = d.div_ceil(PW);
    // (`dp ≤ d + 23`: `gram` of `d²` values exists, so `d` is far below `usize::MAX`.)
    let dp = panels * PW;
    // The tiles meeting the lower triangle, each 8 × 6 column-major, one after the other in
    // the order `block_product` visits them (a sequential stream for the prefetcher).
    let tiles: usize = (0..dp / MR).map(|p| tiles_in_row(p * MR)).sum();
    let acc_len = buffer::elements::<f64>(&[tiles, MR * NR], "the Gram accumulator")?;
    let (mut acc_buf, acc_off) = aligned_zeroed(acc_len, "the Gram accumulator")?;
    let pack_len = buffer::elements::<f64>(&[2, KC, dp], "a packed block of rows")?;
    let (mut pack_buf, pack_off) = aligned_zeroed(pack_len, "a packed block of rows")?;
    let acc = &mut acc_buf[acc_off..acc_off + acc_len];
    let pack = &mut pack_buf[pack_off..pack_off + pack_len];
    let mut y = buffer::try_zeroed_f64(KC.min(n) * d, "a block of shifted rows")?;
    colsum.fill(0.0);
    #[cfg(target_arch = "x86_64")]
    for (b, rows) in x.chunks(KC * d).enumerate() {
        let kc = rows.len() / d;
        // The rows of the next block (empty after the last one).
        let rest = &x[((b + 1) * KC * d).min(x.len())..];
        let next = &rest[..rest.len().min(KC * d)];
        // SAFETY: AVX2 and FMA checked above; the buffers have the lengths the kernels need
        // (`pack`: `2 · KC · dp`, `acc`: every tile, both 32-byte aligned).
        unsafe {
            pack_rows(rows, kc, d, shift, &mut y, pack, colsum);
            block_product(pack, kc, panels, acc, next);
        }
    }
    let mut t = 0;
    for p in 0..dp / MR {
        let i0 = p * MR;
        for q in 0..tiles_in_row(i0) {
            let tile = &acc[t * MR * NR..(t + 1) * MR * NR];
            for (jj, col) in tile.chunks_exact(MR).enumerate() {
                let j = q * NR + jj;
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

/// Number of column tiles (of 6) meeting the lower triangle in the row tile starting at `i0`:
/// those starting before its last row.
fn tiles_in_row(i0: usize) -> usize {
    (i0 + MR).div_ceil(NR)
}

/// Packs `kc` rows of `x` minus `shift` into the 8-column panels (first `KC · dp` values of
/// `pack`) and the 6-column panels (the next `KC · dp`), and adds them to `colsum`; `y` is
/// scratch for `KC · d` values. The rows are first shifted into `y` (contiguous reads and
/// writes), then each panel is written contiguously from `y` (in L2).
///
/// SAFETY (caller): the CPU has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn pack_rows(
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
    panels::<MR>(y, kc, d, a);
    panels::<NR>(y, kc, d, b);
}

/// Copies the `kc` rows of the row-major `kc × d` matrix `y` into panels of `W` columns:
/// column `c` of row `r` to `dst[((c / W) · KC + r) · W + c % W]` (entries beyond `d` are left
/// as they are: zero).
#[inline(always)]
fn panels<const W: usize>(y: &[f64], kc: usize, d: usize, dst: &mut [f64]) {
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

/// Adds the products of one packed block (`kc` rows) to every 8 × 6 tile of the padded
/// `dp × dp` result (`dp = 24 · panels`) that meets the lower triangle; `acc` holds these
/// tiles one after the other (see `shifted_gram_lower`). Meanwhile the input rows `next` (of
/// the next block) are prefetched.
///
/// SAFETY (caller): the CPU has AVX2 and FMA; `pack` holds `2 · KC · dp` values and `acc`
/// every tile.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn block_product(pack: &[f64], kc: usize, panels: usize, acc: &mut [f64], next: &[f64]) {
    use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
    let dp = panels * PW;
    assert!(pack.len() >= 2 * KC * dp && kc <= KC);
    let (a, b) = pack.split_at(KC * dp);
    // Cache lines of the next block of rows, requested a share per row tile so that they
    // arrive (from memory) while this block is multiplied.
    let lines = next.len().div_ceil(8);
    let per_tile = lines.div_ceil(dp / MR);
    let mut t = 0;
    for p in 0..dp / MR {
        for l in p * per_tile..((p + 1) * per_tile).min(lines) {
            // SAFETY: `l * 8 < next.len()`; a prefetch does not change the program's meaning.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(next.as_ptr().add(l * 8).cast()) };
        }
        let count = tiles_in_row(p * MR);
        assert!((t + count) * MR * NR <= acc.len());
        for q in 0..count {
            // SAFETY: the tile reads `kc ≤ KC` rows of panel `p` of `a` and panel `q` of `b`
            // (`q < dp / 6`) and updates tile `t` of `acc` (checked above).
            unsafe {
                tile(
                    kc,
                    a.as_ptr().add(p * KC * MR),
                    b.as_ptr().add(q * KC * NR),
                    acc.as_mut_ptr().add((t + q) * MR * NR),
                    MR,
                )
            };
        }
        t += count;
    }
}

/// `c[i + j * ldc] += Σ_k a[8k + i] · b[6k + j]` for `i < 8`, `j < 6`, `k < kc`.
///
/// SAFETY (caller): AVX2 and FMA; the pointers cover these ranges.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn tile(kc: usize, a: *const f64, b: *const f64, c: *mut f64, ldc: usize) {
    use std::arch::x86_64::*;
    let z = _mm256_setzero_pd();
    let mut lo = [z; NR];
    let mut hi = [z; NR];
    // SAFETY: every offset is inside the ranges guaranteed by the caller.
    unsafe {
        for k in 0..kc {
            let ak = a.add(k * MR);
            let bk = b.add(k * NR);
            let a0 = _mm256_loadu_pd(ak);
            let a1 = _mm256_loadu_pd(ak.add(4));
            for j in 0..NR {
                let bj = _mm256_broadcast_sd(&*bk.add(j));
                lo[j] = _mm256_fmadd_pd(a0, bj, lo[j]);
                hi[j] = _mm256_fmadd_pd(a1, bj, hi[j]);
            }
        }
        for j in 0..NR {
            let p = c.add(j * ldc);
            _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), lo[j]));
            let p = p.add(4);
            _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), hi[j]));
        }
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
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    #[test]
    fn matches_the_plain_sums_for_awkward_sizes() {
        if !available() {
            return;
        }
        // d below, at and above a panel; n below, at and above a packed block.
        for &(n, d) in &[(1usize, 1usize), (5, 11), (130, 12), (257, 13), (300, 37)] {
            let x = values(n * d, (n * 7 + d) as u64);
            let shift: Vec<f64> = (0..d).map(|j| 0.01 * j as f64).collect();
            let mut gram = vec![-1.0; d * d];
            let mut colsum = vec![0.0; d];
            assert!(shifted_gram_lower(&x, n, d, &shift, &mut gram, &mut colsum).unwrap());
            for j in 0..d {
                let want: f64 = (0..n).map(|r| x[r * d + j] - shift[j]).sum();
                assert!((colsum[j] - want).abs() < 1e-12 * n as f64);
                for i in 0..d {
                    let got = gram[j * d + i];
                    if i < j {
                        assert_eq!(got, -1.0, "upper triangle untouched");
                        continue;
                    }
                    let want: f64 = (0..n)
                        .map(|r| (x[r * d + i] - shift[i]) * (x[r * d + j] - shift[j]))
                        .sum();
                    assert!((got - want).abs() < 1e-12 * n as f64, "({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn non_finite_input_is_reported() {
        if !available() {
            return;
        }
        let (n, d) = (200, 14);
        for bad in [f64::NAN, f64::INFINITY] {
            let mut x = values(n * d, 3);
            x[150 * d + 13] = bad;
            let mut gram = vec![0.0; d * d];
            let mut colsum = vec![0.0; d];
            let ok = shifted_gram_lower(&x, n, d, &vec![0.0; d], &mut gram, &mut colsum).unwrap();
            assert!(!ok);
        }
    }
}

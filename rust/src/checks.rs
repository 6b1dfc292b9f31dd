//! Input checks shared by the kernels.

use rayon::prelude::*;

/// Values per parallel chunk of [`first_non_finite`].
const CHUNK: usize = 1 << 15;

/// Index of the first NaN or infinity in `x`, if any. Scans in parallel, without branches in
/// the hot loop, so checking a large corpus costs a small fraction of filtering it.
pub fn first_non_finite(x: &[f64]) -> Option<usize> {
    let bad = |c: &[f64]| c.iter().fold(false, |acc, v| acc | !v.is_finite());
    let any = if x.len() > CHUNK {
        x.par_chunks(CHUNK).any(bad)
    } else {
        bad(x)
    };
    if any {
        x.iter().position(|v| !v.is_finite())
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_first_bad_value() {
        let mut x = vec![1.0; 3 * CHUNK + 5];
        assert_eq!(first_non_finite(&x), None);
        x[2 * CHUNK + 3] = f64::NEG_INFINITY;
        x[3 * CHUNK] = f64::NAN;
        assert_eq!(first_non_finite(&x), Some(2 * CHUNK + 3));
        assert_eq!(first_non_finite(&[0.0, f64::NAN]), Some(1));
        assert_eq!(first_non_finite(&[]), None);
    }
}

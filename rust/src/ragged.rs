//! Ragged corpora: many trials of different lengths concatenated along time.
//!
//! A corpus is one `(total_frames, channels)` array plus `offsets`, the first frame of each
//! trial: trial `i` spans frames `offsets[i]..offsets[i + 1]`, the last one runs to
//! `total_frames`.

use crate::{Error, Result};

/// Checks `offsets` against a corpus of `total` frames and returns each trial's frame range
/// `(start, end)` (end exclusive).
///
/// Requirements: at least one offset, `offsets[0] == 0`, strictly increasing, every offset
/// `< total` (so that no trial is empty).
pub fn trial_bounds(offsets: &[i64], total: usize) -> Result<Vec<(usize, usize)>> {
    if offsets.is_empty() {
        return Err(Error::Shape(
            "offsets is empty: give the first frame of each trial (offsets[0] = 0)".into(),
        ));
    }
    if offsets[0] != 0 {
        return Err(Error::InvalidArgument(format!(
            "offsets[0] must be 0 (the first trial starts at frame 0), got {}",
            offsets[0]
        )));
    }
    for (i, w) in offsets.windows(2).enumerate() {
        if w[1] <= w[0] {
            return Err(Error::InvalidArgument(format!(
                "offsets must be strictly increasing: offsets[{}] = {} follows offsets[{i}] = {}",
                i + 1,
                w[1],
                w[0]
            )));
        }
    }
    let last = *offsets.last().unwrap();
    if last >= total as i64 {
        return Err(Error::InvalidArgument(format!(
            "offsets[{}] = {last} is out of range: every offset must be < the number of \
             frames ({total})",
            offsets.len() - 1
        )));
    }
    let mut bounds: Vec<(usize, usize)> = offsets
        .windows(2)
        .map(|w| (w[0] as usize, w[1] as usize))
        .collect();
    bounds.push((last as usize, total));
    Ok(bounds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_of_a_valid_corpus() {
        assert_eq!(
            trial_bounds(&[0, 3, 10], 12).unwrap(),
            vec![(0, 3), (3, 10), (10, 12)]
        );
        assert_eq!(trial_bounds(&[0], 5).unwrap(), vec![(0, 5)]);
    }

    #[test]
    fn invalid_offsets_are_refused() {
        assert!(matches!(trial_bounds(&[], 5), Err(Error::Shape(_))));
        assert!(matches!(
            trial_bounds(&[1, 3], 5),
            Err(Error::InvalidArgument(_))
        ));
        let err = trial_bounds(&[0, 3, 3], 5).unwrap_err().to_string();
        assert!(err.contains("strictly increasing") && err.contains("offsets[2] = 3"));
        assert!(matches!(
            trial_bounds(&[0, 5], 5),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            trial_bounds(&[0, -1], 5),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            trial_bounds(&[0], 0),
            Err(Error::InvalidArgument(_))
        ));
    }
}

//! Pairing the poses of a reference and an estimate by time stamp, as `evo`'s
//! `associate_trajectories` (nearest-time method) does.

use super::EvalError;
use crate::trajectory::Trajectory;

/// How poses are paired in time (`evo`'s `--t_max_diff` and `--t_offset`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AssociationOptions {
    /// Largest allowed `|t_ref − (t_est + t_offset)|` of a pair (ns). Default 10 ms, as
    /// `evo`'s 0.01 s.
    pub max_diff_ns: u64,
    /// Offset added to the estimate's stamps before pairing (ns). Default 0.
    pub t_offset_ns: i64,
}

impl Default for AssociationOptions {
    fn default() -> Self {
        Self {
            max_diff_ns: 10_000_000,
            t_offset_ns: 0,
        }
    }
}

/// The paired poses: `reference.samples[k]` and `estimate.samples[k]` belong together.
/// Both keep their own stamps (the offset is only used for pairing).
#[derive(Debug, Clone, PartialEq)]
pub struct Matched {
    /// Reference poses of the pairs.
    pub reference: Trajectory,
    /// Estimated poses of the pairs.
    pub estimate: Trajectory,
}

impl Matched {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.reference.len()
    }

    /// Whether there is no pair.
    pub fn is_empty(&self) -> bool {
        self.reference.is_empty()
    }
}

/// Pairs the poses of `reference` and `estimate` by time stamp, exactly as `evo`
/// (1.38, `SyncMethod.nearest_time`) does:
///
/// - The trajectory with fewer poses is the *short* one (the estimate when both are
///   equally long); each of its poses, in order, is paired with the pose of the *long*
///   one whose stamp is nearest, if that is within `max_diff_ns`. Poses of the short
///   trajectory without such a partner are dropped.
/// - If the long trajectory's stamps never decrease, the nearest stamp is found by
///   binary search and a tie goes to the earlier stamp (with repeated stamps, the last
///   of the repeats below); otherwise by a linear scan, and a tie goes to the first
///   index.
///
/// Like `evo`'s, this pairing is one-to-one on the short side only: two poses of the
/// short trajectory may share their nearest partner (only if the short trajectory is
/// locally denser than the long one). It differs from `evo` only in arithmetic: stamps
/// are compared as exact integer nanoseconds, where `evo` compares `f64` seconds, so a
/// difference of exactly `max_diff` is always accepted here.
///
/// Fails with [`EvalError::NoMatches`] if no pair is found.
pub fn associate(
    reference: &Trajectory,
    estimate: &Trajectory,
    options: &AssociationOptions,
) -> Result<Matched, EvalError> {
    let offset = i128::from(options.t_offset_ns);
    let reference_stamps = reference.iter().map(|s| i128::from(s.t_ns));
    let estimate_stamps = estimate.iter().map(|s| i128::from(s.t_ns) + offset);
    let estimate_is_long = estimate.len() > reference.len();
    let pairs = if estimate_is_long {
        nearest_indices(
            &reference_stamps.collect::<Vec<_>>(),
            &estimate_stamps.collect::<Vec<_>>(),
            options.max_diff_ns,
        )
    } else {
        nearest_indices(
            &estimate_stamps.collect::<Vec<_>>(),
            &reference_stamps.collect::<Vec<_>>(),
            options.max_diff_ns,
        )
        .into_iter()
        .map(|(e, r)| (r, e))
        .collect()
    };
    if pairs.is_empty() {
        return Err(EvalError::NoMatches {
            reference_poses: reference.len(),
            estimate_poses: estimate.len(),
            max_diff_ns: options.max_diff_ns,
            t_offset_ns: options.t_offset_ns,
        });
    }
    Ok(Matched {
        reference: pairs.iter().map(|&(r, _)| reference.samples[r]).collect(),
        estimate: pairs.iter().map(|&(_, e)| estimate.samples[e]).collect(),
    })
}

/// For each stamp of `short`, the index of the nearest stamp of `long` within
/// `max_diff`: pairs `(short index, long index)` (`evo`'s `matching_time_indices`).
fn nearest_indices(short: &[i128], long: &[i128], max_diff: u64) -> Vec<(usize, usize)> {
    let max_diff = i128::from(max_diff);
    let Some((&first, &last)) = long.first().zip(long.last()) else {
        return Vec::new();
    };
    if !long.windows(2).all(|w| w[0] <= w[1]) {
        return short
            .iter()
            .enumerate()
            .filter_map(|(i, &s)| {
                // min_by_key keeps the first of equal keys, as numpy's argmin.
                let (j, diff) = long
                    .iter()
                    .map(|&l| (l - s).abs())
                    .enumerate()
                    .min_by_key(|&(_, d)| d)?;
                (diff <= max_diff).then_some((i, j))
            })
            .collect();
    }
    short
        .iter()
        .enumerate()
        .filter_map(|(i, &s)| {
            if s < first - max_diff || s > last + max_diff {
                return None;
            }
            // The first stamp after `s` (numpy `searchsorted(side="right")`), clamped.
            let upper = long.partition_point(|&l| l <= s).min(long.len() - 1);
            let diff_upper = long[upper] - s;
            // No stamp below: an infinite difference, which never passes `max_diff`.
            let diff_lower = upper.checked_sub(1).map_or(i128::MAX, |k| s - long[k]);
            if diff_upper <= max_diff && diff_upper < diff_lower {
                Some((i, upper))
            } else if diff_lower <= max_diff && diff_lower <= diff_upper {
                Some((i, upper - 1))
            } else {
                None
            }
        })
        .collect()
}

//! A laser's no-return reading, found from the data: scanners report "no return" as their
//! largest range, and that value differs per log (32.8–81.9 m in the CARMEN logs), so a
//! constant or a `PARAM` that disagrees with the readings would turn no-returns into a
//! phantom arc of points.

use super::stats::{RangeMax, RangeMaxSource};

/// Readings within this share of the largest one count as saturated.
const SATURATION_BAND: f64 = 0.01;

/// Saturated readings needed to call the largest reading the no-return value.
const MIN_SATURATED: usize = 3;

/// The range limit of `scans` (their readings, from the start of a log): `0.99 · s` when
/// at least three readings lie within 1 % of the largest reading `s` (everything from
/// there up is no return), else `param` if the log has one, else `default`.
pub(crate) fn range_limit<'a>(
    scans: impl Iterator<Item = &'a [f32]> + Clone,
    param: Option<f64>,
    default: f64,
) -> RangeMax {
    let largest = scans
        .clone()
        .flatten()
        .copied()
        .filter(|r| r.is_finite())
        .fold(0.0_f32, f32::max);
    let limit = f64::from(largest) * (1.0 - SATURATION_BAND);
    let saturated = scans.flatten().filter(|&&r| f64::from(r) >= limit).count();
    match param {
        _ if largest > 0.0 && saturated >= MIN_SATURATED => RangeMax {
            value: limit,
            source: RangeMaxSource::Saturation,
        },
        Some(value) => RangeMax {
            value,
            source: RangeMaxSource::Param,
        },
        None => RangeMax {
            value: default,
            source: RangeMaxSource::Default,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saturated_reading_sets_the_limit_whatever_the_param_says() {
        let scans: [&[f32]; 2] = [&[1.0, 32.763, 32.767], &[5.0, 32.759, 2.0]];
        let r = range_limit(scans.iter().copied(), Some(50.0), 50.0);
        assert_eq!(r.source, RangeMaxSource::Saturation);
        assert!(
            (r.value - 32.767_f32 as f64 * 0.99).abs() < 1e-9,
            "{}",
            r.value
        );
    }

    #[test]
    fn without_saturation_the_param_then_the_default_hold() {
        let scans: [&[f32]; 1] = [&[1.0, 2.0, 4.0, 0.75]];
        let r = range_limit(scans.iter().copied(), Some(4.0), 50.0);
        assert_eq!((r.value, r.source), (4.0, RangeMaxSource::Param));
        let r = range_limit(scans.iter().copied(), None, 50.0);
        assert_eq!((r.value, r.source), (50.0, RangeMaxSource::Default));
        let r = range_limit(std::iter::empty(), None, 50.0);
        assert_eq!(r.source, RangeMaxSource::Default);
    }
}

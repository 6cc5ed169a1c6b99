//! Property tests: for random scans (random geometry and ranges with NaN, ±∞, zero,
//! negative and huge readings mixed into straight pieces) extraction never panics and
//! every line it reports is well formed.

use lrf_lines::{ExtractionParams, LaserScan, LineExtractor};
use proptest::prelude::*;
use std::f64::consts::PI;

/// One reading: mostly a point of one of a few random lines, sometimes junk.
fn ranges() -> impl Strategy<Value = (f64, f64, Vec<f32>)> {
    // At most 400 beams × 0.015 rad: a valid header (one turn at most).
    let header = (-PI..PI, prop_oneof![0.001..0.015, -0.015..-0.001]);
    let lines = prop::collection::vec((0.2..15.0_f64, -PI..PI), 1..5);
    let junk = prop::collection::vec(
        prop_oneof![
            4 => Just(None),
            1 => prop_oneof![
                Just(f32::NAN),
                Just(f32::INFINITY),
                Just(f32::NEG_INFINITY),
                Just(0.0_f32),
                Just(-1.0_f32),
                Just(1e30_f32),
                0.0_f32..40.0,
            ]
            .prop_map(Some),
        ],
        0..400,
    );
    (header, lines, junk).prop_map(|((angle_min, inc), lines, junk)| {
        let ranges = scan_ranges(angle_min, inc, &lines, &junk);
        (angle_min, inc, ranges)
    })
}

/// Beam i reads `junk[i]` if set, else sees line `k = i·lines.len()/n` at `r / cos(φ − ψ)`
/// (negative behind the sensor: one more kind of junk).
fn scan_ranges(angle_min: f64, inc: f64, lines: &[(f64, f64)], junk: &[Option<f32>]) -> Vec<f32> {
    let n = junk.len().max(1);
    junk.iter()
        .enumerate()
        .map(|(i, j)| {
            j.unwrap_or_else(|| {
                let (r, psi) = lines[i * lines.len() / n];
                let phi = angle_min + i as f64 * inc;
                (r / (phi - psi).cos()) as f32
            })
        })
        .collect()
}

prop_compose! {
    fn params()(
        range_sigma in 0.001..0.1,
        bearing_sigma in 0.0..0.01,
        split_distance in 0.01..0.3,
        max_point_gap in 0.05..1.0,
        min_incidence in 0.01..1.5,
        min_points in 2usize..12,
        min_length in 0.0..1.0,
    ) -> ExtractionParams {
        ExtractionParams {
            range_sigma,
            bearing_sigma,
            split_distance,
            max_point_gap,
            min_incidence,
            min_points,
            min_length,
            merge_probability: 0.99,
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn lines_are_well_formed((angle_min, inc, ranges) in ranges(), params in params()) {
        let scan = LaserScan { angle_min, angle_increment: inc, range_min: 0.05, range_max: 30.0, ranges: &ranges };
        let mut extractor = LineExtractor::new(params).unwrap();
        let mut out = Vec::new();
        extractor.extract(&scan, &mut out).unwrap();
        for l in &out {
            prop_assert!(l.line.rho >= 0.0 && l.line.rho.is_finite(), "{l:?}");
            prop_assert!(l.line.beta > -PI && l.line.beta <= PI, "{l:?}");
            let c = l.covariance;
            prop_assert!(c.iter().all(|v| v.is_finite()), "{l:?}");
            prop_assert_eq!(c[(0, 1)], c[(1, 0)]);
            prop_assert!(c[(0, 0)] > 0.0 && c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(1, 0)] > 0.0, "{l:?}");
            prop_assert!(l.num_points >= params.min_points, "{l:?}");
            prop_assert!(l.length() >= params.min_length, "{l:?}");
            prop_assert!(l.line.signed_distance(&l.start).abs() < 1e-6 && l.line.signed_distance(&l.end).abs() < 1e-6);
        }
        // The same scan again gives the same lines (the reused buffers carry no state).
        let first = out.clone();
        extractor.extract(&scan, &mut out).unwrap();
        prop_assert_eq!(first, out);
    }
}

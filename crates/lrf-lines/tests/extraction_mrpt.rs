//! A real scan: five scans of the MRPT Málaga office log (testdata/mrpt-scans-excerpt.txt,
//! see testdata/README.md) taken in a 10 m wide hall, twice, ~70 scans apart on the loop.
//!
//! Facts read off the data beforehand (a plain total-least-squares fit of the side beams):
//! the right wall is 2.8–3.5 m away with its normal near −90°, the left wall 6.5–7.2 m
//! away near +90°; the walls are parallel to 0.4° and 9.95–10.03 m apart in every scan.
//! The extractor, with its default (SICK LMS 2xx) parameters, must find both walls as
//! single lines at least 2.5 m long, antiparallel within 1°, 10.0 ± 0.15 m apart (the sum
//! of their r), with σ_r < 1 cm, and the five widths must agree within 0.15 m.

use ekf_core::angle_diff;
use lrf_lines::{ExtractionParams, LaserScan, LineExtractor, ObservedLine};
use std::f64::consts::{FRAC_PI_2, PI};

/// `(max_range, ranges)` of every RAWSCAN line (361 beams over π from −π/2).
fn read_scans() -> Vec<(f64, Vec<f32>)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../testdata/mrpt-scans-excerpt.txt"
    );
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| l.starts_with("RAWSCAN"))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let n: usize = f[2].parse().unwrap();
            assert_eq!(n, 361);
            assert!((f[3].parse::<f64>().unwrap() - PI).abs() < 1e-5);
            let max_range: f64 = f[4].parse().unwrap();
            let ranges: Vec<f32> = f[8..8 + n].iter().map(|r| r.parse().unwrap()).collect();
            (max_range, ranges)
        })
        .collect()
}

/// The longest line whose normal points within 15° of `direction`.
fn wall(lines: &[ObservedLine], direction: f64) -> Option<&ObservedLine> {
    lines
        .iter()
        .filter(|l| angle_diff(l.line.beta, direction).abs() < 15_f64.to_radians())
        .max_by(|a, b| a.length().total_cmp(&b.length()))
}

#[test]
fn hall_walls_are_found_parallel_and_ten_metres_apart() {
    let scans = read_scans();
    assert_eq!(scans.len(), 5);
    let mut extractor = LineExtractor::new(ExtractionParams::default()).unwrap();
    let mut lines = Vec::new();
    let mut widths = Vec::new();
    for (k, (max_range, ranges)) in scans.iter().enumerate() {
        let scan = LaserScan {
            angle_min: -FRAC_PI_2,
            angle_increment: PI / 360.0,
            range_min: 0.0,
            range_max: *max_range,
            ranges,
        };
        extractor.extract(&scan, &mut lines).unwrap();
        let right = wall(&lines, -FRAC_PI_2).unwrap_or_else(|| panic!("scan {k}: {lines:#?}"));
        let left = wall(&lines, FRAC_PI_2).unwrap_or_else(|| panic!("scan {k}: {lines:#?}"));
        let context = format!("scan {k}: right {right:?}\nleft {left:?}");
        assert!((2.5..4.0).contains(&right.line.rho), "{context}");
        assert!((6.0..7.5).contains(&left.line.rho), "{context}");
        assert!(right.length() > 2.5 && left.length() > 2.5, "{context}");
        let antiparallel = angle_diff(left.line.beta, right.line.beta + PI);
        assert!(antiparallel.abs() < 1_f64.to_radians(), "{context}");
        let width = left.line.rho + right.line.rho;
        assert!((width - 10.0).abs() < 0.15, "width {width}; {context}");
        for w in [right, left] {
            assert!(w.covariance[(0, 0)].sqrt() < 0.01, "{context}");
            assert!(w.num_points >= 40, "{context}");
        }
        widths.push(width);
    }
    let (lo, hi) = widths
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &w| (lo.min(w), hi.max(w)));
    assert!(hi - lo < 0.15, "widths {widths:?}");
}

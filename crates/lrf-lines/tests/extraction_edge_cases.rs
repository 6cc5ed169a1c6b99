//! Degenerate scans give no lines and no panic; bad parameters and scan headers are
//! errors that name the field.

use lrf_lines::{
    ExtractionError, ExtractionParams, LaserScan, LineExtractor, ObservedLine, ScanError,
};
use nalgebra::{Matrix2, Point2};

fn scan(ranges: &[f32]) -> LaserScan<'_> {
    LaserScan {
        angle_min: -std::f64::consts::FRAC_PI_2,
        angle_increment: 0.5_f64.to_radians(),
        range_min: 0.0,
        range_max: 80.0,
        ranges,
    }
}

/// Runs the extractor on `ranges` with `out` pre-filled, so clearing is checked too.
fn lines_of(ranges: &[f32]) -> Vec<ObservedLine> {
    let mut extractor = LineExtractor::new(ExtractionParams::default()).unwrap();
    let stale = ObservedLine {
        line: ekf_core::Line::new(1.0, 0.0).unwrap(),
        covariance: Matrix2::identity(),
        start: Point2::new(1.0, 0.0),
        end: Point2::new(1.0, 1.0),
        num_points: 10,
    };
    let mut out = vec![stale];
    extractor.extract(&scan(ranges), &mut out).unwrap();
    out
}

#[test]
fn degenerate_scans_give_no_lines() {
    assert!(lines_of(&[]).is_empty(), "empty ranges");
    assert!(lines_of(&[f32::NAN; 361]).is_empty(), "all NaN");
    assert!(lines_of(&[80.0; 361]).is_empty(), "all at max range");
    assert!(lines_of(&[f32::INFINITY; 361]).is_empty(), "all +inf");
    assert!(lines_of(&[0.0; 361]).is_empty(), "all zero");
    let mut one = [f32::NAN; 361];
    one[100] = 2.0;
    assert!(lines_of(&one).is_empty(), "exactly one valid reading");
    assert!(lines_of(&[2.0]).is_empty(), "a one-beam scan");
    // Every reading 2 m: a circle around the sensor, cut into chords short enough to be
    // within the split distance. Whatever comes out must be finite.
    for l in lines_of(&[2.0; 361]) {
        assert!(l.line.rho.is_finite() && l.covariance.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn invalid_parameters_are_named() {
    let bad = ExtractionParams {
        split_distance: 0.0,
        ..ExtractionParams::default()
    };
    let err = LineExtractor::new(bad).unwrap_err();
    assert!(matches!(
        err,
        ExtractionError::InvalidParameter {
            name: "split_distance",
            ..
        }
    ));
    assert!(err.to_string().contains("split_distance"), "{err}");
    let bad = ExtractionParams {
        min_points: 0,
        ..ExtractionParams::default()
    };
    assert!(LineExtractor::new(bad)
        .unwrap_err()
        .to_string()
        .contains("min_points"));
}

#[test]
fn invalid_scan_headers_are_named() {
    let mut extractor = LineExtractor::new(ExtractionParams::default()).unwrap();
    let ranges = [1.0_f32; 10];
    let mut out = Vec::new();
    let cases = [
        (
            LaserScan {
                angle_increment: 0.0,
                ..scan(&ranges)
            },
            "angle_increment",
        ),
        (
            LaserScan {
                angle_min: f64::NAN,
                ..scan(&ranges)
            },
            "angle_min",
        ),
        (
            LaserScan {
                range_min: 90.0,
                ..scan(&ranges)
            },
            "range_max",
        ),
        (
            LaserScan {
                range_min: f64::INFINITY,
                ..scan(&ranges)
            },
            "range_min",
        ),
    ];
    for (s, field) in cases {
        let err = extractor.extract(&s, &mut out).unwrap_err();
        assert_eq!(
            err,
            ExtractionError::InvalidScan(ScanError {
                field,
                expected: match err {
                    ExtractionError::InvalidScan(e) => e.expected,
                    ExtractionError::InvalidParameter { .. } => "",
                },
            })
        );
        assert!(err.to_string().contains(field), "{err}");
        assert!(std::error::Error::source(&err).is_some());
    }
}

#[test]
fn params_round_trip_through_serde_with_defaults() {
    // A config that sets only some fields gets the documented defaults for the rest.
    let json = r#"{"range_sigma": 0.02, "min_points": 10}"#;
    let p: ExtractionParams = serde_json::from_str(json).unwrap();
    assert_eq!(p.range_sigma, 0.02);
    assert_eq!(p.min_points, 10);
    assert_eq!(p.split_distance, ExtractionParams::default().split_distance);
    let back: ExtractionParams = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(back, p);
}

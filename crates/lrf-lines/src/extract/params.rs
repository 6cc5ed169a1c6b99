//! The tuning parameters of line extraction, their defaults for a SICK LMS 2xx and their
//! validation.

use super::ExtractionError;
use serde::{Deserialize, Serialize};

/// Parameters of [`LineExtractor`](super::LineExtractor). Missing fields in a config file
/// take the [`Default`] values, which suit a SICK LMS 2xx (0.25°–1° resolution, cm/mm
/// range mode, indoor walls within ~15 m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExtractionParams {
    /// Range noise σ_ρ of one reading (m). Default 0.01: the LMS 2xx's statistical error
    /// is 5–10 mm indoors, and its output is quantised to 1 cm in cm mode. A floor: a
    /// scan whose points scatter more is extracted with the noise it shows
    /// ([`LineExtractor::measured_range_sigma`](super::LineExtractor::measured_range_sigma)).
    pub range_sigma: f64,
    /// Bearing noise σ_φ of one beam (rad). Default 0.001 (≈ 0.06°): a small fraction
    /// of the 0.25° angular resolution, the beam-direction jitter of the mirror.
    pub bearing_sigma: f64,
    /// A segment is split at the point farthest from the chord through its end points
    /// when that distance exceeds this (m). Default 0.05 (5 σ_ρ, so noise alone rarely
    /// splits a wall, while a 5 cm step does). A scan noisier than `range_sigma` is split
    /// at [`SPLIT_SIGMAS`](super::SPLIT_SIGMAS) of its measured σ_ρ when that is more.
    pub split_distance: f64,
    /// Consecutive valid points at most this far apart always belong to one segment, and
    /// two collinear lines separated by at most this may merge (m). Default 0.3: doorways
    /// and occlusion shadows are wider. Farther from the sensor the limit grows with the
    /// beam spacing (see `min_incidence`).
    pub max_point_gap: f64,
    /// The most oblique incidence (angle between beam and surface) at which a surface is
    /// still taken as one (rad): two neighbouring points at nearer range `ρ` also belong
    /// together when they are at most `ρ · sin Δφ / sin(λ − Δφ) + 3σ_ρ` apart, the spacing
    /// of beams `Δφ` apart on a wall at incidence `λ` (adaptive breakpoint detector,
    /// Borges and Aldon 2004). Default 10°: a 1° scanner then keeps a wall at 10 m seen
    /// at 60° (0.2 m spacing, limit 1.28 m) in one piece, which a fixed 0.3 m would cut.
    pub min_incidence: f64,
    /// Fewest points a line may be fitted to. Default 6 (a weighted fit of two
    /// parameters needs a few more points than two to have a meaningful covariance).
    pub min_points: usize,
    /// Shortest line kept, between its projected end points (m). Default 0.4: shorter
    /// pieces are furniture and clutter more often than walls.
    pub min_length: f64,
    /// Probability of the chi-square gate (2 dof) under which two adjacent lines count as
    /// the same line and are merged. Default 0.99 (threshold 9.21).
    pub merge_probability: f64,
}

impl Default for ExtractionParams {
    fn default() -> Self {
        Self {
            range_sigma: 0.01,
            bearing_sigma: 0.001,
            split_distance: 0.05,
            max_point_gap: 0.3,
            min_incidence: 10.0_f64.to_radians(),
            min_points: 6,
            min_length: 0.4,
            merge_probability: 0.99,
        }
    }
}

impl ExtractionParams {
    /// Returns the parameters unchanged if every field is in range: `range_sigma`,
    /// `split_distance`, `max_point_gap` finite and > 0; `min_incidence` in (0, π/2); `bearing_sigma`, `min_length`
    /// finite and ≥ 0; `min_points ≥ 2`; `merge_probability` in (0, 1). Otherwise an
    /// [`ExtractionError::InvalidParameter`] naming the first bad field.
    pub fn validated(self) -> Result<Self, ExtractionError> {
        let bad = |name, expected| Err(ExtractionError::InvalidParameter { name, expected });
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !positive(self.range_sigma) {
            return bad("range_sigma", "a finite standard deviation > 0 (m)");
        }
        if !non_negative(self.bearing_sigma) {
            return bad("bearing_sigma", "a finite standard deviation ≥ 0 (rad)");
        }
        if !positive(self.split_distance) {
            return bad("split_distance", "a finite distance > 0 (m)");
        }
        if !positive(self.max_point_gap) {
            return bad("max_point_gap", "a finite distance > 0 (m)");
        }
        if !(self.min_incidence > 0.0 && self.min_incidence < core::f64::consts::FRAC_PI_2) {
            return bad("min_incidence", "an angle in (0, π/2) (rad)");
        }
        if self.min_points < 2 {
            return bad("min_points", "at least 2");
        }
        if !non_negative(self.min_length) {
            return bad("min_length", "a finite length ≥ 0 (m)");
        }
        if !(self.merge_probability > 0.0 && self.merge_probability < 1.0) {
            return bad("merge_probability", "a probability in (0, 1)");
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_each_bad_field_is_named() {
        let d = ExtractionParams::default();
        assert_eq!(d.validated(), Ok(d));
        let name = |p: ExtractionParams| match p.validated() {
            Err(ExtractionError::InvalidParameter { name, .. }) => name,
            other => panic!("expected an invalid parameter, got {other:?}"),
        };
        let cases = [
            (
                ExtractionParams {
                    range_sigma: 0.0,
                    ..d
                },
                "range_sigma",
            ),
            (
                ExtractionParams {
                    bearing_sigma: f64::NAN,
                    ..d
                },
                "bearing_sigma",
            ),
            (
                ExtractionParams {
                    split_distance: -1.0,
                    ..d
                },
                "split_distance",
            ),
            (
                ExtractionParams {
                    max_point_gap: f64::INFINITY,
                    ..d
                },
                "max_point_gap",
            ),
            (
                ExtractionParams {
                    min_incidence: 0.0,
                    ..d
                },
                "min_incidence",
            ),
            (ExtractionParams { min_points: 1, ..d }, "min_points"),
            (
                ExtractionParams {
                    min_length: -0.1,
                    ..d
                },
                "min_length",
            ),
            (
                ExtractionParams {
                    merge_probability: 1.0,
                    ..d
                },
                "merge_probability",
            ),
            (
                ExtractionParams {
                    merge_probability: f64::NAN,
                    ..d
                },
                "merge_probability",
            ),
        ];
        for (p, want) in cases {
            assert_eq!(name(p), want);
        }
    }
}

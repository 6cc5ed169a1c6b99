//! Laser scans shaped like ROS `sensor_msgs/LaserScan`: the beam geometry, which readings
//! are valid, and the header checks every consumer runs before trusting a scan.

use core::f64::consts::TAU;
use core::fmt;

/// One laser scan: beam `i` has bearing `angle_min + i·angle_increment` (counter-clockwise
/// in the sensor frame) and range `ranges[i]` (m). Readings that are not finite, are
/// `≤ range_min` or `≥ range_max` are invalid (no return, dazzle, overflow codes) and are
/// never turned into points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserScan<'a> {
    /// Bearing of the first beam (rad).
    pub angle_min: f64,
    /// Angle between consecutive beams (rad); negative for clockwise scanners.
    pub angle_increment: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m); readings at or beyond it are invalid.
    pub range_max: f64,
    /// Ranges (m), as `float32` on the wire.
    pub ranges: &'a [f32],
}

impl LaserScan<'_> {
    /// Bearing of beam `i`: `φ_i = angle_min + i·angle_increment` (rad, not wrapped).
    #[inline]
    pub fn beam_angle(&self, i: usize) -> f64 {
        // Beam counts are far below 2^53, so the conversion is exact.
        self.angle_min + i as f64 * self.angle_increment
    }

    /// `true` when `range` is a real return: finite and strictly inside
    /// (`range_min`, `range_max`). NaN, ±∞, zero and the scanner's overflow/dazzle codes
    /// (reported at or above `range_max`) are invalid. The limits are also compared at
    /// `float32` precision, so a reading equal to a limit sent as `float32` (as ROS does)
    /// is invalid although its `f64` value is a hair off.
    #[inline]
    pub fn is_valid(&self, range: f32) -> bool {
        let r = f64::from(range);
        // `as f32` rounds to nearest (saturating to ±∞), the limit as it was on the wire.
        r.is_finite()
            && r > self.range_min
            && r < self.range_max
            && range > self.range_min as f32
            && range < self.range_max as f32
    }

    /// Number of valid readings (see [`LaserScan::is_valid`]).
    pub fn valid_count(&self) -> usize {
        self.ranges.iter().filter(|&&r| self.is_valid(r)).count()
    }

    /// Checks the header: `angle_min`, `angle_increment`, `range_min` and `range_max`
    /// finite; `angle_increment ≠ 0`; `0 ≤ range_min < range_max`; the sweep
    /// `|angle_increment|·(len − 1)` at most one turn (2π). The ranges themselves are not
    /// checked: invalid readings are skipped, not errors.
    pub fn validate(&self) -> Result<(), ScanError> {
        let bad = |field, expected| Err(ScanError { field, expected });
        if !self.angle_min.is_finite() {
            return bad("angle_min", "a finite angle (rad)");
        }
        if !self.angle_increment.is_finite() || self.angle_increment == 0.0 {
            return bad("angle_increment", "a finite, non-zero angle (rad)");
        }
        if !self.range_min.is_finite() || self.range_min < 0.0 {
            return bad("range_min", "a finite distance ≥ 0 (m)");
        }
        if !self.range_max.is_finite() || self.range_max <= self.range_min {
            return bad("range_max", "a finite distance > range_min (m)");
        }
        let sweep = self.angle_increment.abs() * self.ranges.len().saturating_sub(1) as f64;
        if sweep > TAU * (1.0 + 1e-9) {
            return bad(
                "angle_increment",
                "|angle_increment|·(len − 1) ≤ 2π (at most one turn)",
            );
        }
        Ok(())
    }
}

/// A scan header field that failed [`LaserScan::validate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScanError {
    /// The offending `LaserScan` field, e.g. `"angle_increment"`.
    pub field: &'static str,
    /// What the field must be.
    pub expected: &'static str,
}

impl fmt::Display for ScanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "invalid laser scan: {} must be {}",
            self.field, self.expected
        )
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ScanError {}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(ranges: &[f32]) -> LaserScan<'_> {
        LaserScan {
            angle_min: -1.0,
            angle_increment: 0.5,
            range_min: 0.1,
            range_max: 10.0,
            ranges,
        }
    }

    #[test]
    fn beam_angles_and_validity() {
        let s = scan(&[
            1.0,
            f32::NAN,
            0.1,
            10.0,
            12.0,
            f32::INFINITY,
            -1.0,
            0.0,
            9.99,
        ]);
        assert_eq!(s.beam_angle(0), -1.0);
        assert_eq!(s.beam_angle(4), 1.0);
        let valid: [bool; 9] = core::array::from_fn(|i| s.is_valid(s.ranges[i]));
        assert_eq!(
            valid,
            [true, false, false, false, false, false, false, false, true]
        );
        assert_eq!(s.valid_count(), 2);
    }

    #[test]
    fn header_errors_name_the_field() {
        let ok = scan(&[1.0; 5]);
        assert_eq!(ok.validate(), Ok(()));
        let field = |s: LaserScan<'_>| s.validate().unwrap_err().field;
        assert_eq!(
            field(LaserScan {
                angle_min: f64::NAN,
                ..ok
            }),
            "angle_min"
        );
        assert_eq!(
            field(LaserScan {
                angle_increment: 0.0,
                ..ok
            }),
            "angle_increment"
        );
        assert_eq!(
            field(LaserScan {
                angle_increment: f64::INFINITY,
                ..ok
            }),
            "angle_increment"
        );
        assert_eq!(
            field(LaserScan {
                range_min: -0.1,
                ..ok
            }),
            "range_min"
        );
        assert_eq!(
            field(LaserScan {
                range_max: 0.1,
                ..ok
            }),
            "range_max"
        );
        assert_eq!(
            field(LaserScan {
                range_max: f64::NAN,
                ..ok
            }),
            "range_max"
        );
        // Five beams 2 rad apart sweep 8 rad, more than a turn.
        assert_eq!(
            field(LaserScan {
                angle_increment: 2.0,
                ..ok
            }),
            "angle_increment"
        );
        let msg = ok
            .validate()
            .and(
                LaserScan {
                    range_min: -1.0,
                    ..ok
                }
                .validate(),
            )
            .unwrap_err()
            .to_string();
        assert!(msg.contains("range_min"), "{msg}");
    }
}

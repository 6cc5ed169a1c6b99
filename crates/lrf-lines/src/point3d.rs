//! A 3-D point from a 2-D scanner pitched about its y axis (the paper's §II 3-D laser
//! built from a SICK LMS 221 on a tilting mount).

use nalgebra::Point3;

/// The 3-D point, in the sensor frame (x forward, y left, z up; REP-103), of a return at
/// bearing `β` and range `ρ` in a scan plane pitched by `α`:
///
/// ```text
/// x = ρ cos β cos α,   y = ρ sin β,   z = −ρ cos β sin α
/// ```
///
/// i.e. the flat-scan point `(ρ cos β, ρ sin β, 0)` rotated by `R_y(α)` about the
/// sensor's y axis (the pitch axis through the mirror centre; an offset between pivot and
/// mirror is part of the mounting, not of this function). `α = 0` is the flat scan.
/// Positive `α` tilts the scan plane **downward**: the beam straight ahead (`β = 0`)
/// goes to `z = −ρ sin α`, below the sensor, as a positive (nose-down) pitch does in
/// REP-103. Beams along the pitch axis (`β = ±π/2`) do not move. Angles in radians,
/// range in metres.
pub fn pitched_scan_point(alpha: f64, beta: f64, rho: f64) -> Point3<f64> {
    let (sin_a, cos_a) = libm::sincos(alpha);
    let (sin_b, cos_b) = libm::sincos(beta);
    Point3::new(rho * cos_b * cos_a, rho * sin_b, -rho * cos_b * sin_a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_6};

    fn close(p: Point3<f64>, want: [f64; 3]) {
        for (got, want) in p.iter().zip(want) {
            assert!((got - want).abs() < 1e-12, "{p} vs {want:?}");
        }
    }

    #[test]
    fn hand_computed_points() {
        // Flat scan: the plain polar → Cartesian conversion.
        close(
            pitched_scan_point(0.0, FRAC_PI_6, 2.0),
            [3.0_f64.sqrt(), 1.0, 0.0],
        );
        // Straight ahead, pitched 30° down: 2 m along the beam is √3 ahead, 1 below.
        close(
            pitched_scan_point(FRAC_PI_6, 0.0, 2.0),
            [3.0_f64.sqrt(), 0.0, -1.0],
        );
        // Pitched up (α < 0): the point rises.
        close(
            pitched_scan_point(-FRAC_PI_6, 0.0, 2.0),
            [3.0_f64.sqrt(), 0.0, 1.0],
        );
        // A beam along the pitch axis (left) is not moved by the pitch.
        close(pitched_scan_point(0.3, FRAC_PI_2, 1.5), [0.0, 1.5, 0.0]);
        // β = 45°, α = 45°, ρ = 2: x = 2·(√2/2)·(√2/2) = 1, y = √2, z = −1.
        close(
            pitched_scan_point(FRAC_PI_4, FRAC_PI_4, 2.0),
            [1.0, 2.0_f64.sqrt(), -1.0],
        );
        // The range is preserved.
        let p = pitched_scan_point(0.2, -1.1, 3.7);
        assert!((p.coords.norm() - 3.7).abs() < 1e-12);
    }
}

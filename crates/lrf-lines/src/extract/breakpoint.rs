//! Where a run of scan points breaks: the adaptive breakpoint detector of Borges and
//! Aldon (2004), with a fixed floor.
//!
//! Two consecutive beams `Δφ` apart that hit one straight surface at incidence `λ` (the
//! angle between the beam and the surface) at the nearer range `ρ` are
//! `ρ · sin Δφ / sin(λ − Δφ)` apart (the law of sines in the triangle of the sensor and
//! the two points). A surface seen more obliquely than `min_incidence` is not trusted to
//! be one, so points farther apart than that distance, plus three range σ, belong to
//! different surfaces. A fixed gap alone either cuts far walls of a 1° scanner into
//! pieces too short to keep (at 10 m and 60° incidence its points are 0.35 m apart) or
//! joins near objects across doorways.

/// The largest distance between two neighbouring points of one surface, as a function of
/// their nearer range:
/// `D(ρ) = max(d_min, ρ · sin Δφ / sin(λ_min − Δφ) + 3σ_ρ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Breakpoint {
    /// `d_min`: the distance that always joins (m).
    floor: f64,
    /// `sin Δφ / sin(λ_min − Δφ)`, 0 when `λ_min ≤ Δφ` (the beams are too sparse for the
    /// adaptive rule, and only the floor applies).
    per_metre: f64,
    /// `3σ_ρ` (m).
    noise: f64,
}

impl Breakpoint {
    /// The rule for beams `angle_increment` apart (rad, either sign), surfaces seen at no
    /// less than `min_incidence` (rad), readings with range noise `range_sigma` (m) and
    /// the fixed gap `floor` (m).
    pub fn new(floor: f64, min_incidence: f64, angle_increment: f64, range_sigma: f64) -> Self {
        let step = angle_increment.abs();
        let per_metre = if min_incidence > step {
            libm::sin(step) / libm::sin(min_incidence - step)
        } else {
            0.0
        };
        Self {
            floor,
            per_metre,
            noise: 3.0 * range_sigma,
        }
    }

    /// `D(ρ)` for two points at ranges `a` and `b` (m): `ρ = min(a, b)`.
    #[inline]
    pub fn max_gap(&self, a: f64, b: f64) -> f64 {
        self.floor.max(a.min(b) * self.per_metre + self.noise)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two beams `step` apart on a straight wall at incidence `lambda` to the first one
    /// at range `rho`: the distance between the two points, by intersecting the second
    /// beam with the wall. Sensor at the origin, first beam along +x, the wall through
    /// `(rho, 0)` along `(cos λ, sin λ)`, receding: solve
    /// `t·(cos Δφ, sin Δφ) = (rho, 0) + s·(cos λ, sin λ)` for `s` (Cramer's rule).
    fn spacing_on_wall(rho: f64, lambda: f64, step: f64) -> f64 {
        let det = -step.cos() * lambda.sin() + lambda.cos() * step.sin();
        let s = -(step.sin() * rho) / det;
        s.abs()
    }

    #[test]
    fn the_adaptive_gap_is_the_spacing_at_the_least_incidence_plus_three_sigma() {
        let (step, lambda) = (1.0_f64.to_radians(), 10.0_f64.to_radians());
        let rule = Breakpoint::new(0.0, lambda, step, 0.01);
        for rho in [1.0, 4.0, 12.5] {
            let want = spacing_on_wall(rho, lambda, step) + 0.03;
            assert!(
                (rule.max_gap(rho, 2.0 * rho) - want).abs() < 1e-9,
                "at {rho} m"
            );
        }
        // A wall seen at 60° is well inside the rule; one at 5° is cut.
        assert!(spacing_on_wall(10.0, 60.0_f64.to_radians(), step) < rule.max_gap(10.0, 11.0));
        assert!(spacing_on_wall(10.0, 5.0_f64.to_radians(), step) > rule.max_gap(10.0, 11.0));
    }

    #[test]
    fn the_floor_holds_near_the_sensor_and_when_the_beams_are_too_sparse() {
        let rule = Breakpoint::new(0.3, 10.0_f64.to_radians(), -0.5_f64.to_radians(), 0.01);
        assert_eq!(rule.max_gap(1.0, 1.0), 0.3);
        assert!(rule.max_gap(8.0, 9.0) > 0.3);
        let sparse = Breakpoint::new(0.3, 10.0_f64.to_radians(), 12.0_f64.to_radians(), 0.01);
        assert_eq!(sparse.max_gap(30.0, 30.0), 0.3);
    }
}

//! Merging of adjacent collinear lines: a chi-square test on the difference of their
//! `(r, ψ)`, a gap check, and a refit of the union of their points.

use super::breakpoint::Breakpoint;
use super::fit::{fit_line, LineFit, PointNoise};
use super::points::{Points, Run};
use alloc::vec::Vec;
use core::f64::consts::{FRAC_PI_2, PI};
use core::ops::Range;
use ekf_core::wrap_angle;
use nalgebra::Vector2;

/// A fitted line and the points it was fitted to: the beams of `pieces[support]`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Candidate {
    /// The points of the line: a range of the fitted pieces (beam ranges, in scan order).
    pub support: Range<usize>,
    /// The weighted fit of those points.
    pub fit: LineFit,
}

/// What decides whether two neighbouring lines are one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MergeRule {
    /// Chi-square threshold (2 dof) on the Mahalanobis distance of the `(r, ψ)` difference.
    pub gate: f64,
    /// Point noise for the refit.
    pub noise: PointNoise,
}

/// Merges neighbours in `candidates` (in scan order, with supports that tile `pieces`
/// without holes) while their `(r, ψ)` pass the chi-square gate and the gap between the
/// last point of one and the first of the next is within `breakpoint`; the merged line is the weighted refit of both supports' points (never the
/// dropped clutter between them). Works in place, left to right, so a wall cut into
/// several pieces merges back into one.
pub(crate) fn merge_collinear(
    points: &Points<'_>,
    pieces: &[Run],
    candidates: &mut Vec<Candidate>,
    rule: &MergeRule,
    breakpoint: &Breakpoint,
) {
    let mut kept: usize = 0;
    for i in 0..candidates.len() {
        let next = candidates[i].clone();
        if let Some(previous) = kept.checked_sub(1).and_then(|k| candidates.get(k)) {
            if let Some(merged) = try_merge(points, pieces, previous, &next, rule, breakpoint) {
                candidates[kept - 1] = merged;
                continue;
            }
        }
        candidates[kept] = next;
        kept += 1;
    }
    candidates.truncate(kept);
}

fn try_merge(
    points: &Points<'_>,
    pieces: &[Run],
    a: &Candidate,
    b: &Candidate,
    rule: &MergeRule,
    breakpoint: &Breakpoint,
) -> Option<Candidate> {
    let last_beam = pieces
        .get(a.support.end.checked_sub(1)?)?
        .end
        .checked_sub(1)?;
    let first_beam = pieces.get(b.support.start)?.start;
    let (last, first) = (points.xy(last_beam)?, points.xy(first_beam)?);
    let (dx, dy) = (last.0 - first.0, last.1 - first.1);
    let limit = breakpoint.max_gap(
        *points.range.get(last_beam)?,
        *points.range.get(first_beam)?,
    );
    if a.support.end != b.support.start
        || dx * dx + dy * dy > limit * limit
        || mahalanobis_squared(&a.fit, &b.fit)? > rule.gate
    {
        return None;
    }
    let support = a.support.start..b.support.end;
    let fit = fit_line(points, pieces.get(support.clone())?, &rule.noise)?;
    Some(Candidate { support, fit })
}

/// `Δᵀ (Σ_a + Σ_b)⁻¹ Δ` for `Δ = (r_a − r_b, wrap(ψ_a − ψ_b))`. When the normals point
/// opposite ways (a line through or near the origin), `b` is first rewritten as the same
/// line `(−r_b, ψ_b + π)`, whose covariance has the r–ψ term negated. `None` if the summed
/// covariance is singular.
pub(crate) fn mahalanobis_squared(a: &LineFit, b: &LineFit) -> Option<f64> {
    let mut sum = a.covariance + b.covariance;
    let mut delta = Vector2::new(a.r - b.r, wrap_angle(a.psi - b.psi));
    if delta.y.abs() > FRAC_PI_2 {
        delta = Vector2::new(a.r + b.r, wrap_angle(a.psi - b.psi - PI));
        let coupling = a.covariance[(0, 1)] - b.covariance[(0, 1)];
        sum[(0, 1)] = coupling;
        sum[(1, 0)] = coupling;
    }
    let (s11, s12, s22) = (sum[(0, 0)], sum[(0, 1)], sum[(1, 1)]);
    let det = s11 * s22 - s12 * s12;
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let d2 =
        (s22 * delta.x * delta.x - 2.0 * s12 * delta.x * delta.y + s11 * delta.y * delta.y) / det;
    d2.is_finite().then_some(d2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;

    fn fit(r: f64, psi: f64, coupling: f64) -> LineFit {
        LineFit {
            r,
            psi,
            covariance: Matrix2::new(1e-4, coupling, coupling, 1e-4),
        }
    }

    #[test]
    fn mahalanobis_known_values() {
        // Δ = (0.02, 0), Σ = 2e-4 I → 0.0004 / 2e-4 = 2.
        let d2 = mahalanobis_squared(&fit(1.0, 0.1, 0.0), &fit(0.98, 0.1, 0.0)).unwrap();
        assert!((d2 - 2.0).abs() < 1e-9);
        // Across ±π: ψ = π − 0.01 and −π + 0.01 differ by 0.02 → 0.0004 / 2e-4.
        let d2 = mahalanobis_squared(&fit(1.0, PI - 0.01, 0.0), &fit(1.0, -PI + 0.01, 0.0));
        assert!((d2.unwrap() - 2.0).abs() < 1e-9);
        // A line through the origin seen with opposite normals is the same line.
        let d2 = mahalanobis_squared(&fit(0.001, 0.5, 0.0), &fit(0.001, 0.5 - PI, 0.0));
        assert!(d2.unwrap() < 0.1);
        assert_eq!(
            mahalanobis_squared(&fit(1.0, 0.0, 1e-4), &fit(1.0, 0.0, 1e-4)),
            None
        );
    }
}

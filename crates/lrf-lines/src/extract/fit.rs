//! Weighted least-squares line fit with per-point range and bearing noise (Pfister,
//! Roumeliotis, Burdick, ICRA 2003) and its covariance, the inverse Fisher information.

use super::moments::{Moments, NormalLine};
use super::points::{Points, Run};
use ekf_core::wrap_angle;
use nalgebra::Matrix2;

/// Gauss-Newton iterations at most; the total-least-squares start is already close, so
/// two or three are usual.
const MAX_ITERATIONS: usize = 6;
/// Converged when the step is below a tenth of its own standard deviation:
/// `δᵀ J δ < 10⁻²`. The remaining error is then a small fraction of σ, and each pass
/// over the points is the main cost of extraction.
const STEP_TOLERANCE: f64 = 1e-2;
/// A point's normal variance is floored at this fraction of σ_ρ², so a beam exactly
/// parallel to the line (cos(φ−ψ) = 0) with σ_φ = 0 cannot get an infinite weight.
const VARIANCE_FLOOR: f64 = 1e-6;

/// End points farther than this many of their own σ from the fitted line are trimmed.
const TRIM_SIGMAS: f64 = 3.0;
/// Trim-and-refit rounds at most.
const MAX_TRIM_ROUNDS: usize = 6;

/// Per-point noise: σ_ρ² (m²) and σ_φ² (rad²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PointNoise {
    /// σ_ρ² (m²).
    pub range_var: f64,
    /// σ_φ² (rad²).
    pub bearing_var: f64,
}

/// A fitted line `x cos ψ + y sin ψ = r` with `r ≥ 0`, `ψ` in (−π, π], and the 2×2
/// covariance of `(r, ψ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LineFit {
    /// r ≥ 0 (m).
    pub r: f64,
    /// ψ in (−π, π] (rad).
    pub psi: f64,
    /// Covariance of (r, ψ).
    pub covariance: Matrix2<f64>,
}

/// Fits a line to the points of the beam ranges `pieces` (in order) by weighted least
/// squares (Pfister et al. 2003).
///
/// Point `i` at `(ρ_i, φ_i)` has the normal distance `d_i = ρ_i cos(φ_i − ψ) − r` with
/// `var(d_i) = σ_ρ² cos²(φ_i − ψ) + ρ_i² σ_φ² sin²(φ_i − ψ)`. Starting from the
/// unweighted total-least-squares line, Gauss-Newton steps on `(r, ψ)` minimise
/// `Σ d_i² / var(d_i)`, with `g_i = ∂d_i/∂(r, ψ) = (−1, ρ_i sin(φ_i − ψ))`,
/// `J = Σ w_i g_i g_iᵀ`, `w_i = 1/var(d_i)`, step `δ = −J⁻¹ Σ w_i g_i d_i`. The
/// covariance is `J⁻¹`, the inverse of the full Fisher information, keeping the r–ψ
/// coupling. `None` when the points do not determine a line (fewer than two distinct
/// points, or non-finite sums).
pub(crate) fn fit_line(points: &Points<'_>, pieces: &[Run], noise: &PointNoise) -> Option<LineFit> {
    let start = total_least_squares(points, pieces)?;
    let (mut r, mut psi) = (start.r, start.psi);
    // (sin ψ, cos ψ) of the current ψ.
    let mut normal = (start.sin, start.cos);
    let mut covariance = Matrix2::zeros();
    for _ in 0..MAX_ITERATIONS {
        let (j, b) = fisher_information(points, pieces, noise, r, normal);
        covariance = invert_symmetric(&j)?;
        let step = -(covariance * b);
        r += step.x;
        psi += step.y;
        // The covariance stays the one at the point before this last, tiny step: the
        // information changes by a negligible amount over a tenth of a σ.
        if (step.transpose() * j * step).x < STEP_TOLERANCE {
            break;
        }
        normal = libm::sincos(psi);
    }
    if r < 0.0 {
        // (r, ψ) → (−r, ψ + π) is the same line; its Jacobian diag(−1, 1) flips the
        // sign of the r–ψ covariance.
        r = -r;
        psi += core::f64::consts::PI;
        covariance[(0, 1)] = -covariance[(0, 1)];
        covariance[(1, 0)] = -covariance[(1, 0)];
    }
    let psi = wrap_angle(psi);
    (r.is_finite() && psi.is_finite()).then_some(LineFit { r, psi, covariance })
}

/// [`fit_line`] of the beams `segment`, then trims the run of end points, at the worse end, whose normal
/// distance exceeds 3σ of their own `var(d_i)` and refits, until both ends are inliers
/// (a few rounds at most). This
/// removes the points of the neighbouring wall that a split near a corner leaves at the
/// end of a segment (the split point, the farthest from the chord, is only near the
/// corner when the noise allows). Returns the kept sub-range of `segment` and its fit, or
/// `None` if fewer than `min_points` remain.
pub(crate) fn fit_trimmed(
    points: &Points<'_>,
    segment: Run,
    noise: &PointNoise,
    min_points: usize,
) -> Option<(Run, LineFit)> {
    let mut range = segment;
    for _ in 0..MAX_TRIM_ROUNDS {
        let fit = fit_line(points, core::slice::from_ref(&range), noise)?;
        let normal = libm::sincos(fit.psi);
        let residual = |i: usize| normalized_residual(points, i, &fit, normal, noise);
        let last = range.end.checked_sub(1)?;
        // Trim only the worse end: a fit pulled by outliers at one end can make the good
        // points at the other end look bad too.
        let trim_head = residual(range.start)? >= residual(last)?;
        let outlier = |&i: &usize| residual(i).is_some_and(|d| d > TRIM_SIGMAS);
        let trimmed = if trim_head {
            range.clone().take_while(outlier).count()
        } else {
            range.clone().rev().take_while(outlier).count()
        };
        if trimmed == 0 {
            return Some((range, fit));
        }
        range = if trim_head {
            range.start + trimmed..range.end
        } else {
            range.start..range.end - trimmed
        };
        if range.len() < min_points {
            return None;
        }
    }
    let fit = fit_line(points, core::slice::from_ref(&range), noise)?;
    Some((range, fit))
}

/// `|d_i| / √var(d_i)`: the normal distance of the point of beam `i` from the line in
/// units of its own standard deviation (same `var(d_i)` as the fit); `(s_psi, c_psi)` =
/// (sin ψ, cos ψ).
fn normalized_residual(
    points: &Points<'_>,
    i: usize,
    fit: &LineFit,
    (s_psi, c_psi): (f64, f64),
    noise: &PointNoise,
) -> Option<f64> {
    let (range, cos, sin) = (
        *points.range.get(i)?,
        *points.cos.get(i)?,
        *points.sin.get(i)?,
    );
    let cos_d = cos * c_psi + sin * s_psi;
    let g2 = range * (sin * c_psi - cos * s_psi);
    let var = noise.range_var * cos_d * cos_d + noise.bearing_var * g2 * g2;
    Some(
        libm::fabs(range * cos_d - fit.r)
            / libm::sqrt(floored(var, VARIANCE_FLOOR * noise.range_var)),
    )
}

/// The unweighted total-least-squares line of the points of `pieces` (see
/// [`Moments::line`]), with the sums taken relative to the first point for numerical
/// stability.
fn total_least_squares(points: &Points<'_>, pieces: &[Run]) -> Option<NormalLine> {
    let (ox, oy) = points.xy(pieces.first()?.start)?;
    let (mut sum, mut n) = (Moments::default(), 0);
    for piece in pieces {
        let (xs, ys) = (points.x.get(piece.clone())?, points.y.get(piece.clone())?);
        for (&x, &y) in xs.iter().zip(ys) {
            sum = sum.plus(x - ox, y - oy);
        }
        n += xs.len();
    }
    sum.with_count(n).line((ox, oy))
}

/// `J = Σ w_i g_i g_iᵀ` and the gradient half `b = Σ w_i g_i d_i` at `(r, ψ)`, `ψ`
/// given as `(sin ψ, cos ψ)`; the angle differences come from the cached beam cos/sin,
/// with no trigonometry per point.
///
/// The points go by blocks of [`BLOCK`]: first every point's terms of the sums, in a
/// loop without dependencies between points, which vectorises; then the sums, point after
/// point, so in the same order and with the same results as one loop doing both.
fn fisher_information(
    points: &Points<'_>,
    pieces: &[Run],
    noise: &PointNoise,
    r: f64,
    (s_psi, c_psi): (f64, f64),
) -> (Matrix2<f64>, nalgebra::Vector2<f64>) {
    let floor = VARIANCE_FLOOR * noise.range_var;
    let (mut j11, mut j12, mut j22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    // Per point of a block: w, w g₂, w g₂², w d, w g₂ d.
    let mut terms = [[0.0; BLOCK]; 5];
    for piece in pieces {
        let (Some(ranges), Some(coss), Some(sins)) = (
            points.range.get(piece.clone()),
            points.cos.get(piece.clone()),
            points.sin.get(piece.clone()),
        ) else {
            continue;
        };
        let blocks = ranges
            .chunks(BLOCK)
            .zip(coss.chunks(BLOCK))
            .zip(sins.chunks(BLOCK));
        for ((ranges, coss), sins) in blocks {
            let [ws, wg2s, wg2g2s, wds, wg2ds] = &mut terms;
            let out = ws
                .iter_mut()
                .zip(wg2s.iter_mut())
                .zip(wg2g2s.iter_mut())
                .zip(wds.iter_mut())
                .zip(wg2ds.iter_mut());
            let polar = ranges.iter().zip(coss).zip(sins);
            for (((((w_out, wg2_out), wg2g2_out), wd_out), wg2d_out), ((&range, &cos), &sin)) in
                out.zip(polar)
            {
                let cos_d = cos * c_psi + sin * s_psi; // cos(φ − ψ)
                let sin_d = sin * c_psi - cos * s_psi; // sin(φ − ψ)
                let d = range * cos_d - r;
                let g2 = range * sin_d;
                let var = noise.range_var * cos_d * cos_d + noise.bearing_var * g2 * g2;
                let w = 1.0 / floored(var, floor);
                let wg2 = w * g2;
                *w_out = w;
                *wg2_out = wg2;
                *wg2g2_out = wg2 * g2;
                *wd_out = w * d;
                *wg2d_out = wg2 * d;
            }
            let n = ranges.len();
            let (Some(ws), Some(wg2s), Some(wg2g2s), Some(wds), Some(wg2ds)) = (
                ws.get(..n),
                wg2s.get(..n),
                wg2g2s.get(..n),
                wds.get(..n),
                wg2ds.get(..n),
            ) else {
                continue;
            };
            let sums = ws.iter().zip(wg2s).zip(wg2g2s).zip(wds).zip(wg2ds);
            for ((((&w, &wg2), &wg2g2), &wd), &wg2d) in sums {
                j11 += w;
                j12 -= wg2;
                j22 += wg2g2;
                b1 -= wd;
                b2 += wg2d;
            }
        }
    }
    (
        Matrix2::new(j11, j12, j12, j22),
        nalgebra::Vector2::new(b1, b2),
    )
}

/// Points per block in [`fisher_information`].
const BLOCK: usize = 16;

/// `var.max(floor)` (also `floor` for a NaN `var`), written as one comparison so it
/// compiles to a single `maxsd` in the per-point loops: `f64::max` must also handle a
/// NaN `floor`, which costs several instructions per point.
#[inline(always)]
fn floored(var: f64, floor: f64) -> f64 {
    if var > floor {
        var
    } else {
        floor
    }
}

/// Inverse of a symmetric 2×2 matrix, exactly symmetric; `None` unless it is positive
/// definite with finite entries.
fn invert_symmetric(m: &Matrix2<f64>) -> Option<Matrix2<f64>> {
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let det = a * d - b * b;
    if !(det > 0.0 && a > 0.0 && det.is_finite()) {
        return None;
    }
    let inv = Matrix2::new(d / det, -b / det, -b / det, a / det);
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

#[cfg(test)]
mod tests {
    use super::super::points::testing::TestScan;
    use super::*;
    use alloc::vec::Vec;

    /// `(ρ, φ)` of points on the line (r, ψ), seen from the origin at bearings `phis`.
    fn on_line(r: f64, psi: f64, phis: impl Iterator<Item = f64>) -> Vec<(f64, f64)> {
        phis.map(|phi| (r / (phi - psi).cos(), phi)).collect()
    }

    /// [`fit_line`] of all the points.
    fn fit_all(points: Vec<(f64, f64)>, noise: &PointNoise) -> Option<LineFit> {
        let n = points.len();
        fit_line(
            &TestScan::polar(points).points(),
            core::slice::from_ref(&(0..n)),
            noise,
        )
    }

    const NOISE: PointNoise = PointNoise {
        range_var: 1e-4,
        bearing_var: 1e-6,
    };

    #[test]
    fn exact_points_give_the_exact_line() {
        let pts = on_line(2.0, 0.3, (0..40).map(|i| -0.4 + 0.02 * i as f64));
        let fit = fit_all(pts, &NOISE).unwrap();
        assert!(
            (fit.r - 2.0).abs() < 1e-12 && (fit.psi - 0.3).abs() < 1e-12,
            "{fit:?}"
        );
        // A wall behind the sensor: normal at ψ = π exactly (wrapped, r ≥ 0).
        let pts = on_line(
            1.5,
            core::f64::consts::PI,
            (0..30).map(|i| 2.8 + 0.02 * i as f64),
        );
        let fit = fit_all(pts, &NOISE).unwrap();
        assert!((fit.r - 1.5).abs() < 1e-12, "{fit:?}");
        assert!((wrap_angle(fit.psi - core::f64::consts::PI)).abs() < 1e-12);
    }

    #[test]
    fn covariance_of_a_perpendicular_wall_matches_the_closed_form() {
        // With σ_φ = 0 and every beam along the normal (a tiny bearing spread), each point
        // has var(d) = σ_ρ², so var(r) → σ_ρ²/n at the foot of the normal.
        let noise = PointNoise {
            range_var: 1e-4,
            bearing_var: 0.0,
        };
        let pts = on_line(3.0, 0.0, (0..21).map(|i| -0.1 + 0.01 * i as f64));
        let fit = fit_all(pts, &noise).unwrap();
        let c = fit.covariance;
        assert!(
            (c[(0, 0)] - 1e-4 / 21.0).abs() / (1e-4 / 21.0) < 0.02,
            "{c}"
        );
        assert_eq!(c[(0, 1)], c[(1, 0)]);
        assert!(c[(0, 0)] > 0.0 && c.determinant() > 0.0);
        // Symmetric points about the normal foot: no r–ψ coupling.
        assert!(c[(0, 1)].abs() < 1e-12 * c[(1, 1)].max(1.0));
    }

    #[test]
    fn coupling_sign_follows_the_segment_offset() {
        // A wall x = 2 seen only on its left (y > 0): moving ψ positive tilts the fitted
        // line, which must be compensated in r: the correlation is non-zero.
        let pts = on_line(2.0, 0.0, (0..30).map(|i| 0.5 + 0.01 * i as f64));
        let c = fit_all(pts, &NOISE).unwrap().covariance;
        assert!(c[(0, 1)] > 0.0, "{c}");
        let pts = on_line(2.0, 0.0, (0..30).map(|i| -0.5 - 0.01 * i as f64));
        let c = fit_all(pts, &NOISE).unwrap().covariance;
        assert!(c[(0, 1)] < 0.0, "{c}");
    }

    #[test]
    fn trimming_drops_the_neighbouring_wall_at_a_corner() {
        // 40 points on x = 2, then 6 points 5 cm apart turning onto the wall y = 1.2.
        let mut pts = on_line(2.0, 0.0, (0..40).map(|i| -0.3 + 0.02 * i as f64));
        pts.extend((1..=6).map(|i| {
            let (x, y) = (2.0 - 0.05 * i as f64, 1.2);
            (x.hypot(y), y.atan2(x))
        }));
        let scan = TestScan::polar(pts);
        let points = scan.points();
        let (range, fit) = fit_trimmed(&points, 0..46, &NOISE, 5).unwrap();
        assert_eq!(range, 0..40);
        assert!(
            (fit.r - 2.0).abs() < 1e-9 && fit.psi.abs() < 1e-9,
            "{fit:?}"
        );
        // Nothing to trim on a clean segment; too few left is None.
        assert_eq!(fit_trimmed(&points, 0..40, &NOISE, 5).unwrap().0, 0..40);
        assert_eq!(fit_trimmed(&points, 0..46, &NOISE, 41), None);
    }

    #[test]
    fn degenerate_inputs() {
        assert_eq!(fit_all(Vec::new(), &NOISE), None);
        assert_eq!(fit_all(Vec::from([(1.0, 0.0)]), &NOISE), None);
        assert_eq!(fit_all(Vec::from([(1.0, 0.0), (1.0, 0.0)]), &NOISE), None);
        let scan = TestScan::polar([(1.0, 0.0), (1.0, 0.5), (1.0, 1.0)]);
        assert_eq!(fit_line(&scan.points(), &[], &NOISE), None);
    }
}

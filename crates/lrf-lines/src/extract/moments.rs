//! Running sums of point moments, so the total-least-squares line of any stretch of a
//! run costs O(1) from prefix sums instead of a pass over its points.

use core::ops::Sub;

/// Count and sums `(n, Σx, Σy, Σx², Σy², Σxy)` of points, in coordinates relative to an
/// origin (the first point of their run, which keeps the sums small and exact enough).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Moments {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
}

impl Moments {
    /// These sums plus the point `(x, y)` (relative to the origin), with the count
    /// unchanged: the count of a stretch of points is its length, set by
    /// [`Moments::with_count`], so the per-point loops need not add it up.
    #[inline]
    pub fn plus(&self, x: f64, y: f64) -> Self {
        Self {
            n: self.n,
            sx: self.sx + x,
            sy: self.sy + y,
            sxx: self.sxx + x * x,
            syy: self.syy + y * y,
            sxy: self.sxy + x * y,
        }
    }

    /// These sums, as those of `n` points. (Counts are far below 2⁵³, so the
    /// conversion is exact and equals counting one by one in `f64`.)
    #[inline]
    pub fn with_count(self, n: usize) -> Self {
        Self {
            n: n as f64,
            ..self
        }
    }

    /// Mean squared distance of the points from their total-least-squares line: the
    /// smaller eigenvalue of the centred scatter matrix over n,
    /// `(c_xx + c_yy)/2 − √(((c_xx − c_yy)/2)² + c_xy²)` all over `n`. 0 for fewer than
    /// two points.
    pub fn mean_squared_residual(&self) -> f64 {
        if self.n < 2.0 {
            return 0.0;
        }
        let (mx, my) = (self.sx / self.n, self.sy / self.n);
        let cxx = self.sxx - self.n * mx * mx;
        let cyy = self.syy - self.n * my * my;
        let cxy = self.sxy - self.n * mx * my;
        let half_diff = 0.5 * (cxx - cyy);
        let smallest = 0.5 * (cxx + cyy) - libm::sqrt(half_diff * half_diff + cxy * cxy);
        smallest.max(0.0) / self.n
    }

    /// The total-least-squares line `(r, ψ)` of the points, given the origin the sums are
    /// relative to. With the centred second moments `c_xx, c_yy, c_xy`:
    /// `ψ = ½ atan2(−2 c_xy, c_yy − c_xx)` (the normal of least spread) and
    /// `r = x̄ cos ψ + ȳ sin ψ` through the centroid (r may be negative). `None` for fewer
    /// than two points or no spread.
    pub fn line(&self, origin: (f64, f64)) -> Option<NormalLine> {
        if self.n < 2.0 {
            return None;
        }
        let (mx, my) = (self.sx / self.n, self.sy / self.n);
        let cxx = self.sxx - self.n * mx * mx;
        let cyy = self.syy - self.n * my * my;
        let cxy = self.sxy - self.n * mx * my;
        let spread = cxx + cyy;
        if spread.is_nan() || spread <= 0.0 {
            return None;
        }
        let psi = 0.5 * libm::atan2(-2.0 * cxy, cyy - cxx);
        let (sin, cos) = libm::sincos(psi);
        let r = (origin.0 + mx) * cos + (origin.1 + my) * sin;
        r.is_finite().then_some(NormalLine { r, psi, cos, sin })
    }
}

/// A line `x cos ψ + y sin ψ = r` with the cos and sin of its `ψ`, which its users need
/// too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NormalLine {
    /// r (m); may be negative.
    pub r: f64,
    /// ψ (rad).
    pub psi: f64,
    /// cos ψ.
    pub cos: f64,
    /// sin ψ.
    pub sin: f64,
}

impl Sub for Moments {
    type Output = Self;

    /// The sums of a stretch from two prefix sums: `P[j] − P[i]` covers points `i..j`.
    fn sub(self, o: Self) -> Self {
        Self {
            n: self.n - o.n,
            sx: self.sx - o.sx,
            sy: self.sy - o.sy,
            sxx: self.sxx - o.sxx,
            syy: self.syy - o.syy,
            sxy: self.sxy - o.sxy,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_from_sums_and_differences() {
        // Points on x = 2 (relative to the origin (2, 0): x = 0, y = 0..4).
        let mut prefix = [Moments::default(); 6];
        for i in 0..5 {
            prefix[i + 1] = prefix[i].plus(0.0, i as f64);
        }
        let NormalLine { r, psi, cos, sin } = prefix[5].with_count(5).line((2.0, 0.0)).unwrap();
        assert!((r - 2.0).abs() < 1e-12 && psi.abs() < 1e-12);
        assert_eq!((sin, cos), libm::sincos(psi));
        // A stretch by difference: points 1..4, same line.
        let stretch = (prefix[4] - prefix[1]).with_count(3);
        let NormalLine { r, psi, .. } = stretch.line((2.0, 0.0)).unwrap();
        assert!((r - 2.0).abs() < 1e-12 && psi.abs() < 1e-12);
        assert_eq!((prefix[2] - prefix[1]).with_count(1).line((2.0, 0.0)), None);
        let same = Moments::default()
            .plus(1.0, 1.0)
            .plus(1.0, 1.0)
            .with_count(2);
        assert_eq!(same.line((0.0, 0.0)), None);
        assert!(prefix[5].with_count(5).mean_squared_residual().abs() < 1e-12);
        // Pairs of points 0.1 either side of y = 0 at x = 0, 1, 2: mean squared residual
        // exactly 0.01.
        let pairs = (0..3)
            .fold(Moments::default(), |m, i| {
                m.plus(i as f64, 0.1).plus(i as f64, -0.1)
            })
            .with_count(6);
        assert!((pairs.mean_squared_residual() - 0.01).abs() < 1e-12);
    }
}

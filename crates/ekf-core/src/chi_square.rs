//! Chi-square distribution for integer degrees of freedom, and gates built from its
//! quantiles.
//!
//! Gates are stated as a probability and degrees of freedom (0.99 with 2 dof → 9.21 for a
//! 2-D line innovation), never as "sigmas".

use crate::validate::finite;
use crate::{Error, Real};

/// Largest degrees of freedom supported by [`chi_square_cdf`] and the quantile (each
/// evaluation of the CDF costs `O(dof)`).
pub const MAX_DOF: u32 = 10_000;

/// The chi-square CDF `P(k/2, x/2)` for integer `k` in 1..=[`MAX_DOF`], from the closed
/// forms: `k` even, `1 − e^{−x/2} Σ_{i<k/2} (x/2)^i / i!`; `k` odd,
/// `erf(√(x/2)) − e^{−x/2} Σ_{i<(k−1)/2} (x/2)^{i+½} / Γ(i+3/2)`. Each term is formed
/// from its logarithm, so `e^{−x/2}` cannot underflow at large `k`.
pub fn chi_square_cdf(x: f64, dof: u32) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let h = 0.5 * x;
    let ln_h = libm::log(h);
    // ln of the first term, and the offset of the power and factorial: i and i + 1 for
    // even k, i + ½ and i + 3/2 for odd k.
    let (mut ln_term, offset, count, head) = if dof.is_multiple_of(2) {
        (-h, 0.0, dof / 2, 1.0)
    } else {
        // e^{−h}·h^{1/2}/Γ(3/2), Γ(3/2) = √π/2.
        let ln_gamma_3_2 = libm::log(0.5 * libm::sqrt(core::f64::consts::PI));
        (
            -h + 0.5 * ln_h - ln_gamma_3_2,
            0.5,
            (dof - 1) / 2,
            libm::erf(libm::sqrt(h)),
        )
    };
    let mut sum = 0.0;
    for i in 0..count {
        sum += libm::exp(ln_term);
        ln_term += ln_h - libm::log(f64::from(i) + 1.0 + offset);
    }
    (head - sum).clamp(0.0, 1.0)
}

/// The chi-square quantile: the `x` with `chi_square_cdf(x, dof) = p`, found by
/// bisection to full double precision. `p` in (0, 1), `dof` in 1..=[`MAX_DOF`].
pub fn chi_square_quantile(p: f64, dof: u32) -> Result<f64, Error> {
    finite(p, "gate probability")?;
    if !(p > 0.0 && p < 1.0) {
        return Err(Error::OutOfRange {
            what: "gate probability",
            expected: "in (0, 1)",
        });
    }
    if dof == 0 || dof > MAX_DOF {
        return Err(Error::OutOfRange {
            what: "degrees of freedom",
            expected: "in 1..=10000",
        });
    }
    let mut hi = f64::from(dof).max(1.0);
    while chi_square_cdf(hi, dof) < p {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if chi_square_cdf(mid, dof) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// A validation gate: a measurement is accepted when its normalised innovation squared
/// `NIS = yᵀ S⁻¹ y` is at most `threshold`, the chi-square quantile for `dof` degrees of
/// freedom (the measurement's dimension).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ChiSquareGate<T> {
    /// NIS threshold.
    pub threshold: T,
    /// Degrees of freedom the threshold was computed for; must equal the measurement's
    /// dimension when the gate is applied.
    pub dof: u32,
}

impl<T: Real> ChiSquareGate<T> {
    /// The gate that passes a fraction `p` of consistent measurements of dimension `dof`:
    /// `threshold = χ²_dof⁻¹(p)`, e.g. `(0.99, 2)` → 9.21, `(0.99, 1)` → 6.63.
    pub fn from_probability(p: f64, dof: u32) -> Result<Self, Error> {
        Ok(Self {
            threshold: T::lit(chi_square_quantile(p, dof)?),
            dof,
        })
    }

    /// `true` when `nis ≤ threshold`. NaN is never accepted.
    pub fn accepts(&self, nis: T) -> bool {
        nis <= self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textbook_quantiles() {
        // Values from standard chi-square tables (printed to 4 decimals).
        let table = [
            (0.95, 1, 3.8415),
            (0.99, 1, 6.6349),
            (0.95, 2, 5.9915),
            (0.99, 2, 9.2103),
            (0.95, 3, 7.8147),
            (0.99, 3, 11.3449),
            (0.025, 60, 40.4817),
            (0.975, 60, 83.2977),
        ];
        for (p, k, want) in table {
            let got = chi_square_quantile(p, k).unwrap();
            assert!((got - want).abs() < 6e-5, "p={p} k={k}: {got} vs {want}");
            // The quantile inverts the CDF to full precision.
            assert!((chi_square_cdf(got, k) - p).abs() < 1e-13);
        }
        // dof 2 has the closed form −2 ln(1 − p).
        let exact = -2.0 * (1.0_f64 - 0.99).ln();
        assert!((chi_square_quantile(0.99, 2).unwrap() - exact).abs() < 1e-12);
        let g = ChiSquareGate::<f32>::from_probability(0.99, 2).unwrap();
        assert!((g.threshold - 9.21034).abs() < 1e-4);
        assert!(g.accepts(9.2) && !g.accepts(9.3) && !g.accepts(f32::NAN));
    }

    #[test]
    fn large_degrees_of_freedom() {
        // The quantile at the mean of χ²(k) tends to ½ (Wilson–Hilferty: the median is
        // about k(1 − 2/(9k))³); the 95 % band of an NEES average over 100 runs of 3 dof.
        for k in [300_u32, 1000, 5000, MAX_DOF] {
            let median = chi_square_quantile(0.5, k).unwrap();
            let wh = f64::from(k) * (1.0 - 2.0 / (9.0 * f64::from(k))).powi(3);
            assert!((median - wh).abs() < 1e-3 * wh, "k={k}: {median} vs {wh}");
            assert!((chi_square_cdf(median, k) - 0.5).abs() < 1e-12);
        }
        // Tables: χ²₀.₀₂₅(300) = 253.9, χ²₀.₉₇₅(300) = 349.9.
        assert!((chi_square_quantile(0.025, 300).unwrap() - 253.912).abs() < 0.01);
        assert!((chi_square_quantile(0.975, 300).unwrap() - 349.874).abs() < 0.01);
    }

    #[test]
    fn bad_arguments() {
        assert!(chi_square_quantile(1.0, 2).is_err());
        assert!(chi_square_quantile(0.5, 0).is_err());
        assert!(chi_square_quantile(0.5, MAX_DOF + 1).is_err());
        assert!(chi_square_quantile(f64::NAN, 2).is_err());
    }
}

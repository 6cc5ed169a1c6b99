//! A synthetic compass made from reference poses plus seeded Gaussian noise, for logs
//! that have no compass. The records say `synthetic: true`.
//!
//! The noise comes from SplitMix64 and the Box–Muller transform: a few lines, fully
//! deterministic for a seed on every platform, and no dependency for one normal draw.

use super::record::Compass;
use ekf_core::{wrap_angle, Pose2};

/// Options of the synthetic compass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SyntheticCompass {
    /// Standard deviation of the heading noise (degrees, as configured by users).
    pub sigma_deg: f64,
    /// Seed of the noise; the same seed gives the same headings.
    pub seed: u64,
}

/// Draws the synthetic headings.
#[derive(Debug, Clone)]
pub(crate) struct CompassNoise {
    sigma_rad: f64,
    state: u64,
}

impl CompassNoise {
    pub(crate) fn new(options: SyntheticCompass) -> Self {
        Self {
            sigma_rad: options.sigma_deg.to_radians(),
            state: options.seed,
        }
    }

    /// A compass reading at `t_ns` for the true pose `reference`.
    pub(crate) fn reading(&mut self, t_ns: u64, reference: &Pose2<f64>) -> Compass {
        Compass {
            t_ns,
            heading: wrap_angle(reference.theta + self.sigma_rad * self.standard_normal()),
            variance: self.sigma_rad * self.sigma_rad,
            synthetic: true,
        }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1]: the top 53 bits, shifted off zero so `ln` is finite.
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    fn standard_normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_seeded_and_roughly_standard() {
        let options = SyntheticCompass {
            sigma_deg: 2.0,
            seed: 7,
        };
        let mut a = CompassNoise::new(options);
        let mut b = CompassNoise::new(options);
        let n = 20_000;
        let draws: Vec<f64> = (0..n).map(|_| a.standard_normal()).collect();
        let again: Vec<f64> = (0..n).map(|_| b.standard_normal()).collect();
        assert_eq!(draws, again);
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|d| (d - mean) * (d - mean)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
    }

    #[test]
    fn reading_is_labelled_and_wrapped() {
        let mut noise = CompassNoise::new(SyntheticCompass {
            sigma_deg: 1.0,
            seed: 1,
        });
        let c = noise.reading(5, &Pose2::new(0.0, 0.0, core::f64::consts::PI - 1e-4));
        assert!(c.synthetic);
        assert_eq!(c.t_ns, 5);
        assert!(c.heading > -core::f64::consts::PI && c.heading <= core::f64::consts::PI);
        assert!((c.variance - 1f64.to_radians().powi(2)).abs() < 1e-15);
    }
}

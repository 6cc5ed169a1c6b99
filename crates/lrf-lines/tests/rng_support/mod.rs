//! The seeded generator of the extraction and matching test support: SplitMix64 uniforms
//! and Box–Muller normals, tiny and deterministic, good enough for noise.

/// SplitMix64 with Box–Muller normals.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller) with `u1 = 1 − uniform`, in (0, 1]: the draws of the
    /// extraction tests.
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        self.box_muller(u1)
    }

    /// Standard normal (Box–Muller) with `u1 = uniform` floored at 1e-300: the draws of the
    /// map, matching and localizer tests, another sequence than [`Rng::normal`]'s from the
    /// same seed, kept so that their seeded noise stays as it was.
    pub fn normal_floored(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        self.box_muller(u1)
    }

    /// The Box–Muller normal of `u1` and the next uniform.
    fn box_muller(&mut self, u1: f64) -> f64 {
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

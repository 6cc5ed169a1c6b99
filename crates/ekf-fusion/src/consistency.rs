//! A consistency monitor on the laser innovations: does the filter's covariance explain
//! the lines it fuses?
//!
//! The lines a scan fuses, one after the other, have NIS values whose sum is the scan's
//! joint NIS, chi-square with two degrees of freedom per line when the filter is
//! consistent. Over the last [`WINDOW_SCANS`] scans that fused lines the sums add up, and
//! so do the degrees of freedom. The filter counts as **over-confident** while the
//! window's NIS is above the [`BAND_PROBABILITY`] quantile of its chi-square
//! distribution: the innovations are larger than its covariance says they can be (motion
//! noisier than its model, a map that is off, a wrong association). Each line passed a
//! 2-dof gate before it was fused, which cuts off large values, so a window above the
//! band is far outside it.
//!
//! The monitor reports (the counts, and [`crate::ScanFused::over_confident`] at the start
//! of each over-confident stretch, which `ekf replay` turns into one `/ekf/diagnostics`
//! message); it does not change the filter.

use alloc::collections::VecDeque;
use ekf_core::chi_square_cdf;

/// Scans with fused lines in the window.
pub const WINDOW_SCANS: usize = 20;

/// The window's NIS is over-confident above this quantile of its chi-square distribution.
pub const BAND_PROBABILITY: f64 = 0.999;

/// `Φ⁻¹(BAND_PROBABILITY)`, the standard normal quantile of the band.
const BAND_NORMAL_QUANTILE: f64 = 3.090_232_306_167_813_5;

/// Half-width of the relative band around the Wilson–Hilferty quantile within which
/// [`above_band`] computes the exact CDF; the approximation's relative error at the
/// band's probability is far below it (2.3 % at 2 dof, 0.13 % at the 40 dof a full
/// window has at least, less beyond; tested).
const APPROXIMATION_MARGIN: f64 = 0.05;

/// What the monitor saw over a run.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ConsistencyCounts {
    /// Scans that fused lines.
    pub scans: u64,
    /// Of those, scans that ended a full window above the band.
    pub over_confident_scans: u64,
    /// Stretches of over-confident scans.
    pub over_confident_stretches: u64,
    /// The NIS of every fused line summed, over its degrees of freedom (1 when
    /// consistent, less because of the gates); `None` before a line is fused.
    pub nis_per_dof: Option<f64>,
}

/// The monitor's window.
#[derive(Debug, Clone, Default)]
pub struct ConsistencyMonitor {
    window: VecDeque<(f64, u32)>,
    window_nis: f64,
    window_dof: u32,
    total_nis: f64,
    total_dof: u64,
    over: bool,
}

impl ConsistencyMonitor {
    /// Takes the NIS of the lines one scan fused; returns `true` if the filter has just
    /// become over-confident (the first scan of a stretch).
    pub fn scan(
        &mut self,
        fused_nis: impl IntoIterator<Item = f64>,
        counts: &mut ConsistencyCounts,
    ) -> bool {
        let (mut nis, mut dof) = (0.0, 0u32);
        for v in fused_nis {
            nis += v;
            dof += 2;
        }
        if dof == 0 {
            return false;
        }
        counts.scans += 1;
        self.total_nis += nis;
        self.total_dof += u64::from(dof);
        counts.nis_per_dof = Some(self.total_nis / self.total_dof as f64);
        self.window.push_back((nis, dof));
        self.window_nis += nis;
        self.window_dof += dof;
        if self.window.len() > WINDOW_SCANS {
            if let Some((n, d)) = self.window.pop_front() {
                self.window_nis -= n;
                self.window_dof -= d;
            }
        }
        let full = self.window.len() == WINDOW_SCANS;
        let over = full && above_band(self.window_nis, self.window_dof);
        let started = over && !self.over;
        self.over = over;
        counts.over_confident_scans += u64::from(over);
        counts.over_confident_stretches += u64::from(started);
        started
    }
}

/// The Wilson–Hilferty approximation of the chi-square quantile at [`BAND_PROBABILITY`]:
/// `k (1 − 2/(9k) + z √(2/(9k)))³`, `z = Φ⁻¹(BAND_PROBABILITY)`.
fn wilson_hilferty_band(dof: u32) -> f64 {
    let k = f64::from(dof);
    let v = 2.0 / (9.0 * k);
    let c = 1.0 - v + BAND_NORMAL_QUANTILE * libm::sqrt(v);
    k * c * c * c
}

/// Whether `nis` lies above the [`BAND_PROBABILITY`] quantile of chi-square(`dof`):
/// `nis > χ²⁻¹(p)` ⟺ `F(nis) > p`, `F` the CDF, which is increasing. The
/// Wilson–Hilferty quantile decides it outright when `nis` is more than
/// [`APPROXIMATION_MARGIN`] (relative) away from it; closer, one exact CDF evaluation
/// does, `O(dof)`. Bisecting for the exact quantile instead costs some sixty CDF
/// evaluations per new `dof`, milliseconds at the hundreds of dof a window reaches.
fn above_band(nis: f64, dof: u32) -> bool {
    let approximate = wilson_hilferty_band(dof);
    if nis > approximate * (1.0 + APPROXIMATION_MARGIN) {
        true
    } else if nis < approximate * (1.0 - APPROXIMATION_MARGIN) {
        false
    } else {
        chi_square_cdf(nis, dof) > BAND_PROBABILITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wilson_hilferty_band_is_well_within_the_margin_of_the_exact_quantile() {
        for dof in (2..=200).step_by(2).chain([400, 1000, 4000, 10_000]) {
            let exact = ekf_core::chi_square_quantile(BAND_PROBABILITY, dof).unwrap();
            let error = (wilson_hilferty_band(dof) / exact - 1.0).abs();
            // Measured: 2.30 % at 2 dof, 0.121 % at 40 (the least a full window has),
            // falling with the dof.
            let bound = if dof < 40 { 0.025 } else { 0.0013 };
            assert!(error < bound, "dof {dof}: relative error {error}");
        }
    }

    #[test]
    fn above_band_agrees_with_the_exact_quantile_on_both_sides() {
        for dof in [2, 4, 10, 40, 120, 400, 2000] {
            let q = ekf_core::chi_square_quantile(BAND_PROBABILITY, dof).unwrap();
            for f in [0.5, 0.9, 0.96, 0.999, 0.999_999] {
                assert!(!above_band(q * f, dof), "dof {dof}, {f} of the quantile");
            }
            for f in [1.000_001, 1.001, 1.04, 1.1, 2.0] {
                assert!(above_band(q * f, dof), "dof {dof}, {f} of the quantile");
            }
        }
    }

    #[test]
    fn a_window_of_consistent_scans_is_not_flagged_and_one_of_large_innovations_is() {
        let mut m = ConsistencyMonitor::default();
        let mut c = ConsistencyCounts::default();
        // Three lines a scan with NIS 2 each: exactly the mean of chi-square(2).
        for _ in 0..50 {
            assert!(!m.scan([2.0, 2.0, 2.0], &mut c));
        }
        assert_eq!((c.scans, c.over_confident_scans), (50, 0));
        assert_eq!(c.nis_per_dof, Some(1.0));
        // Scans without fused lines change nothing.
        assert!(!m.scan([], &mut c));
        assert_eq!(c.scans, 50);
        // Lines that pass their 2-dof gate (9.21) but sit near it, scan after scan:
        // 120 dof with a sum of 20·24 = 480, far above chi-square(120)'s 0.999 quantile
        // (173.6). The window fills with them after a few scans.
        let flagged: Vec<bool> = (0..20).map(|_| m.scan([8.0, 8.0, 8.0], &mut c)).collect();
        let first = flagged.iter().position(|&f| f).expect("flagged");
        assert_eq!(flagged.iter().filter(|&&f| f).count(), 1, "one stretch");
        assert!(first < 10, "flagged after {first} scans");
        assert_eq!(c.over_confident_stretches, 1);
        assert_eq!(c.over_confident_scans, 20 - first as u64);
        // Back to consistent lines: the stretch ends once they dominate the window.
        for _ in 0..40 {
            m.scan([2.0, 2.0, 2.0], &mut c);
        }
        assert!(!m.over);
        assert!(m.scan([8.0; 40], &mut c), "a new stretch is counted again");
        assert_eq!(c.over_confident_stretches, 2);
    }
}

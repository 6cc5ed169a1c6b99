//! Summary statistics of a set of non-negative errors, as `evo`'s
//! `get_all_statistics` reports them.

use super::EvalError;
use serde::Serialize;

/// Statistics of errors `e_1 … e_n`, with `evo`'s names and definitions (numpy):
///
/// - `rmse = √(Σ e_k² / n)`, `sse = Σ e_k²`
/// - `mean = Σ e_k / n`, `std = √(Σ (e_k − mean)² / n)` (population, numpy `ddof = 0`)
/// - `median`: the middle value, or the mean of the two middle values for even `n`
/// - `min`, `max`
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Statistics {
    /// Root mean square error.
    pub rmse: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Smallest error.
    pub min: f64,
    /// Largest error.
    pub max: f64,
    /// Sum of squared errors.
    pub sse: f64,
}

impl Statistics {
    /// The statistics of `errors`; fails with [`EvalError::NoErrors`] if it is empty.
    pub fn from_errors(errors: &[f64]) -> Result<Self, EvalError> {
        if errors.is_empty() {
            return Err(EvalError::NoErrors);
        }
        let n = errors.len() as f64;
        let sse: f64 = errors.iter().map(|e| e * e).sum();
        let mean = errors.iter().sum::<f64>() / n;
        let variance = errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n;
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let mid = sorted.len() / 2;
        let median = if sorted.len() % 2 == 1 {
            sorted[mid]
        } else {
            (sorted[mid - 1] + sorted[mid]) / 2.0
        };
        Ok(Self {
            rmse: (sse / n).sqrt(),
            mean,
            median,
            std: variance.sqrt(),
            min: sorted[0],
            max: sorted[sorted.len() - 1],
            sse,
        })
    }
}

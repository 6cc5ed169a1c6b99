//! The range noise of a scan, measured from the scan itself.
//!
//! Scanners differ far more than one default can cover: a SICK LMS 2xx in mm mode is good
//! to about 1 cm, while a PLS or an LMS logged at 5 cm resolution (four of the nine
//! CARMEN logs of docs/RESULTS.md) scatters its points about a wall by 2–4 cm. Line
//! extraction that assumes 1 cm cuts such walls into fragments too short to keep, and
//! gives the lines it keeps covariances several times too small.
//!
//! The measure: on a straight surface the middle one of three consecutive points lies on
//! the chord of the other two, so its distance from that chord,
//! `d = n·(p_i − (p_{i−1} + p_{i+1})/2)` (`n` the chord's unit normal), is noise alone,
//! with `var(d) = σ_ρ² (c_i² + (c_{i−1}² + c_{i+1}²)/4)`, `c_j = n·u_j` the cosine
//! between beam `j` and the normal (range noise acts along the beam). Each triple of one
//! run (the breakpoint rule's neighbours) whose beams meet the chord within
//! [`MAX_OBLIQUITY_COS`] gives `z = d / √(c_i² + (c_{i−1}² + c_{i+1}²)/4)`, a sample of
//! `σ_ρ`. Corners, clutter and edges are outliers among them: the estimate is the RMS of
//! the samples within [`CLIP_SIGMAS`] of the current estimate, started from the median
//! absolute sample and repeated [`CLIP_ROUNDS`] times, scaled for the clipped tails. (The
//! median alone reads quantised ranges wrong: with 5 cm steps half the samples are 0 or
//! ±2.5 cm exactly.)

use super::points::{Points, Run};
use alloc::vec::Vec;

/// Triples whose beams are all within this cosine of the chord's normal: more
/// obliquely, the point's noise hardly moves it off the chord and the sample says
/// little (cos 60°).
pub(crate) const MAX_OBLIQUITY_COS: f64 = 0.5;

/// Fewest samples for an estimate.
pub(crate) const MIN_SAMPLES: usize = 20;

/// Most triples looked at: a scan with more takes every `k`-th, evenly over the scan.
/// 256 samples give σ_ρ to about 5 % (one standard deviation), and keep the measure a
/// small part of extraction's cost on a 721-beam scanner.
pub(crate) const MAX_SAMPLES: usize = 256;

/// Samples farther than this many standard deviations from the chord are outliers.
const CLIP_SIGMAS: f64 = 3.0;

/// Clipping rounds after the median start.
const CLIP_ROUNDS: usize = 3;

/// `1/Φ⁻¹(3/4)`: the median absolute value of a standard normal sample is this many times
/// smaller than its standard deviation.
const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;

/// The standard deviation of a standard normal truncated to `±CLIP_SIGMAS` is this many
/// times smaller than 1: `√(1 − 2·3·φ(3)/(2Φ(3) − 1))`.
const CLIPPED_SIGMA: f64 = 0.986_582_7;

/// The range noise σ_ρ (m) of the points of `runs`, or `None` with fewer than
/// [`MIN_SAMPLES`] usable triples. `samples` is scratch space.
pub(crate) fn range_noise(
    points: &Points<'_>,
    runs: &[Run],
    samples: &mut Vec<f64>,
) -> Option<f64> {
    samples.clear();
    let triples: usize = runs.iter().map(|r| r.len().saturating_sub(2)).sum();
    let stride = triples.div_ceil(MAX_SAMPLES).max(1);
    let mut k = 0usize;
    for run in runs {
        for i in run.start + 1..run.end.saturating_sub(1) {
            k += 1;
            if !k.is_multiple_of(stride) {
                continue;
            }
            if let Some(z) = chord_sample(points, i) {
                samples.push(z);
            }
        }
    }
    if samples.len() < MIN_SAMPLES {
        return None;
    }
    let middle = samples.len() / 2;
    let (_, median, _) = samples.select_nth_unstable_by(middle, |a, b| a.total_cmp(b));
    let mut sigma = *median * MAD_TO_SIGMA;
    for _ in 0..CLIP_ROUNDS {
        let limit = CLIP_SIGMAS * sigma;
        let (sum, n) = samples
            .iter()
            .filter(|&&z| z <= limit)
            .fold((0.0, 0usize), |(s, n), &z| (s + z * z, n + 1));
        if n < MIN_SAMPLES {
            break;
        }
        sigma = libm::sqrt(sum / n as f64) / CLIPPED_SIGMA;
    }
    (sigma > 0.0 && sigma.is_finite()).then_some(sigma)
}

/// `|z|` of the triple centred on beam `i` (see the module doc), if its beams meet the
/// chord steeply enough.
fn chord_sample(points: &Points<'_>, i: usize) -> Option<f64> {
    let (x0, y0) = points.xy(i - 1)?;
    let (x1, y1) = points.xy(i)?;
    let (x2, y2) = points.xy(i + 1)?;
    let (dx, dy) = (x2 - x0, y2 - y0);
    let length_sq = dx * dx + dy * dy;
    if length_sq <= 0.0 {
        return None;
    }
    let inverse = 1.0 / libm::sqrt(length_sq);
    let (nx, ny) = (-dy * inverse, dx * inverse);
    let c = |j: usize| -> Option<f64> {
        Some(libm::fabs(
            points.cos.get(j)? * nx + points.sin.get(j)? * ny,
        ))
    };
    let (c0, c1, c2) = (c(i - 1)?, c(i)?, c(i + 1)?);
    if c0.min(c1).min(c2) < MAX_OBLIQUITY_COS {
        return None;
    }
    let d = nx * (x1 - 0.5 * (x0 + x2)) + ny * (y1 - 0.5 * (y0 + y2));
    Some(libm::fabs(d) / libm::sqrt(c1 * c1 + 0.25 * (c0 * c0 + c2 * c2)))
}

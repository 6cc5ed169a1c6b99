//! The [`LineExtractor`]: parameters plus the scratch buffers the pipeline reuses from
//! scan to scan.

use super::breakpoint::Breakpoint;
use super::fit::{fit_line, fit_trimmed, LineFit, PointNoise};
use super::merge::{mahalanobis_squared, merge_collinear, Candidate, MergeRule};
use super::points::{collect, BeamTable, Points, Run, ScanPoints};
use super::range_noise::range_noise;
use super::split::split_runs;
use super::{ExtractionError, ExtractionParams};
use crate::{LaserScan, ObservedLine};
use alloc::vec::Vec;
use core::ops::Range;
use ekf_core::{chi_square_quantile, Line};
use nalgebra::Point2;

/// Extracts [`ObservedLine`]s from laser scans. Keeps the cos/sin of the beam angles
/// (recomputed only when `angle_min`, `angle_increment` or the number of beams change)
/// and its working buffers, so after the first scan extraction does not allocate.
#[derive(Debug, Clone)]
pub struct LineExtractor {
    params: ExtractionParams,
    merge_rule: MergeRule,
    beams: BeamTable,
    scan: ScanPoints,
    stack: Vec<Run>,
    segments: Vec<Run>,
    candidates: Vec<Candidate>,
    /// Per line of the last scan, its range of `segments`.
    supports: Vec<Range<usize>>,
    /// Scratch for the range noise measure.
    noise_samples: Vec<f64>,
    /// The last scan's range noise as measured (m), if it had enough samples.
    measured_range_sigma: Option<f64>,
    /// The split distance the last scan was extracted with (m).
    split_distance: f64,
}

/// A scan whose measured range noise σ_ρ exceeds `range_sigma` is split where a point is
/// farther from its chord than this many σ_ρ, when that is more than `split_distance`.
/// Three: the measured σ_ρ already holds the scan's whole scatter (a reading quantised
/// to 5 cm steps is at most 2.5 cm, 1.7σ, off), and a larger multiple leaves corners
/// between walls at shallow angles unsplit (5σ of such a scanner is 12 cm).
pub const SPLIT_SIGMAS: f64 = 3.0;

impl LineExtractor {
    /// An extractor with validated `params`; the merge gate is the chi-square quantile
    /// `χ²₂⁻¹(merge_probability)` (9.21 for 0.99).
    pub fn new(params: ExtractionParams) -> Result<Self, ExtractionError> {
        let params = params.validated()?;
        let gate = chi_square_quantile(params.merge_probability, 2).map_err(|_| {
            ExtractionError::InvalidParameter {
                name: "merge_probability",
                expected: "a probability in (0, 1)",
            }
        })?;
        Ok(Self {
            params,
            merge_rule: MergeRule {
                gate,
                noise: PointNoise {
                    range_var: params.range_sigma * params.range_sigma,
                    bearing_var: params.bearing_sigma * params.bearing_sigma,
                },
            },
            beams: BeamTable::default(),
            scan: ScanPoints::default(),
            stack: Vec::new(),
            segments: Vec::new(),
            candidates: Vec::new(),
            supports: Vec::new(),
            noise_samples: Vec::new(),
            measured_range_sigma: None,
            split_distance: params.split_distance,
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &ExtractionParams {
        &self.params
    }

    /// The range noise σ_ρ (m) the last scan's points showed, if it had enough straight
    /// stretches to tell: the scatter of each point about the chord of its two neighbours
    /// (docs/ARCHITECTURE.md §3). A scanner noisier than `range_sigma` (one that reports
    /// 5 cm steps, say) is then extracted and weighted with this instead.
    pub fn measured_range_sigma(&self) -> Option<f64> {
        self.measured_range_sigma
    }

    /// Clears `out` and fills it with the lines of `scan`, in scan order.
    ///
    /// Steps: valid readings → points, cut into runs at invalid beams and at gaps over
    /// `max(max_point_gap, ρ · sin Δφ / sin(min_incidence − Δφ) + 3 range_sigma)` (the
    /// adaptive breakpoint rule, `ρ` the nearer range); the scan's range noise measured
    /// from its runs (see [`measured_range_sigma`](Self::measured_range_sigma)), and
    /// `σ_ρ = max(range_sigma, measured)` used from here on; each run split at the point
    /// farthest from its chord while that distance exceeds
    /// `max(split_distance, `[`SPLIT_SIGMAS`]` σ_ρ)` (the split point moved to where the
    /// points change sides once both pieces are straight); pieces with fewer than
    /// `min_points` points or a chord shorter than `min_length` dropped; a weighted fit
    /// per piece (Pfister et al., covariance = inverse Fisher information, with `σ_ρ`),
    /// with end points beyond 3σ trimmed;
    /// neighbours merged and refitted when
    /// `(Δr, Δψ)ᵀ(Σ_a + Σ_b)⁻¹(Δr, Δψ) ≤ χ²₂⁻¹(merge_probability)` and their gap passes
    /// the same breakpoint rule; lines shorter than `min_length` dropped. End points are the
    /// first and last points projected onto the line. A scan without valid readings gives no lines; only an invalid header is an
    /// error ([`ExtractionError::InvalidScan`]).
    pub fn extract(
        &mut self,
        scan: &LaserScan<'_>,
        out: &mut Vec<ObservedLine>,
    ) -> Result<(), ExtractionError> {
        out.clear();
        self.supports.clear();
        scan.validate()?;
        self.beams.update(scan);
        let breakpoint = Breakpoint::new(
            self.params.max_point_gap,
            self.params.min_incidence,
            scan.angle_increment,
            self.params.range_sigma,
        );
        collect(scan, &self.beams, &breakpoint, &mut self.scan);
        let points = self.scan.points(&self.beams);
        self.measured_range_sigma = range_noise(&points, &self.scan.runs, &mut self.noise_samples);
        let range_sigma = self
            .measured_range_sigma
            .map_or(self.params.range_sigma, |s| s.max(self.params.range_sigma));
        self.merge_rule.noise.range_var = range_sigma * range_sigma;
        self.split_distance = self.params.split_distance.max(SPLIT_SIGMAS * range_sigma);
        self.segments.clear();
        split_runs(
            &self.scan,
            &points,
            self.split_distance,
            self.params.min_points,
            &mut self.stack,
            &mut self.segments,
        );
        fit_segments(
            &points,
            &mut self.segments,
            &mut self.candidates,
            &self.params,
            &self.merge_rule.noise,
        );
        merge_collinear(
            &points,
            &self.segments,
            &mut self.candidates,
            &self.merge_rule,
            &breakpoint,
        );
        for c in &self.candidates {
            if let Some(line) = observed_line(&points, &self.segments, c) {
                if line.length() >= self.params.min_length {
                    out.push(line);
                    self.supports.push(c.support.clone());
                }
            }
        }
        Ok(())
    }
}

impl LineExtractor {
    /// The line fitted (weighted least squares, as [`extract`](Self::extract) fits, without
    /// trimming) to the points of the last extracted scan's beams `pieces` — ranges of
    /// beam indices, in scan order, all of valid readings — with the end points the first
    /// and last points projected onto it. `None` if the points do not determine a line,
    /// a range lies outside the scan, or a point lies farther than `split_distance` from
    /// the line (where extraction would split them: they are not one straight wall).
    pub(crate) fn fit_beams(&self, pieces: &[Range<usize>]) -> Option<ObservedLine> {
        let points = self.scan.points(&self.beams);
        let fit = fit_line(&points, pieces, &self.merge_rule.noise)?;
        let (s, c) = libm::sincos(fit.psi);
        for piece in pieces {
            let (xs, ys) = (points.x.get(piece.clone())?, points.y.get(piece.clone())?);
            let straight = xs
                .iter()
                .zip(ys)
                .all(|(&x, &y)| libm::fabs(x * c + y * s - fit.r) <= self.split_distance);
            if !straight {
                return None;
            }
        }
        observed_line(
            &points,
            pieces,
            &Candidate {
                support: 0..pieces.len(),
                fit,
            },
        )
    }

    /// Whether two observed lines are one line by the test extraction merges neighbours
    /// with: `(Δr, Δψ)ᵀ(Σ_a + Σ_b)⁻¹(Δr, Δψ) ≤ χ²₂⁻¹(merge_probability)`.
    pub(crate) fn collinear(&self, a: &ObservedLine, b: &ObservedLine) -> bool {
        let fit = |l: &ObservedLine| LineFit {
            r: l.line.rho,
            psi: l.line.beta,
            covariance: l.covariance,
        };
        mahalanobis_squared(&fit(a), &fit(b)).is_some_and(|d2| d2 <= self.merge_rule.gate)
    }

    /// The beams of the `line`-th line of the last extracted scan: ranges of beam indices
    /// in scan order, what [`fit_beams`](Self::fit_beams) takes.
    pub(crate) fn beams_of(&self, line: usize) -> Option<&[Range<usize>]> {
        self.segments.get(self.supports.get(line)?.clone())
    }

    /// The last extracted scan's beams as unit directions in the sensor frame,
    /// `(cos φ_i, sin φ_i)`.
    pub(crate) fn beam_directions(&self) -> (&[f64], &[f64]) {
        self.beams.directions()
    }
}

/// Fits every segment long enough (trimming outlying end points) into `candidates`, one
/// piece each, and keeps in `segments` the fitted pieces only (their trimmed beam ranges,
/// in order), so the candidates' supports tile it without holes: a merge then refits its
/// pieces, never the dropped clutter between them.
fn fit_segments(
    points: &Points<'_>,
    segments: &mut Vec<Run>,
    candidates: &mut Vec<Candidate>,
    params: &ExtractionParams,
    noise: &PointNoise,
) {
    candidates.clear();
    let mut kept = 0;
    for i in 0..segments.len() {
        let Some(seg) = segments.get(i).cloned() else {
            continue;
        };
        let (Some(first), Some(last)) = (
            points.xy(seg.start),
            seg.end.checked_sub(1).and_then(|i| points.xy(i)),
        ) else {
            continue;
        };
        if seg.len() < params.min_points
            || libm::hypot(last.0 - first.0, last.1 - first.1) < params.min_length
        {
            continue;
        }
        let Some((piece, fit)) = fit_trimmed(points, seg, noise, params.min_points) else {
            continue;
        };
        if let Some(slot) = segments.get_mut(kept) {
            *slot = piece;
        }
        candidates.push(Candidate {
            support: kept..kept + 1,
            fit,
        });
        kept += 1;
    }
    segments.truncate(kept);
}

/// The candidate as an [`ObservedLine`], end points projected onto the fitted line.
fn observed_line(points: &Points<'_>, pieces: &[Run], c: &Candidate) -> Option<ObservedLine> {
    let line = Line::new(c.fit.r, c.fit.psi).ok()?;
    let support = pieces.get(c.support.clone())?;
    let first = points.xy(support.first()?.start)?;
    let last = points.xy(support.last()?.end.checked_sub(1)?)?;
    Some(ObservedLine {
        line,
        covariance: c.fit.covariance,
        start: line.project(&Point2::new(first.0, first.1)),
        end: line.project(&Point2::new(last.0, last.1)),
        num_points: support.iter().map(Run::len).sum(),
    })
}

//! The [`LineExtractor`]: parameters plus the scratch buffers the pipeline reuses from
//! scan to scan.

use super::fit::{fit_trimmed, PointNoise};
use super::merge::{merge_collinear, Candidate, MergeRule};
use super::points::{collect, BeamTable, Run, ScanPoint, ScanPoints};
use super::split::split_runs;
use super::{ExtractionError, ExtractionParams};
use crate::{LaserScan, ObservedLine};
use alloc::vec::Vec;
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
}

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
                max_gap: params.max_point_gap,
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
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &ExtractionParams {
        &self.params
    }

    /// Clears `out` and fills it with the lines of `scan`, in scan order.
    ///
    /// Steps: valid readings → points, cut into runs at invalid beams and at gaps over
    /// `max_point_gap`; each run split at the point farthest from its chord while that
    /// distance exceeds `split_distance` (the split point moved to where the points change
    /// sides once both pieces are straight); pieces with fewer than `min_points` points or
    /// a chord shorter than `min_length` dropped; a weighted fit per piece (Pfister et al.,
    /// covariance = inverse Fisher information), with end points beyond 3σ trimmed;
    /// neighbours merged and refitted when
    /// `(Δr, Δψ)ᵀ(Σ_a + Σ_b)⁻¹(Δr, Δψ) ≤ χ²₂⁻¹(merge_probability)` and their gap is at
    /// most `max_point_gap`; lines shorter than `min_length` dropped. End points are the
    /// first and last points projected onto the line. A scan without valid readings gives no lines; only an invalid header is an
    /// error ([`ExtractionError::InvalidScan`]).
    pub fn extract(
        &mut self,
        scan: &LaserScan<'_>,
        out: &mut Vec<ObservedLine>,
    ) -> Result<(), ExtractionError> {
        out.clear();
        scan.validate()?;
        self.beams.update(scan);
        collect(scan, &self.beams, self.params.max_point_gap, &mut self.scan);
        self.segments.clear();
        split_runs(
            &self.scan,
            self.params.split_distance,
            self.params.min_points,
            &mut self.stack,
            &mut self.segments,
        );
        self.fit_segments();
        merge_collinear(&self.scan.points, &mut self.candidates, &self.merge_rule);
        for c in &self.candidates {
            if let Some(line) = observed_line(&self.scan.points, c) {
                if line.length() >= self.params.min_length {
                    out.push(line);
                }
            }
        }
        Ok(())
    }

    /// Fits every segment long enough (trimming outlying end points), and moves the
    /// fitted points to the front of the point buffer so the kept segments tile it without
    /// holes: a merge then refits one contiguous range, never the dropped clutter between
    /// two pieces. Compaction writes at or before the segment being read (`copy_within`).
    fn fit_segments(&mut self) {
        self.candidates.clear();
        let mut write = 0;
        for seg in &self.segments {
            let (Some(first), Some(last)) = (
                self.scan.points.get(seg.start),
                seg.end.checked_sub(1).and_then(|i| self.scan.points.get(i)),
            ) else {
                continue;
            };
            if seg.len() < self.params.min_points
                || libm::hypot(last.x - first.x, last.y - first.y) < self.params.min_length
            {
                continue;
            }
            let Some((kept, fit)) = self
                .scan
                .points
                .get(seg.clone())
                .and_then(|p| fit_trimmed(p, &self.merge_rule.noise, self.params.min_points))
            else {
                continue;
            };
            let support = write..write + kept.len();
            self.scan
                .points
                .copy_within(seg.start + kept.start..seg.start + kept.end, write);
            write = support.end;
            self.candidates.push(Candidate { support, fit });
        }
        // From here on `scan.points` holds the candidates' supports only; its runs and
        // prefix sums are stale until the next `collect`.
        self.scan.points.truncate(write);
    }
}

/// The candidate as an [`ObservedLine`], end points projected onto the fitted line.
fn observed_line(points: &[ScanPoint], c: &Candidate) -> Option<ObservedLine> {
    let line = Line::new(c.fit.r, c.fit.psi).ok()?;
    let first = points.get(c.support.start)?;
    let last = points.get(c.support.end.checked_sub(1)?)?;
    Some(ObservedLine {
        line,
        covariance: c.fit.covariance,
        start: line.project(&Point2::new(first.x, first.y)),
        end: line.project(&Point2::new(last.x, last.y)),
        num_points: c.support.len(),
    })
}

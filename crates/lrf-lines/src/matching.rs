//! Data association: which map wall each observed line is, by the Mahalanobis distance in
//! innovation space (ekf-core's laser-line model), a chi-square gate and a segment-overlap
//! check, with each map wall used at most once per scan.

use crate::map::{interval_along, LineMap};
use crate::ObservedLine;
use alloc::vec::Vec;
use core::fmt;
use ekf_core::{angle_diff, ChiSquareGate, Ekf, Error, Innovation, LaserLine, Pose2};
use nalgebra::Point2;
use serde::{Deserialize, Serialize};

/// Matching parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MatchParams {
    /// Probability of the chi-square gate on the 2-D line innovation: a pair is a
    /// candidate when `NIS = yᵀ S⁻¹ y ≤ χ²₂⁻¹(p)`. Default 0.99 (threshold 9.21).
    pub gate_probability: f64,
    /// Overlap (m) along the map wall that always suffices; see
    /// [`min_overlap_fraction`](Self::min_overlap_fraction). Default 0.2 m.
    pub min_overlap: f64,
    /// The required overlap is `min(min_overlap, min_overlap_fraction · ℓ)`, `ℓ` the
    /// length of the observed segment projected onto the wall, so a short observed
    /// segment must lie mostly on the wall and a long one needs `min_overlap`. Default 0.5.
    pub min_overlap_fraction: f64,
}

impl Default for MatchParams {
    fn default() -> Self {
        Self {
            gate_probability: 0.99,
            min_overlap: 0.2,
            min_overlap_fraction: 0.5,
        }
    }
}

/// An observed line associated with a map wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineMatch {
    /// Index of the observed line.
    pub observed: usize,
    /// Index of the map wall in [`LineMap::segments`].
    pub map: usize,
    /// The innovation at the state matching was run at: `y = (r, ψ) − (r̂, ψ̂)` (ψ
    /// wrapped), its covariance `S = H P Hᵀ + R`, and `NIS = yᵀ S⁻¹ y`.
    pub innovation: Innovation<f64, 2>,
    /// Length (m) by which the observed segment, projected into the world at the
    /// predicted sensor pose, overlaps the wall along the wall's direction.
    pub overlap: f64,
}

/// Why an observed line was not matched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RejectReason {
    /// No map wall within the chi-square gate.
    OutsideGate,
    /// Some walls passed the gate but none overlapped the observed segment enough;
    /// `map` is the one with the smallest NIS.
    NoOverlap {
        /// The closest wall (by NIS) that passed the gate.
        map: usize,
    },
    /// Every wall that passed both tests was taken by another observed line with a
    /// smaller NIS; `map` is this line's best wall, `by` the line that took it.
    MapLineTaken {
        /// This line's best wall.
        map: usize,
        /// The observed line it was assigned to.
        by: usize,
    },
    /// The observed line has a non-finite value or a covariance that is not symmetric
    /// positive definite.
    InvalidLine(Error),
}

impl fmt::Display for RejectReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RejectReason::OutsideGate => f.write_str("outside gate"),
            RejectReason::NoOverlap { map } => write!(f, "no overlap (closest map line {map})"),
            RejectReason::MapLineTaken { map, by } => write!(
                f,
                "map line {map} already taken by a better match (observed line {by})"
            ),
            RejectReason::InvalidLine(e) => write!(f, "invalid line: {e}"),
        }
    }
}

/// An observed line that was not matched, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rejection {
    /// Index of the observed line.
    pub observed: usize,
    /// Why it was not matched.
    pub reason: RejectReason,
}

/// A gated pair that also passed the overlap check.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    observed: usize,
    map: usize,
    innovation: Innovation<f64, 2>,
    overlap: f64,
}

/// What is known about one observed line while matching.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Status {
    Unmatched(RejectReason),
    Matched,
}

/// Per-wall values computed once per scan: `cos β`, `sin β` and the wall's extent along
/// its direction.
#[derive(Debug, Clone, Copy)]
struct WallCache {
    cos: f64,
    sin: f64,
    extent: (f64, f64),
}

/// The result of matching one scan, reused across scans: [`Matcher::match_lines`] clears
/// and refills its buffers, so once they have grown to the largest scan and map, matching
/// does not allocate.
#[derive(Debug, Clone, Default)]
pub struct MatchResult {
    matches: Vec<LineMatch>,
    rejections: Vec<Rejection>,
    candidates: Vec<Candidate>,
    status: Vec<Status>,
    owner: Vec<Option<usize>>,
    walls: Vec<WallCache>,
}

impl MatchResult {
    /// An empty result; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// The matches, in the order they were assigned (increasing NIS).
    pub fn matches(&self) -> &[LineMatch] {
        &self.matches
    }

    /// The observed lines that were not matched, by increasing observed index.
    pub fn rejections(&self) -> &[Rejection] {
        &self.rejections
    }

    /// The match of observed line `observed`, if it has one.
    pub fn match_of(&self, observed: usize) -> Option<&LineMatch> {
        self.matches.iter().find(|m| m.observed == observed)
    }

    fn clear(&mut self, num_observed: usize, num_walls: usize) {
        self.matches.clear();
        self.rejections.clear();
        self.candidates.clear();
        self.status.clear();
        self.status
            .resize(num_observed, Status::Unmatched(RejectReason::OutsideGate));
        self.owner.clear();
        self.owner.resize(num_walls, None);
        self.walls.clear();
    }
}

/// Associates observed lines with map walls.
///
/// For every pair (observed line `i`, wall `j`) at the filter's current state (the
/// predicted pose `x⁻` and covariance `P⁻`), the innovation of ekf-core's [`LaserLine`]
/// model gives `NIS_ij = yᵀ S⁻¹ y`. A pair is a candidate when
/// 1. `NIS_ij ≤ χ²₂⁻¹(gate_probability)`, and
/// 2. the observed segment, its end points mapped into the world with the predicted
///    sensor pose `x⁻ ⊕ mount` and projected onto the wall's direction, overlaps the
///    wall's extent by at least `min(min_overlap, min_overlap_fraction · ℓ)`.
///
/// Conflicts are resolved globally and greedily: candidates are sorted by NIS (ties by
/// observed, then wall index) and assigned in that order, skipping lines already matched
/// and walls already taken. So each wall is used at most once, and a wall goes to the
/// line that fits it best. Pairs whose heading residual alone exceeds the gate
/// (`NIS ≥ y_ψ² / S_ψψ`, `S_ψψ = P_θθ + R_ψψ`) are skipped before the full innovation
/// is computed; this changes no decision.
#[derive(Debug, Clone)]
pub struct Matcher {
    params: MatchParams,
    gate: ChiSquareGate<f64>,
}

impl Matcher {
    /// A matcher with `params`. Fails on a gate probability outside (0, 1), or a negative
    /// or non-finite overlap parameter.
    pub fn new(params: MatchParams) -> Result<Self, Error> {
        let gate = ChiSquareGate::from_probability(params.gate_probability, 2)?;
        for (v, what) in [
            (params.min_overlap, "matching min_overlap"),
            (params.min_overlap_fraction, "matching min_overlap_fraction"),
        ] {
            if !v.is_finite() {
                return Err(Error::NonFinite { what });
            }
            if v < 0.0 {
                return Err(Error::OutOfRange {
                    what,
                    expected: ">= 0",
                });
            }
        }
        Ok(Self { params, gate })
    }

    /// The parameters.
    pub fn params(&self) -> &MatchParams {
        &self.params
    }

    /// The chi-square gate (2 dof).
    pub fn gate(&self) -> &ChiSquareGate<f64> {
        &self.gate
    }

    /// Matches `observed` (sensor frame) against `map` at the state of `ekf`, with the
    /// laser mounted at `mount` on the robot, into `out` (cleared first). Never fails:
    /// an invalid observed line is rejected with [`RejectReason::InvalidLine`], and a
    /// wall whose innovation cannot be computed (non-finite) is never a candidate.
    pub fn match_lines(
        &self,
        observed: &[ObservedLine],
        map: &LineMap,
        ekf: &Ekf<f64>,
        mount: &Pose2<f64>,
        out: &mut MatchResult,
    ) {
        out.clear(observed.len(), map.segments.len());
        let sensor = ekf.pose().compose(mount);
        for segment in &map.segments {
            let (sin, cos) = (libm::sin(segment.line.beta), libm::cos(segment.line.beta));
            out.walls.push(WallCache {
                cos,
                sin,
                extent: interval_along(&segment.line, &segment.start, &segment.end),
            });
        }
        for (i, line) in observed.iter().enumerate() {
            if let Err(e) = validate_observed(line) {
                out.status[i] = Status::Unmatched(RejectReason::InvalidLine(e));
                continue;
            }
            self.gate_line(i, line, map, ekf, mount, &sensor, out);
        }
        out.candidates.sort_unstable_by(|a, b| {
            a.innovation
                .nis
                .total_cmp(&b.innovation.nis)
                .then(a.observed.cmp(&b.observed))
                .then(a.map.cmp(&b.map))
        });
        for c in &out.candidates {
            match (out.status[c.observed], out.owner[c.map]) {
                (Status::Matched, _) => {}
                (Status::Unmatched(_), None) => {
                    out.status[c.observed] = Status::Matched;
                    out.owner[c.map] = Some(c.observed);
                    out.matches.push(LineMatch {
                        observed: c.observed,
                        map: c.map,
                        innovation: c.innovation,
                        overlap: c.overlap,
                    });
                }
                // The first taken wall met in NIS order is this line's best one.
                (Status::Unmatched(RejectReason::MapLineTaken { .. }), Some(_)) => {}
                (Status::Unmatched(_), Some(by)) => {
                    out.status[c.observed] =
                        Status::Unmatched(RejectReason::MapLineTaken { map: c.map, by });
                }
            }
        }
        for (i, status) in out.status.iter().enumerate() {
            if let Status::Unmatched(reason) = status {
                out.rejections.push(Rejection {
                    observed: i,
                    reason: *reason,
                });
            }
        }
    }

    /// Finds the candidate walls of one valid observed line and records why it has none.
    #[allow(clippy::too_many_arguments)]
    fn gate_line(
        &self,
        i: usize,
        line: &ObservedLine,
        map: &LineMap,
        ekf: &Ekf<f64>,
        mount: &Pose2<f64>,
        sensor: &Pose2<f64>,
        out: &mut MatchResult,
    ) {
        let threshold = self.gate.threshold;
        let s_psi = ekf.covariance()[(2, 2)] + line.covariance[(1, 1)];
        let a = sensor.transform_point(&line.start);
        let b = sensor.transform_point(&line.end);
        let mut closest_without_overlap: Option<(usize, f64)> = None;
        for (j, (segment, wall)) in map.segments.iter().zip(&out.walls).enumerate() {
            // Heading residual: ψ̂ = β − θ_s (+π if C < 0), C = ρ − x_s cos β − y_s sin β.
            let c = segment.line.rho - sensor.x * wall.cos - sensor.y * wall.sin;
            let flip = if c < 0.0 { core::f64::consts::PI } else { 0.0 };
            let y_psi = angle_diff(line.line.beta, segment.line.beta - sensor.theta + flip);
            if !(y_psi * y_psi <= threshold * s_psi) {
                continue;
            }
            let model = LaserLine {
                observed: line.line,
                covariance: line.covariance,
                map_line: segment.line,
                mount: *mount,
            };
            let Ok(innovation) = ekf.innovation(&model) else {
                continue;
            };
            if !self.gate.accepts(innovation.nis) {
                continue;
            }
            match overlap(wall, &a, &b, &self.params) {
                Some(overlap) => out.candidates.push(Candidate {
                    observed: i,
                    map: j,
                    innovation,
                    overlap,
                }),
                None => {
                    if closest_without_overlap.is_none_or(|(_, nis)| innovation.nis < nis) {
                        closest_without_overlap = Some((j, innovation.nis));
                    }
                }
            }
        }
        if let Some((map, _)) = closest_without_overlap {
            out.status[i] = Status::Unmatched(RejectReason::NoOverlap { map });
        }
    }
}

/// `Some(overlap length)` if the observed segment `a–b` (world frame) overlaps the wall's
/// extent along the wall's direction `d = (−sin β, cos β)` by at least
/// `min(min_overlap, min_overlap_fraction · ℓ)`.
fn overlap(
    wall: &WallCache,
    a: &Point2<f64>,
    b: &Point2<f64>,
    params: &MatchParams,
) -> Option<f64> {
    let (ta, tb) = (
        -a.x * wall.sin + a.y * wall.cos,
        -b.x * wall.sin + b.y * wall.cos,
    );
    let (lo, hi) = (ta.min(tb), ta.max(tb));
    let overlap = hi.min(wall.extent.1) - lo.max(wall.extent.0);
    let required = params
        .min_overlap
        .min(params.min_overlap_fraction * (hi - lo));
    (overlap >= required).then_some(overlap)
}

/// Fails unless the line, its end points and covariance are finite and the covariance is
/// symmetric positive definite.
pub(crate) fn validate_observed(observed: &ObservedLine) -> Result<(), Error> {
    let values = [
        observed.line.rho,
        observed.line.beta,
        observed.start.x,
        observed.start.y,
        observed.end.x,
        observed.end.y,
    ];
    if values
        .iter()
        .chain(observed.covariance.iter())
        .any(|v| !v.is_finite())
    {
        return Err(Error::NonFinite {
            what: "observed line",
        });
    }
    let c = &observed.covariance;
    let scale = c.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if (c[(0, 1)] - c[(1, 0)]).abs() > 1e-9 * scale {
        return Err(Error::NotSymmetric {
            what: "observed line covariance",
        });
    }
    if c.cholesky().is_none() {
        return Err(Error::NotPositiveDefinite {
            what: "observed line covariance",
        });
    }
    Ok(())
}

//! Data association: which map wall each observed line is, by the Mahalanobis distance in
//! innovation space (ekf-core's laser-line model), a chi-square gate and a segment-overlap
//! check per pair, then the largest jointly compatible set of pairs ([`joint`]), each map
//! wall used at most once per scan.

pub mod joint;

use crate::checks::non_negative_params;
use crate::map::{LineMap, MapSegment};
use crate::ObservedLine;
use alloc::vec::Vec;
use core::f64::consts::{PI, TAU};
use core::fmt;
use ekf_core::{
    angle_diff, ChiSquareGate, Considered, Ekf, Error, Innovation, LaserLine, Line, Pose2,
};
use nalgebra::{Matrix2, Matrix3, Point2};
use serde::{Deserialize, Serialize};

/// What the matcher knows of the error of a map's walls beyond the map noise of
/// [`MatchParams::line_noise`]: nothing for `()`. A wall with an error (see
/// [`ekf_core::Considered`]) is gated with the innovation covariance that includes it, as
/// the filter fuses the line (there at the state after the lines fused before it).
pub trait WallErrors {
    /// The error of wall `wall` (line `line`) as a laser at `mount` on a robot at `pose`
    /// sees it, or `None` if it has none. It does not depend on the observed line.
    fn considered(
        &self,
        wall: usize,
        line: &Line<f64>,
        mount: &Pose2<f64>,
        pose: &Pose2<f64>,
    ) -> Option<Considered<f64, 2, 2>>;
}

impl WallErrors for () {
    fn considered(
        &self,
        _wall: usize,
        _line: &Line<f64>,
        _mount: &Pose2<f64>,
        _pose: &Pose2<f64>,
    ) -> Option<Considered<f64, 2, 2>> {
        None
    }
}

/// Matching parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    /// Standard deviation of a matched line's distance beyond its fit covariance (m),
    /// added to the observed line's `R_rr`: a given map's own error (walls placed from
    /// estimated poses), walls that are not perfectly straight or flat, the robot moving
    /// during the sweep. A first-scan map's walls carry their own error (placement and
    /// fit) on top of this (see [`crate::Localizer::with_first_scan_map`]). Default 0.02 m.
    pub map_sigma_r: f64,
    /// The same for the line's direction (rad), added to `R_ψψ`. Default 1°.
    pub map_sigma_psi: f64,
    /// After a scan's matched lines are fused (at least two of them), fit and fuse the
    /// walls they missed from the scan points that lie on them (see
    /// [`crate::Localizer`]). Default `true`.
    pub refit_missed_walls: bool,
}

impl Default for MatchParams {
    fn default() -> Self {
        Self {
            gate_probability: 0.99,
            min_overlap: 0.2,
            min_overlap_fraction: 0.5,
            map_sigma_r: 0.02,
            map_sigma_psi: 1.0_f64.to_radians(),
            refit_missed_walls: true,
        }
    }
}

impl MatchParams {
    /// The measurement noise of a matched line: the observed line's covariance plus the
    /// map's, `R = R_obs + diag(σ_map,r², σ_map,ψ²)`.
    pub fn line_noise(&self, observed: &Matrix2<f64>) -> Matrix2<f64> {
        observed
            + Matrix2::from_diagonal(&nalgebra::Vector2::new(
                self.map_sigma_r * self.map_sigma_r,
                self.map_sigma_psi * self.map_sigma_psi,
            ))
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
    /// This line's best wall (by NIS) went to another observed line of the jointly
    /// compatible hypothesis, and none of its other walls fits that hypothesis; `map` is
    /// this line's best wall, `by` the line that took it.
    MapLineTaken {
        /// This line's best wall.
        map: usize,
        /// The observed line it was assigned to.
        by: usize,
    },
    /// Walls passed both tests, but pairing any of them with this line contradicts the
    /// other pairs of the hypothesis chosen (no one pose explains them together); `map`
    /// is this line's best wall.
    Incompatible {
        /// This line's best wall (by NIS).
        map: usize,
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
            RejectReason::MapLineTaken { map, by } => {
                write!(f, "map line {map} went to observed line {by}")
            }
            RejectReason::Incompatible { map } => write!(
                f,
                "not jointly compatible with the scan's other matches (closest map line {map})"
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

/// The sort key of a gated pair that also passed the overlap check; the pair itself is
/// `MatchResult::pairs[pair]` (kept apart so sorting moves 32 bytes, not 200).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Candidate {
    nis: f64,
    observed: usize,
    map: usize,
    pair: usize,
}

/// Candidates in increasing NIS, ties by observed line, then wall.
fn by_nis(a: &Candidate, b: &Candidate) -> core::cmp::Ordering {
    a.nis
        .total_cmp(&b.nis)
        .then(a.observed.cmp(&b.observed))
        .then(a.map.cmp(&b.map))
}

/// What is known about one observed line while matching.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Status {
    Unmatched(RejectReason),
    Matched,
}

/// Per-wall values of one scan: `cos β`, `sin β`, the wall's extent along its direction
/// and its considered error.
#[derive(Debug, Clone, Copy)]
struct WallCache {
    /// The `β` that `cos` and `sin` were computed from.
    beta: f64,
    cos: f64,
    sin: f64,
    extent: (f64, f64),
    /// The wall's considered error at the predicted state, if the map has one.
    considered: Option<Considered<f64, 2, 2>>,
}

impl WallCache {
    /// The values of `segment`, reusing the trigonometry of `previous` (the same wall's
    /// values at the last scan) when the wall's `β` is bit for bit the same: a map that
    /// does not change between scans costs no `sin`/`cos` after the first.
    fn new(
        segment: &MapSegment,
        previous: Option<&WallCache>,
        considered: Option<Considered<f64, 2, 2>>,
    ) -> Self {
        let beta = segment.line.beta;
        let (sin, cos) = match previous {
            Some(w) if w.beta.to_bits() == beta.to_bits() => (w.sin, w.cos),
            _ => (libm::sin(beta), libm::cos(beta)),
        };
        // Coordinates along the direction d = (−sin β, cos β).
        let along = |p: &Point2<f64>| -p.x * sin + p.y * cos;
        let (t0, t1) = (along(&segment.start), along(&segment.end));
        Self {
            beta,
            cos,
            sin,
            extent: (t0.min(t1), t0.max(t1)),
            considered,
        }
    }
}

/// The result of matching one scan, reused across scans: [`Matcher::match_lines`] clears
/// and refills its buffers, so once they have grown to the largest scan and map, matching
/// does not allocate.
#[derive(Debug, Clone, Default)]
pub struct MatchResult {
    matches: Vec<LineMatch>,
    rejections: Vec<Rejection>,
    candidates: Vec<Candidate>,
    pairs: Vec<LineMatch>,
    status: Vec<Status>,
    owner: Vec<Option<usize>>,
    walls: Vec<WallCache>,
    /// Per observed line with candidates: `(observed, first, end)` of its candidates.
    lines: Vec<(usize, usize, usize)>,
    joint: joint::JointSearch,
    /// The candidates of the hypothesis chosen.
    chosen: Vec<usize>,
    /// Candidate indices in increasing NIS (greedy pairing).
    greedy: Vec<usize>,
}

impl MatchResult {
    /// An empty result; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// The matches, by increasing NIS (the order the localizer fuses them in).
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

    /// Chooses among the gated candidates (at the state covariance `p`, gate probability
    /// `probability`) and records each line's outcome: the jointly compatible hypothesis
    /// ([`joint`]), or, when a wall of the map carries a considered error, the greedy one.
    ///
    /// The joint test is a linear update of the state alone. A first-scan map's walls
    /// were placed from the state, so their errors are correlated with it and with each
    /// other, and the per-pair covariance `S` already nets that out; the joint test has no
    /// model of it and would refuse consistent pairs. Such scans (one room, the map seen
    /// from where it was made) are paired greedily: candidates in increasing NIS, each
    /// taken unless its line is matched or its wall taken.
    fn associate(&mut self, p: &Matrix3<f64>, probability: f64) {
        for &(_, first, end) in &self.lines {
            self.candidates[first..end].sort_unstable_by(by_nis);
        }
        // The most confident lines first: their pairs bound the search soonest.
        let candidates = &self.candidates;
        self.lines
            .sort_unstable_by(|a, b| by_nis(&candidates[a.1], &candidates[b.1]));
        self.chosen.clear();
        if self.walls.iter().any(|w| w.considered.is_some()) {
            self.choose_greedily();
        } else {
            self.joint.run(
                self.lines.iter().map(|&(_, first, end)| (first, end)),
                &self.candidates,
                &self.pairs,
                p,
                probability,
                &mut self.owner,
                joint::NODE_BUDGET,
            );
            self.chosen.extend(self.joint.best());
        }
        for &c in &self.chosen {
            let c = self.candidates[c];
            self.status[c.observed] = Status::Matched;
            self.owner[c.map] = Some(c.observed);
            self.matches.push(self.pairs[c.pair]);
        }
        self.matches.sort_unstable_by(|a, b| {
            a.innovation
                .nis
                .total_cmp(&b.innovation.nis)
                .then(a.observed.cmp(&b.observed))
        });
        for &(observed, first, _) in &self.lines {
            if self.status[observed] == Status::Matched {
                continue;
            }
            let map = self.candidates[first].map;
            self.status[observed] = Status::Unmatched(match self.owner[map] {
                Some(by) => RejectReason::MapLineTaken { map, by },
                None => RejectReason::Incompatible { map },
            });
        }
    }

    /// Greedy pairing into `chosen`: all candidates in increasing NIS, each taken unless
    /// its line or its wall already is (marked in `status` and `owner` as it goes).
    fn choose_greedily(&mut self) {
        self.greedy.clear();
        self.greedy.extend(0..self.candidates.len());
        let candidates = &self.candidates;
        self.greedy
            .sort_unstable_by(|&a, &b| by_nis(&candidates[a], &candidates[b]));
        for &i in &self.greedy {
            let c = &self.candidates[i];
            if self.status[c.observed] != Status::Matched && self.owner[c.map].is_none() {
                self.status[c.observed] = Status::Matched;
                self.owner[c.map] = Some(c.observed);
                self.chosen.push(i);
            }
        }
    }

    fn clear(&mut self, num_observed: usize, num_walls: usize) {
        self.matches.clear();
        self.rejections.clear();
        self.candidates.clear();
        self.pairs.clear();
        self.status.clear();
        self.status
            .resize(num_observed, Status::Unmatched(RejectReason::OutsideGate));
        self.owner.clear();
        self.owner.resize(num_walls, None);
        self.lines.clear();
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
/// Of the candidates, the hypothesis kept pairs the most lines, each wall at most once,
/// while the pairs are jointly compatible at the same probability
/// (`D² ≤ χ²_{2k}⁻¹(gate_probability)` for `k` pairs), ties going to the smaller joint
/// NIS: joint compatibility branch and bound ([`joint`]). Lines that would contradict
/// the others stay unmatched. Against a map whose walls carry considered errors (a
/// first-scan map), pairing is greedy instead: candidates in increasing NIS, each wall
/// to the line that fits it best. The matches are listed in increasing NIS, the order
/// the localizer fuses them in.
///
/// Before the full innovation of a pair is computed, two lower bounds on its NIS skip
/// pairs that cannot pass the gate, which changes no decision: for a 2-D Gaussian
/// `yᵀ S⁻¹ y ≥ y_k² / S_kk` for each component, with `S_ψψ = P_θθ + R_ψψ` exactly (the
/// ψ row of `H` is `(0, 0, −1)`) and `S_rr ≤ (1 + |t_mount|²)·tr P + R_rr` (the r row of
/// `H` has norm² `1 + (∂C/∂θ)²` and `|∂C/∂θ| ≤ |t_mount|`, the mount's offset).
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
        non_negative_params(&[
            (params.min_overlap, "matching min_overlap"),
            (params.min_overlap_fraction, "matching min_overlap_fraction"),
            (params.map_sigma_r, "matching map_sigma_r"),
            (params.map_sigma_psi, "matching map_sigma_psi"),
        ])?;
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
        self.match_lines_with(observed, map, &(), ekf, mount, out);
    }

    /// [`match_lines`](Self::match_lines) against a map whose walls have the errors
    /// `errors` (indexed like `map.segments`).
    pub fn match_lines_with(
        &self,
        observed: &[ObservedLine],
        map: &LineMap,
        errors: &impl WallErrors,
        ekf: &Ekf<f64>,
        mount: &Pose2<f64>,
        out: &mut MatchResult,
    ) {
        out.clear(observed.len(), map.segments.len());
        let pose = ekf.pose();
        // The last scan's wall values stay in `out.walls` for their trigonometry.
        out.walls.truncate(map.segments.len());
        for (j, segment) in map.segments.iter().enumerate() {
            let considered = errors.considered(j, &segment.line, mount, &pose);
            let wall = WallCache::new(segment, out.walls.get(j), considered);
            match out.walls.get_mut(j) {
                Some(w) => *w = wall,
                None => out.walls.push(wall),
            }
        }
        for (i, line) in observed.iter().enumerate() {
            if let Err(e) = line.validate() {
                out.status[i] = Status::Unmatched(RejectReason::InvalidLine(e));
                continue;
            }
            self.gate_line(i, line, map, ekf, mount, out);
        }
        out.associate(ekf.covariance(), self.params.gate_probability);
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
    /// The cheap checks come first (NIS bounds, then overlap); the full innovation only
    /// for walls that pass both.
    fn gate_line(
        &self,
        i: usize,
        line: &ObservedLine,
        map: &LineMap,
        ekf: &Ekf<f64>,
        mount: &Pose2<f64>,
        out: &mut MatchResult,
    ) {
        let pair = PairGate::new(
            line,
            self.params.line_noise(&line.covariance),
            ekf,
            mount,
            &self.gate,
        );
        let first = out.candidates.len();
        for (j, (segment, wall)) in map.segments.iter().zip(&out.walls).enumerate() {
            if wall.considered.is_none() && !pair.may_pass(segment, wall) {
                continue;
            }
            let Some(overlap) = overlap(wall, &pair.a, &pair.b, &self.params) else {
                continue;
            };
            if let Some(innovation) = pair.gated_innovation(segment, wall.considered.as_ref()) {
                out.candidates.push(Candidate {
                    nis: innovation.nis,
                    observed: i,
                    map: j,
                    pair: out.pairs.len(),
                });
                out.pairs.push(LineMatch {
                    observed: i,
                    map: j,
                    innovation,
                    overlap,
                });
            }
        }
        if out.candidates.len() > first {
            out.lines.push((i, first, out.candidates.len()));
            return;
        }
        // No candidate: "no overlap" if some wall passed the gate, else "outside gate".
        let closest = map
            .segments
            .iter()
            .zip(&out.walls)
            .enumerate()
            .filter_map(|(j, (segment, wall))| {
                if wall.considered.is_none() && !pair.may_pass(segment, wall) {
                    return None;
                }
                let innovation = pair.gated_innovation(segment, wall.considered.as_ref())?;
                Some((j, innovation.nis))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((map, _)) = closest {
            out.status[i] = Status::Unmatched(RejectReason::NoOverlap { map });
        }
    }
}

/// The gate applied to one observed line and any wall, with what it needs precomputed.
struct PairGate<'a> {
    line: &'a ObservedLine,
    /// The line's measurement noise `R` (observed plus map).
    noise: Matrix2<f64>,
    ekf: &'a Ekf<f64>,
    mount: &'a Pose2<f64>,
    gate: &'a ChiSquareGate<f64>,
    sensor: Pose2<f64>,
    /// `S_ψψ = P_θθ + R_ψψ`.
    s_psi: f64,
    /// An upper bound on `S_rr`: `(1 + |t_mount|²)·tr P + R_rr`.
    s_r_max: f64,
    /// The observed end points in the world, at the predicted sensor pose.
    a: Point2<f64>,
    b: Point2<f64>,
}

impl<'a> PairGate<'a> {
    fn new(
        line: &'a ObservedLine,
        noise: Matrix2<f64>,
        ekf: &'a Ekf<f64>,
        mount: &'a Pose2<f64>,
        gate: &'a ChiSquareGate<f64>,
    ) -> Self {
        let p = ekf.covariance();
        let sensor = ekf.pose().compose(mount);
        // ‖H_r‖² = 1 + (∂C/∂θ)² ≤ 1 + |t_mount|², and H P Hᵀ ≤ ‖H‖² tr P.
        let lever = mount.x * mount.x + mount.y * mount.y;
        Self {
            line,
            noise,
            ekf,
            mount,
            gate,
            sensor,
            s_psi: p[(2, 2)] + noise[(1, 1)],
            s_r_max: (1.0 + lever) * p.trace() + noise[(0, 0)],
            a: sensor.transform_point(&line.start),
            b: sensor.transform_point(&line.end),
        }
    }

    /// `false` if a lower bound on the pair's NIS already exceeds the gate:
    /// `y_ψ² / S_ψψ` or `y_r² / S_rr,max`, with `ψ̂ = β − θ_s (+π if C < 0)`,
    /// `r̂ = |C|`, `C = ρ − x_s cos β − y_s sin β`.
    fn may_pass(&self, segment: &MapSegment, wall: &WallCache) -> bool {
        let c = segment.line.rho - self.sensor.x * wall.cos - self.sensor.y * wall.sin;
        let flip = if c < 0.0 { PI } else { 0.0 };
        let y_psi = wrapped_diff(
            self.line.line.beta,
            segment.line.beta - self.sensor.theta + flip,
        );
        let y_r = self.line.line.rho - c.abs();
        let threshold = self.gate.threshold;
        y_psi * y_psi <= threshold * self.s_psi && y_r * y_r <= threshold * self.s_r_max
    }

    /// The line model of the pair, with the line's measurement noise `R`.
    fn model(&self, segment: &MapSegment) -> LaserLine<f64> {
        LaserLine {
            observed: self.line.line,
            covariance: self.noise,
            map_line: segment.line,
            mount: *self.mount,
        }
    }

    /// The pair's innovation (ekf-core's [`LaserLine`] model) if it passes the gate, with
    /// the wall's considered error if it has one.
    fn gated_innovation(
        &self,
        segment: &MapSegment,
        considered: Option<&Considered<f64, 2, 2>>,
    ) -> Option<Innovation<f64, 2>> {
        let model = self.model(segment);
        let innovation = match considered {
            Some(c) => self.ekf.innovation_considering(&model, c),
            None => self.ekf.innovation(&model),
        }
        .ok()?;
        self.gate.accepts(innovation.nis).then_some(innovation)
    }
}

/// `a − b` wrapped to (−π, π]; a few additions of 2π in the common case of arguments
/// near the range, [`angle_diff`] otherwise.
fn wrapped_diff(a: f64, b: f64) -> f64 {
    let d = a - b;
    if d > PI && d <= 3.0 * PI {
        d - TAU
    } else if d <= -PI && d > -3.0 * PI {
        d + TAU
    } else if d > -PI && d <= PI {
        d
    } else {
        angle_diff(a, b)
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

//! Building a map from a whole run: repeated sightings of the same wall are fused into
//! one segment.

use super::wall_index::WallIndex;
use super::{interval_along, point_on_line, LineMap, MapSegment};
use crate::checks::non_negative_params;
use crate::observed::normalized;
use crate::ObservedLine;
use alloc::vec::Vec;
use ekf_core::{angle_diff, wrap_angle, ChiSquareGate, Error, Line, Pose2};
use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};

/// How [`MapBuilder`] decides that two sightings are the same wall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MapBuilderParams {
    /// Probability of the chi-square test (2 dof) on the difference of `(ρ, β)`.
    /// Default 0.99 (threshold 9.21).
    pub gate_probability: f64,
    /// Standard deviation added to `ρ` in that test (m), for the error of the given poses
    /// and for walls that are not perfectly straight. Default 0.05 m.
    pub tolerance_rho: f64,
    /// Standard deviation added to `β` in that test (rad). Default 2° (0.0349 rad).
    pub tolerance_beta: f64,
    /// Largest gap along the line between two collinear segments that still makes them one
    /// wall (m); 0 requires them to touch or overlap. Default 0.3 m (a door is wider).
    pub max_gap: f64,
    /// [`MapBuilder::finish`] drops walls fused from fewer sightings. Default 1 (keep all).
    pub min_sightings: u32,
}

impl Default for MapBuilderParams {
    fn default() -> Self {
        Self {
            gate_probability: 0.99,
            tolerance_rho: 0.05,
            tolerance_beta: 2.0_f64.to_radians(),
            max_gap: 0.3,
            min_sightings: 1,
        }
    }
}

/// A wall being built: its line `(ρ, β)` with covariance, the end points of its extent
/// (on the line), and how many sightings it was fused from.
#[derive(Debug, Clone, Copy)]
struct Wall {
    line: Line<f64>,
    covariance: Matrix2<f64>,
    start: Point2<f64>,
    end: Point2<f64>,
    sightings: u32,
}

/// Builds a [`LineMap`] from the lines of many scans taken at known sensor poses.
///
/// The rule: each sighting, a line `(r, ψ)` with covariance `Σ` taken at sensor pose
/// `(x_s, y_s, θ_s)`, becomes the world line `ρ = r + x_s cos β + y_s sin β`, `β = ψ + θ_s`
/// with covariance `J Σ Jᵀ`, `J = [[1, −x_s sin β + y_s cos β], [0, 1]]` (the pose is
/// taken as exact). It is fused into the existing wall with the smallest
/// `D² = dᵀ (Σ_wall + Σ + J T Jᵀ)⁻¹ d`, `d = (Δρ, wrap(Δβ))` (after expressing both lines
/// with normals less than 90° apart), `T = diag(tolerance_rho², tolerance_beta²)` the
/// tolerance on the offset and direction where the two segments are (`J = [[1, t], [0,
/// 1]]`, `t` the middle of their extents along the line), among the walls that
/// 1. pass the gate `D² ≤ χ²₂⁻¹(gate_probability)`, and
/// 2. are collinear neighbours: projected onto the wall's line, the two segments overlap
///    or leave a gap of at most `max_gap`.
///
/// Only walls that come within `max_gap +` [`NEAR_M`] of the sighting are tested (found
/// through a spatial index, so the cost of a sighting does not grow with the map). If no
/// wall qualifies, the sighting starts a new wall. Fusion weights by information
/// (`K = Σ_wall (Σ_wall + Σ)⁻¹`, `x = x_wall + K d`, `Σ_wall ← (I − K) Σ_wall`) and the
/// extent becomes the union of both segments' projections onto the fused line.
/// [`finish`](Self::finish) then merges walls that the same test joins (a sighting can
/// bridge two walls), drops walls seen fewer than `min_sightings` times, and returns the
/// segments in the order the walls were first seen.
#[derive(Debug, Clone)]
pub struct MapBuilder {
    params: MapBuilderParams,
    gate: ChiSquareGate<f64>,
    tolerance: Matrix2<f64>,
    /// Every wall started so far, in the order first seen; `None` once merged into an
    /// earlier one by `finish`.
    walls: Vec<Option<Wall>>,
    index: WallIndex,
    /// Scratch for the candidates of one query (kept to not allocate per sighting).
    candidates: Vec<usize>,
}

/// How far apart, besides `max_gap` along the line, two segments may be and still be
/// tested as the same wall (m). Walls the gate joins are far closer: their separation
/// where they overlap has the spread of the line fits plus `tolerance_rho` (centimetres),
/// so a metre only matters for walls no test would join.
pub const NEAR_M: f64 = 1.0;

impl MapBuilder {
    /// A builder with `params`. Fails on a gate probability outside (0, 1), a negative or
    /// non-finite tolerance or gap.
    pub fn new(params: MapBuilderParams) -> Result<Self, Error> {
        let gate = ChiSquareGate::from_probability(params.gate_probability, 2)?;
        non_negative_params(&[
            (params.tolerance_rho, "map builder tolerance_rho"),
            (params.tolerance_beta, "map builder tolerance_beta"),
            (params.max_gap, "map builder max_gap"),
        ])?;
        let tolerance = Matrix2::from_diagonal(&Vector2::new(
            params.tolerance_rho * params.tolerance_rho,
            params.tolerance_beta * params.tolerance_beta,
        ));
        Ok(Self {
            params,
            gate,
            tolerance,
            walls: Vec::new(),
            index: WallIndex::default(),
            candidates: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &MapBuilderParams {
        &self.params
    }

    /// Number of walls so far (before the merging and filtering of `finish`).
    pub fn num_walls(&self) -> usize {
        self.walls.iter().flatten().count()
    }

    /// Adds the lines of one scan taken at `sensor_pose` (robot pose ⊕ laser mount).
    /// Fails, leaving the builder unchanged, if the pose or any line is not finite or a
    /// line's covariance is not positive definite. Zero-length lines are skipped.
    pub fn add_scan(
        &mut self,
        lines: &[ObservedLine],
        sensor_pose: &Pose2<f64>,
    ) -> Result<(), Error> {
        sensor_pose.validated("sensor pose")?;
        for observed in lines {
            observed.validate()?;
        }
        for observed in lines {
            if let Some(sighting) = sighting(observed, sensor_pose) {
                self.add_wall(sighting);
            }
        }
        Ok(())
    }

    /// Merges walls that the fusion rule joins, drops walls seen fewer than
    /// `min_sightings` times, and returns the map (frame `"map"`).
    pub fn finish(mut self) -> LineMap {
        self.merge_walls();
        let min = self.params.min_sightings;
        let segments = self
            .walls
            .iter()
            .flatten()
            .filter(|w| w.sightings >= min)
            .filter_map(|w| MapSegment::from_points(w.start, w.end).ok())
            .collect();
        LineMap::new(segments)
    }

    /// Fuses `sighting` into the nearest wall that passes the test, or starts a wall.
    fn add_wall(&mut self, sighting: Wall) {
        self.find_candidates(&sighting);
        let best = self
            .candidates
            .iter()
            .filter_map(|&i| {
                let wall = self.walls[i].as_ref()?;
                self.distance(wall, &sighting).map(|d2| (i, d2))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match best {
            Some((i, _)) => self.fuse_into(i, &sighting),
            None => {
                self.index
                    .insert(self.walls.len(), &sighting.start, &sighting.end);
                self.walls.push(Some(sighting));
            }
        }
    }

    /// Fuses pairs of walls that pass the test until none does; the earlier wall absorbs
    /// the later ones, in the order they were first seen.
    fn merge_walls(&mut self) {
        for i in 0..self.walls.len() {
            // A grown wall may reach walls it was tested against before: go on until a
            // pass over the later walls merges none.
            loop {
                let mut merged = false;
                let mut after = i;
                while let Some(j) = self.next_mergeable(i, after) {
                    let Some(other) = self.walls[j].take() else {
                        break;
                    };
                    self.fuse_into(i, &other);
                    merged = true;
                    after = j;
                }
                if !merged {
                    break;
                }
            }
        }
    }

    /// The first wall after index `after` that wall `i` (if still a wall) would absorb.
    fn next_mergeable(&mut self, i: usize, after: usize) -> Option<usize> {
        let wall = self.walls[i]?;
        self.find_candidates(&wall);
        self.candidates.iter().copied().find(|&j| {
            j > after
                && self.walls[j]
                    .as_ref()
                    .is_some_and(|other| self.distance(&wall, other).is_some())
        })
    }

    /// Fills `candidates` with the walls near `wall` (see [`NEAR_M`]).
    fn find_candidates(&mut self, wall: &Wall) {
        let reach = self.params.max_gap + NEAR_M;
        self.index
            .near(&wall.start, &wall.end, reach, &mut self.candidates);
    }

    /// Replaces wall `i` with its fusion with `other` and indexes its new extent.
    fn fuse_into(&mut self, i: usize, other: &Wall) {
        if let Some(wall) = self.walls[i].as_mut() {
            *wall = fuse(wall, other);
            self.index.insert(i, &wall.start, &wall.end);
        }
    }

    /// `Some(D²)` if `b` is the same wall as `a` by the gate and the gap test.
    fn distance(&self, a: &Wall, b: &Wall) -> Option<f64> {
        let (b_line, b_cov) = aligned(&b.line, &b.covariance, &a.line);
        let d = Vector2::new(
            b_line.rho - a.line.rho,
            angle_diff(b_line.beta, a.line.beta),
        );
        let (a0, a1) = interval_along(&a.line, &a.start, &a.end);
        let (b0, b1) = interval_along(&a.line, &b.start, &b.end);
        let tolerance = tolerance_at(&self.tolerance, 0.5 * (a0.min(b0) + a1.max(b1)));
        let s = a.covariance + b_cov + tolerance;
        let d2 = d.dot(&(s.try_inverse()? * d));
        if !self.gate.accepts(d2) {
            return None;
        }
        let gap = a0.max(b0) - a1.min(b1);
        (gap <= self.params.max_gap).then_some(d2)
    }
}

/// The tolerance `T` on a wall's offset and direction at the point `t` along its line
/// (where the walls being compared are), as a covariance of the world line `(ρ, β)`:
/// `J T Jᵀ`, `J = [[1, t], [0, 1]]`. Turning a line by `δβ` about the foot of its normal
/// from the origin moves it by `t δβ` at `t`, so a direction tolerance taken at the origin
/// would let walls far from it pass metres apart (2° at 70 m is 2.4 m).
fn tolerance_at(tolerance: &Matrix2<f64>, t: f64) -> Matrix2<f64> {
    let j = Matrix2::new(1.0, t, 0.0, 1.0);
    j * tolerance * j.transpose()
}

/// One observed line as a wall in the world frame, or `None` if it has zero length.
fn sighting(observed: &ObservedLine, sensor: &Pose2<f64>) -> Option<Wall> {
    let seen = observed.seen_from(sensor);
    let (line, covariance) = (seen.line, seen.covariance);
    let start = line.project(&seen.start);
    let end = line.project(&seen.end);
    ((end - start).norm() > 0.0).then_some(Wall {
        line,
        covariance,
        start,
        end,
        sightings: 1,
    })
}

/// `line` with its covariance, rewritten as `(−ρ, β + π)` if its normal points away from
/// `reference`'s by more than 90°, so the two can be subtracted component-wise.
fn aligned(
    line: &Line<f64>,
    covariance: &Matrix2<f64>,
    reference: &Line<f64>,
) -> (Line<f64>, Matrix2<f64>) {
    if angle_diff(line.beta, reference.beta).abs() > core::f64::consts::FRAC_PI_2 {
        let flip = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
        (
            Line {
                rho: -line.rho,
                beta: wrap_angle(line.beta + core::f64::consts::PI),
            },
            flip * covariance * flip,
        )
    } else {
        (*line, *covariance)
    }
}

/// The information-weighted fusion of two walls with the union of their extents.
fn fuse(a: &Wall, b: &Wall) -> Wall {
    let (b_line, b_cov) = aligned(&b.line, &b.covariance, &a.line);
    let d = Vector2::new(
        b_line.rho - a.line.rho,
        angle_diff(b_line.beta, a.line.beta),
    );
    let Some(inv) = (a.covariance + b_cov).try_inverse() else {
        return *a;
    };
    let k = a.covariance * inv;
    let x = Vector2::new(a.line.rho, a.line.beta) + k * d;
    let p = (Matrix2::identity() - k) * a.covariance;
    let (line, covariance) = normalized(x[0], x[1], (p + p.transpose()) * 0.5);
    let mut t_min = f64::INFINITY;
    let mut t_max = f64::NEG_INFINITY;
    for (p0, p1) in [(&a.start, &a.end), (&b.start, &b.end)] {
        let (t0, t1) = interval_along(&line, p0, p1);
        t_min = t_min.min(t0);
        t_max = t_max.max(t1);
    }
    Wall {
        line,
        covariance,
        start: point_on_line(&line, t_min),
        end: point_on_line(&line, t_max),
        sightings: a.sightings.saturating_add(b.sightings),
    }
}

//! Recognising a place mapped before: the scan's lines searched for in a submap of old
//! key scans near where the robot thinks it is (the relocalization search), the pose
//! refined by an EKF update on those walls, and the hypothesis kept only if the key scans
//! after it fit the same correction ([`LoopClosures`]).

use super::key_scans::KeyScans;
use super::pose_graph::{relative, Edge, PoseGraph};
use super::scan_match::{align, ReferenceCloud};
use super::SlamParams;
use ekf_core::{angle_diff, Pose2};
use lrf_lines::{
    relocalize, LineMap, Localizer, LocalizerConfig, ObservedLine, RelocalizeParams, SearchWindow,
};
use nalgebra::{Matrix3, Vector3};

/// A loop closure found at one key scan and not yet confirmed by the ones after it.
#[derive(Debug, Clone)]
struct Pending {
    /// The old key scan the submap is anchored at.
    anchor: usize,
    /// The submap (old key scans near the anchor, at their graph poses) ...
    submap: LineMap,
    /// ... and its points.
    cloud: ReferenceCloud,
    /// World-frame correction `C` with `C ⊕ x_k` the pose found for key scan `k`.
    correction: Pose2<f64>,
    /// The edges found so far, anchor → key scan.
    edges: Vec<Edge>,
}

/// Counts of what the loop-closure search did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LoopCounts {
    /// Searches run (key scans with an old key scan within reach).
    pub searches: u64,
    /// Hypotheses that a search found and the refinement kept.
    pub hypotheses: u64,
    /// Hypotheses that the key scans after them did not confirm.
    pub refuted: u64,
    /// Confirmed closures that the graph refused: farther from where its other edges put
    /// the robot than their uncertainty allows ([`PoseGraph::consistency`]).
    pub inconsistent: u64,
    /// Loop closures added to the graph.
    pub closures: u64,
}

/// A confirmed closure whose edges are not all within `χ²₃` at this probability of the
/// graph ([`PoseGraph::consistency`]) is refused (`χ²₃(0.999)` is 16.3). On
/// infinite-corridor a closure that matched a corridor 4.1 m along itself came to 82 (and
/// one of 4.5 m to 108 in a variant of the build); of the true closures before 1500 s all
/// but two (17 and 30) are below 16. At 0.99 (11.3) a true closure of freiburg-campus,
/// outdoors, is refused.
const CONSISTENCY_PROBABILITY: f64 = 0.999;

/// The search, the verification of its hypotheses and their counts.
#[derive(Debug)]
pub struct LoopClosures {
    params: SlamParams,
    localizer: LocalizerConfig,
    relocalize: RelocalizeParams,
    pending: Option<Pending>,
    /// Path length (m) at the last closure added.
    last_closure_path: f64,
    counts: LoopCounts,
}

/// What checking one key scan gave.
pub enum Outcome {
    /// Nothing to add.
    Nothing,
    /// A confirmed closure: add these edges (the front end optimises the graph at once
    /// unless it already agrees with them).
    Closed(Vec<Edge>),
}

impl LoopClosures {
    /// With the SLAM parameters and the localizer's configuration (laser mount, matching)
    /// for the refinement.
    pub fn new(params: SlamParams, localizer: LocalizerConfig) -> Self {
        Self {
            params,
            localizer,
            // Two walls on the submap make a hypothesis: the key scans after it must
            // confirm it before it is a closure.
            relocalize: RelocalizeParams {
                min_inliers: 2,
                ..RelocalizeParams::default()
            },
            pending: None,
            last_closure_path: 0.0,
            counts: LoopCounts::default(),
        }
    }

    /// The counts so far.
    pub fn counts(&self) -> LoopCounts {
        self.counts
    }

    /// Checks the newest key scan `k` (graph poses in `poses`): confirms or refutes a
    /// pending hypothesis, or searches for a new one.
    pub fn check(&mut self, keys: &KeyScans, graph: &PoseGraph, k: usize) -> Outcome {
        let poses = graph.poses();
        if let Some(mut pending) = self.pending.take() {
            let predicted = pending.correction.compose(&poses[k]);
            let confirmed = self
                .refine_chain(keys, poses, k, &pending.submap, &pending.cloud, &predicted)
                .filter(|(pose, _)| close(pose, &predicted, &self.params));
            let Some((pose, information)) = confirmed else {
                self.counts.refuted += 1;
                return Outcome::Nothing;
            };
            pending.edges.push(edge(
                pending.anchor,
                k,
                &poses[pending.anchor],
                &pose,
                information,
            ));
            if pending.edges.len() <= self.params.verify_key_scans {
                self.pending = Some(pending);
                return Outcome::Nothing;
            }
            return self.conclude(graph, pending.edges, keys.get(k).path);
        }
        let path = keys.get(k).path;
        if path - self.last_closure_path < self.params.loop_cooldown_path {
            return Outcome::Nothing;
        }
        let reach = |j: usize| {
            let since = (path - keys.get(j).path).min(path - self.last_closure_path);
            (self.params.loop_radius + self.params.loop_drift * since)
                .min(self.params.loop_max_radius)
        };
        let here = poses[k];
        // Key scans far enough behind to close a loop with.
        let old = |j: &usize| path - keys.get(*j).path >= self.params.loop_min_path;
        let anchor = (0..k)
            .filter(old)
            .map(|j| (j, distance(&poses[j], &here)))
            .filter(|&(j, d)| d <= reach(j))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(j, _)| j);
        let Some(anchor) = anchor else {
            return Outcome::Nothing;
        };
        self.counts.searches += 1;
        // The old key scans nearest the anchor, at most `submap_max_keys`: a place
        // revisited many times does not make the search slower each time.
        let mut near: Vec<(usize, f64)> = (0..k)
            .filter(old)
            .map(|j| (j, distance(&poses[j], &poses[anchor])))
            .filter(|&(_, d)| d <= self.params.submap_radius)
            .collect();
        near.sort_by(|a, b| a.1.total_cmp(&b.1));
        near.truncate(self.params.submap_max_keys);
        let submap = keys.map_of(
            poses,
            near.iter().map(|&(j, _)| j),
            &self.localizer.laser_mount,
        );
        let window = SearchWindow::around(nalgebra::Point2::new(here.x, here.y), reach(anchor));
        let walls = keys.chain_walls(
            poses,
            k,
            self.params.chain_path,
            &self.localizer.laser_mount,
        );
        let found = relocalize(
            &walls,
            &submap,
            &self.localizer.laser_mount,
            &window,
            &self.relocalize,
        )
        .filter(|r| r.is_unambiguous(&self.relocalize))
        .map(|r| r.best.pose)
        .filter(|pose| angle_diff(pose.theta, here.theta).abs() <= self.params.loop_max_turn);
        let Some(found) = found else {
            return Outcome::Nothing;
        };
        let cloud = keys.cloud_of(
            poses,
            near.iter().map(|&(j, _)| j),
            self.params.scan_match.max_distance,
        );
        let Some((pose, information)) = self.refine_chain(keys, poses, k, &submap, &cloud, &found)
        else {
            return Outcome::Nothing;
        };
        self.counts.hypotheses += 1;
        let first = edge(anchor, k, &poses[anchor], &pose, information);
        if self.params.verify_key_scans == 0 {
            return self.conclude(graph, vec![first], path);
        }
        self.pending = Some(Pending {
            anchor,
            correction: pose.compose(&here.inverse()),
            edges: vec![first],
            submap,
            cloud,
        });
        Outcome::Nothing
    }

    /// A confirmed closure (`edges`, found at path length `path`): added if every edge is
    /// consistent with the graph ([`CONSISTENCY_PROBABILITY`]), else refused. A wrong
    /// closure that passed the search's ambiguity test and its confirmations (the next key
    /// scans in the same corridor find the same wrong door) is still far from where the
    /// odometry and the other closures put the robot.
    fn conclude(&mut self, graph: &PoseGraph, edges: Vec<Edge>, path: f64) -> Outcome {
        // Three degrees of freedom and a probability in (0, 1) always have a quantile.
        let bound =
            ekf_core::chi_square_quantile(CONSISTENCY_PROBABILITY, 3).unwrap_or(f64::INFINITY);
        let consistent = graph
            .consistency(&edges)
            .is_ok_and(|chi2| chi2.iter().all(|&c| c <= bound));
        if !consistent {
            self.counts.inconsistent += 1;
            return Outcome::Nothing;
        }
        self.counts.closures += 1;
        self.last_closure_path = path;
        Outcome::Closed(edges)
    }

    /// The pose of key scan `k` in the submap (`submap`, its points `cloud`) from
    /// `start`: the chain's lines [`refine`]d on the submap's walls, then the chain's
    /// points aligned to the submap's ([`align`]) where enough of them match; with the
    /// information the lines gave.
    fn refine_chain(
        &self,
        keys: &KeyScans,
        poses: &[Pose2<f64>],
        k: usize,
        submap: &LineMap,
        cloud: &ReferenceCloud,
        start: &Pose2<f64>,
    ) -> Option<(Pose2<f64>, Matrix3<f64>)> {
        let path = self.params.chain_path;
        let lines = keys.chain_lines(poses, k, path, &self.localizer.laser_mount);
        let (pose, information) = refine(&self.params, &self.localizer, &lines, submap, start)?;
        let points = keys.chain_points(poses, k, path);
        let pose = align(cloud, &points, pose, &self.params.scan_match).map_or(pose, |a| a.pose);
        Some((pose, information))
    }
}

/// The pose of the scan with `lines` against `map`, refined from `start` by one EKF
/// update on the walls its lines match (prior `σ = refine_sigma_xy`,
/// `refine_sigma_theta`), and the information the lines gave, `Σ⁻¹ − P₀⁻¹` (world
/// frame); `None` if fewer than `min_loop_lines` lines fused.
pub(super) fn refine(
    params: &SlamParams,
    localizer: &LocalizerConfig,
    lines: &[ObservedLine],
    map: &LineMap,
    start: &Pose2<f64>,
) -> Option<(Pose2<f64>, Matrix3<f64>)> {
    let (sxy, sth) = (params.refine_sigma_xy, params.refine_sigma_theta);
    let prior = Vector3::new(sxy * sxy, sxy * sxy, sth * sth);
    let p0 = Matrix3::from_diagonal(&prior);
    let mut filter = Localizer::new(localizer.clone(), *start, p0, map.clone()).ok()?;
    let report = filter.update_lines(lines).ok()?;
    if report.fused < params.min_loop_lines {
        return None;
    }
    let posterior = filter.covariance().try_inverse()?;
    let gained = posterior - Matrix3::from_diagonal(&prior.map(|v| 1.0 / v));
    Some((
        filter.pose(),
        positive_part(&(0.5 * (gained + gained.transpose()))),
    ))
}

/// The symmetric matrix with its negative eigenvalues (round-off) set to zero.
fn positive_part(m: &Matrix3<f64>) -> Matrix3<f64> {
    let eigen = m.symmetric_eigen();
    let clamped = eigen.eigenvalues.map(|v| v.max(0.0));
    let q = eigen.eigenvectors;
    let p = q * Matrix3::from_diagonal(&clamped) * q.transpose();
    0.5 * (p + p.transpose())
}

/// The edge anchor → key scan measured by a pose found for the key scan, with the
/// world-frame information `Ω_w` turned into the residual's frame: the residual is the
/// position error in the found pose's frame, so `Ω = Gᵀ Ω_w G`, `G = diag(R(θ), 1)`.
fn edge(
    anchor: usize,
    k: usize,
    anchor_pose: &Pose2<f64>,
    found: &Pose2<f64>,
    world_information: Matrix3<f64>,
) -> Edge {
    let (s, c) = found.theta.sin_cos();
    let g = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    let information = g.transpose() * world_information * g;
    Edge {
        from: anchor,
        to: k,
        measured: relative(anchor_pose, found),
        information: 0.5 * (information + information.transpose()),
        robust: true,
    }
}

fn distance(a: &Pose2<f64>, b: &Pose2<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// A confirmation agrees with the hypothesis' correction.
fn close(a: &Pose2<f64>, b: &Pose2<f64>, params: &SlamParams) -> bool {
    distance(a, b) <= params.verify_distance
        && angle_diff(a.theta, b.theta).abs() <= params.verify_angle
}

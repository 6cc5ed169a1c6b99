//! The SLAM front end, handed every fused scan by the replay loop: the filter localizes in
//! a local map of the last key scans (so its error grows only with the path since them),
//! and without a compass each scan's points are aligned to theirs ([`align`]); a scan
//! taken far enough from the last key scan becomes a key scan, tied to it in the pose
//! graph by the filter's relative pose; loop closures found and confirmed
//! ([`LoopClosures`]) are added, and unless the graph already agrees with them it is
//! optimised and the filter restarted at its key scan's corrected pose.

use super::key_scans::{KeyScan, KeyScans};
use super::loop_closure::{LoopClosures, Outcome};
use super::pose_graph::{relative, Edge, PoseGraph};
use super::rematch::rematch;
use super::scan_match::{
    align, align_swept, preference_bound, preferred, Alignment, ReferenceCloud, ScanPoints,
};
use super::SlamParams;
use crate::replay::{ReplayError, ScanHook};
use ekf_core::{angle_diff, Pose2};
use ekf_fusion::{Fuser, Predicted, Scan, ScanFused};
use lrf_lines::{LineMap, LocalizerConfig};
use nalgebra::{Matrix3, Vector3};

/// A closure whose edges cost more than `χ²(this, 3 per edge)` at the graph's poses is
/// a surprise: the graph is optimised and the filter restarted at once.
const SURPRISE_PROBABILITY: f64 = 0.99;

/// Starts closer than this (m, rad) converge to the same alignment: a second is not tried.
const SAME_START_M: f64 = 0.01;
/// See [`SAME_START_M`].
const SAME_START_RAD: f64 = 0.5 * core::f64::consts::PI / 180.0;

/// Where the predicted heading is uncertain beyond one alignment's reach, the scan is
/// also aligned from the prediction turned by multiples of this angle (rad), within the
/// prediction's [`HEADING_WINDOW_SIGMAS`] σ, or around the circle after a motion gap
/// (with no odometry the robot may have turned any amount unseen: seattle, 78° in 3 s).
/// 5° starts leave at most 2.5° to go, within the alignment's reach for walls up to about
/// 7 m away (`max_distance` 0.3 m).
const SWEEP_STEP_RAD: f64 = 5.0 * core::f64::consts::PI / 180.0;

/// The heading window searched around the prediction ([`SWEEP_STEP_RAD`]), in its
/// standard deviations: where a normal error of the heading falls but in 0.3 % of
/// scans.
const HEADING_WINDOW_SIGMAS: f64 = 3.0;

/// A scan's pose as the front end had it, and the key scan it follows.
#[derive(Debug, Clone, Copy)]
pub struct ScanPose {
    /// The scan's stamp (ns).
    pub t_ns: u64,
    /// The front end's pose.
    pub front: Pose2<f64>,
    /// The last key scan at or before it.
    pub key: usize,
}

/// The front end's state (see the module documentation).
#[derive(Debug)]
pub struct FrontEnd {
    params: SlamParams,
    mount: Pose2<f64>,
    keys: KeyScans,
    graph: PoseGraph,
    loops: LoopClosures,
    scans: Vec<ScanPose>,
    /// The pose at the last scan, for the path length.
    last_pose: Option<Pose2<f64>>,
    path: f64,
    /// Gauss–Newton iterations run over all optimisations.
    pub(super) iterations: usize,
    /// Optimisations run.
    pub(super) optimizations: usize,
    /// Closures were added since the last optimisation.
    unoptimized: bool,
    /// Scans fused again with a widened covariance ([`rematch`]).
    pub(super) rematched: u64,
    /// The points of the local map's key scans, for the scan matcher.
    cloud: ReferenceCloud,
    /// Scans whose pose the scan matcher corrected.
    pub(super) aligned: u64,
    /// Whether each scan's points are aligned to the local map's (without a compass).
    align_scans: bool,
}

impl FrontEnd {
    /// A front end with `params`, its localizer configured as `localizer` (laser mount,
    /// matching) for the loop closures' refinement; `align_scans`: each scan's points are
    /// aligned to the local map's. Without a compass the lines alone let the heading
    /// drift (loop closures off, aligned RMSE: edmonton 1.24 m with the lines alone,
    /// 0.79 m with the alignment; infinite-corridor 33.6 m and 16.6 m); with
    /// one the compass holds it, and the alignment, which slides along a corridor by a
    /// few centimetres a scan, only adds drift (simulated two-rooms, loop closures off:
    /// 0.044 m without, 2.8 m with).
    pub fn new(params: SlamParams, localizer: LocalizerConfig, align_scans: bool) -> Self {
        Self {
            align_scans,
            mount: localizer.laser_mount,
            keys: KeyScans::new(params.map_builder),
            graph: PoseGraph::new(),
            loops: LoopClosures::new(params, localizer),
            params,
            scans: Vec::new(),
            last_pose: None,
            path: 0.0,
            iterations: 0,
            optimizations: 0,
            unoptimized: false,
            rematched: 0,
            cloud: ReferenceCloud::default(),
            aligned: 0,
        }
    }

    /// The key scans.
    pub fn keys(&self) -> &KeyScans {
        &self.keys
    }

    /// The graph.
    pub fn graph(&self) -> &PoseGraph {
        &self.graph
    }

    /// The loop closures' counts.
    pub fn loops(&self) -> super::loop_closure::LoopCounts {
        self.loops.counts()
    }

    /// Path length driven (m).
    pub fn path(&self) -> f64 {
        self.path
    }

    /// Optimises the graph (Gauss–Newton, at most `max_iterations`).
    fn optimize(&mut self) -> Result<(), ReplayError> {
        let report = self
            .graph
            .optimize(self.params.max_iterations)
            .map_err(slam_error)?;
        self.iterations += report.iterations;
        self.optimizations += 1;
        self.unoptimized = false;
        Ok(())
    }

    /// Optimises the graph once more if closures were added since the last optimisation;
    /// call at the end of the log, before [`map`](Self::map) and
    /// [`corrected_scans`](Self::corrected_scans).
    pub fn finish(&mut self) -> Result<(), ReplayError> {
        if self.unoptimized {
            self.optimize()?;
        }
        Ok(())
    }

    /// Every scan's pose corrected by its key scan's graph pose:
    /// `x_k ⊕ (front_k⁻¹ ⊕ front_t)`.
    pub fn corrected_scans(&self) -> impl Iterator<Item = (u64, Pose2<f64>)> + '_ {
        self.scans.iter().map(|s| {
            let key = self.keys.get(s.key);
            let local = key.front.inverse().compose(&s.front);
            (s.t_ns, self.graph.poses()[s.key].compose(&local))
        })
    }

    /// The map of every key scan at its graph pose.
    pub fn map(&self) -> LineMap {
        self.keys
            .map_of(self.graph.poses(), 0..self.keys.len(), &self.mount)
    }

    /// The local map for key scan `k`: the key scans up to `local_map_path` behind it,
    /// as walls and as points.
    fn local_map(&self, k: usize) -> (LineMap, ReferenceCloud) {
        let chain = self.keys.chain(k, self.params.local_map_path);
        let poses = self.graph.poses();
        (
            self.keys.map_of(poses, chain.clone(), &self.mount),
            self.keys
                .cloud_of(poses, chain, self.params.scan_match.max_distance),
        )
    }

    /// The scan's points aligned to the local map's ([`align`]) from the filter's pose
    /// and, when the scan's lines moved the filter by more than [`SAME_START_M`] or
    /// [`SAME_START_RAD`], from the pose predicted before them; of two alignments, the
    /// [`preferred`] one (McNemar's test at
    /// [`PREFERENCE_PROBABILITY`](super::scan_match::PREFERENCE_PROBABILITY)). A scan's few
    /// lines can pull the filter along a corridor (fhw: 0.7 m twice) or onto walls turned
    /// by ten degrees or more at a turn (edmonton: 14° once, out of the matcher's reach),
    /// and the matcher, started there, settles in a local minimum that the prediction's
    /// start avoids. A turn can leave the predicted heading uncertain by more than the
    /// matcher reaches (csail's odometry errs by up to 17° on a 60° turn), and after a
    /// `motion_gap` the robot may have turned any amount unseen: then the best of the
    /// alignments from every [`SWEEP_STEP_RAD`] turn of the prediction within
    /// [`HEADING_WINDOW_SIGMAS`] of its heading's σ, or around the circle after a gap
    /// ([`align_swept`]), is kept instead if the points prefer it the same way (aligned
    /// RMSE: csail 0.474 → 0.148 m, seattle 2.65 → 0.045 m; docs/maps.md).
    fn align_from(
        &self,
        points: &ScanPoints,
        fused: Pose2<f64>,
        predicted: Option<&Predicted>,
        motion_gap: bool,
    ) -> Option<Alignment> {
        let params = &self.params.scan_match;
        let tracked = self.align_tracked(points, fused, predicted);
        let Some(predicted) = predicted else {
            return tracked;
        };
        let reach = match motion_gap {
            true => core::f64::consts::PI,
            false => HEADING_WINDOW_SIGMAS * predicted.covariance[(2, 2)].max(0.0).sqrt(),
        };
        // No turn is tried where `reach` is under one step.
        let swept = align_swept(
            &self.cloud,
            points,
            predicted.pose,
            SWEEP_STEP_RAD,
            reach,
            params,
        );
        match (tracked, swept) {
            (Some(t), Some(s)) => Some(preferred(
                &self.cloud,
                points,
                (t, s),
                predicted,
                params,
                preference_bound(),
            )),
            (t, s) => t.or(s),
        }
    }

    /// The alignment of a scan the motion tracked: from the filter's pose and, if the
    /// scan's lines moved it, from the prediction (see [`align_from`](Self::align_from)).
    fn align_tracked(
        &self,
        points: &ScanPoints,
        fused: Pose2<f64>,
        predicted: Option<&Predicted>,
    ) -> Option<Alignment> {
        let params = &self.params.scan_match;
        let elsewhere = |p: &&Predicted| {
            (p.pose.x - fused.x).hypot(p.pose.y - fused.y) > SAME_START_M
                || angle_diff(p.pose.theta, fused.theta).abs() > SAME_START_RAD
        };
        let from_fused = align(&self.cloud, points, fused, params);
        let Some(predicted) = predicted.filter(elsewhere) else {
            return from_fused;
        };
        let from_predicted = align(&self.cloud, points, predicted.pose, params);
        let (Some(f), Some(p)) = (from_fused, from_predicted) else {
            return from_fused.or(from_predicted);
        };
        Some(preferred(
            &self.cloud,
            points,
            (f, p),
            predicted,
            params,
            preference_bound(),
        ))
    }

    /// The edge from the previous key scan: the filter's relative pose, with the
    /// front end's error model (`σ_xy = odometry_sigma_xy + odometry_sigma_xy_per_m · d`,
    /// `σ_θ = odometry_sigma_theta + odometry_sigma_theta_per_rad · |Δθ|`).
    fn odometry_edge(&self, from: usize, to: usize, measured: Pose2<f64>) -> Edge {
        let p = &self.params;
        let d = measured.x.hypot(measured.y);
        let sxy = p.odometry_sigma_xy + p.odometry_sigma_xy_per_m * d;
        let sth = p.odometry_sigma_theta + p.odometry_sigma_theta_per_rad * measured.theta.abs();
        Edge {
            from,
            to,
            measured,
            information: Matrix3::from_diagonal(&Vector3::new(
                1.0 / (sxy * sxy),
                1.0 / (sxy * sxy),
                1.0 / (sth * sth),
            )),
            robust: false,
        }
    }
}

impl ScanHook for FrontEnd {
    fn scan_fused(
        &mut self,
        now: u64,
        fused: &ScanFused,
        scan: &Scan,
        fuser: &mut Fuser,
    ) -> Result<bool, ReplayError> {
        let lines = fuser.localizer().last_lines().to_vec();
        let mut pose = match rematch(fuser, &lines, &self.params) {
            Some(pose) => {
                self.rematched += 1;
                pose
            }
            None => fuser.localizer().pose(),
        };
        // The scan's points: for the alignment, and for a key scan (made below if it is).
        let points = self
            .align_scans
            .then(|| ScanPoints::from_scan(scan, &self.mount));
        let aligned = points.as_ref().and_then(|points| {
            self.align_from(points, pose, fused.predicted.as_ref(), fused.motion_gap)
        });
        if let Some(aligned) = aligned {
            let covariance = *fuser.localizer().covariance();
            fuser
                .localizer_mut()
                .reset(aligned.pose, covariance)
                .map_err(slam_error)?;
            pose = aligned.pose;
            self.aligned += 1;
        }
        if let Some(last) = self.last_pose.replace(pose) {
            self.path += (pose.x - last.x).hypot(pose.y - last.y);
        }
        let previous = self.keys.len().checked_sub(1);
        let is_key = match previous {
            None => !lines.is_empty(),
            Some(p) => self.params.is_key(&self.keys.get(p).front, &pose),
        };
        if !is_key {
            if let Some(key) = previous {
                self.scans.push(ScanPose {
                    t_ns: now,
                    front: pose,
                    key,
                });
            }
            return Ok(false);
        }
        let k = self.keys.push(KeyScan {
            front: pose,
            lines,
            points: points.unwrap_or_else(|| ScanPoints::from_scan(scan, &self.mount)),
            path: self.path,
        });
        match previous {
            None => {
                self.graph.add_node(pose);
            }
            Some(p) => {
                let measured = relative(&self.keys.get(p).front, &pose);
                let estimate = self.graph.poses()[p].compose(&measured);
                self.graph.add_node(estimate);
                self.graph
                    .add_edge(self.odometry_edge(p, k, measured))
                    .map_err(slam_error)?;
            }
        }
        if let Outcome::Closed(edges) = self.loops.check(&self.keys, &self.graph, k) {
            // A closure the graph already agrees with (its edges' cost within the
            // chi-square bound) changes nothing now: it joins the final optimisation.
            let surprise: f64 = edges.iter().map(|e| self.graph.edge_cost(e)).sum();
            let dof = 3 * edges.len() as u32;
            let bound =
                ekf_core::chi_square_quantile(SURPRISE_PROBABILITY, dof).map_err(slam_error)?;
            for edge in edges {
                self.graph.add_edge(edge).map_err(slam_error)?;
            }
            if surprise <= bound {
                self.unoptimized = true;
            } else {
                self.optimize()?;
                let corrected = self.graph.poses()[k];
                let covariance = *fuser.localizer().covariance();
                fuser
                    .localizer_mut()
                    .reset(corrected, covariance)
                    .map_err(slam_error)?;
                self.keys.get_mut(k).front = corrected;
                self.last_pose = Some(corrected);
            }
        }
        self.scans.push(ScanPose {
            t_ns: now,
            front: self.keys.get(k).front,
            key: k,
        });
        let (local, cloud) = self.local_map(k);
        fuser.localizer_mut().replace_map(local);
        self.cloud = cloud;
        Ok(true)
    }
}

/// A failure of the graph as a replay error.
fn slam_error(e: impl std::fmt::Display) -> ReplayError {
    ReplayError::Slam(e.to_string())
}

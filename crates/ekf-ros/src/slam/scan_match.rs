//! Point-to-line ICP of a scan's points against the points of the key scans near it: the
//! SLAM front end's correction of the filter's pose (docs/maps.md, "Building a map
//! without a reference").
//!
//! A line update moves the pose by what a scan's few extracted lines say; on ranges
//! rounded to a few centimetres a short line's direction is off by a degree or more, and
//! a map grown from the filter's poses keeps every such error, so the heading drifts.
//! Every beam of the scan, matched to the surface the earlier scans saw there, pins the
//! pose down far better: the residual of point `pᵢ` (robot frame) against its nearest
//! reference point `qᵢ` with surface normal `nᵢ` is `rᵢ = nᵢ·(R(θ)pᵢ + t − qᵢ)` (Censi's
//! point-to-line metric), and the pose minimises
//! `Σ ρ(rᵢ²/σ²) + (x − x₀)ᵀ P₀⁻¹ (x − x₀)`, `ρ` Huber's and `P₀` a weak prior around
//! the start `x₀` (the filter's pose, or the pose predicted before the scan's lines)
//! that holds the directions the points do not constrain (along a corridor) where the
//! start had them.

use crate::slam_config::{MatchParams, REFERENCE_VOXEL};
use ekf_core::{angle_diff, Pose2};
use ekf_fusion::{Predicted, Scan};
use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2, Vector3};
use std::cmp::Ordering;
use std::collections::HashSet;
use std::sync::LazyLock;

/// Of two poses of a scan, its points choose one only if McNemar's test rejects "neither
/// fits better" at this probability ([`points_prefer`]).
pub const PREFERENCE_PROBABILITY: f64 = 0.99;

/// `χ²₁(PREFERENCE_PROBABILITY)`, the bound of [`points_prefer`] that [`align`] and the
/// front end use.
pub fn preference_bound() -> f64 {
    static BOUND: LazyLock<f64> = LazyLock::new(|| {
        // A probability in (0, 1) and one degree of freedom always have a quantile; an
        // infinite bound would never prefer.
        ekf_core::chi_square_quantile(PREFERENCE_PROBABILITY, 1).unwrap_or(f64::INFINITY)
    });
    *BOUND
}

/// Beams on each side of a point whose points fit its surface normal.
const NORMAL_HALF_WINDOW: usize = 3;
/// Points farther than this (m) from the point do not fit its normal.
const NORMAL_RADIUS: f64 = 0.5;
/// The surface is a line if its points' spread across it is at most this (m, one σ).
const NORMAL_MAX_THICKNESS: f64 = 0.03;

/// A scan's points (robot frame), each with its surface normal where its neighbours
/// along the scan lie on a line.
#[derive(Debug, Clone, Default)]
pub struct ScanPoints {
    points: Vec<Vector2<f64>>,
    normals: Vec<Option<Vector2<f64>>>,
}

impl ScanPoints {
    /// The valid beams of `scan`, placed in the robot frame by the laser's `mount`.
    pub fn from_scan(scan: &Scan, mount: &Pose2<f64>) -> Self {
        let as_scan = scan.as_scan();
        let points: Vec<Vector2<f64>> = scan
            .ranges
            .iter()
            .enumerate()
            .filter(|(_, &r)| as_scan.is_valid(r))
            .map(|(i, &r)| {
                let (s, c) = as_scan.beam_angle(i).sin_cos();
                let r = f64::from(r);
                let p = mount.transform_point(&nalgebra::Point2::new(r * c, r * s));
                Vector2::new(p.x, p.y)
            })
            .collect();
        Self::from_points(points)
    }

    /// Points in scan order, each with the normal its neighbours give.
    fn from_points(points: Vec<Vector2<f64>>) -> Self {
        let normals = (0..points.len())
            .map(|i| surface_normal(&points, i))
            .collect();
        Self { points, normals }
    }

    /// The points of several scans in one frame, each `(pose, scan)` placed at `pose`
    /// (its robot frame in that frame).
    pub fn merged<'a>(scans: impl IntoIterator<Item = (Pose2<f64>, &'a ScanPoints)>) -> Self {
        let mut merged = Self::default();
        for (pose, scan) in scans {
            for (p, n) in scan.placed(&pose) {
                merged.points.push(p);
                merged.normals.push(n);
            }
        }
        merged
    }

    /// Every n-th point, n the smallest that leaves at most `most` of them.
    pub fn thinned(self, most: usize) -> Self {
        let stride = self.points.len().div_ceil(most.max(1)).max(1);
        Self {
            points: self.points.into_iter().step_by(stride).collect(),
            normals: self.normals.into_iter().step_by(stride).collect(),
        }
    }

    /// The points and normals moved by `pose` (a point `p` goes to `R(θ)p + t`).
    fn placed(
        &self,
        pose: &Pose2<f64>,
    ) -> impl Iterator<Item = (Vector2<f64>, Option<Vector2<f64>>)> + '_ {
        let (s, c) = pose.theta.sin_cos();
        let rotation = Matrix2::new(c, -s, s, c);
        let t = Vector2::new(pose.x, pose.y);
        self.points
            .iter()
            .zip(&self.normals)
            .map(move |(p, n)| (rotation * p + t, n.map(|n| rotation * n)))
    }

    /// How many points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// No points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The normal of the line through point `i` and its neighbours along the scan within
/// [`NORMAL_RADIUS`] (the smallest eigenvector of their scatter), if they are at least
/// three and lie on a line to [`NORMAL_MAX_THICKNESS`].
fn surface_normal(points: &[Vector2<f64>], i: usize) -> Option<Vector2<f64>> {
    let lo = i.saturating_sub(NORMAL_HALF_WINDOW);
    let hi = (i + NORMAL_HALF_WINDOW + 1).min(points.len());
    let near: Vec<&Vector2<f64>> = points[lo..hi]
        .iter()
        .filter(|p| (*p - points[i]).norm() <= NORMAL_RADIUS)
        .collect();
    if near.len() < 3 {
        return None;
    }
    let mean = near.iter().fold(Vector2::zeros(), |a, p| a + *p) / near.len() as f64;
    let scatter = near.iter().fold(Matrix2::zeros(), |a, p| {
        let d = *p - mean;
        a + d * d.transpose()
    }) / near.len() as f64;
    let eigen = SymmetricEigen::new(scatter);
    let (small, large) = match eigen.eigenvalues[0] <= eigen.eigenvalues[1] {
        true => (0, 1),
        false => (1, 0),
    };
    let thin = eigen.eigenvalues[small].max(0.0).sqrt() <= NORMAL_MAX_THICKNESS;
    let long = eigen.eigenvalues[large] > 0.0;
    (thin && long).then(|| eigen.eigenvectors.column(small).into_owned())
}

/// A point and the normal of the surface it lies on.
type Surface = (Vector2<f64>, Vector2<f64>);

/// Reference points with normals (map frame), sorted by the cell of a grid over their
/// bounding box so that the nearest one is looked for in nine cells.
#[derive(Debug, Clone, Default)]
pub struct ReferenceCloud {
    /// The points and their normals, those of each cell together (row by row).
    points: Vec<Surface>,
    cell: f64,
    /// The grid's first cell (cell coordinates) ...
    origin: (i64, i64),
    /// ... and its size in cells.
    width: usize,
    height: usize,
    /// Cell `c`'s points are `points[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
}

impl ReferenceCloud {
    /// The points with a normal of each `(pose, scan)`, placed at the pose, one per
    /// [`REFERENCE_VOXEL`]; grid cells of `cell` (m), the largest distance a match is
    /// looked for at.
    pub fn new<'a>(
        scans: impl IntoIterator<Item = (Pose2<f64>, &'a ScanPoints)>,
        cell: f64,
    ) -> Self {
        let mut voxels = HashSet::new();
        let mut points = Vec::new();
        for (pose, scan) in scans {
            for (q, n) in scan.placed(&pose) {
                let Some(n) = n else { continue };
                if voxels.insert(cell_of(&q, REFERENCE_VOXEL)) {
                    points.push((q, n));
                }
            }
        }
        let keys: Vec<(i64, i64)> = points.iter().map(|(q, _)| cell_of(q, cell)).collect();
        let (Some(x0), Some(y0), Some(x1), Some(y1)) = (
            keys.iter().map(|k| k.0).min(),
            keys.iter().map(|k| k.1).min(),
            keys.iter().map(|k| k.0).max(),
            keys.iter().map(|k| k.1).max(),
        ) else {
            return Self::default();
        };
        let (width, height) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
        let index = |k: &(i64, i64)| (k.1 - y0) as usize * width + (k.0 - x0) as usize;
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by_key(|&i| index(&keys[i]));
        let mut starts = vec![0u32; width * height + 1];
        for k in &keys {
            starts[index(k) + 1] += 1;
        }
        for c in 0..width * height {
            starts[c + 1] += starts[c];
        }
        Self {
            points: order.iter().map(|&i| points[i]).collect(),
            cell,
            origin: (x0, y0),
            width,
            height,
            starts,
        }
    }

    /// How many points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// The points of cell `(cx, cy)` (cell coordinates); none outside the grid.
    fn in_cell(&self, cx: i64, cy: i64) -> &[Surface] {
        let (ix, iy) = (cx - self.origin.0, cy - self.origin.1);
        if ix < 0 || iy < 0 || ix as usize >= self.width || iy as usize >= self.height {
            return &[];
        }
        let c = iy as usize * self.width + ix as usize;
        &self.points[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    /// The nearest reference point within the cell size of `p`.
    fn nearest(&self, p: &Vector2<f64>) -> Option<&Surface> {
        let (cx, cy) = cell_of(p, self.cell);
        let mut best: Option<(f64, &Surface)> = None;
        for dy in -1..=1 {
            for dx in -1..=1 {
                for point in self.in_cell(cx + dx, cy + dy) {
                    let d = (point.0 - p).norm_squared();
                    if d <= self.cell * self.cell && best.is_none_or(|(b, _)| d < b) {
                        best = Some((d, point));
                    }
                }
            }
        }
        best.map(|(_, point)| point)
    }
}

/// The cell of size `cell` (m) that holds `p`, in cell coordinates (exact: map
/// coordinates are far below 2⁵³ cells).
fn cell_of(p: &Vector2<f64>, cell: f64) -> (i64, i64) {
    ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64)
}

/// Which of two poses of the robot, `a` and `b`, the scan's points fit better, by
/// McNemar's test on the points that lie within the Huber threshold (`2σ`) of their
/// nearest reference surface at one pose and not at the other: with `n_a` such points at
/// `a` only and `n_b` at `b` only, `(|n_a − n_b| − 1)² / (n_a + n_b)` (Edwards' continuity
/// correction) is about χ²₁ if neither pose fits better; neighbouring beams on one wall do
/// not err independently, so the test prefers a pose more readily than its probability
/// says. [`Ordering::Greater`] (`a`) or [`Ordering::Less`] (`b`) when it exceeds
/// `bound`; `None` when the points do not tell them apart.
pub fn points_prefer(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    (a, b): (&Pose2<f64>, &Pose2<f64>),
    params: &MatchParams,
    bound: f64,
) -> Option<Ordering> {
    let fits = |w: &Vector2<f64>| fits_surface(reference, w, params);
    let (mut only_a, mut only_b) = (0u32, 0u32);
    for ((wa, _), (wb, _)) in scan.placed(a).zip(scan.placed(b)) {
        match (fits(&wa), fits(&wb)) {
            (true, false) => only_a += 1,
            (false, true) => only_b += 1,
            _ => {}
        }
    }
    let (na, nb) = (f64::from(only_a), f64::from(only_b));
    let statistic = match only_a + only_b {
        0 => 0.0,
        _ => ((na - nb).abs() - 1.0).max(0.0).powi(2) / (na + nb),
    };
    (statistic > bound).then(|| only_a.cmp(&only_b))
}

/// Whether the point `w` (reference frame) lies within the Huber threshold (`2σ`) of its
/// nearest reference surface.
fn fits_surface(reference: &ReferenceCloud, w: &Vector2<f64>, params: &MatchParams) -> bool {
    reference
        .nearest(w)
        .is_some_and(|(q, n)| n.dot(&(w - q)).abs() <= 2.0 * params.sigma)
}

/// How many of the scan's points, placed at `pose`, fit their nearest reference surface
/// ([`fits_surface`]).
fn fitting_points(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    pose: &Pose2<f64>,
    params: &MatchParams,
) -> usize {
    scan.placed(pose)
        .filter(|(w, _)| fits_surface(reference, w, params))
        .count()
}

/// Of the turns of a sweep ([`align_swept`]), how many are aligned: those where most of
/// the scan's points have a reference point within reach before any alignment.
const SWEEP_ALIGNED_TURNS: usize = 3;

/// The alignment of `scan` from `start` turned by a multiple of `step` (rad) up to
/// `reach` (rad; `π` or more: around the circle) each way (`+step`, `−step`, `+2·step`,
/// ...; `start` itself is not tried), for a scan whose heading is known only that well,
/// where one start reaches a few degrees. Coarse to fine: every turn is scored by how many
/// of the scan's points have a reference point within `max_distance` there, the
/// [`SWEEP_ALIGNED_TURNS`] best (the first of equals) are aligned, and of those
/// alignments the one with the most [`fitting_points`] wins. `None` if `reach` is less
/// than `step` or no alignment succeeds.
pub fn align_swept(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    start: Pose2<f64>,
    step: f64,
    reach: f64,
    params: &MatchParams,
) -> Option<Alignment> {
    if scan.is_empty() || reference.len() == 0 {
        return None;
    }
    let half_turn = (core::f64::consts::PI / step).round().max(1.0) as i32;
    let steps = ((reach.min(core::f64::consts::PI) / step).floor() as i32).min(half_turn);
    let mut turns: Vec<(usize, Pose2<f64>)> = (1..=steps)
        .flat_map(|k| [k, -k])
        .filter(|&k| k != -half_turn)
        .map(|k| {
            let theta = ekf_core::wrap_angle(start.theta + f64::from(k) * step);
            let pose = Pose2::new(start.x, start.y, theta);
            let within_reach = scan
                .placed(&pose)
                .filter(|(w, _)| reference.nearest(w).is_some())
                .count();
            (within_reach, pose)
        })
        .collect();
    // Stable: equals keep their order, nearest turns first.
    turns.sort_by_key(|&(within_reach, _)| std::cmp::Reverse(within_reach));
    let mut best: Option<(usize, Alignment)> = None;
    for (_, pose) in turns.into_iter().take(SWEEP_ALIGNED_TURNS) {
        let Some(a) = align(reference, scan, pose, params) else {
            continue;
        };
        let fitting = fitting_points(reference, scan, &a.pose, params);
        if best.as_ref().is_none_or(|(most, _)| fitting > *most) {
            best = Some((fitting, a));
        }
    }
    best.map(|(_, a)| a)
}

/// Of two alignments of `scan`, the one whose pose its points fit significantly better
/// ([`points_prefer`] with `bound`), else the one nearer the prediction: smaller
/// `dᵀ P⁻¹ d`, `d` the pose minus the predicted pose (heading wrapped), `P` the predicted
/// covariance. Where the points cannot tell two alignments apart, the motion decides.
pub fn preferred(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    (a, b): (Alignment, Alignment),
    predicted: &Predicted,
    params: &MatchParams,
    bound: f64,
) -> Alignment {
    match points_prefer(reference, scan, (&a.pose, &b.pose), params, bound) {
        Some(Ordering::Greater) => a,
        Some(Ordering::Less) => b,
        _ if mahalanobis(predicted, &b.pose) < mahalanobis(predicted, &a.pose) => b,
        _ => a,
    }
}

/// The squared Mahalanobis distance of `pose` from the prediction (see [`preferred`]);
/// infinite if the predicted covariance is singular.
fn mahalanobis(predicted: &Predicted, pose: &Pose2<f64>) -> f64 {
    let p = &predicted.pose;
    let d = Vector3::new(pose.x - p.x, pose.y - p.y, angle_diff(pose.theta, p.theta));
    predicted
        .covariance
        .try_inverse()
        .map_or(f64::INFINITY, |information| d.dot(&(information * d)))
}

/// The outcome of [`align`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// The robot's pose that puts the scan's points on the reference surfaces.
    pub pose: Pose2<f64>,
    /// Points matched at that pose.
    pub matched: usize,
    /// The information matrix of the points' residuals at the pose (without the prior).
    pub information: Matrix3<f64>,
}

/// Aligns `scan` (robot frame) to `reference` starting from `initial` (see the module
/// documentation): Gauss–Newton with Huber weights (`k = 2σ`), the matches found again at
/// each iteration. `None` if too few points match or the solve fails. If the points fit
/// `initial` significantly better than where the iterations ended ([`points_prefer`] at
/// [`preference_bound`]), the alignment is at `initial`: along a corridor the points
/// hardly hold the position, a full Gauss–Newton step can jump a door's width, and the
/// matches found anew there hold it (infinite-corridor at 520.7 s: 1 m back along the
/// corridor, to a pose 127 points fit where 144 fitted the start, and three more scans
/// after it; that one step cost the map 4.9 m). `matched` and `information` are always
/// those of where the iterations ended.
pub fn align(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    initial: Pose2<f64>,
    params: &MatchParams,
) -> Option<Alignment> {
    let ended = gauss_newton(reference, scan, initial, params)?;
    let worse = points_prefer(
        reference,
        scan,
        (&initial, &ended.pose),
        params,
        preference_bound(),
    ) == Some(Ordering::Greater);
    Some(match worse {
        true => Alignment {
            pose: initial,
            ..ended
        },
        false => ended,
    })
}

/// The iterations of [`align`].
fn gauss_newton(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    initial: Pose2<f64>,
    params: &MatchParams,
) -> Option<Alignment> {
    if scan.is_empty() || reference.len() == 0 {
        return None;
    }
    let prior = Matrix3::from_diagonal(&Vector3::new(
        params.prior_sigma_xy.powi(-2),
        params.prior_sigma_xy.powi(-2),
        params.prior_sigma_theta.powi(-2),
    ));
    let huber = 2.0 * params.sigma;
    let mut x = Vector3::new(initial.x, initial.y, initial.theta);
    let mut result = None;
    for _ in 0..params.max_iterations {
        let (s, c) = x.z.sin_cos();
        let rotation = Matrix2::new(c, -s, s, c);
        let t = Vector2::new(x.x, x.y);
        let mut information = Matrix3::zeros();
        let mut gradient = Vector3::zeros();
        let mut matched = 0;
        for p in &scan.points {
            let w = rotation * p + t;
            let Some((q, n)) = reference.nearest(&w) else {
                continue;
            };
            matched += 1;
            let r = n.dot(&(w - q));
            // ∂w/∂θ = R'(θ) p.
            let dw = Vector2::new(-s * p.x - c * p.y, c * p.x - s * p.y);
            let j = Vector3::new(n.x, n.y, n.dot(&dw));
            let weight = match r.abs() <= huber {
                true => 1.0,
                false => huber / r.abs(),
            } / (params.sigma * params.sigma);
            information += weight * j * j.transpose();
            gradient += weight * r * j;
        }
        if (matched as f64) < params.min_matched_share * scan.len() as f64 {
            return None;
        }
        let offset = Vector3::new(
            x.x - initial.x,
            x.y - initial.y,
            angle_diff(x.z, initial.theta),
        );
        let step = (information + prior)
            .cholesky()?
            .solve(&-(gradient + prior * offset));
        x += step;
        result = Some(Alignment {
            pose: Pose2::new(x.x, x.y, ekf_core::wrap_angle(x.z)),
            matched,
            information,
        });
        if step.xy().norm() < 1e-4 && step.z.abs() < 1e-5 {
            break;
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall from one end to the other.
    type Wall = ((f64, f64), (f64, f64));

    /// Points every 2 cm along the walls, in order.
    fn walls(segments: &[Wall]) -> Vec<Vector2<f64>> {
        segments
            .iter()
            .flat_map(|&((x0, y0), (x1, y1))| {
                let n = ((x1 - x0).hypot(y1 - y0) / 0.02).round() as usize;
                (0..=n).map(move |i| {
                    let f = i as f64 / n as f64;
                    Vector2::new(x0 + f * (x1 - x0), y0 + f * (y1 - y0))
                })
            })
            .collect()
    }

    /// The points as a robot at `pose` sees them (robot frame).
    fn seen_from(points: &[Vector2<f64>], pose: &Pose2<f64>) -> ScanPoints {
        let inverse = pose.inverse();
        ScanPoints::from_points(
            points
                .iter()
                .map(|p| {
                    let q = inverse.transform_point(&nalgebra::Point2::new(p.x, p.y));
                    Vector2::new(q.x, q.y)
                })
                .collect(),
        )
    }

    /// A room open on one side.
    const ROOM: [Wall; 3] = [
        ((0.0, 4.0), (0.0, 0.0)),
        ((0.0, 0.0), (5.0, 0.0)),
        ((5.0, 0.0), (5.0, 4.0)),
    ];

    /// The points as the reference, seen from the origin.
    fn reference(points: &[Vector2<f64>]) -> ReferenceCloud {
        let scan = ScanPoints::from_points(points.to_vec());
        ReferenceCloud::new([(Pose2::new(0.0, 0.0, 0.0), &scan)], 0.3)
    }

    #[test]
    fn a_room_scan_is_aligned_to_the_pose_it_was_seen_from() {
        let room = walls(&ROOM);
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 0.0));
        // Start 0.14 m and 0.03 rad off the pose the scan was seen from.
        let start = Pose2::new(2.6, 1.9, 0.03);
        let aligned = align(&reference(&room), &scan, start, &MatchParams::default()).unwrap();
        assert!((aligned.pose.x - 2.5).abs() < 1e-3, "{:?}", aligned.pose);
        assert!((aligned.pose.y - 2.0).abs() < 1e-3, "{:?}", aligned.pose);
        assert!(aligned.pose.theta.abs() < 1e-4, "{:?}", aligned.pose);
        assert_eq!(aligned.matched, scan.len());
        // Three walls in two directions constrain every direction.
        let eigen = aligned.information.symmetric_eigen();
        assert!(eigen.eigenvalues.iter().all(|&v| v > 1e3), "{eigen:?}");
    }

    #[test]
    fn along_a_corridor_the_prior_holds_the_position_the_points_do_not() {
        let corridor = walls(&[((0.0, 1.0), (20.0, 1.0)), ((20.0, -1.0), (0.0, -1.0))]);
        let scan = seen_from(&corridor, &Pose2::new(10.0, 0.0, 0.0));
        let start = Pose2::new(10.2, 0.1, 0.02);
        let aligned = align(&reference(&corridor), &scan, start, &MatchParams::default()).unwrap();
        // Across the corridor and in heading the walls decide; along it nothing does.
        assert!(aligned.pose.y.abs() < 1e-3, "{:?}", aligned.pose);
        assert!(aligned.pose.theta.abs() < 1e-4, "{:?}", aligned.pose);
        assert!((aligned.pose.x - 10.2).abs() < 0.01, "{:?}", aligned.pose);
        assert!(aligned.information[(0, 0)] < 1e-6 * aligned.information[(1, 1)]);
    }

    #[test]
    fn a_scan_far_from_the_reference_is_not_aligned() {
        let room = walls(&ROOM);
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 0.0));
        let params = MatchParams::default();
        assert!(align(&reference(&room), &scan, Pose2::new(4.0, 3.5, 0.0), &params).is_none());
        assert!(align(
            &ReferenceCloud::default(),
            &scan,
            Pose2::new(2.5, 2.0, 0.0),
            &params
        )
        .is_none());
    }

    #[test]
    fn a_scan_turned_far_beyond_one_start_s_reach_is_found_by_the_sweep() {
        let room = walls(&ROOM);
        let reference = reference(&room);
        let params = MatchParams::default();
        // Seen after an unseen turn of 80°: started from the heading before it, the
        // alignment does not get there.
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 80f64.to_radians()));
        let start = Pose2::new(2.6, 1.9, 0.0);
        let from_start = align(&reference, &scan, start, &params);
        assert!(
            from_start.is_none_or(|a| angle_diff(a.pose.theta, 80f64.to_radians()).abs() > 0.1),
            "{from_start:?}"
        );
        let step = 5f64.to_radians();
        // Within 30° of the start, the turn is not found.
        let near = align_swept(&reference, &scan, start, step, 30f64.to_radians(), &params);
        assert!(
            near.is_none_or(|a| angle_diff(a.pose.theta, 80f64.to_radians()).abs() > 0.1),
            "{near:?}"
        );
        let swept =
            align_swept(&reference, &scan, start, step, 90f64.to_radians(), &params).unwrap();
        assert!((swept.pose.x - 2.5).abs() < 1e-3, "{:?}", swept.pose);
        assert!((swept.pose.y - 2.0).abs() < 1e-3, "{:?}", swept.pose);
        assert!(
            angle_diff(swept.pose.theta, 80f64.to_radians()).abs() < 1e-4,
            "{:?}",
            swept.pose
        );
        assert_eq!(
            fitting_points(&reference, &scan, &swept.pose, &params),
            scan.len()
        );
        // Nothing to align to.
        let empty = ReferenceCloud::default();
        assert!(align_swept(&empty, &scan, start, step, 90f64.to_radians(), &params).is_none());
    }

    /// An alignment at `pose` (only the pose matters to [`preferred`]).
    fn at(x: f64, y: f64) -> Alignment {
        Alignment {
            pose: Pose2::new(x, y, 0.0),
            matched: 0,
            information: Matrix3::zeros(),
        }
    }

    /// A prediction at `(x, y)`, 0.1 m and 0.05 rad one σ.
    fn predicted_at(x: f64, y: f64) -> Predicted {
        Predicted {
            pose: Pose2::new(x, y, 0.0),
            covariance: Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.0025)),
        }
    }

    /// `χ²₁(0.99)`.
    const BOUND: f64 = 6.635;

    #[test]
    fn the_points_prefer_the_pose_they_were_seen_from() {
        let room = walls(&ROOM);
        let reference = reference(&room);
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 0.0));
        let params = MatchParams::default();
        let (truth, off) = (Pose2::new(2.5, 2.0, 0.0), Pose2::new(2.5, 2.2, 0.0));
        let prefer = |a, b| points_prefer(&reference, &scan, (a, b), &params, BOUND);
        assert_eq!(prefer(&truth, &off), Some(Ordering::Greater));
        assert_eq!(prefer(&off, &truth), Some(Ordering::Less));
        assert_eq!(prefer(&truth, &truth), None);
        // The points decide even against a prediction next to the worse pose.
        let chosen = preferred(
            &reference,
            &scan,
            (at(2.5, 2.2), at(2.5, 2.0)),
            &predicted_at(2.5, 2.2),
            &params,
            BOUND,
        );
        assert_eq!(chosen.pose, truth);
    }

    #[test]
    fn where_the_points_cannot_tell_two_poses_apart_the_prediction_decides() {
        // A 20 m corridor; the robot at x = 10 sees 10 m of it, which fit as well 0.7 m
        // further along.
        let corridor = [((0.0, 1.0), (20.0, 1.0)), ((20.0, -1.0), (0.0, -1.0))];
        let reference = reference(&walls(&corridor));
        let seen = walls(&[((5.0, 1.0), (15.0, 1.0)), ((15.0, -1.0), (5.0, -1.0))]);
        let scan = seen_from(&seen, &Pose2::new(10.0, 0.0, 0.0));
        let params = MatchParams::default();
        let (here, along) = (Pose2::new(10.0, 0.0, 0.0), Pose2::new(10.7, 0.0, 0.0));
        assert_eq!(
            points_prefer(&reference, &scan, (&here, &along), &params, BOUND),
            None
        );
        let choose = |predicted: Predicted| {
            preferred(
                &reference,
                &scan,
                (at(10.0, 0.0), at(10.7, 0.0)),
                &predicted,
                &params,
                BOUND,
            )
            .pose
        };
        assert_eq!(choose(predicted_at(10.6, 0.05)), along);
        assert_eq!(choose(predicted_at(10.1, 0.05)), here);
    }

    #[test]
    fn normals_are_found_on_walls_and_not_on_clutter() {
        let line = ScanPoints::from_points(walls(&[((1.0, -1.0), (1.0, 1.0))]));
        for n in &line.normals {
            let n = n.unwrap();
            assert!((n.x.abs() - 1.0).abs() < 1e-9 && n.y.abs() < 1e-9, "{n:?}");
        }
        // Points 10 cm apart across and along: no line through them.
        let clutter: Vec<_> = (0..20)
            .map(|i| Vector2::new(1.0 + 0.1 * (i % 2) as f64, 0.05 * i as f64))
            .collect();
        let clutter = ScanPoints::from_points(clutter);
        assert!(clutter.normals.iter().all(Option::is_none));
    }

    #[test]
    fn merged_scans_are_placed_at_their_poses() {
        let one = ScanPoints::from_points(walls(&[((1.0, 0.0), (1.0, 0.2))]));
        let pose = Pose2::new(2.0, 3.0, std::f64::consts::FRAC_PI_2);
        let merged = ScanPoints::merged([(Pose2::new(0.0, 0.0, 0.0), &one), (pose, &one)]);
        assert_eq!(merged.len(), 2 * one.len());
        let moved = merged.points[one.len()];
        // (1, 0) turned 90° is (0, 1), then moved by (2, 3).
        assert!((moved - Vector2::new(2.0, 4.0)).norm() < 1e-12, "{moved:?}");
        let normal = merged.normals[one.len()].unwrap();
        assert!(normal.x.abs() < 1e-9 && (normal.y.abs() - 1.0).abs() < 1e-9);
    }
}

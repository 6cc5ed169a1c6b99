//! Relocalization: where in a line map could the robot be, from one scan's lines alone?
//!
//! Two observed lines that are not parallel fix a pose against two map walls: the walls'
//! directions give the heading (up to a half turn, tried both ways), and their two line
//! equations then give the position. Every such pair among the scan's longest lines is
//! tried against every pair of map walls whose angle between them is the same (within
//! [`RelocalizeParams::angle_tolerance`]) and whose walls are long enough to hold what
//! was seen. Each pose is then scored against *all* the scan's long lines: an observed
//! line is an inlier when, placed in the world, it lies on a map wall (normal distance
//! of both end points within [`RelocalizeParams::inlier_distance`], direction within the
//! tolerance) and overlaps it. The score is the inliers' total length.
//!
//! A search is only as good as its margin over the alternatives: indoors, long parallel
//! corridors make many poses fit nearly as well. So the result reports the best pose and
//! the best score of a pose that is *elsewhere* (farther than
//! [`RelocalizeParams::distinct_distance`] or [`RelocalizeParams::distinct_angle`]); the
//! caller accepts the best only when it wins clearly ([`Relocalization::is_unambiguous`])
//! and verifies it over the next scans.

use crate::map::{line_direction, LineMap, MapSegment};
use crate::observed::ObservedLine;
use alloc::collections::{BTreeMap, BTreeSet};
use alloc::vec::Vec;
use core::f64::consts::PI;
use ekf_core::{angle_diff, wrap_angle, Pose2};
use nalgebra::{Point2, Vector2};

/// Settings of the relocalization search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelocalizeParams {
    /// Observed lines used, the longest first.
    pub max_lines: usize,
    /// Shortest observed line used (m).
    pub min_line_length: f64,
    /// Smallest angle between the two lines of a pair (rad): nearly parallel lines do not
    /// fix the position along them.
    pub min_pair_angle: f64,
    /// Direction agreement of an observed line with a map wall (rad).
    pub angle_tolerance: f64,
    /// Normal distance of an inlier's end points from its wall (m).
    pub inlier_distance: f64,
    /// Fewest inlier lines for a pose to count.
    pub min_inliers: usize,
    /// A pose this far from the best (m) counts as elsewhere.
    pub distinct_distance: f64,
    /// ... or turned this much from it (rad).
    pub distinct_angle: f64,
    /// The best score must be at least this multiple of the best elsewhere.
    pub min_margin: f64,
    /// Most candidate poses a search keeps ([`Relocalization::candidates`]).
    pub max_candidates: usize,
}

impl RelocalizeParams {
    /// Whether a pose with `inliers` inlier lines and `score` (m) explains scans of
    /// `observed_length` (m) well enough to stand: at least
    /// [`min_inliers`](Self::min_inliers) inliers and half of the observed length
    /// (weighted by fit). One scan's search or several scans' sums alike.
    pub fn explains(&self, inliers: usize, score: f64, observed_length: f64) -> bool {
        inliers >= self.min_inliers && score >= 0.5 * observed_length
    }

    /// Whether pose `a` is elsewhere than `b`: farther than
    /// [`distinct_distance`](Self::distinct_distance) or turned more than
    /// [`distinct_angle`](Self::distinct_angle).
    pub fn elsewhere(&self, a: &Pose2<f64>, b: &Pose2<f64>) -> bool {
        libm::hypot(a.x - b.x, a.y - b.y) > self.distinct_distance
            || angle_diff(a.theta, b.theta).abs() > self.distinct_angle
    }
}

impl Default for RelocalizeParams {
    fn default() -> Self {
        Self {
            max_lines: 8,
            min_line_length: 0.6,
            min_pair_angle: 30f64.to_radians(),
            angle_tolerance: 3f64.to_radians(),
            inlier_distance: 0.15,
            min_inliers: 3,
            distinct_distance: 0.5,
            distinct_angle: 10f64.to_radians(),
            min_margin: 1.2,
            max_candidates: 8,
        }
    }
}

/// Where the search may put the robot: within `radius` (m) of `center`, and with a
/// heading within `heading` if one is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchWindow {
    /// Centre of the search (world frame, m).
    pub center: Point2<f64>,
    /// Largest distance from the centre (m); `f64::INFINITY` for the whole map.
    pub radius: f64,
    /// Headings the robot may have; `None` for any.
    pub heading: Option<HeadingWindow>,
}

/// Headings within `tolerance` of `theta` (rad): `|wrap(θ − theta)| ≤ tolerance`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingWindow {
    /// The heading the window is centred on (rad).
    pub theta: f64,
    /// Largest difference from it (rad).
    pub tolerance: f64,
}

impl SearchWindow {
    /// The whole map, any heading.
    pub fn global() -> Self {
        Self {
            center: Point2::origin(),
            radius: f64::INFINITY,
            heading: None,
        }
    }

    /// Within `radius` of `center`, any heading.
    pub fn around(center: Point2<f64>, radius: f64) -> Self {
        Self {
            center,
            radius,
            heading: None,
        }
    }

    /// Whether `pose` lies in the window.
    pub fn contains(&self, pose: &Pose2<f64>) -> bool {
        (Point2::new(pose.x, pose.y) - self.center).norm() <= self.radius
            && self
                .heading
                .is_none_or(|h| angle_diff(pose.theta, h.theta).abs() <= h.tolerance)
    }
}

/// One candidate pose and how well the scan fits there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hypothesis {
    /// The robot's pose.
    pub pose: Pose2<f64>,
    /// Observed lines that lie on a map wall there.
    pub inliers: usize,
    /// Their total length, each weighted by how closely it lies on its wall (m; see
    /// [`relocalize`]).
    pub score: f64,
}

/// The outcome of a search.
#[derive(Debug, Clone, PartialEq)]
pub struct Relocalization {
    /// The best pose.
    pub best: Hypothesis,
    /// The best score of a pose elsewhere (0 if there is none).
    pub runner_up: f64,
    /// The best poses, each elsewhere than every better one, best first (`best` is the
    /// first), at most [`RelocalizeParams::max_candidates`]: what a verification over
    /// the next scans chooses among ([`fit_poses`]).
    pub candidates: Vec<Hypothesis>,
    /// Total length of the observed lines used (m).
    pub observed_length: f64,
    /// Poses scored.
    pub hypotheses: usize,
}

impl Relocalization {
    /// The best pose explains the scan ([`RelocalizeParams::explains`]).
    pub fn explains_scan(&self, params: &RelocalizeParams) -> bool {
        params.explains(self.best.inliers, self.best.score, self.observed_length)
    }

    /// The best pose explains the scan and beats every pose elsewhere by
    /// `params.min_margin`.
    pub fn is_unambiguous(&self, params: &RelocalizeParams) -> bool {
        self.explains_scan(params) && self.best.score >= params.min_margin * self.runner_up
    }
}

/// A line of the scan in the robot frame: end points, direction angle (mod π), length.
#[derive(Debug, Clone, Copy)]
struct RobotLine {
    a: Point2<f64>,
    b: Point2<f64>,
    angle: f64,
    length: f64,
}

/// Direction angle of a segment, in [0, π).
fn direction_angle(a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let d = b - a;
    let t = libm::atan2(d.y, d.x);
    if t < 0.0 {
        t + PI
    } else if t >= PI {
        t - PI
    } else {
        t
    }
}

/// Difference of two direction angles modulo π, in (−π/2, π/2]: how far two lines are
/// from parallel, whether given by their directions or by their normals. The search pairs
/// only lines at least [`RelocalizeParams::min_pair_angle`] apart by it.
pub fn direction_diff(a: f64, b: f64) -> f64 {
    let d = wrap_angle(2.0 * (a - b)) / 2.0;
    if d <= -PI / 2.0 {
        d + PI
    } else {
        d
    }
}

/// Searches `map` for the robot poses that fit the scan's `lines` (sensor frame, laser
/// at `mount` on the robot) within `window`; `None` if the scan has no usable pair of
/// lines or no pose gets `params.min_inliers`.
///
/// Pairs are formed with the two longest lines only, walls are looked up by direction
/// (sorted, binary search) and by place (a grid), and poses that round to one already
/// scored (10 cm, 1°) are not scored again, so the cost grows with the map about as
/// `M · M·tol/π` rather than `M²`.
pub fn relocalize(
    lines: &[ObservedLine],
    map: &LineMap,
    mount: &Pose2<f64>,
    window: &SearchWindow,
    params: &RelocalizeParams,
) -> Option<Relocalization> {
    let observed = robot_lines(lines, mount, params);
    let observed_length: f64 = observed.iter().map(|l| l.length).sum();
    // A wall can hold a seen line only if it comes within the line's range of the window.
    let reach = window.radius + range_of(&observed);
    let index = WallIndex::new(
        map,
        params.inlier_distance,
        |w| w.distance_to(&window.center) <= reach,
        |w| w.distance_to(&window.center) <= reach + params.inlier_distance,
    );
    // Pairs with the two longest lines: one of them may be clutter the map lacks.
    let anchors = 2;

    let mut hypotheses: Vec<Hypothesis> = Vec::new();
    let mut seen: BTreeSet<(i64, i64, i64)> = BTreeSet::new();
    let mut scored = 0;
    for (i, oi) in observed.iter().enumerate().take(anchors) {
        for oj in observed.iter().skip(i + 1) {
            let pair_angle = direction_diff(oj.angle, oi.angle);
            if pair_angle.abs() < params.min_pair_angle {
                continue;
            }
            for &(angle_a, a) in &index.by_angle {
                let wa = &map.segments[a];
                if wa.length() + params.inlier_distance < oi.length {
                    continue;
                }
                for b in index.with_angle(angle_a + pair_angle, params.angle_tolerance) {
                    let wb = &map.segments[b];
                    if a == b || wb.length() + params.inlier_distance < oj.length {
                        continue;
                    }
                    for flip in [0.0, PI] {
                        let theta = wrap_angle(angle_a - oi.angle + flip);
                        if window
                            .heading
                            .is_some_and(|h| angle_diff(theta, h.theta).abs() > h.tolerance)
                        {
                            continue;
                        }
                        let Some(pose) = pose_from_pair(theta, oi, wa, oj, wb) else {
                            continue;
                        };
                        if !window.contains(&pose)
                            || !on_wall(&pose, oi, wa, params)
                            || !on_wall(&pose, oj, wb, params)
                        {
                            continue;
                        }
                        let key = (
                            libm::round(pose.x / 0.1) as i64,
                            libm::round(pose.y / 0.1) as i64,
                            libm::round(pose.theta.to_degrees()) as i64,
                        );
                        if !seen.insert(key) {
                            continue;
                        }
                        scored += 1;
                        let h = score(&pose, &observed, map, &index, params);
                        if h.inliers >= params.min_inliers {
                            hypotheses.push(h);
                        }
                    }
                }
            }
        }
    }
    hypotheses.sort_by(|x, y| y.score.total_cmp(&x.score));
    let mut candidates: Vec<Hypothesis> = Vec::new();
    for h in &hypotheses {
        if candidates.len() >= params.max_candidates.max(2) {
            break;
        }
        if candidates
            .iter()
            .all(|c| params.elsewhere(&h.pose, &c.pose))
        {
            candidates.push(*h);
        }
    }
    let best = *candidates.first()?;
    let runner_up = candidates.get(1).map_or(0.0, |h| h.score);
    candidates.truncate(params.max_candidates.max(1));
    Some(Relocalization {
        best,
        runner_up,
        candidates,
        observed_length,
        hypotheses: scored,
    })
}

/// The farthest end point of `observed` from the robot (m): a wall farther than this
/// from the robot cannot hold any of the lines.
fn range_of(observed: &[RobotLine]) -> f64 {
    observed
        .iter()
        .map(|l| l.a.coords.norm().max(l.b.coords.norm()))
        .fold(0.0, f64::max)
}

/// The scan's lines usable by the search, in the robot frame (laser at `mount`): those
/// at least [`RelocalizeParams::min_line_length`] long, the longest
/// [`RelocalizeParams::max_lines`] of them, longest first.
fn robot_lines(
    lines: &[ObservedLine],
    mount: &Pose2<f64>,
    params: &RelocalizeParams,
) -> Vec<RobotLine> {
    let mut observed: Vec<RobotLine> = lines
        .iter()
        .filter(|l| l.length() >= params.min_line_length)
        .map(|l| {
            let (a, b) = (
                mount.transform_point(&l.start),
                mount.transform_point(&l.end),
            );
            RobotLine {
                a,
                b,
                angle: direction_angle(&a, &b),
                length: l.length(),
            }
        })
        .collect();
    observed.sort_by(|x, y| y.length.total_cmp(&x.length));
    observed.truncate(params.max_lines);
    observed
}

/// How well one scan fits given poses: each pose scored as a search scores its
/// hypotheses, with the length of the observed lines used.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseFits {
    /// One per pose, in order.
    pub fits: Vec<Hypothesis>,
    /// Total length of the observed lines used (m).
    pub observed_length: f64,
}

/// Scores the scan's `lines` (laser at `mount`) at each of `poses` against `map`, as
/// [`relocalize`] scores its hypotheses: the verification of a search's candidates over
/// the scans after it, each candidate where the motion model carried it.
pub fn fit_poses(
    lines: &[ObservedLine],
    map: &LineMap,
    mount: &Pose2<f64>,
    poses: &[Pose2<f64>],
    params: &RelocalizeParams,
) -> PoseFits {
    let observed = robot_lines(lines, mount, params);
    let reach = range_of(&observed) + params.inlier_distance;
    let index = WallIndex::new(
        map,
        params.inlier_distance,
        |_| false,
        |w| {
            poses
                .iter()
                .any(|p| w.distance_to(&Point2::new(p.x, p.y)) <= reach)
        },
    );
    PoseFits {
        fits: poses
            .iter()
            .map(|p| score(p, &observed, map, &index, params))
            .collect(),
        observed_length: observed.iter().map(|l| l.length).sum(),
    }
}

/// Side of a [`WallIndex`] grid cell (m).
const CELL: f64 = 2.0;

/// The map's walls by direction and by place.
struct WallIndex {
    /// `(direction angle in [0, π), wall)`, sorted by angle.
    by_angle: Vec<(f64, usize)>,
    /// Grid cell → walls within `margin` of it.
    cells: BTreeMap<(i64, i64), Vec<usize>>,
}

impl WallIndex {
    /// The walls of `map` that pass `pair` by direction (the walls a line pair may be
    /// put on), and those that pass `place` by place (the walls an observed line may lie
    /// on: every wall within reach of where the robot may be, so leaving out the others
    /// changes no score).
    fn new(
        map: &LineMap,
        margin: f64,
        pair: impl Fn(&MapSegment) -> bool,
        place: impl Fn(&MapSegment) -> bool,
    ) -> Self {
        let mut by_angle: Vec<(f64, usize)> = map
            .segments
            .iter()
            .enumerate()
            .filter(|(_, s)| pair(s))
            .map(|(i, s)| (direction_angle(&s.start, &s.end), i))
            .collect();
        by_angle.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut cells: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
        for (i, s) in map.segments.iter().enumerate().filter(|(_, s)| place(s)) {
            // Samples along the wall at most half a cell apart, each marking the cells
            // of the box around it that reaches half-way to the next sample plus the
            // margin (narrower than a cell, so its four corners find every cell).
            let steps = libm::ceil(s.length() / (0.5 * CELL)).max(1.0) as usize;
            let reach = 0.5 * s.length() / steps as f64 + margin;
            for k in 0..=steps {
                let p = s.start + (s.end - s.start) * (k as f64 / steps as f64);
                for (dx, dy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let c = cell(&Point2::new(p.x + dx * reach, p.y + dy * reach));
                    let list = cells.entry(c).or_default();
                    if !list.contains(&i) {
                        list.push(i);
                    }
                }
            }
        }
        Self { by_angle, cells }
    }

    /// Walls whose direction is within `tolerance` of `angle` (mod π).
    fn with_angle(&self, angle: f64, tolerance: f64) -> impl Iterator<Item = usize> + '_ {
        let a = libm::fmod(libm::fmod(angle, PI) + PI, PI);
        let (lo, hi) = (a - tolerance, a + tolerance);
        // The window wraps at 0 and π: look it up as up to three plain ranges.
        [(lo, hi), (lo + PI, hi + PI), (lo - PI, hi - PI)]
            .into_iter()
            .flat_map(move |(l, h)| {
                let start = self.by_angle.partition_point(|&(x, _)| x < l);
                let end = self.by_angle.partition_point(|&(x, _)| x <= h);
                self.by_angle[start..end.max(start)].iter().map(|&(_, i)| i)
            })
    }

    /// Walls that may pass near `p`.
    fn near(&self, p: &Point2<f64>) -> &[usize] {
        self.cells.get(&cell(p)).map_or(&[], Vec::as_slice)
    }
}

fn cell(p: &Point2<f64>) -> (i64, i64) {
    (
        libm::floor(p.x / CELL) as i64,
        libm::floor(p.y / CELL) as i64,
    )
}

/// The robot pose at heading `theta` that puts observed line `oi` on wall `wa` and `oj`
/// on `wb`: with `n` a wall's unit normal and `ρ` its distance, the robot position `t`
/// solves `n · (t + R(θ) m) = ρ` for a point `m` of each observed line.
fn pose_from_pair(
    theta: f64,
    oi: &RobotLine,
    wa: &MapSegment,
    oj: &RobotLine,
    wb: &MapSegment,
) -> Option<Pose2<f64>> {
    let rot = Pose2::new(0.0, 0.0, theta);
    let mi = rot.transform_point(&nalgebra::center(&oi.a, &oi.b));
    let mj = rot.transform_point(&nalgebra::center(&oj.a, &oj.b));
    let (na, nb) = (normal(wa), normal(wb));
    let ra = wa.line.rho - na.dot(&mi.coords);
    let rb = wb.line.rho - nb.dot(&mj.coords);
    let det = na.x * nb.y - na.y * nb.x;
    if det.abs() < 1e-6 {
        return None;
    }
    let x = (ra * nb.y - rb * na.y) / det;
    let y = (na.x * rb - nb.x * ra) / det;
    Some(Pose2::new(x, y, theta))
}

fn normal(s: &MapSegment) -> Vector2<f64> {
    Vector2::new(libm::cos(s.line.beta), libm::sin(s.line.beta))
}

/// How closely the observed segment `a`–`b` (world frame, length `length`) lies on
/// `wall`: `exp(−(d_a² + d_b²) / (2 σ²))` of its end points' normal distances, with `σ`
/// half the inlier distance; `None` unless both end points are within the inlier
/// distance, the directions agree within the tolerance and the segment overlaps the wall
/// by half its length.
fn fit(
    wall: &MapSegment,
    a: &Point2<f64>,
    b: &Point2<f64>,
    length: f64,
    params: &RelocalizeParams,
) -> Option<f64> {
    let (da, db) = (wall.line.signed_distance(a), wall.line.signed_distance(b));
    if da.abs() > params.inlier_distance || db.abs() > params.inlier_distance {
        return None;
    }
    if direction_diff(
        direction_angle(a, b),
        direction_angle(&wall.start, &wall.end),
    )
    .abs()
        > params.angle_tolerance
    {
        return None;
    }
    let dir = line_direction(&wall.line);
    let (s0, s1) = (dir.dot(&wall.start.coords), dir.dot(&wall.end.coords));
    let (o0, o1) = (dir.dot(&a.coords), dir.dot(&b.coords));
    let overlap = o0.max(o1).min(s0.max(s1)) - o0.min(o1).max(s0.min(s1));
    let sigma = 0.5 * params.inlier_distance;
    (overlap >= 0.5 * length).then(|| libm::exp(-(da * da + db * db) / (2.0 * sigma * sigma)))
}

/// Whether observed line `o` lies on `wall` with the robot at `pose`.
fn on_wall(pose: &Pose2<f64>, o: &RobotLine, wall: &MapSegment, params: &RelocalizeParams) -> bool {
    let (a, b) = (pose.transform_point(&o.a), pose.transform_point(&o.b));
    fit(wall, &a, &b, o.length, params).is_some()
}

/// How well the scan fits at `pose`: each observed line that lies on a wall ([`fit`]) is
/// an inlier and adds its length weighted by its best fit, so that of two poses a few
/// centimetres apart the one that fits better scores higher.
fn score(
    pose: &Pose2<f64>,
    observed: &[RobotLine],
    map: &LineMap,
    index: &WallIndex,
    params: &RelocalizeParams,
) -> Hypothesis {
    let mut h = Hypothesis {
        pose: *pose,
        inliers: 0,
        score: 0.0,
    };
    for o in observed {
        let (a, b) = (pose.transform_point(&o.a), pose.transform_point(&o.b));
        let best = index
            .near(&nalgebra::center(&a, &b))
            .iter()
            .filter_map(|&w| fit(&map.segments[w], &a, &b, o.length, params))
            .fold(None, |best: Option<f64>, f| {
                Some(best.map_or(f, |b| b.max(f)))
            });
        if let Some(best) = best {
            h.inliers += 1;
            h.score += o.length * best;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> MapSegment {
        MapSegment::from_points(Point2::new(x0, y0), Point2::new(x1, y1)).unwrap()
    }

    /// An L-shaped room with a slanted cabinet, so that it has one pose per scan.
    fn room() -> LineMap {
        LineMap::new(alloc::vec![
            wall(6.0, 2.0, 7.0, 2.8),
            wall(0.0, 0.0, 10.0, 0.0),
            wall(10.0, 0.0, 10.0, 6.0),
            wall(10.0, 6.0, 4.0, 6.0),
            wall(4.0, 6.0, 4.0, 3.0),
            wall(4.0, 3.0, 0.0, 3.0),
            wall(0.0, 3.0, 0.0, 0.0),
        ])
    }

    /// The walls seen from `robot` as observed lines in the sensor frame (laser at
    /// `mount`): each wall's part within `reach` of the robot, whole.
    fn observe(map: &LineMap, robot: &Pose2<f64>, mount: &Pose2<f64>) -> Vec<ObservedLine> {
        let sensor = robot.compose(mount);
        map.segments
            .iter()
            .map(|w| {
                let (a, b) = (
                    sensor.inverse_transform_point(&w.start),
                    sensor.inverse_transform_point(&w.end),
                );
                ObservedLine {
                    line: ekf_core::Line::from_segment(&a, &b).unwrap(),
                    covariance: nalgebra::Matrix2::identity() * 1e-4,
                    start: a,
                    end: b,
                    num_points: 50,
                }
            })
            .collect()
    }

    #[test]
    fn the_pose_is_found_anywhere_in_the_map() {
        let map = room();
        let mount = Pose2::new(0.2, 0.0, -PI / 2.0);
        let params = RelocalizeParams::default();
        for robot in [
            Pose2::new(2.0, 1.5, 0.3),
            Pose2::new(8.0, 4.0, -2.5),
            Pose2::new(6.0, 1.0, PI),
        ] {
            let lines = observe(&map, &robot, &mount);
            let r =
                relocalize(&lines, &map, &mount, &SearchWindow::global(), &params).expect("a pose");
            let p = r.best.pose;
            assert!(
                (p.x - robot.x).hypot(p.y - robot.y) < 1e-6
                    && angle_diff(p.theta, robot.theta).abs() < 1e-6,
                "{p:?} for {robot:?}"
            );
            assert_eq!(r.best.inliers, 7);
            assert!(r.best.score > r.runner_up, "{r:?}");
        }
    }

    /// A plain 8 m × 4 m rectangle.
    fn rectangle() -> LineMap {
        LineMap::new(alloc::vec![
            wall(0.0, 0.0, 8.0, 0.0),
            wall(8.0, 0.0, 8.0, 4.0),
            wall(8.0, 4.0, 0.0, 4.0),
            wall(0.0, 4.0, 0.0, 0.0),
        ])
    }

    #[test]
    fn a_window_keeps_the_search_local_and_a_symmetric_room_is_ambiguous() {
        // A plain rectangle looks the same from a pose and its half-turn twin.
        let map = rectangle();
        let mount = Pose2::identity();
        let robot = Pose2::new(2.0, 1.0, 0.2);
        let lines = observe(&map, &robot, &mount);
        let params = RelocalizeParams::default();
        let global = relocalize(&lines, &map, &mount, &SearchWindow::global(), &params).unwrap();
        assert!(!global.is_unambiguous(&params), "{global:?}");
        let near = SearchWindow::around(Point2::new(2.3, 1.2), 1.0);
        let local = relocalize(&lines, &map, &mount, &near, &params).unwrap();
        assert!(local.is_unambiguous(&params), "{local:?}");
        assert!((local.best.pose.x - 2.0).abs() < 1e-6 && (local.best.pose.y - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_heading_window_keeps_only_the_poses_turned_within_it() {
        // The rectangle again: the robot's pose and its half-turn twin both fit, anywhere
        // in the room; a heading window tells them apart.
        let map = rectangle();
        let mount = Pose2::identity();
        let robot = Pose2::new(2.0, 1.0, 0.2);
        let lines = observe(&map, &robot, &mount);
        let params = RelocalizeParams::default();
        let turned = |theta: f64| SearchWindow {
            center: Point2::new(4.0, 2.0),
            radius: 10.0,
            heading: Some(HeadingWindow {
                theta,
                tolerance: 5f64.to_radians(),
            }),
        };
        let found = |window: &SearchWindow| relocalize(&lines, &map, &mount, window, &params);
        let right = found(&turned(0.2 + 4f64.to_radians())).expect("the robot's pose");
        assert!(right.is_unambiguous(&params), "{right:?}");
        let p = right.best.pose;
        assert!((p.x - 2.0).hypot(p.y - 1.0) < 1e-6 && angle_diff(p.theta, 0.2).abs() < 1e-9);
        let twin = found(&turned(0.2 + PI)).expect("the twin").best.pose;
        assert!((twin.x - 6.0).hypot(twin.y - 3.0) < 1e-6, "{twin:?}");
        assert!(angle_diff(twin.theta, 0.2 + PI).abs() < 1e-9);
        // 6° off either: nothing in the window.
        assert!(found(&turned(0.2 + 6f64.to_radians())).is_none());
        assert!(SearchWindow::around(Point2::new(4.0, 2.0), 10.0).contains(&twin));
        assert!(!turned(0.2).contains(&twin));
    }

    #[test]
    fn parallel_lines_alone_give_no_pose() {
        let map = room();
        let lines: Vec<ObservedLine> =
            observe(&map, &Pose2::new(2.0, 1.5, 0.0), &Pose2::identity())
                .into_iter()
                .filter(|l| libm::fabs(libm::sin(l.line.beta)) < 0.5)
                .collect();
        assert!(relocalize(
            &lines,
            &map,
            &Pose2::identity(),
            &SearchWindow::global(),
            &RelocalizeParams::default()
        )
        .is_none());
    }
}

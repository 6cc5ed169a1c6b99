//! The error of a map built from the first scan, carried as the Localizer runs.
//!
//! A wall placed from a scan line `z = (r, ψ)` seen from the pose `x_b` has the error
//! `δm = G δx_b + F δz`, with `F = H_m⁻¹` and `G = −H_m⁻¹ H` from the line model `h(x, m)`
//! at the placement (a line seen from a known pose gives the map line back). The two
//! parts are treated differently:
//! - the placement error `b = δx_b`, shared by every wall (the whole map is shifted and
//!   turned with it), is **estimated**: its estimate is applied to the map, moving it
//!   rigidly (a wall when a line is fused against it, all of them once a scan's lines or
//!   a state measurement are fused), so what is carried is its covariance `P_bb` and its
//!   correlation `P_xb` with the state. At the placement the state's error is `b` itself
//!   (`P_xb = P_bb = P`). A compass, which measures the heading in its own frame, thus
//!   turns the map into that frame as the run goes on; a position fix shifts it;
//! - each wall's fit error `f_j = F δz_j`, covariance `C_j = F R_j Fᵀ`, is **considered**
//!   (Schmidt–Kalman, see [`ekf_core::Considered`]): not estimated, since it is different
//!   for every wall, but carried through its correlations `X_j = Cov(δx, f_j)` and
//!   `Y_j = Cov(b, f_j)`, so the filter cannot average it away as it would fresh noise.
//!
//! A line matched to wall `j` measures `h(x, m_j)` with `δm_j = G_j b + f_j`; every
//! update of the state (`x ← x + K y`, gain `K` from [`ekf_core::Ekf`]) updates the
//! placement with `K_b = Cov(b, y) S⁻¹` as the augmented Kalman filter would.

use crate::{LineMap, MapSegment, ObservedLine, WallErrors};
use alloc::vec::Vec;
use ekf_core::{
    angle_diff, Considered, ConsideredUpdate, Error, Innovation, LaserLine, Line, Measurement,
    Pose2, UpdateOutcome,
};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x2, Vector3};

/// One wall's error.
#[derive(Debug, Clone, Copy, PartialEq)]
struct WallError {
    /// `C = F R Fᵀ`: the wall's own (fit) error, independent of every other wall's.
    own: Matrix2<f64>,
    /// `G = ∂(ρ, β)/∂(x, y, θ)` of the placement pose.
    placement_jacobian: Matrix2x3<f64>,
    /// `X = Cov(δx, f)`: the state's error correlated with the wall's fit error.
    cross: Matrix3x2<f64>,
    /// `Y = Cov(b, f)`: the placement's error correlated with the wall's fit error.
    placement_cross: Matrix3x2<f64>,
    /// The placement the wall's segment and `G` were last moved to (see
    /// [`MapErrors::move_wall`]).
    placed_from: Pose2<f64>,
}

impl WallError {
    /// The same error for the wall's line written the other way round, `(−ρ, β + π)`:
    /// `δρ` changes sign, so `C ← T C T`, `X ← X T`, `Y ← Y T` with `T = diag(−1, 1)`.
    fn flipped(&self) -> Self {
        let t = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
        Self {
            own: t * self.own * t,
            cross: self.cross * t,
            placement_cross: self.placement_cross * t,
            ..*self
        }
    }

    fn is_finite(&self) -> bool {
        all_finite(self.own.as_slice())
            && all_finite(self.cross.as_slice())
            && all_finite(self.placement_cross.as_slice())
    }
}

/// The placement: where the map was placed from (as corrected so far) and its error.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Placement {
    /// The pose the map is placed from.
    pose: Pose2<f64>,
    /// `P_bb`: the covariance of the placement's error `b`.
    covariance: Matrix3<f64>,
    /// `P_xb = Cov(δx, b)`.
    state_cross: Matrix3<f64>,
    /// `true` once a line has been fused against the map: the robot's heading relative to
    /// the map has been seen since it was placed.
    seen_again: bool,
}

impl Placement {
    /// Placed from `pose` with covariance `covariance`: the state's error is `b` itself.
    fn new(pose: Pose2<f64>, covariance: Matrix3<f64>) -> Self {
        Self {
            pose,
            covariance,
            state_cross: covariance,
            seen_again: false,
        }
    }
}

/// The errors of a first-scan map's walls and their correlation with the state, indexed
/// like the map's segments; none (the default) for a given map.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MapErrors {
    walls: Vec<WallError>,
    /// The laser's mounting pose, for the walls' `G`.
    mount: Pose2<f64>,
    placement: Placement,
    /// What [`save`](Self::save) kept, in buffers reused from scan to scan.
    saved: Saved,
}

/// A copy of the [`MapErrors`] and the map's walls to go back to.
#[derive(Debug, Clone, PartialEq)]
struct Saved {
    walls: Vec<WallError>,
    segments: Vec<MapSegment>,
    placement: Placement,
}

impl Default for MapErrors {
    /// No walls: a given map, whose error is the matching's map noise.
    fn default() -> Self {
        let nothing = Placement::new(Pose2::identity(), Matrix3::zeros());
        Self {
            walls: Vec::new(),
            mount: Pose2::identity(),
            placement: nothing,
            saved: Saved {
                walls: Vec::new(),
                segments: Vec::new(),
                placement: nothing,
            },
        }
    }
}

impl MapErrors {
    /// The errors of `map`, whose wall `j` was placed from `lines[sources[j]]` seen by the
    /// laser at `mount` on a robot at `pose` with covariance `covariance`
    /// (see [`LineMap::from_scan_with_sources`]).
    pub(crate) fn of_first_scan(
        map: &LineMap,
        lines: &[ObservedLine],
        sources: &[usize],
        pose: &Pose2<f64>,
        covariance: &Matrix3<f64>,
        mount: &Pose2<f64>,
    ) -> Self {
        let walls = map
            .segments
            .iter()
            .zip(sources)
            .map(|(segment, &source)| {
                let (f, placement_jacobian) = placement_jacobians(&segment.line, pose, mount);
                WallError {
                    own: f * lines[source].covariance * f.transpose(),
                    placement_jacobian,
                    cross: Matrix3x2::zeros(),
                    placement_cross: Matrix3x2::zeros(),
                    placed_from: *pose,
                }
            })
            .collect();
        Self {
            walls,
            mount: *mount,
            placement: Placement::new(*pose, *covariance),
            ..Self::default()
        }
    }

    /// `true` for a map without errors (a given map).
    pub(crate) fn is_empty(&self) -> bool {
        self.walls.is_empty()
    }

    /// Keeps the errors and `map`'s walls for [`restore`](Self::restore) (nothing for a
    /// map without errors; no allocation once the buffers have grown).
    pub(crate) fn save(&mut self, map: &LineMap) {
        if self.is_empty() {
            return;
        }
        let saved = &mut self.saved;
        saved.walls.clone_from(&self.walls);
        saved.segments.clone_from(&map.segments);
        saved.placement = self.placement;
    }

    /// Goes back to what [`save`](Self::save) kept.
    pub(crate) fn restore(&mut self, map: &mut LineMap) {
        if self.is_empty() {
            return;
        }
        let saved = &self.saved;
        self.walls.clone_from(&saved.walls);
        map.segments.clone_from(&saved.segments);
        self.placement = saved.placement;
    }

    /// After process noise `q v vᵀ` was added to the state, an error of variance `q`
    /// along `v = Cov(δx, θ) / P_θθ` (`along_pose`; `p_theta` is that `P_θθ`), which the
    /// placement may share: until a line has been fused against the map, nothing has
    /// told the robot's heading from the map's since the map was placed from it (the
    /// start's heading itself may be the error), so the placement's error moves with the
    /// state's along its own regression on the heading, `u = Cov(b, θ) / P_θθ`, and the
    /// joint noise is `q (v; u)(v; u)ᵀ`: `P_xb ← P_xb + q v uᵀ`, `P_bb ← P_bb + q u uᵀ`.
    /// Once a line has been fused, the error is the robot's alone and the placement is
    /// left as it is. The walls' fit errors are independent of it (`X`, `Y` stay).
    pub(crate) fn heading_noise_added(&mut self, along_pose: &Vector3<f64>, p_theta: f64, q: f64) {
        if self.is_empty() || self.placement.seen_again {
            return;
        }
        let along_placement = self.placement.state_cross.row(2).transpose() / p_theta;
        self.placement.state_cross += along_pose * along_placement.transpose() * q;
        self.placement.covariance += along_placement * along_placement.transpose() * q;
    }

    /// After a prediction with transition Jacobian `a`: `X ← a X`, `P_xb ← a P_xb`.
    pub(crate) fn predicted(&mut self, a: &Matrix3<f64>) {
        self.placement.state_cross = a * self.placement.state_cross;
        for wall in &mut self.walls {
            wall.cross = a * wall.cross;
        }
    }

    /// After a measurement of the state alone (`h(x)`, innovation `inn`, no wall) was
    /// fused with `outcome`: the placement takes its share of the innovation and the
    /// correlations are carried along. Moves `map`'s walls with the placement. Fails
    /// on a non-finite result, leaving things half updated: the caller restores what it
    /// [saved](Self::save).
    pub(crate) fn state_measured<const M: usize>(
        &mut self,
        inn: &Innovation<f64, M>,
        outcome: &UpdateOutcome<f64>,
        map: &mut LineMap,
    ) -> Result<(), Error> {
        if self.is_empty() || !outcome.accepted {
            return Ok(());
        }
        let k_b = self.placement.state_cross.transpose() * inn.h.transpose() * inn.s_inverse();
        // K_x S K_bᵀ = K_x H P_xb, so P_xb ← (I − K_x H) P_xb.
        self.placement.state_cross = outcome.transition * self.placement.state_cross;
        for wall in &mut self.walls {
            wall.placement_cross -= k_b * inn.h * wall.cross;
            wall.cross = outcome.transition * wall.cross;
        }
        self.placement.covariance =
            symmetric(&(self.placement.covariance - k_b * inn.s * k_b.transpose()));
        self.correct(&(k_b * inn.y))?;
        self.move_walls(map);
        Ok(())
    }

    /// After a line matched to wall `j` was fused (with `considered` from
    /// [`WallErrors::considered`], outcome `update`, wall `j` [moved](Self::move_wall) to
    /// the placement first): as [`state_measured`](Self::state_measured), with the wall's
    /// own error in the correlations, but the walls stay where they are until moved (a
    /// scan's lines are fused one after the other; each needs only its own wall moved).
    pub(crate) fn line_fused(
        &mut self,
        j: usize,
        considered: &Considered<f64, 2, 2>,
        update: &ConsideredUpdate<f64, 2>,
    ) -> Result<(), Error> {
        let Some(fused) = self.walls.get(j).copied() else {
            return Ok(());
        };
        if !update.outcome.accepted {
            return Ok(());
        }
        self.placement.seen_again = true;
        let (inn, h_m) = (&update.innovation, considered.jacobian);
        let g = fused.placement_jacobian;
        let p = &mut self.placement;
        // Cov(b, y) = P_bx Hᵀ + (P_bb Gᵀ + Y_j) H_mᵀ.
        let cov_b_y = p.state_cross.transpose() * inn.h.transpose()
            + (p.covariance * g.transpose() + fused.placement_cross) * h_m.transpose();
        let k_b = cov_b_y * inn.s_inverse();
        for (k, wall) in self.walls.iter_mut().enumerate() {
            // Cov(y, f_k) = H X_k + H_m Cov(δm_j, f_k), Cov(δm_j, f_k) = G_j Y_k + C_j δ_jk;
            // the H X_k part is in the transition of `cross_after`.
            let mut h_m_cov = h_m * g * wall.placement_cross;
            if k == j {
                h_m_cov += h_m * fused.own;
            }
            wall.placement_cross -= k_b * (inn.h * wall.cross + h_m_cov);
            wall.cross = update.cross_after(&wall.cross, &h_m_cov);
        }
        p.state_cross -= update.gain * inn.s * k_b.transpose();
        p.covariance = symmetric(&(p.covariance - k_b * inn.s * k_b.transpose()));
        self.correct(&(k_b * inn.y))
    }

    /// Applies the estimate `δb` of the placement's error (true minus placed, as every
    /// error here): the map's placement moves from the pose it was placed from, `x_b`, to
    /// `x_b + δb`; the walls follow it rigidly when [moved](Self::move_wall). Fails,
    /// changing nothing, if the correction, the errors or the new placement are not
    /// finite (a finite placement moves a finite map to a finite one).
    fn correct(&mut self, delta: &Vector3<f64>) -> Result<(), Error> {
        let p = &mut self.placement;
        if !(all_finite(delta.as_slice())
            && all_finite(p.covariance.as_slice())
            && all_finite(p.state_cross.as_slice())
            && self.walls.iter().all(WallError::is_finite))
        {
            return Err(Error::NonFinite {
                what: "first-scan map error",
            });
        }
        let old = p.pose;
        let new = Pose2::new(old.x + delta.x, old.y + delta.y, old.theta + delta.z);
        p.pose = new.validated("first-scan map placement")?;
        Ok(())
    }

    /// Moves wall `j` of `map` (its segment, line and `G`) rigidly from the placement it
    /// was last moved to onto the current one: its line by [`Line::from_frame`] of that
    /// motion, its end points with it, `G` taken at the new placement. A wall whose line
    /// comes out written the other way round (it passes near the origin) has its error
    /// flipped with it. Nothing to do for a wall already there.
    pub(crate) fn move_wall(&mut self, j: usize, map: &mut LineMap) {
        let new = self.placement.pose;
        let (Some(wall), Some(segment)) = (self.walls.get_mut(j), map.segments.get_mut(j)) else {
            return;
        };
        if wall.placed_from == new {
            return;
        }
        let motion = new.compose(&wall.placed_from.inverse());
        let line = segment.line.from_frame(&motion);
        let turned = angle_diff(line.beta, segment.line.beta + motion.theta);
        if turned.abs() > core::f64::consts::FRAC_PI_2 {
            *wall = wall.flipped();
        }
        wall.placement_jacobian = placement_jacobians(&line, &new, &self.mount).1;
        wall.placed_from = new;
        segment.start = motion.transform_point(&segment.start);
        segment.end = motion.transform_point(&segment.end);
        segment.line = line;
    }

    /// [`move_wall`](Self::move_wall) for every wall: the map where the placement is.
    pub(crate) fn move_walls(&mut self, map: &mut LineMap) {
        for j in 0..self.walls.len() {
            self.move_wall(j, map);
        }
    }
}

impl WallErrors for MapErrors {
    /// Wall `j`'s error `δm_j = G_j b + f_j` as a line matched to it sees it: `H_m` at
    /// `pose`, `Cov(δx, δm_j) = P_xb G_jᵀ + X_j` and
    /// `Cov(δm_j) = G_j P_bb G_jᵀ + G_j Y_j + Y_jᵀ G_jᵀ + C_j`. `None` for a wall it does
    /// not know (every wall of a given map).
    fn considered(
        &self,
        j: usize,
        line: &Line<f64>,
        mount: &Pose2<f64>,
        pose: &Pose2<f64>,
    ) -> Option<Considered<f64, 2, 2>> {
        let wall = self.walls.get(j)?;
        let g = wall.placement_jacobian;
        let g_y = g * wall.placement_cross;
        Some(Considered {
            jacobian: wall_model(line, mount).map_jacobian(pose),
            cross: self.placement.state_cross * g.transpose() + wall.cross,
            covariance: g * self.placement.covariance * g.transpose()
                + g_y
                + g_y.transpose()
                + wall.own,
        })
    }
}

/// `true` if every value is finite.
fn all_finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// `(M + Mᵀ)/2`.
fn symmetric(m: &Matrix3<f64>) -> Matrix3<f64> {
    (m + m.transpose()) * 0.5
}

/// `F = ∂(ρ, β)/∂(r, ψ)` and `G = ∂(ρ, β)/∂(x, y, θ)` of the wall `line` placed from a
/// line seen by the laser at `mount` on a robot at `pose`: `F = H_m⁻¹`, `G = −H_m⁻¹ H`.
fn placement_jacobians(
    line: &Line<f64>,
    pose: &Pose2<f64>,
    mount: &Pose2<f64>,
) -> (Matrix2<f64>, Matrix2x3<f64>) {
    let model = wall_model(line, mount);
    let (_, h) = model.predict(pose);
    // H_m = [[±1, ·], [0, 1]] has determinant ±1: always invertible.
    let f = inverse_unit_triangular(&model.map_jacobian(pose));
    (f, -(f * h))
}

/// The line model of the wall `line` for its Jacobians `H` and `H_m`, which depend on the
/// wall, the mount and the pose only, not on what was observed.
fn wall_model(line: &Line<f64>, mount: &Pose2<f64>) -> LaserLine<f64> {
    LaserLine {
        observed: *line,
        covariance: Matrix2::identity(),
        map_line: *line,
        mount: *mount,
    }
}

/// The inverse of `[[a, b], [0, 1]]` with `a = ±1`: `[[a, −a b], [0, 1]]`.
fn inverse_unit_triangular(m: &Matrix2<f64>) -> Matrix2<f64> {
    let a = m[(0, 0)];
    Matrix2::new(a, -a * m[(0, 1)], 0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::{angle_diff, Line};
    use nalgebra::Point2;
    use proptest::prelude::*;

    const H: f64 = 1e-6;

    /// A line `(r, ψ)` in the sensor frame with end points 1 m either side of its foot.
    fn observed(r: f64, psi: f64) -> ObservedLine {
        let line = Line::new(r, psi).unwrap();
        let foot = Point2::new(r * psi.cos(), r * psi.sin());
        let along = nalgebra::Vector2::new(-psi.sin(), psi.cos());
        ObservedLine {
            line,
            covariance: Matrix2::new(4e-4, 1e-5, 1e-5, 3e-5),
            start: foot - along,
            end: foot + along,
            num_points: 40,
        }
    }

    /// The first-scan wall `(ρ, β)` of `line` seen from `pose` with the laser at `mount`.
    fn placed(line: &ObservedLine, pose: &Pose2<f64>, mount: &Pose2<f64>) -> (f64, f64) {
        let map = LineMap::from_scan(core::slice::from_ref(line), &pose.compose(mount)).unwrap();
        let wall = map.segments[0].line;
        (wall.rho, wall.beta)
    }

    fn column(up: (f64, f64), down: (f64, f64)) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(
            (up.0 - down.0) / (2.0 * H),
            angle_diff(up.1, down.1) / (2.0 * H),
        )
    }

    #[test]
    fn heading_noise_moves_an_unseen_placement_with_the_state_only() {
        let (pose, mount) = (Pose2::new(1.0, 2.0, 0.3), Pose2::identity());
        let line = observed(2.0, 0.4);
        let map = LineMap::from_scan(&[line], &pose).unwrap();
        let p = Matrix3::new(4e-4, 1e-5, 2e-5, 1e-5, 3e-4, -1e-5, 2e-5, -1e-5, 1e-4);
        let mut errors = MapErrors::of_first_scan(&map, &[line], &[0], &pose, &p, &mount);
        // Just placed: b's error is the state's, so its regression on θ is v itself and
        // the joint noise q (v; v)(v; v)ᵀ adds q v vᵀ to P_xb and to P_bb alike.
        let v = p.column(2) / p[(2, 2)];
        let q = 5e-4;
        errors.heading_noise_added(&v, p[(2, 2)], q);
        let added = v * v.transpose() * q;
        assert!((errors.placement.state_cross - (p + added)).amax() < 1e-18);
        assert!((errors.placement.covariance - (p + added)).amax() < 1e-18);
        // The joint covariance of (x, b) with the state's noise added is still PSD.
        let mut joint = nalgebra::Matrix6::zeros();
        joint.fixed_view_mut::<3, 3>(0, 0).copy_from(&(p + added));
        joint
            .fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&errors.placement.state_cross);
        joint
            .fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&errors.placement.state_cross.transpose());
        joint
            .fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&errors.placement.covariance);
        let smallest = joint.symmetric_eigenvalues().min();
        assert!(smallest > -1e-15, "{smallest}");
        // Once a line has been fused against the map, the placement stays as it is.
        errors.placement.seen_again = true;
        let seen = errors.placement;
        errors.heading_noise_added(&v, p[(2, 2)], q);
        assert_eq!(errors.placement, seen);
    }

    #[test]
    fn a_wall_moved_across_the_origin_keeps_its_error() {
        // The wall y = 0.002 (ρ = 0.002, β = π/2), seen from the origin.
        let (pose, mount) = (Pose2::identity(), Pose2::identity());
        let line = observed(0.002, core::f64::consts::FRAC_PI_2);
        let mut map = LineMap::from_scan(&[line], &pose).unwrap();
        let p = Matrix3::from_diagonal_element(1e-6);
        let mut errors = MapErrors::of_first_scan(&map, &[line], &[0], &pose, &p, &mount);
        let before = errors.walls[0];
        assert!(before.own[(0, 1)].abs() > 0.0);
        // Moved 4 mm down it is y = −0.002, written (0.002, −π/2): δρ changes sign.
        errors.correct(&Vector3::new(0.0, -0.004, 0.0)).unwrap();
        assert_eq!(errors.walls[0].own, before.own, "not moved yet");
        errors.move_walls(&mut map);
        let wall = map.segments[0].line;
        assert!((wall.rho - 0.002).abs() < 1e-9);
        assert!((wall.beta + core::f64::consts::FRAC_PI_2).abs() < 1e-9);
        let t = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
        assert_eq!(errors.walls[0].own, t * before.own * t);
        // And back: the first form and error again.
        errors.correct(&Vector3::new(0.0, 0.004, 0.0)).unwrap();
        errors.move_walls(&mut map);
        assert_eq!(errors.walls[0].own, before.own);
        assert!((map.segments[0].line.beta - core::f64::consts::FRAC_PI_2).abs() < 1e-9);
        // A correction that is not finite changes nothing.
        let (kept_map, kept_errors) = (map.clone(), errors.clone());
        assert!(errors.correct(&Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
        errors.move_walls(&mut map);
        assert_eq!((&map, &errors), (&kept_map, &kept_errors));
    }

    #[test]
    fn walls_moved_late_land_where_walls_moved_at_once_do() {
        // The laser at the origin; the third wall passes 1 mm from it.
        let (pose, mount) = (Pose2::identity(), Pose2::identity());
        let lines = [
            observed(2.0, 0.1),
            observed(1.5, 1.7),
            observed(0.001, -1.2),
        ];
        let mut at_once = LineMap::from_scan(&lines, &pose).unwrap();
        let mut late = at_once.clone();
        let p = Matrix3::from_diagonal_element(1e-4);
        let mut errors = MapErrors::of_first_scan(&at_once, &lines, &[0, 1, 2], &pose, &p, &mount);
        let mut late_errors = errors.clone();
        let third = errors.walls[2].own;
        // The first correction takes the third wall across the origin (its line is then
        // written the other way round and its error flipped), the second does not.
        let corrections = [
            Vector3::new(-0.01, 0.02, 0.004),
            Vector3::new(0.003, -0.005, -0.002),
        ];
        for (k, delta) in corrections.iter().enumerate() {
            errors.correct(delta).unwrap();
            errors.move_walls(&mut at_once);
            late_errors.correct(delta).unwrap();
            if k == 0 {
                // Only the wall a line is about to be fused against.
                late_errors.move_wall(1, &mut late);
                assert_eq!(late.segments[1], at_once.segments[1]);
                assert_eq!(late_errors.walls[1], errors.walls[1]);
                assert_ne!(late.segments[0], at_once.segments[0]);
            }
        }
        late_errors.move_walls(&mut late);
        for (a, b) in late.segments.iter().zip(&at_once.segments) {
            assert!((a.start - b.start).norm() < 1e-12 && (a.end - b.end).norm() < 1e-12);
            assert!((a.line.rho - b.line.rho).abs() < 1e-12);
            assert!(angle_diff(a.line.beta, b.line.beta).abs() < 1e-12);
        }
        for (a, b) in late_errors.walls.iter().zip(&errors.walls) {
            assert_eq!(a.own, b.own, "flipped alike");
            assert!((a.placement_jacobian - b.placement_jacobian).amax() < 1e-12);
        }
        assert_eq!(late_errors.placement, errors.placement);
        let t = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
        assert_eq!(
            errors.walls[2].own,
            t * third * t,
            "the third wall flipped once"
        );
    }

    #[test]
    fn walls_moved_late_through_line_fusions_carry_the_same_errors() {
        // Five lines fused against a three-wall map, seen from (3 cm, −2 cm, 0.01 rad)
        // while the map was placed from the origin: once moving every wall after each
        // line, once moving only the wall about to be used and the rest at the end.
        let (pose, mount) = (Pose2::identity(), Pose2::new(-0.1, 0.0, 0.0));
        let lines = [observed(2.0, 0.1), observed(1.5, 1.7), observed(1.2, -1.1)];
        let map = LineMap::from_scan(&lines, &pose.compose(&mount)).unwrap();
        let p = Matrix3::new(4e-4, 1e-5, 2e-5, 1e-5, 3e-4, -1e-5, 2e-5, -1e-5, 1e-4);
        let errors = MapErrors::of_first_scan(&map, &lines, &[0, 1, 2], &pose, &p, &mount);
        let filter = ekf_core::Ekf::new(pose, p).unwrap();
        let (mut at_once, mut late) =
            ((map.clone(), errors.clone(), filter), (map, errors, filter));
        let truth = Pose2::new(0.03, -0.02, 0.01);
        let noise = Matrix3::from_diagonal(&Vector3::new(4e-4, 4e-4, 1e-4));
        // A position fix at the truth after the second line: the placement takes its
        // share, so the map moves (all of it at once, in both).
        let fix = ekf_core::Position::new(0.03, -0.02, Matrix2::identity() * 1e-4).unwrap();
        for (k, j) in [1, 0, 1, 0, 2].into_iter().enumerate() {
            for (moved_late, (map, errors, filter)) in [(false, &mut at_once), (true, &mut late)] {
                if k == 2 {
                    let update = filter
                        .update_considering(&fix, &ekf_core::Considered::none(), None)
                        .unwrap();
                    errors
                        .state_measured(&update.innovation, &update.outcome, map)
                        .unwrap();
                }
                filter.add_process_noise(&noise).unwrap();
                if moved_late {
                    errors.move_wall(j, map);
                }
                let wall = map.segments[j].line;
                let model = LaserLine {
                    observed: wall.to_frame(&truth.compose(&mount)),
                    covariance: Matrix2::new(1e-4, 0.0, 0.0, 1e-5),
                    map_line: wall,
                    mount,
                };
                let considered = errors.considered(j, &wall, &mount, &filter.pose()).unwrap();
                let update = filter
                    .update_considering(&model, &considered, None)
                    .unwrap();
                errors.line_fused(j, &considered, &update).unwrap();
                if !moved_late {
                    errors.move_walls(map);
                }
            }
        }
        late.1.move_walls(&mut late.0);
        let ((map_a, errors_a, filter_a), (map_l, errors_l, filter_l)) = (&at_once, &late);
        assert!((filter_a.state() - filter_l.state()).amax() < 1e-12);
        assert!((filter_a.covariance() - filter_l.covariance()).amax() < 1e-15);
        for (a, b) in errors_l.walls.iter().zip(&errors_a.walls) {
            assert!(
                a.cross.amax() > 1e-8,
                "the fusions correlated the walls with the state"
            );
            assert!((a.cross - b.cross).amax() < 1e-15);
            assert!((a.placement_cross - b.placement_cross).amax() < 1e-15);
            assert!((a.placement_jacobian - b.placement_jacobian).amax() < 1e-12);
        }
        // Both maps are the first scan placed afresh from the corrected placement.
        let placement = errors_a.placement.pose;
        assert!(
            placement.to_vector().amax() > 1e-3,
            "the placement moved: {placement:?}"
        );
        let fresh = LineMap::from_scan(&lines, &placement.compose(&mount)).unwrap();
        for ((a, l), f) in map_a
            .segments
            .iter()
            .zip(&map_l.segments)
            .zip(&fresh.segments)
        {
            for m in [a, l] {
                assert!((m.line.rho - f.line.rho).abs() < 1e-12);
                assert!(angle_diff(m.line.beta, f.line.beta).abs() < 1e-12);
                assert!((m.start - f.start).norm() < 1e-12 && (m.end - f.end).norm() < 1e-12);
            }
        }
    }

    proptest! {
        #[test]
        fn placement_jacobians_match_finite_differences(
            x in -5.0..5.0, y in -5.0..5.0, theta in -3.1..3.1,
            mx in -0.5..0.5, my in -0.2..0.2, mtheta in -3.1..3.1,
            r in 0.5..8.0, psi in -3.1..3.1,
        ) {
            let (pose, mount) = (Pose2::new(x, y, theta), Pose2::new(mx, my, mtheta));
            let line = observed(r, psi);
            let (rho, _) = placed(&line, &pose, &mount);
            // ρ = |…| is not differentiable where the wall passes through the origin.
            prop_assume!(rho > 1e-3);
            let map = LineMap::from_scan(core::slice::from_ref(&line), &pose.compose(&mount)).unwrap();
            let p = Matrix3::from_diagonal_element(1e-4);
            let errors = MapErrors::of_first_scan(&map, &[line], &[0], &pose, &p, &mount);
            let wall = errors.walls[0];

            let mut g = Matrix2x3::zeros();
            for k in 0..3 {
                let (mut up, mut down) = (pose.to_vector(), pose.to_vector());
                up[k] += H;
                down[k] -= H;
                let at = |v| placed(&line, &Pose2::from_vector(&v), &mount);
                g.set_column(k, &column(at(up), at(down)));
            }
            prop_assert!((wall.placement_jacobian - g).amax() < 1e-5 * (1.0 + rho), "G {} vs {}", wall.placement_jacobian, g);

            let mut f = Matrix2::zeros();
            for (k, (dr, dpsi)) in [(H, 0.0), (0.0, H)].into_iter().enumerate() {
                let at = |s: f64| placed(&observed(r + s * dr, psi + s * dpsi), &pose, &mount);
                f.set_column(k, &column(at(1.0), at(-1.0)));
            }
            let expected_own = f * line.covariance * f.transpose();
            prop_assert!((wall.own - expected_own).amax() < 1e-9, "F R Fᵀ {} vs {}", wall.own, expected_own);
            // At the placement the state's error is the placement's: P_xb = P_bb = P.
            prop_assert_eq!(errors.placement.state_cross, p);
            prop_assert_eq!(errors.placement.covariance, p);
            prop_assert_eq!(wall.cross, Matrix3x2::zeros());
        }
    }
}

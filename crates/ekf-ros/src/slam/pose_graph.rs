//! A 2D pose graph: robot poses tied by measured relative poses (odometry between key
//! scans, loop closures), solved by Gauss–Newton with a sparse Cholesky factorisation
//! (faer's, with its fill-reducing ordering), so a loop that ties the end of a long run
//! to its start costs about as much as the chain alone.
//!
//! Each edge `i → j` measured `z = (t_z, θ_z)` with information `Ω` contributes
//! `eᵀ Ω e` with the residual
//!
//! `e_t = R(θ_z)ᵀ (R(θ_i)ᵀ (t_j − t_i) − t_z)`, `e_θ = wrap(θ_j − θ_i − θ_z)`,
//!
//! zero when pose `j` seen from pose `i` is exactly `z`. The first pose is held fixed (it
//! fixes the map frame). Loop-closure edges may be robust: a Huber weight
//! `w = min(1, k / √(eᵀ Ω e))`, `k² = χ²₃(0.99)`, so that one wrong closure that slipped
//! through its verification bends the graph less than it would with a square cost.

use ekf_core::{wrap_angle, Pose2};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// A measured relative pose between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// The node the measurement is taken from.
    pub from: usize,
    /// The node it sees.
    pub to: usize,
    /// Pose of `to` in the frame of `from`.
    pub measured: Pose2<f64>,
    /// Information (inverse covariance) of `(x, y, θ)` of the measurement, in the frame
    /// of the measured pose (the residual's frame).
    pub information: Matrix3<f64>,
    /// Down-weight the edge when its residual is large (Huber; for loop closures).
    pub robust: bool,
}

/// Why a graph could not be built or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraphError {
    /// An edge names a node the graph does not have.
    #[error("edge {from} → {to}: the graph has {nodes} nodes")]
    NoSuchNode {
        /// The edge's first node.
        from: usize,
        /// The edge's second node.
        to: usize,
        /// Nodes in the graph.
        nodes: usize,
    },
    /// An edge's measurement or information is not finite, or the information is not
    /// symmetric positive semi-definite.
    #[error("edge {from} → {to}: {what}")]
    BadEdge {
        /// The edge's first node.
        from: usize,
        /// The edge's second node.
        to: usize,
        /// What is wrong.
        what: &'static str,
    },
    /// The normal equations are singular: a node is not tied to the first one.
    #[error("the pose graph's normal equations are singular: a node is not tied to the first")]
    Singular,
}

/// What an optimisation did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optimized {
    /// Gauss–Newton iterations run.
    pub iterations: usize,
    /// The weighted cost `Σ w eᵀ Ω e` before.
    pub initial_cost: f64,
    /// And after.
    pub final_cost: f64,
}

/// The graph: node poses (the current estimate) and edges.
#[derive(Debug, Clone, Default)]
pub struct PoseGraph {
    poses: Vec<Pose2<f64>>,
    edges: Vec<Edge>,
}

/// `k²` of the Huber weight: `χ²₃(0.99)`.
const HUBER_K2: f64 = 11.344_866_730_144_37;

/// An iteration whose largest step is below this (m or rad) ends the optimisation.
const CONVERGED_STEP: f64 = 1e-6;

impl PoseGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a node at `pose` (its initial estimate); returns its index.
    pub fn add_node(&mut self, pose: Pose2<f64>) -> usize {
        self.poses.push(pose);
        self.poses.len() - 1
    }

    /// Adds an edge. Fails on an unknown node, a non-finite measurement or an information
    /// matrix that is not symmetric positive semi-definite.
    pub fn add_edge(&mut self, edge: Edge) -> Result<(), GraphError> {
        let (from, to) = (edge.from, edge.to);
        let nodes = self.poses.len();
        if from >= nodes || to >= nodes || from == to {
            return Err(GraphError::NoSuchNode { from, to, nodes });
        }
        let bad = |what| Err(GraphError::BadEdge { from, to, what });
        let m = edge.measured;
        if !(m.x.is_finite() && m.y.is_finite() && m.theta.is_finite()) {
            return bad("the measured pose is not finite");
        }
        let info = edge.information;
        if info.iter().any(|v| !v.is_finite()) {
            return bad("the information is not finite");
        }
        if (info - info.transpose()).abs().max() > 1e-9 * info.abs().max().max(1.0) {
            return bad("the information is not symmetric");
        }
        if info.symmetric_eigenvalues().min() < -1e-9 * info.abs().max().max(1.0) {
            return bad("the information is not positive semi-definite");
        }
        self.edges.push(edge);
        Ok(())
    }

    /// The node poses.
    pub fn poses(&self) -> &[Pose2<f64>] {
        &self.poses
    }

    /// The edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The weighted cost `Σ w eᵀ Ω e` at the current poses.
    pub fn cost(&self) -> f64 {
        self.edges
            .iter()
            .map(|e| {
                let c = self.edge_cost(e);
                weight(e, c) * c
            })
            .sum()
    }

    /// The unweighted cost `eᵀ Ω e` of `edge` (in the graph or not) at the current
    /// poses; infinite if it names a node the graph does not have.
    pub fn edge_cost(&self, edge: &Edge) -> f64 {
        match (self.poses.get(edge.from), self.poses.get(edge.to)) {
            (Some(pi), Some(pj)) => {
                let r = residual(edge, pi, pj);
                (r.transpose() * edge.information * r)[0]
            }
            _ => f64::INFINITY,
        }
    }

    /// Gauss–Newton on the poses (the first held fixed), at most `max_iterations`
    /// iterations, stopping when a step moves no pose by more than 1e-6 m or rad or the
    /// cost stops falling.
    pub fn optimize(&mut self, max_iterations: usize) -> Result<Optimized, GraphError> {
        let initial_cost = self.cost();
        let mut report = Optimized {
            iterations: 0,
            initial_cost,
            final_cost: initial_cost,
        };
        if self.poses.len() < 2 {
            return Ok(report);
        }
        // The pattern of the normal equations is the same at every iteration: its
        // ordering and symbolic factorisation are computed once.
        let mut symbolic = None;
        for _ in 0..max_iterations {
            let step = self.gauss_newton_step(&mut symbolic)?;
            let before = self.poses.clone();
            for (i, pose) in self.poses.iter_mut().enumerate().skip(1) {
                let k = 3 * (i - 1);
                pose.x += step[k];
                pose.y += step[k + 1];
                pose.theta = wrap_angle(pose.theta + step[k + 2]);
            }
            report.iterations += 1;
            let cost = self.cost();
            if cost > report.final_cost * (1.0 + 1e-12) {
                // A step that made it worse (far from the minimum, with robust edges):
                // keep the better poses.
                self.poses = before;
                break;
            }
            report.final_cost = cost;
            if step.iter().all(|s| s.abs() < CONVERGED_STEP) {
                break;
            }
        }
        Ok(report)
    }

    /// One step: solves `H Δ = −b` ([`normal_equations`](Self::normal_equations));
    /// `symbolic` is the symbolic factorisation of `H`, made on the first call.
    fn gauss_newton_step(
        &self,
        symbolic: &mut Option<SymbolicLlt<usize>>,
    ) -> Result<Vec<f64>, GraphError> {
        let (h, b) = self.normal_equations()?;
        let pattern = match symbolic {
            Some(pattern) => pattern.clone(),
            None => symbolic.insert(symbolic_factor(&h)?).clone(),
        };
        let llt = Llt::try_new_with_symbolic(pattern, h.as_ref(), Side::Lower)
            .map_err(|_| GraphError::Singular)?;
        let rhs = Mat::from_fn(b.len(), 1, |i, _| -b[i]);
        let x = llt.solve(&rhs);
        let step: Vec<f64> = (0..b.len()).map(|i| x[(i, 0)]).collect();
        if step.iter().any(|s| !s.is_finite()) {
            return Err(GraphError::Singular);
        }
        Ok(step)
    }

    /// The normal equations at the current poses over the poses after the first:
    /// `H = Σ Jᵀ w Ω J` (its lower triangle) and `b = Σ Jᵀ w Ω e`, `w` the Huber weight.
    fn normal_equations(&self) -> Result<(SparseColMat<usize, f64>, Vec<f64>), GraphError> {
        let n = 3 * (self.poses.len() - 1);
        let mut triplets = Vec::with_capacity(36 * self.edges.len() + n);
        let mut b = vec![0.0; n];
        for e in &self.edges {
            let (pi, pj) = (&self.poses[e.from], &self.poses[e.to]);
            let r = residual(e, pi, pj);
            let w = weight(e, (r.transpose() * e.information * r)[0]);
            let omega = e.information * w;
            let (ji, jj) = jacobians(e, pi, pj);
            let blocks = [(e.from, ji), (e.to, jj)];
            for &(a, ja) in &blocks {
                let Some(ka) = a.checked_sub(1).map(|k| 3 * k) else {
                    continue;
                };
                let g = ja.transpose() * omega * r;
                for row in 0..3 {
                    b[ka + row] += g[row];
                }
                for &(c, jc) in &blocks {
                    let Some(kc) = c.checked_sub(1).map(|k| 3 * k) else {
                        continue;
                    };
                    let h = ja.transpose() * omega * jc;
                    for row in 0..3 {
                        for col in 0..3 {
                            if ka + row >= kc + col {
                                triplets.push(Triplet::new(ka + row, kc + col, h[(row, col)]));
                            }
                        }
                    }
                }
            }
        }
        // A tiny Levenberg damping keeps a node seen along one direction only (a loop
        // closure in a corridor) from making the system singular.
        for k in 0..n {
            triplets.push(Triplet::new(k, k, 1e-9));
        }
        let h = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
            .map_err(|_| GraphError::Singular)?;
        Ok((h, b))
    }

    /// How far each of `edges` (not in the graph) is from what the graph says, in its
    /// standard deviations: `eᵀ S⁻¹ e`, `e` its residual at the current poses and
    /// `S = J Σ Jᵀ + Ω⁻¹`, `Σ` the joint covariance of its two poses in the graph (the
    /// blocks of `H⁻¹` at the current poses, the first pose exact; one factorisation for
    /// all the edges) and `J` the residual's Jacobian. About `χ²₃` if the edge measures
    /// the same poses as the graph's edges do; a loop closure far beyond that puts the
    /// robot where the graph's measurements cannot have it (a corridor's door matched to
    /// the next door). A direction the edge does not measure (an eigenvalue of `Ω` below
    /// `10⁻¹²` of its largest) does not count.
    pub fn consistency(&self, edges: &[Edge]) -> Result<Vec<f64>, GraphError> {
        let nodes = self.poses.len();
        for edge in edges {
            let (from, to) = (edge.from, edge.to);
            if from >= nodes || to >= nodes || from == to {
                return Err(GraphError::NoSuchNode { from, to, nodes });
            }
        }
        if edges.is_empty() {
            return Ok(Vec::new());
        }
        let (h, _) = self.normal_equations()?;
        let llt = Llt::try_new_with_symbolic(symbolic_factor(&h)?, h.as_ref(), Side::Lower)
            .map_err(|_| GraphError::Singular)?;
        // The columns of H⁻¹ of each edge's two poses, six per edge (none for the fixed
        // first pose).
        let columns = |node: usize| node.checked_sub(1).map(|k| 3 * k);
        let rhs = Mat::from_fn(h.nrows(), 6 * edges.len(), |row, col| {
            let edge = &edges[col / 6];
            let node = match col % 6 < 3 {
                true => edge.from,
                false => edge.to,
            };
            f64::from(columns(node).is_some_and(|k| row == k + col % 3))
        });
        let inverse = llt.solve(&rhs);
        edges
            .iter()
            .enumerate()
            .map(|(n, edge)| {
                let (pi, pj) = (&self.poses[edge.from], &self.poses[edge.to]);
                let r = residual(edge, pi, pj);
                let (ji, jj) = jacobians(edge, pi, pj);
                let blocks = [(columns(edge.from), ji), (columns(edge.to), jj)];
                // J Σ Jᵀ over the two poses' blocks; Σ's block (a, c) is rows `ka..` of
                // the edge's column block `c`.
                let mut s = Matrix3::zeros();
                for (ka, ja) in blocks.iter().filter_map(|(k, j)| k.map(|k| (k, j))) {
                    for (c, (_, jc)) in blocks.iter().enumerate() {
                        let sigma =
                            Matrix3::from_fn(|row, col| inverse[(ka + row, 6 * n + 3 * c + col)]);
                        s += ja * sigma * jc.transpose();
                    }
                }
                let eigen = edge.information.symmetric_eigen();
                let floor = eigen.eigenvalues.max() * 1e-12;
                let variances = eigen.eigenvalues.map(|v| 1.0 / v.max(floor));
                s += eigen.eigenvectors
                    * Matrix3::from_diagonal(&variances)
                    * eigen.eigenvectors.transpose();
                let s = 0.5 * (s + s.transpose());
                let chi2 = s
                    .cholesky()
                    .map(|c| r.dot(&c.solve(&r)))
                    .ok_or(GraphError::Singular)?;
                match chi2.is_finite() {
                    true => Ok(chi2),
                    false => Err(GraphError::Singular),
                }
            })
            .collect()
    }
}

/// The symbolic Cholesky factorisation of `h` (lower triangle), with faer's
/// fill-reducing ordering.
fn symbolic_factor(h: &SparseColMat<usize, f64>) -> Result<SymbolicLlt<usize>, GraphError> {
    SymbolicLlt::try_new(h.symbolic(), Side::Lower).map_err(|_| GraphError::Singular)
}

/// The Huber weight of an edge with cost `c = eᵀ Ω e` (1 for a plain edge).
fn weight(edge: &Edge, c: f64) -> f64 {
    if edge.robust && c > HUBER_K2 {
        (HUBER_K2 / c).sqrt()
    } else {
        1.0
    }
}

/// `R(θ)`.
fn rotation(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// The edge's residual at poses `pi`, `pj` (module documentation).
pub fn residual(edge: &Edge, pi: &Pose2<f64>, pj: &Pose2<f64>) -> Vector3<f64> {
    let z = &edge.measured;
    let d = Vector2::new(pj.x - pi.x, pj.y - pi.y);
    let et = rotation(z.theta).transpose()
        * (rotation(pi.theta).transpose() * d - Vector2::new(z.x, z.y));
    Vector3::new(et.x, et.y, wrap_angle(pj.theta - pi.theta - z.theta))
}

/// `∂e/∂pᵢ` and `∂e/∂pⱼ` of [`residual`]: with `A = R(θ_z)ᵀ R(θ_i)ᵀ`,
/// `∂e_t/∂t_i = −A`, `∂e_t/∂t_j = A`, `∂e_t/∂θ_i = R(θ_z)ᵀ (dR(θ_i)ᵀ/dθ) (t_j − t_i)`,
/// `∂e_θ/∂θ_i = −1`, `∂e_θ/∂θ_j = 1`.
pub fn jacobians(edge: &Edge, pi: &Pose2<f64>, pj: &Pose2<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let rz_t = rotation(edge.measured.theta).transpose();
    let a = rz_t * rotation(pi.theta).transpose();
    let (s, c) = pi.theta.sin_cos();
    let d_ri_t = Matrix2::new(-s, c, -c, -s);
    let d = Vector2::new(pj.x - pi.x, pj.y - pi.y);
    let dth = rz_t * d_ri_t * d;
    let ji = Matrix3::new(
        -a[(0, 0)],
        -a[(0, 1)],
        dth.x,
        -a[(1, 0)],
        -a[(1, 1)],
        dth.y,
        0.0,
        0.0,
        -1.0,
    );
    let jj = Matrix3::new(
        a[(0, 0)],
        a[(0, 1)],
        0.0,
        a[(1, 0)],
        a[(1, 1)],
        0.0,
        0.0,
        0.0,
        1.0,
    );
    (ji, jj)
}

/// The measurement an edge `i → j` has when both poses are exact: `pᵢ⁻¹ ⊕ pⱼ`.
pub fn relative(pi: &Pose2<f64>, pj: &Pose2<f64>) -> Pose2<f64> {
    pi.inverse().compose(pj)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn edge(from: usize, to: usize, measured: Pose2<f64>, sigma: [f64; 3]) -> Edge {
        Edge {
            from,
            to,
            measured,
            information: Matrix3::from_diagonal(&Vector3::new(
                1.0 / (sigma[0] * sigma[0]),
                1.0 / (sigma[1] * sigma[1]),
                1.0 / (sigma[2] * sigma[2]),
            )),
            robust: false,
        }
    }

    fn pose() -> impl Strategy<Value = Pose2<f64>> {
        (-5.0..5.0f64, -5.0..5.0f64, -3.1..3.1f64).prop_map(|(x, y, t)| Pose2::new(x, y, t))
    }

    proptest! {
        /// The analytic Jacobians agree with central differences.
        #[test]
        fn jacobians_match_finite_differences(pi in pose(), pj in pose(), z in pose()) {
            let e = edge(0, 1, z, [1.0; 3]);
            let (ji, jj) = jacobians(&e, &pi, &pj);
            let h = 1e-6;
            for k in 0..3 {
                let shift = |p: &Pose2<f64>, s: f64| {
                    let mut q = *p;
                    match k { 0 => q.x += s, 1 => q.y += s, _ => q.theta += s }
                    q
                };
                let di = (residual(&e, &shift(&pi, h), &pj) - residual(&e, &shift(&pi, -h), &pj)) / (2.0 * h);
                let dj = (residual(&e, &pi, &shift(&pj, h)) - residual(&e, &pi, &shift(&pj, -h))) / (2.0 * h);
                for r in 0..3 {
                    prop_assert!((di[r] - ji[(r, k)]).abs() < 1e-5, "∂e{r}/∂pi{k}: {} vs {}", di[r], ji[(r, k)]);
                    prop_assert!((dj[r] - jj[(r, k)]).abs() < 1e-5, "∂e{r}/∂pj{k}: {} vs {}", dj[r], jj[(r, k)]);
                }
            }
        }

        /// The residual of the exact relative pose is zero, its heading wrapped.
        #[test]
        fn exact_measurement_has_zero_residual(pi in pose(), pj in pose()) {
            let e = edge(0, 1, relative(&pi, &pj), [1.0; 3]);
            let r = residual(&e, &pi, &pj);
            prop_assert!(r.norm() < 1e-9, "{r}");
        }
    }

    /// A square driven with odometry that turns 2° too little per corner: the loop
    /// closure back to the start pulls every corner onto the true square.
    /// A straight chain of `n` steps of 1 m along x, each `σ = (0.05 m, 0.05 m, 0.01 rad)`,
    /// its poses exact.
    fn straight_chain(n: usize) -> PoseGraph {
        let mut graph = PoseGraph::new();
        for i in 0..=n {
            graph.add_node(Pose2::new(i as f64, 0.0, 0.0));
        }
        for i in 0..n {
            let step = edge(i, i + 1, Pose2::new(1.0, 0.0, 0.0), [0.05, 0.05, 0.01]);
            graph.add_edge(step).unwrap();
        }
        graph
    }

    #[test]
    fn a_closure_is_judged_by_the_graph_s_uncertainty_between_its_poses() {
        // Along a straight chain the position along it is the sum of the steps' errors,
        // independent of the heading's (to first order): a closure from node a to node b
        // measured `d` longer than the chain has χ² = d² / ((b − a) σ² + σ_c²) exactly.
        let graph = straight_chain(10);
        let sc = 0.02;
        for (a, b, d) in [(0, 10, 0.3), (2, 7, -0.2), (3, 4, 0.05), (0, 10, 0.0)] {
            let closure = edge(
                a,
                b,
                Pose2::new((b - a) as f64 + d, 0.0, 0.0),
                [sc, sc, 0.005],
            );
            let expected = d * d / ((b - a) as f64 * 0.05f64.powi(2) + sc * sc);
            let chi2 = graph.consistency(&[closure]).unwrap()[0];
            assert!(
                (chi2 - expected).abs() <= 1e-6 * expected.max(1.0),
                "{a} → {b}, {d} m: {chi2} against {expected}"
            );
        }
        // Far beyond the uncertainty: 1 m over 5 steps of 5 cm is 8.8σ.
        let far = edge(2, 7, Pose2::new(6.0, 0.0, 0.0), [sc, sc, 0.005]);
        assert!(graph.consistency(&[far]).unwrap()[0] > 70.0);
        // Edges judged together (one factorisation) are judged as each alone.
        let near = edge(0, 10, Pose2::new(10.3, 0.1, 0.01), [sc, sc, 0.005]);
        let together = graph.consistency(&[near, far]).unwrap();
        let alone = [
            graph.consistency(&[near]).unwrap()[0],
            graph.consistency(&[far]).unwrap()[0],
        ];
        for (t, a) in together.iter().zip(alone) {
            assert!(
                (t - a).abs() <= 1e-9 * a.max(1.0),
                "{together:?} against {alone:?}"
            );
        }
    }

    #[test]
    fn a_direction_a_closure_does_not_measure_does_not_count() {
        // A closure that sees only across the chain (a corridor's walls) says nothing of
        // the position along it, however far off that is.
        let graph = straight_chain(6);
        let mut across = edge(0, 6, Pose2::new(9.0, 0.0, 0.0), [0.02, 0.02, 0.005]);
        across.information[(0, 0)] = 0.0;
        assert!(graph.consistency(&[across]).unwrap()[0] < 1e-6);
        across.measured.y = 0.5;
        assert!(graph.consistency(&[across]).unwrap()[0] > 1.0);
        let missing = edge(0, 9, Pose2::new(9.0, 0.0, 0.0), [0.02, 0.02, 0.005]);
        assert!(matches!(
            graph.consistency(&[missing]),
            Err(GraphError::NoSuchNode { .. })
        ));
    }

    #[test]
    fn a_loop_closure_corrects_the_drift_of_a_square() {
        let side = 10.0;
        let truth: Vec<Pose2<f64>> = (0..4)
            .map(|k| {
                let t = k as f64 * std::f64::consts::FRAC_PI_2;
                let corners = [(0.0, 0.0), (side, 0.0), (side, side), (0.0, side)];
                Pose2::new(corners[k].0, corners[k].1, t)
            })
            .collect();
        let step = Pose2::new(side, 0.0, std::f64::consts::FRAC_PI_2);
        let biased = Pose2::new(side, 0.0, std::f64::consts::FRAC_PI_2 - 2f64.to_radians());
        let mut graph = PoseGraph::new();
        let mut dead_reckoned = Pose2::new(0.0, 0.0, 0.0);
        graph.add_node(dead_reckoned);
        for k in 1..4 {
            dead_reckoned = dead_reckoned.compose(&biased);
            graph.add_node(dead_reckoned);
            graph
                .add_edge(edge(k - 1, k, biased, [0.1, 0.1, 0.05]))
                .unwrap();
        }
        let drift_before = (graph.poses()[3].x - truth[3].x).hypot(graph.poses()[3].y - truth[3].y);
        assert!(drift_before > 0.5, "{drift_before}");
        // The closure: from corner 3 the start is one exact step on.
        graph
            .add_edge(edge(3, 0, step, [0.01, 0.01, 0.002]))
            .unwrap();
        let report = graph.optimize(20).unwrap();
        assert!(report.final_cost < report.initial_cost);
        for (estimate, truth) in graph.poses().iter().zip(&truth) {
            let d = (estimate.x - truth.x).hypot(estimate.y - truth.y);
            assert!(d < 0.1 * drift_before, "{estimate:?} vs {truth:?}");
        }
        assert_eq!(
            graph.poses()[0],
            Pose2::new(0.0, 0.0, 0.0),
            "the first pose is fixed"
        );
    }

    /// A wrong closure far out of line bends a robust graph much less than a plain one.
    #[test]
    fn a_robust_edge_limits_a_wrong_closure() {
        let build = |robust: bool| {
            let mut graph = PoseGraph::new();
            let step = Pose2::new(1.0, 0.0, 0.0);
            let mut p = Pose2::new(0.0, 0.0, 0.0);
            graph.add_node(p);
            for k in 1..20 {
                p = p.compose(&step);
                graph.add_node(p);
                graph
                    .add_edge(edge(k - 1, k, step, [0.02, 0.02, 0.005]))
                    .unwrap();
            }
            let mut wrong = edge(19, 0, Pose2::new(-15.0, 3.0, 0.0), [0.05, 0.05, 0.01]);
            wrong.robust = robust;
            graph.add_edge(wrong).unwrap();
            graph.optimize(30).unwrap();
            graph.poses()[19]
        };
        let (plain, robust) = (build(false), build(true));
        let bent = |p: Pose2<f64>| (p.x - 19.0).hypot(p.y);
        assert!(bent(plain) > 2.0, "{plain:?}");
        assert!(bent(robust) < 0.5 * bent(plain), "{robust:?} vs {plain:?}");
    }

    #[test]
    fn bad_edges_are_refused() {
        let mut graph = PoseGraph::new();
        graph.add_node(Pose2::new(0.0, 0.0, 0.0));
        graph.add_node(Pose2::new(1.0, 0.0, 0.0));
        let good = edge(0, 1, Pose2::new(1.0, 0.0, 0.0), [0.1; 3]);
        assert!(matches!(
            graph.add_edge(Edge { to: 2, ..good }),
            Err(GraphError::NoSuchNode { nodes: 2, .. })
        ));
        let mut asymmetric = good;
        asymmetric.information[(0, 1)] = 1.0;
        assert!(matches!(
            graph.add_edge(asymmetric),
            Err(GraphError::BadEdge {
                what: "the information is not symmetric",
                ..
            })
        ));
        let mut negative = good;
        negative.information[(2, 2)] = -1.0;
        assert!(matches!(
            graph.add_edge(negative),
            Err(GraphError::BadEdge { .. })
        ));
        let mut nan = good;
        nan.measured.x = f64::NAN;
        assert!(matches!(
            graph.add_edge(nan),
            Err(GraphError::BadEdge { .. })
        ));
        assert!(graph.edges().is_empty());
    }

    #[test]
    fn a_node_tied_to_nothing_stays_where_it_is() {
        let mut graph = PoseGraph::new();
        for x in 0..3 {
            graph.add_node(Pose2::new(x as f64, 0.0, 0.0));
        }
        graph
            .add_edge(edge(0, 1, Pose2::new(1.0, 0.0, 0.0), [0.1; 3]))
            .unwrap();
        // Node 2 has only the damping: its step is 0, and the cost is already 0, so it
        // converges without moving rather than failing.
        let report = graph.optimize(5).unwrap();
        assert_eq!(report.final_cost, 0.0);
        assert_eq!(graph.poses()[2], Pose2::new(2.0, 0.0, 0.0));
    }
}

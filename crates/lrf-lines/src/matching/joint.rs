//! Joint compatibility branch and bound (JCBB, Neira & Tardós 2001): of all ways to pair
//! a scan's observed lines with the walls that pass their individual gates, each wall
//! used at most once, the one that pairs the most lines while the pairs are *jointly*
//! compatible, ties going to the smaller joint NIS.
//!
//! Individual gates admit a wall that fits one line on its own; with a wide prior (after
//! a turn, or in a corridor of parallel walls) several walls fit each line, and taking
//! each line's nearest wall can pair lines with walls that no single pose explains
//! together. The joint test asks for one pose: the stacked innovation `y_H` of a
//! hypothesis `H` with `k` pairs, covariance `S_H = H_H P H_Hᵀ + R_H`, passes when
//! `D²_H = y_Hᵀ S_H⁻¹ y_H ≤ χ²_{2k}⁻¹(p)`.
//!
//! `D²_H` is computed incrementally, one pair at a time, by the linear Kalman update at
//! the state matching was run at: with `(δx, P_H)` after the pairs so far, a new pair's
//! `y' = y − H δx`, `S' = H P_H Hᵀ + R`, adds `y'ᵀ S'⁻¹ y'` to `D²`, and the update
//! `K = P_H Hᵀ S'⁻¹`, `δx += K y'`, `P_H −= K S' Kᵀ` carries it on. For a linear model
//! the sum equals the batch `D²_H` exactly, at `O(1)` per node instead of `O(k³)`.
//!
//! The search goes depth first over the lines (the most confident first, so good
//! hypotheses are found early and bound the rest), each line paired with each of its
//! walls in order of NIS, then left unpaired; a branch is cut when even pairing every
//! line still to come cannot beat the best hypothesis found. A node budget bounds the
//! worst case; the best hypothesis found so far stands when it runs out.

use super::{Candidate, LineMatch};
use alloc::vec::Vec;
use ekf_core::chi_square_quantile;
use nalgebra::{Matrix2, Matrix3, Vector3};

/// Most pairs tried per scan; the best hypothesis found so far stands after that. A
/// scan of 20 lines with three candidate walls each needs a few hundred.
pub const NODE_BUDGET: usize = 4096;

/// A node of the search: the hypothesis so far at one depth (one line decided per
/// depth).
#[derive(Debug, Clone, Copy)]
struct Node {
    /// State correction `δx` of the pairs so far.
    dx: Vector3<f64>,
    /// Covariance after them.
    p: Matrix3<f64>,
    /// Their joint NIS `D²`.
    nis: f64,
    /// How many lines are paired.
    count: usize,
    /// The next option of this depth's line to try: its candidates in order, then "no
    /// wall".
    next: usize,
}

/// The search's buffers, reused across scans.
#[derive(Debug, Clone, Default)]
pub(super) struct JointSearch {
    /// The lines in search order: `(first, end)` of each one's candidates in the
    /// candidate list (sorted by NIS within).
    lines: Vec<(usize, usize)>,
    nodes: Vec<Node>,
    /// Per depth, the candidate chosen for the node below it (`None`: no wall).
    chosen: Vec<Option<usize>>,
    /// The best hypothesis found: per depth, the candidate or `None` (complete unless
    /// the budget ran out first).
    best: Vec<Option<usize>>,
    /// `χ²_{2k}⁻¹(p)` for `k` = 1, 2, … pairs, grown as needed.
    thresholds: Vec<f64>,
    /// The probability `thresholds` was computed for.
    probability: f64,
}

impl JointSearch {
    /// Searches the best jointly compatible hypothesis over `lines` (candidate ranges in
    /// `candidates`, in search order), walls taken marked in `owner` (all `None` on
    /// entry and on return), at the state covariance `p0`, gate probability
    /// `probability`, trying at most `budget` pairs ([`NODE_BUDGET`]);
    /// [`best`](Self::best) then gives its candidates.
    #[allow(clippy::too_many_arguments)] // the matcher's buffers, lent for one search
    pub(super) fn run(
        &mut self,
        lines: impl Iterator<Item = (usize, usize)>,
        candidates: &[Candidate],
        pairs: &[LineMatch],
        p0: &Matrix3<f64>,
        probability: f64,
        owner: &mut [Option<usize>],
        budget: usize,
    ) {
        self.lines.clear();
        self.lines.extend(lines);
        self.prepare_thresholds(probability);
        let n = self.lines.len();
        self.chosen.clear();
        self.chosen.resize(n, None);
        self.best.clear();
        self.best.resize(n, None);
        self.nodes.clear();
        self.nodes.push(Node {
            dx: Vector3::zeros(),
            p: *p0,
            nis: 0.0,
            count: 0,
            next: 0,
        });
        let (mut best_count, mut best_nis) = (0usize, f64::INFINITY);
        let mut budget = budget;
        while let Some(&node) = self.nodes.last() {
            let depth = self.nodes.len() - 1;
            let remaining = n - depth;
            let cannot_win = node.count + remaining < best_count
                || (node.count + remaining == best_count && node.nis >= best_nis);
            if depth == n || cannot_win {
                if depth == n && !cannot_win {
                    (best_count, best_nis) = (node.count, node.nis);
                    self.best.copy_from_slice(&self.chosen);
                }
                self.pop(candidates, owner);
                continue;
            }
            let (first, end) = self.lines[depth];
            let option = first + node.next;
            self.nodes[depth].next += 1;
            if option > end {
                self.pop(candidates, owner);
                continue;
            }
            if option == end {
                // This line without a wall.
                self.chosen[depth] = None;
                self.nodes.push(Node { next: 0, ..node });
                continue;
            }
            let c = &candidates[option];
            if owner[c.map].is_some() {
                continue;
            }
            if budget == 0 {
                // The path so far is a jointly compatible hypothesis too (its lines below
                // this depth unpaired): it stands if it beats the best complete one.
                if node.count > best_count || (node.count == best_count && node.nis < best_nis) {
                    self.best.copy_from_slice(&self.chosen);
                }
                break;
            }
            budget -= 1;
            let Some(child) = extend(&node, &pairs[c.pair], p0) else {
                continue;
            };
            if child.nis <= self.threshold(child.count) {
                owner[c.map] = Some(c.observed);
                self.chosen[depth] = Some(option);
                self.nodes.push(child);
            }
        }
        // Leave `owner` as it came (the budget may have run out deep in the tree).
        while !self.nodes.is_empty() {
            self.pop(candidates, owner);
        }
    }

    /// The candidates of the best hypothesis of the last [`run`](Self::run), one per
    /// paired line.
    pub(super) fn best(&self) -> impl Iterator<Item = usize> + '_ {
        self.best.iter().flatten().copied()
    }

    /// Leaves the deepest node, giving back the wall its parent's choice took.
    fn pop(&mut self, candidates: &[Candidate], owner: &mut [Option<usize>]) {
        self.nodes.pop();
        let Some(parent) = self.nodes.len().checked_sub(1) else {
            return;
        };
        if let Some(c) = self.chosen[parent].take() {
            owner[candidates[c].map] = None;
        }
    }

    /// The joint gate for `k` pairs.
    fn threshold(&self, k: usize) -> f64 {
        self.thresholds[k - 1]
    }

    /// Makes `thresholds` cover every hypothesis size of the scan.
    fn prepare_thresholds(&mut self, probability: f64) {
        if self.probability != probability {
            self.thresholds.clear();
            self.probability = probability;
        }
        while self.thresholds.len() < self.lines.len() {
            let dof = 2 * (self.thresholds.len() as u32 + 1);
            // The probability was validated with the individual gate; a failure here
            // (more than 5,000 lines) closes the gate rather than opening it.
            let t = chi_square_quantile(probability, dof).unwrap_or(f64::NEG_INFINITY);
            self.thresholds.push(t);
        }
    }
}

/// The node after pairing `pair` at `node`: the linear update at the matching state
/// (`R = S − H P₀ Hᵀ`, so a wall's considered error counts as the individual gate
/// counted it). `None` if the innovation covariance is not positive definite.
fn extend(node: &Node, pair: &LineMatch, p0: &Matrix3<f64>) -> Option<Node> {
    let inn = &pair.innovation;
    let h = inn.h;
    let ph = node.p * h.transpose();
    // S' = H P_H Hᵀ + R = S − H (P₀ − P_H) Hᵀ.
    let s = inn.s - h * (p0 * h.transpose() - ph);
    let det = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
    if !(s[(0, 0)] > 0.0 && det > 0.0) {
        return None;
    }
    let s_inv = Matrix2::new(s[(1, 1)], -s[(0, 1)], -s[(1, 0)], s[(0, 0)]) / det;
    let y = inn.y - h * node.dx;
    let nis = (y.transpose() * s_inv * y)[(0, 0)];
    if !nis.is_finite() {
        return None;
    }
    // K = P Hᵀ S⁻¹; P − K S Kᵀ = P − K (P Hᵀ)ᵀ.
    let k = ph * s_inv;
    let p = node.p - k * ph.transpose();
    Some(Node {
        dx: node.dx + k * y,
        p: 0.5 * (p + p.transpose()),
        nis: node.nis + nis,
        count: node.count + 1,
        next: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::{Ekf, LaserLine, Line, Pose2};
    use nalgebra::Matrix2;

    /// Three lines, each with one candidate wall of its own (the walls of a corner and
    /// the wall opposite), all fitting the state exactly.
    fn three_pairs() -> (Vec<Candidate>, Vec<LineMatch>, Matrix3<f64>) {
        let p0 = Matrix3::identity() * 0.01;
        let ekf = Ekf::new(Pose2::identity(), p0).unwrap();
        let walls = [
            Line::new(2.0, 0.0),
            Line::new(3.0, 1.5),
            Line::new(2.5, -1.5),
        ];
        let (mut candidates, mut pairs) = (Vec::new(), Vec::new());
        for (i, wall) in walls.into_iter().enumerate() {
            let wall = wall.unwrap();
            let model = LaserLine {
                observed: wall,
                covariance: Matrix2::identity() * 1e-4,
                map_line: wall,
                mount: Pose2::identity(),
            };
            let innovation = ekf.innovation(&model).unwrap();
            candidates.push(Candidate {
                nis: innovation.nis,
                observed: i,
                map: i,
                pair: i,
            });
            pairs.push(LineMatch {
                observed: i,
                map: i,
                innovation,
                overlap: 1.0,
            });
        }
        (candidates, pairs, p0)
    }

    #[test]
    fn the_path_so_far_stands_when_the_budget_runs_out_before_a_complete_hypothesis() {
        let (candidates, pairs, p0) = three_pairs();
        let mut search = JointSearch::default();
        let mut owner = [None; 3];
        let lines = || [(0, 1), (1, 2), (2, 3)].into_iter();
        let best = |search: &JointSearch| search.best().collect::<Vec<_>>();
        search.run(
            lines(),
            &candidates,
            &pairs,
            &p0,
            0.99,
            &mut owner,
            NODE_BUDGET,
        );
        assert_eq!(best(&search), [0, 1, 2]);
        assert_eq!(owner, [None; 3], "every wall given back");
        // Two pairs tried, then the budget is spent: the two stand.
        search.run(lines(), &candidates, &pairs, &p0, 0.99, &mut owner, 2);
        assert_eq!(best(&search), [0, 1]);
        assert_eq!(owner, [None; 3], "every wall given back");
    }
}

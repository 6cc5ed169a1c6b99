//! The key scans of a SLAM run: the lines each saw (sensor frame), when, and how far the
//! robot had driven; maps are built from any set of them at their graph poses.

use super::scan_match::{ReferenceCloud, ScanPoints};
use ekf_core::Pose2;
use lrf_lines::{LineMap, MapBuilder, MapBuilderParams, ObservedLine};

/// The most points of a chain a loop closure aligns: a few scans' worth, spread over all
/// of the chain's key scans (a simulated laser of 0.25° beams gives 2,800 points over
/// 3 m, and aligning all of them made the refinements most of a build's time).
const CHAIN_POINTS: usize = 1200;

/// One key scan: a node of the pose graph.
#[derive(Debug, Clone)]
pub struct KeyScan {
    /// The front end's pose at the scan, in the frame of the poses it estimated after it
    /// (the graph pose, when the front end was restarted there).
    pub front: Pose2<f64>,
    /// The scan's lines, sensor frame.
    pub lines: Vec<ObservedLine>,
    /// The scan's points, robot frame.
    pub points: ScanPoints,
    /// Path length driven up to the scan (m).
    pub path: f64,
}

/// The key scans, in order, and how their lines are fused into maps.
#[derive(Debug, Clone)]
pub struct KeyScans {
    keys: Vec<KeyScan>,
    builder: MapBuilderParams,
}

impl KeyScans {
    /// No key scans yet; maps fused with `builder`.
    pub fn new(builder: MapBuilderParams) -> Self {
        Self {
            keys: Vec::new(),
            builder,
        }
    }

    /// Adds a key scan; returns its index.
    pub fn push(&mut self, key: KeyScan) -> usize {
        self.keys.push(key);
        self.keys.len() - 1
    }

    /// Key scan `k`.
    pub fn get(&self, k: usize) -> &KeyScan {
        &self.keys[k]
    }

    /// Key scan `k`, to change.
    pub fn get_mut(&mut self, k: usize) -> &mut KeyScan {
        &mut self.keys[k]
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// None yet.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The points of the key scans `which`, each placed at its pose in `poses`.
    pub fn cloud_of(
        &self,
        poses: &[Pose2<f64>],
        which: impl IntoIterator<Item = usize>,
        cell: f64,
    ) -> ReferenceCloud {
        ReferenceCloud::new(
            which.into_iter().map(|k| (poses[k], &self.keys[k].points)),
            cell,
        )
    }

    /// The points of the [`chain`](Self::chain) of key scan `k`, all in `k`'s robot frame
    /// (placed by their poses in `poses`), every n-th kept so that at most
    /// [`CHAIN_POINTS`] remain.
    pub fn chain_points(&self, poses: &[Pose2<f64>], k: usize, path: f64) -> ScanPoints {
        let here = poses[k].inverse();
        ScanPoints::merged(
            self.chain(k, path)
                .map(|j| (here.compose(&poses[j]), &self.keys[j].points)),
        )
        .thinned(CHAIN_POINTS)
    }

    /// Key scan `k` and the key scans up to `path` (m) of driving before it.
    pub fn chain(&self, k: usize, path: f64) -> std::ops::RangeInclusive<usize> {
        let end = self.keys[k].path;
        let first = (0..=k)
            .rev()
            .take_while(|&j| end - self.keys[j].path <= path)
            .last()
            .unwrap_or(k);
        first..=k
    }

    /// The lines of the [`chain`](Self::chain) of key scan `k`, all in `k`'s sensor frame
    /// (placed by their poses in `poses`): one observation with the walls of a few scans,
    /// for a search that one scan's few lines leave ambiguous.
    pub fn chain_lines(
        &self,
        poses: &[Pose2<f64>],
        k: usize,
        path: f64,
        mount: &Pose2<f64>,
    ) -> Vec<ObservedLine> {
        let here = poses[k].compose(mount).inverse();
        self.chain(k, path)
            .flat_map(|j| {
                let sensor = here.compose(&poses[j].compose(mount));
                self.keys[j].lines.iter().map(move |l| l.seen_from(&sensor))
            })
            .collect()
    }

    /// The walls of [`chain_lines`](Self::chain_lines)' key scans fused into one map, as
    /// segments in `k`'s sensor frame: what a search for the place needs (each wall once,
    /// as long as the scans saw it), not what a filter fuses (their covariances are not
    /// kept: a nominal 1 cm, 0.5° is set).
    pub fn chain_walls(
        &self,
        poses: &[Pose2<f64>],
        k: usize,
        path: f64,
        mount: &Pose2<f64>,
    ) -> Vec<ObservedLine> {
        let here = poses[k].compose(mount).inverse();
        let nominal = nalgebra::Matrix2::new(1e-4, 0.0, 0.0, 0.5f64.to_radians().powi(2));
        self.map_of(poses, self.chain(k, path), mount)
            .segments
            .iter()
            .filter_map(|wall| {
                let (start, end) = (
                    here.transform_point(&wall.start),
                    here.transform_point(&wall.end),
                );
                Some(ObservedLine {
                    line: ekf_core::Line::from_segment(&start, &end).ok()?,
                    covariance: nominal,
                    start,
                    end,
                    num_points: 0,
                })
            })
            .collect()
    }

    /// The map of the key scans `which`, each placed at its pose in `poses` ⊕ `mount`,
    /// repeated sightings fused ([`MapBuilder`]).
    pub fn map_of(
        &self,
        poses: &[Pose2<f64>],
        which: impl IntoIterator<Item = usize>,
        mount: &Pose2<f64>,
    ) -> LineMap {
        let Ok(mut builder) = MapBuilder::new(self.builder) else {
            return LineMap::default();
        };
        for k in which {
            // A key scan's lines were validated when its scan was fused.
            let _ = builder.add_scan(&self.keys[k].lines, &poses[k].compose(mount));
        }
        builder.finish()
    }
}

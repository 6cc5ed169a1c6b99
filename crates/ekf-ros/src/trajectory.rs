//! A time-stamped planar pose trajectory: what the filter writes, TUM files hold and the
//! evaluation compares.
//!
//! Chosen layout: one `Vec<StampedPose>` (array of structs), so a stamp can never lose its
//! pose. Stamps are integer nanoseconds (docs/ARCHITECTURE.md §2), so they survive file round trips
//! exactly. The order of the samples is the order they were pushed or read; nothing here
//! sorts or de-duplicates them.

use ekf_core::Pose2;
use serde::Serialize;

/// One pose at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StampedPose {
    /// Time stamp in nanoseconds (ROS time, or any fixed epoch shared by the trajectories
    /// being compared).
    pub t_ns: u64,
    /// The pose `(x, y, θ)` in the map frame: metres, radians.
    pub pose: Pose2<f64>,
}

impl StampedPose {
    /// A stamped pose.
    pub fn new(t_ns: u64, pose: Pose2<f64>) -> Self {
        Self { t_ns, pose }
    }
}

/// A sequence of stamped planar poses.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// The samples in file or recording order.
    pub samples: Vec<StampedPose>,
}

impl Trajectory {
    /// An empty trajectory.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a pose at `t_ns`.
    pub fn push(&mut self, t_ns: u64, pose: Pose2<f64>) {
        self.samples.push(StampedPose::new(t_ns, pose));
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether the trajectory has no pose.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Iterates over the samples in order.
    pub fn iter(&self) -> std::slice::Iter<'_, StampedPose> {
        self.samples.iter()
    }
}

impl From<Vec<StampedPose>> for Trajectory {
    fn from(samples: Vec<StampedPose>) -> Self {
        Self { samples }
    }
}

impl FromIterator<StampedPose> for Trajectory {
    fn from_iter<I: IntoIterator<Item = StampedPose>>(iter: I) -> Self {
        Self {
            samples: iter.into_iter().collect(),
        }
    }
}

impl<'a> IntoIterator for &'a Trajectory {
    type Item = &'a StampedPose;
    type IntoIter = std::slice::Iter<'a, StampedPose>;

    fn into_iter(self) -> Self::IntoIter {
        self.samples.iter()
    }
}

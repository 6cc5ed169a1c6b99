//! A line extracted from one scan: the measurement the filter fuses.

use ekf_core::Line;
use nalgebra::{Matrix2, Point2};

/// A line observed in one scan, in the sensor frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObservedLine {
    /// The line `(r, ψ)` in normal form in the sensor frame (`r ≥ 0`).
    pub line: Line<f64>,
    /// Covariance of `(r, ψ)`: the inverse of the full 2×2 Fisher information of the
    /// weighted fit (m², m·rad, rad²).
    pub covariance: Matrix2<f64>,
    /// First end point of the segment (sensor frame), in scan order.
    pub start: Point2<f64>,
    /// Last end point of the segment (sensor frame), in scan order.
    pub end: Point2<f64>,
    /// Number of scan points the line was fitted to.
    pub num_points: usize,
}

impl ObservedLine {
    /// Length of the segment between its end points (m).
    pub fn length(&self) -> f64 {
        (self.end - self.start).norm()
    }
}

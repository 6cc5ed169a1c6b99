//! Laser scans shaped like ROS `sensor_msgs/LaserScan`.

/// One laser scan: beam `i` has bearing `angle_min + i·angle_increment` (counter-clockwise
/// in the sensor frame) and range `ranges[i]` (m). Readings that are not finite, are
/// `≤ range_min` or `≥ range_max` are invalid (no return, dazzle, overflow codes) and are
/// never turned into points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserScan<'a> {
    /// Bearing of the first beam (rad).
    pub angle_min: f64,
    /// Angle between consecutive beams (rad); negative for clockwise scanners.
    pub angle_increment: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m); readings at or beyond it are invalid.
    pub range_max: f64,
    /// Ranges (m), as `float32` on the wire.
    pub ranges: &'a [f32],
}

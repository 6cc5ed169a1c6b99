//! Maps of wall segments in the world frame: the global map that observed laser lines are
//! matched against (docs/ARCHITECTURE.md §3 "Global map"), built from one scan, from a whole run, or
//! loaded from a JSON file (format in `docs/map-format.md`).

mod builder;
mod json;
mod json_path;
mod wall_index;

pub use builder::{MapBuilder, MapBuilderParams, NEAR_M};
pub use json::{MapFormatError, MapFormatErrorKind, MAP_FORMAT, MAP_FORMAT_VERSION};
pub use wall_index::WallIndex;

use crate::ObservedLine;
use alloc::string::String;
use alloc::vec::Vec;
use ekf_core::{Error, Line, Pose2};
use nalgebra::{Point2, Vector2};

/// The frame id a map gets when nothing else names it.
pub const DEFAULT_FRAME_ID: &str = "map";

/// A wall: a line segment in the world frame.
///
/// Invariant kept by every constructor in this crate: `line` is the line through `start`
/// and `end` (so both lie on it) and the two points are distinct and finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapSegment {
    /// The wall's line `x cos β + y sin β = ρ` in the world frame.
    pub line: Line<f64>,
    /// One end point (world frame, m).
    pub start: Point2<f64>,
    /// The other end point (world frame, m).
    pub end: Point2<f64>,
}

impl MapSegment {
    /// The segment between two points, with `line = Line::from_segment(start, end)`.
    /// Fails if a coordinate is not finite or the points coincide.
    pub fn from_points(start: Point2<f64>, end: Point2<f64>) -> Result<Self, Error> {
        Ok(Self {
            line: Line::from_segment(&start, &end)?,
            start,
            end,
        })
    }

    /// Length of the segment (m).
    pub fn length(&self) -> f64 {
        (self.end - self.start).norm()
    }

    /// Distance from `p` to the segment (m): to the nearest point `start + t (end − start)`,
    /// `t = clamp((p − start)·(end − start) / |end − start|², 0, 1)`.
    pub fn distance_to(&self, p: &Point2<f64>) -> f64 {
        let d = self.end - self.start;
        let t = ((p - self.start).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        (self.start + d * t - p).norm()
    }

    /// The interval `[t_min, t_max]` the segment covers along the direction of `line`
    /// (see [`line_direction`]): `t = p · d` for both end points.
    pub fn extent_along(&self, line: &Line<f64>) -> (f64, f64) {
        interval_along(line, &self.start, &self.end)
    }
}

/// The unit direction of a line, its normal rotated by +90°: `d = (−sin β, cos β)`.
/// A point of the line is `ρ·(cos β, sin β) + t·d`.
pub fn line_direction(line: &Line<f64>) -> Vector2<f64> {
    Vector2::new(-libm::sin(line.beta), libm::cos(line.beta))
}

/// The point of `line` at coordinate `t` along [`line_direction`]:
/// `ρ·(cos β, sin β) + t·(−sin β, cos β)`.
pub fn point_on_line(line: &Line<f64>, t: f64) -> Point2<f64> {
    let (s, c) = (libm::sin(line.beta), libm::cos(line.beta));
    Point2::new(line.rho * c - t * s, line.rho * s + t * c)
}

/// The interval `[min, max]` of the projections `t = p · d` of two points onto the
/// direction `d` of `line`.
pub fn interval_along(line: &Line<f64>, a: &Point2<f64>, b: &Point2<f64>) -> (f64, f64) {
    let d = line_direction(line);
    let (ta, tb) = (a.coords.dot(&d), b.coords.dot(&d));
    (ta.min(tb), ta.max(tb))
}

/// A map of walls in one fixed world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LineMap {
    /// Name of the map's frame (ROS `frame_id`), `"map"` by default.
    pub frame_id: String,
    /// The walls.
    pub segments: Vec<MapSegment>,
}

impl Default for LineMap {
    /// An empty map in frame `"map"`.
    fn default() -> Self {
        Self::new(Vec::new())
    }
}

impl LineMap {
    /// A map of `segments` in frame `"map"`.
    pub fn new(segments: Vec<MapSegment>) -> Self {
        Self {
            frame_id: String::from(DEFAULT_FRAME_ID),
            segments,
        }
    }

    /// The paper's global map (§III): the lines of one scan taken as the walls.
    ///
    /// `sensor_pose` is the laser's pose in the world, i.e. robot pose ⊕ laser mount. Each
    /// line `(r, ψ)` becomes the world line `ρ = r + x_s cos β + y_s sin β`, `β = ψ + θ_s`
    /// (normalised to `ρ ≥ 0`), and its end points are transformed into the world and
    /// projected onto that line, so the segment lies exactly on the fitted line. Lines
    /// whose projected end points coincide are skipped. Fails if the pose or a line is not
    /// finite.
    pub fn from_scan(lines: &[ObservedLine], sensor_pose: &Pose2<f64>) -> Result<Self, Error> {
        Self::from_scan_with_sources(lines, sensor_pose).map(|(map, _)| map)
    }

    /// [`LineMap::from_scan`], and for each wall the index in `lines` of the line it was
    /// placed from.
    pub fn from_scan_with_sources(
        lines: &[ObservedLine],
        sensor_pose: &Pose2<f64>,
    ) -> Result<(Self, Vec<usize>), Error> {
        sensor_pose.validated("sensor pose")?;
        let mut segments = Vec::with_capacity(lines.len());
        let mut sources = Vec::with_capacity(lines.len());
        for (i, observed) in lines.iter().enumerate() {
            let line = Line::new(observed.line.rho, observed.line.beta)?.from_frame(sensor_pose);
            let a = line.project(&sensor_pose.transform_point(&observed.start));
            let b = line.project(&sensor_pose.transform_point(&observed.end));
            match MapSegment::from_points(a, b) {
                Ok(segment) => {
                    segments.push(segment);
                    sources.push(i);
                }
                Err(Error::OutOfRange { .. }) => {} // zero length: not a wall
                Err(e) => return Err(e),
            }
        }
        Ok((Self::new(segments), sources))
    }

    /// A map built from a whole run: every scan's lines with the sensor pose they were
    /// taken from (robot pose ⊕ laser mount, e.g. from a reference trajectory), fused by a
    /// [`MapBuilder`] with `params` (see there for the rule).
    pub fn from_run<'a, I>(scans: I, params: &MapBuilderParams) -> Result<Self, Error>
    where
        I: IntoIterator<Item = (&'a [ObservedLine], Pose2<f64>)>,
    {
        let mut builder = MapBuilder::new(*params)?;
        for (lines, pose) in scans {
            builder.add_scan(lines, &pose)?;
        }
        Ok(builder.finish())
    }

    /// Number of walls.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// `true` if the map has no walls.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }
}

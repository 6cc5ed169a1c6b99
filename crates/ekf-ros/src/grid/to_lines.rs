//! Walls of an occupancy grid as a line map: virtual laser scans cast through the grid's
//! free space, their lines extracted as a real scan's are, and fused by the map builder —
//! so the walls are the surfaces a laser would see, found by the same code and gates.

use super::{raycast, OccupancyGrid, FREE};
use ekf_core::Pose2;
use lrf_lines::{
    ExtractionParams, LaserScan, LineExtractor, LineMap, MapBuilder, MapBuilderParams, ObservedLine,
};
use serde::{Deserialize, Serialize};

/// How the virtual scans are taken.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GridImportParams {
    /// Spacing of the scan positions, a square lattice over the free cells (m). Default
    /// 1.0: every wall is seen from several places, at a cost that grows with the free
    /// area.
    pub scan_spacing: f64,
    /// Beams of a scan, evenly over a full turn. Default 720 (0.5°).
    pub beams: usize,
    /// Range of the virtual laser (m). Default 20.
    pub max_range: f64,
    /// Walls seen from fewer scan positions are dropped (corners of a blocky grid seen
    /// once). Default 3.
    pub min_sightings: u32,
}

impl Default for GridImportParams {
    fn default() -> Self {
        Self {
            scan_spacing: 1.0,
            beams: 720,
            max_range: 20.0,
            min_sightings: 3,
        }
    }
}

/// What was read and found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridImportSummary {
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Side of a cell (m).
    pub resolution: f64,
    /// Free, occupied and unknown cells.
    pub free_cells: usize,
    /// Cells with occupancy above 50 %.
    pub occupied_cells: usize,
    /// Cells of unknown occupancy.
    pub unknown_cells: usize,
    /// Virtual scans taken.
    pub scans: u64,
    /// Lines extracted from them.
    pub lines: u64,
    /// Walls in the map.
    pub segments: usize,
}

/// The summary as `ekf map import-grid` prints it after the map's file name: one line.
impl std::fmt::Display for GridImportSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} segments from a {} × {} grid at {} m ({} free, {} occupied, {} unknown cells; {} virtual scans, {} lines)",
            self.segments,
            self.width,
            self.height,
            self.resolution,
            self.free_cells,
            self.occupied_cells,
            self.unknown_cells,
            self.scans,
            self.lines
        )
    }
}

/// Why a grid gave no map.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridImportError {
    /// A parameter is out of range.
    #[error("grid import: {name} must be {expected}, not {value}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// What it must be.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// The extraction parameters were refused.
    #[error("grid import: {0}")]
    Extraction(#[from] lrf_lines::ExtractionError),
    /// The map builder's parameters were refused.
    #[error("grid import: map builder: {0}")]
    Builder(#[from] ekf_core::Error),
    /// No walls were found.
    #[error("no walls found: {scans} virtual scans from the free cells saw no wall of at least {min_sightings} sightings")]
    NoWalls {
        /// Virtual scans taken.
        scans: u64,
        /// The `min_sightings` in force.
        min_sightings: u32,
    },
}

/// The walls of `grid` (see the module). Scans are taken at the centres of free cells on a
/// lattice `scan_spacing` apart, each beam's range from [`raycast::cast`] (unknown cells
/// and the grid's edge give no return). Lines come from a [`LineExtractor`] with
/// `extraction`, its `range_sigma` raised to at least the grid's quantisation `res/√12`
/// and its `split_distance` to at least one cell (a wall drawn in cells is a staircase
/// up to a cell deep). A [`MapBuilder`] with default gates fuses them, keeping walls of
/// at least `min_sightings` sightings.
pub fn walls_of(
    grid: &OccupancyGrid,
    extraction: &ExtractionParams,
    params: &GridImportParams,
) -> Result<(LineMap, GridImportSummary), GridImportError> {
    let bad = |name, expected, value: f64| GridImportError::BadParameter {
        name,
        expected,
        value,
    };
    if !(params.scan_spacing.is_finite() && params.scan_spacing > 0.0) {
        return Err(bad("scan_spacing", "a length > 0 m", params.scan_spacing));
    }
    if !(params.max_range.is_finite() && params.max_range > 0.0) {
        return Err(bad("max_range", "a length > 0 m", params.max_range));
    }
    if !(8..=100_000).contains(&params.beams) {
        return Err(bad("beams", "8 to 100000", params.beams as f64));
    }
    let res = grid.resolution;
    let extraction = ExtractionParams {
        range_sigma: extraction.range_sigma.max(res / 12f64.sqrt()),
        split_distance: extraction.split_distance.max(res),
        ..*extraction
    };
    let mut extractor = LineExtractor::new(extraction)?;
    let builder_params = MapBuilderParams {
        min_sightings: params.min_sightings,
        ..MapBuilderParams::default()
    };
    let mut builder = MapBuilder::new(builder_params)?;
    let (free_cells, occupied_cells, unknown_cells) = grid.counts();
    let mut summary = GridImportSummary {
        width: grid.width,
        height: grid.height,
        resolution: res,
        free_cells,
        occupied_cells,
        unknown_cells,
        scans: 0,
        lines: 0,
        segments: 0,
    };
    let stride = ((params.scan_spacing / res).round() as usize).max(1);
    let increment = std::f64::consts::TAU / params.beams as f64;
    let angle_min = -std::f64::consts::PI;
    let mut ranges = vec![f32::INFINITY; params.beams];
    let mut lines: Vec<ObservedLine> = Vec::new();
    for iy in (stride / 2..grid.height).step_by(stride) {
        for ix in (stride / 2..grid.width).step_by(stride) {
            let (ix, iy) = (ix as i64, iy as i64);
            if grid.get(ix, iy) != Some(FREE) {
                continue;
            }
            let at = grid.centre(ix, iy);
            for (i, r) in ranges.iter_mut().enumerate() {
                let angle = angle_min + i as f64 * increment;
                *r = raycast::cast(grid, &at, angle, params.max_range)
                    .map_or(f32::INFINITY, |r| r as f32);
            }
            let scan = LaserScan {
                angle_min,
                angle_increment: increment,
                range_min: 0.0,
                range_max: params.max_range,
                ranges: &ranges,
            };
            extractor.extract(&scan, &mut lines)?;
            let sensor = grid.origin.compose(&Pose2::new(at.x, at.y, 0.0));
            // The pose and lines are finite by construction; a refusal would be a bug in
            // the extractor, and losing one virtual scan is harmless.
            if builder.add_scan(&lines, &sensor).is_ok() {
                summary.scans += 1;
                summary.lines += lines.len() as u64;
            }
        }
    }
    let map = builder.finish();
    if map.is_empty() {
        return Err(GridImportError::NoWalls {
            scans: summary.scans,
            min_sightings: params.min_sightings,
        });
    }
    summary.segments = map.len();
    Ok((map, summary))
}

#[cfg(test)]
mod tests {
    use super::super::from_lines;
    use super::*;
    use lrf_lines::MapSegment;
    use nalgebra::Point2;

    #[test]
    fn a_drawn_room_gives_back_its_walls() {
        // An L-shaped room, 8 × 6 m with a 3 × 2 m corner cut out, at an odd position.
        let corners = [
            (0.0, 0.0),
            (8.0, 0.0),
            (8.0, 4.0),
            (5.0, 4.0),
            (5.0, 6.0),
            (0.0, 6.0),
        ];
        let walls: Vec<MapSegment> = (0..corners.len())
            .map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                MapSegment::from_points(
                    Point2::new(a.0 + 3.21, a.1 - 7.65),
                    Point2::new(b.0 + 3.21, b.1 - 7.65),
                )
                .unwrap()
            })
            .collect();
        let room = LineMap::new(walls.clone());
        let grid = from_lines::draw(&room, 0.05, 1.0).unwrap();
        let (map, summary) = walls_of(
            &grid,
            &ExtractionParams::default(),
            &GridImportParams::default(),
        )
        .unwrap();
        // Scans from inside and outside the room see each wall from one side or both;
        // both see the cells' centre line, so each wall comes back once, within half a
        // cell (a wall on a cell boundary is drawn in the cells on one side).
        assert_eq!(map.len(), 6, "{map:#?}\n{summary:?}");
        for w in &walls {
            let found = map.segments.iter().find(|s| {
                ekf_core::angle_diff(s.line.beta, w.line.beta).abs() < 0.01
                    && (s.line.rho - w.line.rho).abs() < 0.04
            });
            let s = found.unwrap_or_else(|| panic!("no match for {w:?} in {map:#?}"));
            // Ends within two cells of the wall's (the band of cells sticks out).
            let (lo, hi) = s.extent_along(&w.line);
            let (wlo, whi) = w.extent_along(&w.line);
            assert!(
                (lo - wlo).abs() < 0.1 && (hi - whi).abs() < 0.1,
                "{s:?} vs {w:?}"
            );
        }
        assert!(summary.scans > 50, "{summary:?}");
    }

    #[test]
    fn bad_parameters_are_named() {
        let grid = OccupancyGrid::filled(10, 10, 0.1, Pose2::new(0.0, 0.0, 0.0), FREE);
        let e = |p: GridImportParams| {
            walls_of(&grid, &ExtractionParams::default(), &p)
                .unwrap_err()
                .to_string()
        };
        let d = GridImportParams::default();
        assert!(e(GridImportParams {
            scan_spacing: 0.0,
            ..d
        })
        .contains("scan_spacing"));
        assert!(e(GridImportParams {
            max_range: f64::NAN,
            ..d
        })
        .contains("max_range"));
        assert!(e(GridImportParams { beams: 2, ..d }).contains("beams"));
        assert!(e(d).contains("no walls found"));
    }
}

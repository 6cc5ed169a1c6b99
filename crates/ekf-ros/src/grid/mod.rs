//! Occupancy grids as ROS keeps maps (`nav_msgs/OccupancyGrid`, saved by `map_saver` as a
//! YAML + PGM/PNG pair): read and written in the Nav2 format ([`nav2`]), turned into a line
//! map by casting virtual laser scans through their free space ([`to_lines`]), and drawn
//! from a line map ([`from_lines`]). docs/maps.md shows the commands that use them.

pub mod from_lines;
pub mod nav2;
pub mod raycast;
pub mod to_lines;

use ekf_core::Pose2;
use lrf_lines::{ExtractionParams, LineMap};
use nalgebra::Point2;
use serde::Serialize;
use std::path::{Path, PathBuf};

pub use from_lines::DrawError;
pub use nav2::GridFileError;
pub use to_lines::{GridImportError, GridImportParams, GridImportSummary};

/// Why a grid map could not be read, drawn or turned into walls.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// The YAML or image file.
    #[error(transparent)]
    File(#[from] GridFileError),
    /// Drawing the line map.
    #[error("{path}: {source}")]
    Draw {
        /// The map being drawn.
        path: PathBuf,
        /// What was wrong.
        source: DrawError,
    },
    /// Finding the grid's walls.
    #[error("{path}: {source}")]
    Import {
        /// The grid's YAML file.
        path: PathBuf,
        /// What was wrong.
        source: GridImportError,
    },
}

/// `ekf map import-grid`: the walls of the `map_server` / Nav2 map `yaml` (see
/// [`to_lines::walls_of`]), with lines extracted by `extraction`.
pub fn import(
    yaml: &Path,
    extraction: &ExtractionParams,
    params: &GridImportParams,
) -> Result<(LineMap, GridImportSummary), GridError> {
    let grid = nav2::load(yaml)?;
    to_lines::walls_of(&grid, extraction, params).map_err(|source| GridError::Import {
        path: yaml.to_path_buf(),
        source,
    })
}

/// What `ekf map export-grid` wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridExportSummary {
    /// The image written beside the YAML file.
    pub image: PathBuf,
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Side of a cell (m).
    pub resolution: f64,
    /// `[x, y, yaw]` of the lower-left corner.
    pub origin: [f64; 3],
    /// Occupied cells.
    pub occupied_cells: usize,
    /// Walls drawn.
    pub segments: usize,
}

/// The summary as `ekf map export-grid` prints it after the YAML file's name: one line.
impl std::fmt::Display for GridExportSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} × {} cells at {} m, origin [{}, {}, {}], {} occupied by {} walls (image {})",
            self.width,
            self.height,
            self.resolution,
            self.origin[0],
            self.origin[1],
            self.origin[2],
            self.occupied_cells,
            self.segments,
            self.image.display()
        )
    }
}

/// `ekf map export-grid`: `map` (read from `map_path`) drawn at `resolution` with `margin`
/// (see [`from_lines::draw`]) and saved as a Nav2 map `yaml` + PGM (see [`nav2::save`]).
pub fn export(
    map: &LineMap,
    map_path: &Path,
    yaml: &Path,
    resolution: f64,
    margin: f64,
) -> Result<GridExportSummary, GridError> {
    let grid = from_lines::draw(map, resolution, margin).map_err(|source| GridError::Draw {
        path: map_path.to_path_buf(),
        source,
    })?;
    let image = nav2::save(&grid, yaml)?;
    let o = grid.origin;
    Ok(GridExportSummary {
        image,
        width: grid.width,
        height: grid.height,
        resolution,
        origin: [o.x, o.y, o.theta],
        occupied_cells: grid.counts().1,
        segments: map.len(),
    })
}

/// Occupancy of a cell whose state is not known (`nav_msgs/OccupancyGrid` convention).
pub const UNKNOWN: i8 = -1;
/// Occupancy of a surely free cell.
pub const FREE: i8 = 0;
/// Occupancy of a surely occupied cell.
pub const OCCUPIED: i8 = 100;

/// A cell stops a ray when its occupancy is above this (%): it is more likely occupied
/// than free.
pub const OBSTACLE_ABOVE: i8 = 50;

/// A 2D occupancy grid, laid out as `nav_msgs/OccupancyGrid`: `width × height` cells of
/// side `resolution`, row-major from the row at `origin` (the map's lower-left corner in
/// the world), each `-1` (unknown) or an occupancy `0..=100` (%).
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Side of a cell (m).
    pub resolution: f64,
    /// Pose of the lower-left corner of cell `(0, 0)` in the world (the grid's x axis
    /// points along `origin.theta`).
    pub origin: Pose2<f64>,
    /// Occupancy by cell, `cells[iy * width + ix]`.
    pub cells: Vec<i8>,
}

impl OccupancyGrid {
    /// A grid of `width × height` cells, all `value`.
    pub fn filled(
        width: usize,
        height: usize,
        resolution: f64,
        origin: Pose2<f64>,
        value: i8,
    ) -> Self {
        Self {
            width,
            height,
            resolution,
            origin,
            cells: vec![value; width * height],
        }
    }

    /// The occupancy of cell `(ix, iy)`, or `None` outside the grid.
    pub fn get(&self, ix: i64, iy: i64) -> Option<i8> {
        let (x, y) = (usize::try_from(ix).ok()?, usize::try_from(iy).ok()?);
        (x < self.width && y < self.height).then(|| self.cells[y * self.width + x])
    }

    /// Sets cell `(ix, iy)`; cells outside the grid are ignored.
    pub fn set(&mut self, ix: i64, iy: i64, value: i8) {
        if let (Ok(x), Ok(y)) = (usize::try_from(ix), usize::try_from(iy)) {
            if x < self.width && y < self.height {
                self.cells[y * self.width + x] = value;
            }
        }
    }

    /// The point in the grid's own frame (m from the lower-left corner, along its rows and
    /// columns) of a world point.
    pub fn to_grid_frame(&self, world: &Point2<f64>) -> Point2<f64> {
        self.origin.inverse_transform_point(world)
    }

    /// The world point of a point in the grid's frame.
    pub fn to_world(&self, grid: &Point2<f64>) -> Point2<f64> {
        self.origin.transform_point(grid)
    }

    /// The cell `(ix, iy)` holding a point of the grid's frame (possibly outside the grid).
    pub fn cell_of(&self, grid: &Point2<f64>) -> (i64, i64) {
        (
            (grid.x / self.resolution).floor() as i64,
            (grid.y / self.resolution).floor() as i64,
        )
    }

    /// The centre of cell `(ix, iy)` in the grid's frame.
    pub fn centre(&self, ix: i64, iy: i64) -> Point2<f64> {
        Point2::new(
            (ix as f64 + 0.5) * self.resolution,
            (iy as f64 + 0.5) * self.resolution,
        )
    }

    /// Cells by kind: `(free, occupied, unknown)`, with occupancy `0`, above
    /// [`OBSTACLE_ABOVE`], and `-1` (cells in between count as neither).
    pub fn counts(&self) -> (usize, usize, usize) {
        let mut counts = (0, 0, 0);
        for &c in &self.cells {
            match c {
                FREE => counts.0 += 1,
                UNKNOWN => counts.2 += 1,
                c if c > OBSTACLE_ABOVE => counts.1 += 1,
                _ => {}
            }
        }
        counts
    }
}

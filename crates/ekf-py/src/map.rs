//! Line maps: the `LineMap` class (load, save, JSON, from arrays, from one scan, from a
//! whole log with or without its reference, from an occupancy grid) and `MapBuilder` (fusing the lines of many scans at known poses).

use crate::arrays::{check_finite, check_shape, new_array, pose3, real_array};
use crate::errors::{file_error, path_error, value_error};
use crate::lines::Lines;
use crate::params::load_config;
use crate::params::{from_dict, to_python};
use ekf_ros::grid::{self, GridImportParams};
use ekf_ros::map_build::{build_map, MapSource};
use ekf_ros::slam::build_slam_map;
use lrf_lines::MapBuilderParams;
use nalgebra::Point2;
use numpy::{Ix2, Ix3, PyArray2, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A map of walls: line segments in one fixed world frame (JSON format in
/// `docs/map-format.md`).
#[pyclass(module = "ekf_loc")]
#[derive(Debug, Clone)]
pub struct LineMap {
    /// The map.
    pub map: lrf_lines::LineMap,
}

#[pymethods]
impl LineMap {
    /// A map from `segments`, an (N, 2, 2) array of `[[x0, y0], [x1, y1]]` end points in
    /// the world frame (m), in frame `frame_id`. Raises `ValueError` for non-finite or
    /// coincident end points.
    #[new]
    #[pyo3(signature = (segments, frame_id = "map"))]
    fn new(segments: &Bound<'_, PyAny>, frame_id: &str) -> PyResult<Self> {
        let a = real_array::<Ix3>(segments, "segments")?;
        let a = a.as_array();
        check_shape(
            "segments",
            a.shape(),
            &[None, Some(2), Some(2)],
            "(N, 2, 2) as [[x0, y0], [x1, y1]]",
        )?;
        check_finite("segments", &a)?;
        let segments = (0..a.shape()[0])
            .map(|i| {
                let p = |k: usize| Point2::new(a[[i, k, 0]], a[[i, k, 1]]);
                lrf_lines::MapSegment::from_points(p(0), p(1))
                    .map_err(|e| value_error(format!("segments[{i}]: {e}")))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let mut map = lrf_lines::LineMap::new(segments);
        map.frame_id = frame_id.to_owned();
        Ok(Self { map })
    }

    /// Reads a JSON map file. Raises `OSError` if it cannot be read and `ValueError`, naming
    /// the entry and field, if it is not a valid map.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let bytes = std::fs::read(&path).map_err(|e| path_error(&path, &e))?;
        lrf_lines::LineMap::from_json_bytes(&bytes)
            .map(|map| Self { map })
            .map_err(|e| value_error(format!("{}: {e}", path.display())))
    }

    /// Parses a map from JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        lrf_lines::LineMap::from_json(text)
            .map(|map| Self { map })
            .map_err(value_error)
    }

    /// The map as JSON text.
    fn to_json(&self) -> PyResult<String> {
        self.map.to_json().map_err(value_error)
    }

    /// Writes the map as a JSON file (created or replaced).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        let text = self.to_json()?;
        std::fs::write(&path, text).map_err(|e| path_error(&path, &e))
    }

    /// The paper's global map (§III): the lines of one scan taken as the walls, placed with
    /// `sensor_pose` = robot pose ⊕ laser mount `(x, y, theta)` in the world.
    #[staticmethod]
    fn from_scan(lines: &Lines, sensor_pose: &Bound<'_, PyAny>) -> PyResult<Self> {
        let pose = pose3(sensor_pose, "sensor_pose")?;
        lrf_lines::LineMap::from_scan(&lines.lines, &pose)
            .map(|map| Self { map })
            .map_err(value_error)
    }

    /// Builds the map of a ROS 2 bag, as `ekf map build` does: with `from_truth` (the
    /// default) every scan placed at the log's reference pose and repeated sightings of a
    /// wall fused (`params`: the map builder's parameters); otherwise the first scan at
    /// the configured initial pose (or the first reference pose with `init_from_truth`).
    /// `config` is an `ekf` TOML config file or a dict of the same groups. Returns the map
    /// and the summary `ekf map build --json` prints.
    #[staticmethod]
    #[pyo3(signature = (path, config = None, *, from_truth = true, init_from_truth = false, params = None))]
    fn build_from_log<'py>(
        py: Python<'py>,
        path: PathBuf,
        config: Option<&Bound<'py, PyAny>>,
        from_truth: bool,
        init_from_truth: bool,
        params: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Self, Bound<'py, PyAny>)> {
        let config = load_config(config)?;
        let source = if from_truth {
            MapSource::Reference(from_dict::<MapBuilderParams>(params, "params")?)
        } else if params.is_some_and(|p| !p.is_none()) {
            return Err(PyValueError::new_err(
                "params applies only to maps built with from_truth=True",
            ));
        } else {
            MapSource::FirstScan { init_from_truth }
        };
        let (map, summary) = py
            .detach(|| build_map(&path, &config, source))
            .map_err(|e| file_error(&e))?;
        Ok((Self { map }, to_python(py, &summary)?))
    }

    /// The map of the log at `path` built without its reference, as `ekf map build
    /// --slam` builds it (same code): the filter localizes in the map as it grows, loops
    /// are closed where the robot comes back, and the key scans' pose graph optimised.
    /// `config` is an `ekf` TOML config file or a dict of the same groups (its `slam`
    /// group sets the builder). Returns the map, an (N, 4) array of the corrected pose at
    /// every scan `[t (s), x, y, theta]`, and the summary `ekf map build --slam --json`
    /// prints. Raises `OSError` / `ValueError` as `replay` does, also when the log breaks
    /// off part-way.
    #[staticmethod]
    #[pyo3(signature = (path, config = None))]
    fn build_slam<'py>(
        py: Python<'py>,
        path: PathBuf,
        config: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Self, Bound<'py, PyArray2<f64>>, Bound<'py, PyAny>)> {
        let config = load_config(config)?;
        let outcome = py
            .detach(|| build_slam_map(&path, &config, &mut |_, _| {}))
            .map_err(|e| file_error(&e))?;
        if let Some(failure) = outcome.failure {
            return Err(file_error(&failure));
        }
        let rows: Vec<f64> = outcome
            .trajectory
            .iter()
            .flat_map(|s| [s.t_ns as f64 * 1e-9, s.pose.x, s.pose.y, s.pose.theta])
            .collect();
        let n = outcome.trajectory.len();
        let trajectory = new_array(py, rows, Ix2(n, 4))?;
        let summary = to_python(py, &outcome.summary)?;
        Ok((Self { map: outcome.map }, trajectory, summary))
    }

    /// The walls of a `map_server` / Nav2 occupancy grid (`yaml`: its YAML file, with a
    /// PGM or PNG image), as `ekf map import-grid` extracts them (same code): virtual
    /// scans over the free cells, their lines fused. `config` sets the line extraction
    /// (its `localizer.extraction` group); `params` is a dict of `scan_spacing`, `beams`,
    /// `max_range`, `min_sightings`. Returns the map and the summary `ekf map import-grid
    /// --json` prints. Raises `OSError` for an unreadable file, `ValueError` for a bad
    /// YAML, image or parameter.
    #[staticmethod]
    #[pyo3(signature = (yaml, config = None, params = None))]
    fn import_grid<'py>(
        py: Python<'py>,
        yaml: PathBuf,
        config: Option<&Bound<'py, PyAny>>,
        params: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Self, Bound<'py, PyAny>)> {
        let config = load_config(config)?;
        let params = from_dict::<GridImportParams>(params, "params")?;
        let (map, summary) = py
            .detach(|| grid::import(&yaml, &config.localizer.extraction, &params))
            .map_err(|e| file_error(&e))?;
        Ok((Self { map }, to_python(py, &summary)?))
    }

    /// (N, 2, 2) end points `[[x0, y0], [x1, y1]]` of the walls (m, world frame).
    #[getter]
    fn segments<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let v = self
            .map
            .segments
            .iter()
            .flat_map(|s| [s.start.x, s.start.y, s.end.x, s.end.y])
            .collect();
        new_array(py, v, Ix3(self.map.len(), 2, 2))
    }

    /// (N, 2) lines `(rho, beta)` of the walls: `x cos beta + y sin beta = rho`, world frame.
    #[getter]
    fn lines<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .map
            .segments
            .iter()
            .flat_map(|s| [s.line.rho, s.line.beta])
            .collect();
        new_array(py, v, Ix2(self.map.len(), 2))
    }

    /// The name of the map's frame (ROS `frame_id`).
    #[getter]
    fn frame_id(&self) -> &str {
        &self.map.frame_id
    }

    fn __len__(&self) -> usize {
        self.map.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "LineMap({} segments, frame_id={:?})",
            self.map.len(),
            self.map.frame_id
        )
    }
}

/// Builds a map from the lines of many scans taken at known sensor poses, fusing repeated
/// sightings of the same wall (the rule is in `lrf_lines::MapBuilder`).
#[pyclass(module = "ekf_loc")]
pub struct MapBuilder {
    builder: lrf_lines::MapBuilder,
}

#[pymethods]
impl MapBuilder {
    /// A builder with `params` (dict: `gate_probability`, `tolerance_rho` (m),
    /// `tolerance_beta` (rad), `max_gap` (m), `min_sightings`; defaults for missing keys).
    #[new]
    #[pyo3(signature = (params = None))]
    fn new(params: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let params: MapBuilderParams = from_dict(params, "params")?;
        lrf_lines::MapBuilder::new(params)
            .map(|builder| Self { builder })
            .map_err(value_error)
    }

    /// Adds the lines of one scan taken at `sensor_pose` = robot pose ⊕ laser mount
    /// `(x, y, theta)` in the world.
    fn add_scan(&mut self, lines: &Lines, sensor_pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let pose = pose3(sensor_pose, "sensor_pose")?;
        self.builder
            .add_scan(&lines.lines, &pose)
            .map_err(value_error)
    }

    /// The map so far (walls merged, those seen fewer than `min_sightings` times dropped);
    /// the builder can take more scans afterwards.
    fn finish(&self) -> LineMap {
        LineMap {
            map: self.builder.clone().finish(),
        }
    }

    /// Walls so far, before the merging of `finish`.
    fn __len__(&self) -> usize {
        self.builder.num_walls()
    }
}

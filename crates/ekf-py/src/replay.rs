//! `replay`: a ROS 2 bag through the filter with `ekf replay`'s own code, returning the
//! estimated trajectory as numpy arrays and the summary `ekf replay --json` prints.

use crate::arrays::{new_array, row_major3};
use crate::errors::{file_error, path_error};
use crate::params::{load_config, to_python};
use ekf_ros::replay::{replay as replay_log, Mode, ReplayOptions};
use ekf_ros::trajectory::Trajectory;
use numpy::{Ix1, Ix3, PyArray1, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// The result of `replay`: the estimate at every motion step and scan (as the TUM file of
/// `ekf replay --tum` has it), the log's reference poses, and the JSON summary.
#[pyclass(module = "ekf_loc", frozen, get_all)]
pub struct ReplayResult {
    /// (N,) log times of the estimates (s).
    pub t: Py<PyArray1<f64>>,
    /// (N,) the same log times in integer nanoseconds, exactly.
    pub t_ns: Py<PyArray1<u64>>,
    /// (N,) estimated x (m, map frame).
    pub x: Py<PyArray1<f64>>,
    /// (N,) estimated y (m).
    pub y: Py<PyArray1<f64>>,
    /// (N,) estimated heading (rad, wrapped to (-pi, pi]).
    pub theta: Py<PyArray1<f64>>,
    /// (N, 3, 3) covariance of `(x, y, theta)`.
    pub covariance: Py<PyArray3<f64>>,
    /// (M,) log times of the reference poses (s).
    pub reference_t: Py<PyArray1<f64>>,
    /// (M,) reference x (m).
    pub reference_x: Py<PyArray1<f64>>,
    /// (M,) reference y (m).
    pub reference_y: Py<PyArray1<f64>>,
    /// (M,) reference heading (rad).
    pub reference_theta: Py<PyArray1<f64>>,
    /// The summary dict, exactly what `ekf replay --json` prints.
    pub summary: Py<PyAny>,
    /// The map at the end: the given one, the first scan's, or with `grow_map` the grown
    /// map.
    pub map: Py<crate::map::LineMap>,
}

/// `mode` by its command-line name.
pub(crate) fn parse_mode(mode: &str) -> PyResult<Mode> {
    Mode::ALL
        .into_iter()
        .find(|m| m.name() == mode)
        .ok_or_else(|| {
            let names: Vec<&str> = Mode::ALL.iter().map(|m| m.name()).collect();
            PyValueError::new_err(format!(
                "mode: expected one of {}, got {mode:?}",
                names.join(", ")
            ))
        })
}

/// Replays the ROS 2 bag at `path` through the filter exactly as `ekf replay` does (same
/// code), writing no files. `config`: an `ekf` TOML config file, a dict of its groups, or
/// None for the defaults. `mode`: `odometry`, `compass`, `laser` or `laser+compass`.
/// `map`: a JSON line map; None builds the map from the first scan (the paper's §III).
/// `init_from_truth`: start at the log's first reference pose. `global_localization`: no
/// initial pose; the map is searched from the first scans (as `ekf replay --global`).
/// `grow_map`: keep adding walls to the first-scan map as the robot explores (as `ekf
/// replay --grow-map`); the result's map is then the grown map.
///
/// Raises `OSError` if a file cannot be read, `ValueError` for an unusable log, config or
/// map (the CLI's messages), also when the log breaks off part-way.
#[pyfunction]
#[pyo3(signature = (path, config = None, mode = "laser+compass", map = None, init_from_truth = false, global_localization = false, grow_map = false))]
// One argument per Python keyword argument, as the CLI has one flag each.
#[allow(clippy::too_many_arguments)]
pub fn replay(
    py: Python<'_>,
    path: PathBuf,
    config: Option<&Bound<'_, PyAny>>,
    mode: &str,
    map: Option<PathBuf>,
    init_from_truth: bool,
    global_localization: bool,
    grow_map: bool,
) -> PyResult<ReplayResult> {
    let config = load_config(config)?;
    let mode = parse_mode(mode)?;
    if let Some(m) = &map {
        // The CLI reports an unreadable map as "path: reason"; the same, as an OSError.
        std::fs::metadata(m).map_err(|e| path_error(m, &e))?;
    }
    let options = ReplayOptions {
        mode,
        map,
        init_from_truth,
        out_mcap: None,
        tum: None,
        keep_trajectories: true,
        global: global_localization,
        grow_map,
    };
    let outcome = py
        .detach(|| replay_log(&path, &config, &options, &mut |_, _| {}))
        .map_err(|e| file_error(&e))?;
    if let Some(failure) = outcome.failure {
        return Err(file_error(&failure));
    }
    let estimate = &outcome.trajectory;
    let n = estimate.len();
    let covariance = outcome.covariances.iter().flat_map(row_major3).collect();
    let column = |t: &Trajectory, f: fn(&ekf_core::Pose2<f64>) -> f64| {
        let v: Vec<f64> = t.iter().map(|s| f(&s.pose)).collect();
        let len = v.len();
        new_array(py, v, Ix1(len)).map(Bound::unbind)
    };
    let seconds = |t: &Trajectory| {
        let v: Vec<f64> = t.iter().map(|s| s.t_ns as f64 * 1e-9).collect();
        let len = v.len();
        new_array(py, v, Ix1(len)).map(Bound::unbind)
    };
    let reference = &outcome.reference;
    Ok(ReplayResult {
        t: seconds(estimate)?,
        t_ns: PyArray1::from_iter(py, estimate.iter().map(|s| s.t_ns)).unbind(),
        x: column(estimate, |p| p.x)?,
        y: column(estimate, |p| p.y)?,
        theta: column(estimate, |p| p.theta)?,
        covariance: new_array(py, covariance, Ix3(n, 3, 3))?.unbind(),
        reference_t: seconds(reference)?,
        reference_x: column(reference, |p| p.x)?,
        reference_y: column(reference, |p| p.y)?,
        reference_theta: column(reference, |p| p.theta)?,
        summary: to_python(py, &outcome.summary)?.unbind(),
        map: Py::new(py, crate::map::LineMap { map: outcome.map })?,
    })
}

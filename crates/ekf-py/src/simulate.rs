//! `simulate`: the simulator of `ekf simulate` (the paper's robot in a room, exact ground
//! truth), returning the run as numpy arrays and optionally writing its ROS 2 bag.

use crate::arrays::new_array;
use crate::errors::{file_error, path_error};
use crate::params::to_python;
use ekf_ros::trajectory::Trajectory;
use ekf_sim::simulate::{load_scenario, run_simulation, SimulateOptions, Steering};
use numpy::{Ix1, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// The result of `simulate`: the true pose at every control step (0.1 s), the in-loop
/// estimate and its NEES when the robot steered by an estimator, the distance of the
/// true position from the commanded path, and the run's counts.
#[pyclass(module = "ekf_loc", frozen, get_all)]
pub struct SimulationResult {
    /// (N,) time of each step since the start (s).
    pub t: Py<PyArray1<f64>>,
    /// (N,) true x (m, the room's frame).
    pub x: Py<PyArray1<f64>>,
    /// (N,) true y (m).
    pub y: Py<PyArray1<f64>>,
    /// (N,) true heading (rad, wrapped to (-pi, pi]).
    pub theta: Py<PyArray1<f64>>,
    /// (N,) the in-loop estimate's x (m); empty when the robot steered by the truth.
    pub estimate_x: Py<PyArray1<f64>>,
    /// (N,) the estimate's y (m); empty without an estimator.
    pub estimate_y: Py<PyArray1<f64>>,
    /// (N,) the estimate's heading (rad); empty without an estimator.
    pub estimate_theta: Py<PyArray1<f64>>,
    /// (N,) the estimate's NEES against the truth (3 dof); empty without an estimator.
    pub nees: Py<PyArray1<f64>>,
    /// (N,) the NEES of its position alone, with P's position block (2 dof).
    pub nees_position: Py<PyArray1<f64>>,
    /// (N,) the NEES of its heading alone (1 dof).
    pub nees_heading: Py<PyArray1<f64>>,
    /// (N,) distance of the true position from the commanded path (m).
    pub path_deviation: Py<PyArray1<f64>>,
    /// The summary dict, exactly what `ekf simulate --json` prints.
    pub summary: Py<PyAny>,
}

fn steering(name: &str) -> PyResult<Steering> {
    match name {
        "truth" => Ok(Steering::Truth),
        "ekf" => Ok(Steering::Ekf),
        "odometry" => Ok(Steering::Odometry),
        other => Err(PyValueError::new_err(format!(
            "steer_by: expected one of truth, ekf, odometry, got {other:?}"
        ))),
    }
}

/// Simulates the paper's robot as `ekf simulate` does (same code). `scenario`: a
/// built-in name (`paper`, `triangle`, `walls`, `l-room`, `corridor`) or a JSON line map
/// whose room the robot drives round 1 m inside. `out`: also write the ROS 2 bag (MCAP)
/// there. `seed`: the same seed gives the same run (and the same bytes). `duration`:
/// simulated seconds (default: the scenario's 120 s). `steer_by`: `truth`, `ekf` (the
/// laser + compass filter in the loop) or `odometry`. `resolution`: laser resolution in
/// degrees (0.25, 0.5, 1). `slips_per_minute`, `compass_bias_deg`, `compass_outliers`:
/// as the command's options.
///
/// Raises `ValueError` for an unknown scenario or an option out of range, `OSError` if
/// the map cannot be read or the bag not written (the command's messages).
#[pyfunction]
#[pyo3(signature = (
    scenario,
    out = None,
    seed = 1,
    duration = None,
    steer_by = "truth",
    resolution = None,
    slips_per_minute = None,
    compass_bias_deg = None,
    compass_outliers = None,
))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    scenario: &str,
    out: Option<PathBuf>,
    seed: u64,
    duration: Option<f64>,
    steer_by: &str,
    resolution: Option<f64>,
    slips_per_minute: Option<f64>,
    compass_bias_deg: Option<f64>,
    compass_outliers: Option<f64>,
) -> PyResult<SimulationResult> {
    if scenario.ends_with(".json") {
        // As `replay` does for maps: an unreadable file is an OSError naming it.
        let path = std::path::Path::new(scenario);
        std::fs::metadata(path).map_err(|e| path_error(path, &e))?;
    }
    let options = SimulateOptions {
        seed,
        duration_s: duration,
        steering: steering(steer_by)?,
        resolution_deg: resolution,
        slips_per_minute,
        compass_bias_deg,
        compass_outliers,
    };
    let (run, summary) = py
        .detach(|| {
            let s = load_scenario(scenario, &options)?;
            run_simulation(&s, &options, out.as_deref())
        })
        .map_err(|e| file_error(&e))?;
    let array = |v: Vec<f64>| {
        let n = v.len();
        new_array(py, v, Ix1(n)).map(Bound::unbind)
    };
    let column = |t: &Trajectory, f: fn(&ekf_core::Pose2<f64>) -> f64| {
        array(t.iter().map(|s| f(&s.pose)).collect())
    };
    Ok(SimulationResult {
        t: array(run.truth.iter().map(|s| s.t_ns as f64 * 1e-9).collect())?,
        x: column(&run.truth, |p| p.x)?,
        y: column(&run.truth, |p| p.y)?,
        theta: column(&run.truth, |p| p.theta)?,
        estimate_x: column(&run.estimate, |p| p.x)?,
        estimate_y: column(&run.estimate, |p| p.y)?,
        estimate_theta: column(&run.estimate, |p| p.theta)?,
        nees: array(run.nees.iter().map(|n| n.pose).collect())?,
        nees_position: array(run.nees.iter().map(|n| n.position).collect())?,
        nees_heading: array(run.nees.iter().map(|n| n.heading).collect())?,
        path_deviation: array(run.path_deviation)?,
        summary: to_python(py, &summary)?.unbind(),
    })
}

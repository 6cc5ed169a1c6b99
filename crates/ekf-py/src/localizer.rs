//! The `Localizer` facade: prediction, compass, and whole scans (extract → match →
//! sequential update) in one object, as embedders use `lrf_lines::Localizer`.

use crate::arrays::{matrix3, matrix3_array, pose3};
use crate::errors::value_error;
use crate::lines::Lines;
use crate::map::LineMap;
use crate::params::from_dict;
use ekf_core::{Motion, WheelSpeeds};
use lrf_lines::{LaserScan, LocalizerConfig};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What `Localizer.update_compass` did with a heading.
#[pyclass(module = "ekf_loc", frozen, get_all)]
#[derive(Debug, Clone, Copy)]
pub struct CompassUpdate {
    /// True if fused (through the gate, or as the recovery from a gate lock-out).
    pub accepted: bool,
    /// NIS of the heading at the predicted state (chi-square, 1 dof).
    pub nis: f64,
    /// Consecutive headings up to this one that failed the gate, each agreeing with the
    /// one before once odometry's turn is taken out; 0 if this one passed.
    pub rejected_in_a_row: u32,
    /// True if it failed the gate but was fused because `rejected_in_a_row` reached the
    /// config's `compass.recover_after`.
    pub recovered: bool,
    /// True if `rejected_in_a_row` reached `recover_after` but the laser refused the
    /// recovery: the last scan's lines fit the filter's heading better (a biased compass).
    pub refused_by_laser: bool,
    /// True if it was not fused because the compass stood still while the robot turned
    /// (a stuck compass).
    pub not_following: bool,
}

#[pymethods]
impl CompassUpdate {
    fn __repr__(&self) -> String {
        let py_bool = |b: bool| if b { "True" } else { "False" };
        format!(
            "CompassUpdate(accepted={}, nis={}, rejected_in_a_row={}, recovered={}, \
             refused_by_laser={}, not_following={})",
            py_bool(self.accepted),
            self.nis,
            self.rejected_in_a_row,
            py_bool(self.recovered),
            py_bool(self.refused_by_laser),
            py_bool(self.not_following)
        )
    }
}

impl From<lrf_lines::CompassUpdate> for CompassUpdate {
    fn from(u: lrf_lines::CompassUpdate) -> Self {
        Self {
            accepted: u.outcome.accepted,
            nis: u.outcome.nis,
            rejected_in_a_row: u.rejected_in_a_row,
            recovered: u.recovered,
            refused_by_laser: u.refused_by_laser,
            not_following: u.not_following,
        }
    }
}

/// One localization step for one robot: the EKF, a line map, line extraction and matching.
#[pyclass(module = "ekf_loc")]
pub struct Localizer {
    inner: lrf_lines::Localizer,
}

#[pymethods]
impl Localizer {
    /// A localizer at `pose` `(x, y, theta)` with 3×3 `covariance`. With `line_map` scans
    /// are matched against it; without one the first scan becomes the map (the paper's
    /// §III). `config` is a dict of the `[localizer]` groups of `ekf config` (`robot`,
    /// `wheel_noise`, `odometry_noise`, `laser_mount`, `extraction`, `matching`, `compass`);
    /// missing groups and keys take their defaults.
    #[new]
    #[pyo3(signature = (pose, covariance, line_map = None, config = None))]
    fn new(
        pose: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
        line_map: Option<&LineMap>,
        config: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let pose = pose3(pose, "pose")?;
        let p = matrix3(covariance, "covariance")?;
        let config: LocalizerConfig = from_dict(config, "config")?;
        let inner = match line_map {
            Some(m) => lrf_lines::Localizer::new(config, pose, p, m.map.clone()),
            None => lrf_lines::Localizer::with_first_scan_map(config, pose, p),
        }
        .map_err(value_error)?;
        Ok(Self { inner })
    }

    /// Prediction from wheel speeds `left`, `right` (rad/s) held for `dt` (s).
    fn predict_wheels(&mut self, left: f64, right: f64, dt: f64) -> PyResult<()> {
        let speeds = WheelSpeeds::new(left, right, dt).map_err(value_error)?;
        self.inner.predict_wheels(&speeds).map_err(value_error)
    }

    /// Prediction from an odometry delta: distance `ds` (m) along the mid-angle heading
    /// and heading change `dtheta` (rad).
    fn predict_odometry(&mut self, ds: f64, dtheta: f64) -> PyResult<()> {
        let motion = Motion::new(ds, dtheta).map_err(value_error)?;
        self.inner.predict_odometry(&motion).map_err(value_error)
    }

    /// Fuses a compass heading (rad, map frame) with the configured variance, or
    /// `variance` (rad²), if it passes the 1-dof gate, or if it ends a gate lock-out
    /// (`compass.recover_after` consistent rejections in a row).
    #[pyo3(signature = (heading, variance = None))]
    fn update_compass(&mut self, heading: f64, variance: Option<f64>) -> PyResult<CompassUpdate> {
        let variance = variance.unwrap_or(self.inner.config().compass.variance);
        self.inner
            .update_compass_with_variance(heading, variance)
            .map(Into::into)
            .map_err(value_error)
    }

    /// One laser scan: extract its lines, match them to the map at the predicted state,
    /// fuse the matches one at a time in order of increasing NIS. Arguments as for
    /// `extract_lines`. Returns counts: `extracted`, `matched`, `rejected`, `fused`,
    /// `refused` (matched but gated out after earlier lines), `map_built`.
    #[pyo3(signature = (ranges, angle_min, angle_increment, range_min = 0.0, range_max = f64::INFINITY))]
    fn update_scan<'py>(
        &mut self,
        py: Python<'py>,
        ranges: &Bound<'py, PyAny>,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let ranges = crate::lines::ranges_f32(ranges)?;
        let scan = LaserScan {
            angle_min,
            angle_increment,
            range_min,
            range_max: crate::lines::finite_range_max(range_max),
            ranges: &ranges,
        };
        let report = self.inner.update_scan(&scan).map_err(value_error)?;
        let d = PyDict::new(py);
        d.set_item("extracted", report.extracted)?;
        d.set_item("matched", report.matched)?;
        d.set_item("rejected", report.rejected)?;
        d.set_item("fused", report.fused)?;
        d.set_item("refused", report.refused)?;
        d.set_item("merged", report.merged)?;
        d.set_item("refitted", report.refitted)?;
        d.set_item("map_built", report.map_built)?;
        Ok(d)
    }

    /// The state `[x, y, theta]` (m, m, rad).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.ekf().state().as_slice())
    }

    /// The 3×3 covariance of `(x, y, theta)`.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix3_array(py, self.inner.covariance())
    }

    /// The laser's pose in the world, pose ⊕ laser mount `(x, y, theta)`.
    #[getter]
    fn sensor_pose(&self) -> (f64, f64, f64) {
        let s = self.inner.sensor_pose();
        (s.x, s.y, s.theta)
    }

    /// The map (empty until the first scan when built from it).
    #[getter]
    fn line_map(&self) -> LineMap {
        LineMap {
            map: self.inner.map().clone(),
        }
    }

    /// The lines extracted from the last scan (sensor frame).
    #[getter]
    fn last_lines(&self) -> Lines {
        Lines::from_vec(self.inner.last_lines().to_vec())
    }

    /// What the last scan's update did with each match, in fusion order: tuples
    /// `(observed index, map index, nis, accepted)`.
    #[getter]
    fn last_fusions(&self) -> Vec<(usize, usize, f64, bool)> {
        self.inner
            .last_fusions()
            .iter()
            .map(|f| (f.observed, f.map, f.nis, f.accepted))
            .collect()
    }
}

//! The Python `Filter` class: the EKF one call at a time, plus `run` for a whole sequence
//! in one native call (see `batch`).

use crate::arrays::{
    check_finite, check_len, check_shape, matrix2, matrix3, matrix3_array, new_array, pose3,
    real_array,
};
use crate::batch;
use crate::core::Core;
use crate::errors::value_error;
use crate::params::from_dict;
use lrf_lines::{LineMap, Localizer, LocalizerConfig};
use numpy::ndarray::s;
use numpy::{Ix1, Ix2, Ix3, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The outcome of one update: whether the measurement passed its chi-square gate and was
/// fused, and its normalised innovation squared (NIS).
#[pyclass(module = "ekf_loc", frozen, get_all)]
#[derive(Debug, Clone, Copy)]
pub struct UpdateOutcome {
    /// True if fused; False if the gate refused it (the state is then unchanged).
    pub accepted: bool,
    /// NIS `yᵀ S⁻¹ y`, chi-square distributed with the measurement's dimension as dof.
    pub nis: f64,
}

#[pymethods]
impl UpdateOutcome {
    fn __repr__(&self) -> String {
        format!(
            "UpdateOutcome(accepted={}, nis={})",
            if self.accepted { "True" } else { "False" },
            self.nis
        )
    }
}

impl From<ekf_core::UpdateOutcome<f64>> for UpdateOutcome {
    fn from(o: ekf_core::UpdateOutcome<f64>) -> Self {
        Self {
            accepted: o.accepted,
            nis: o.nis,
        }
    }
}

/// The outcomes of a sequence of line updates, one entry per line in the order fused.
#[pyclass(module = "ekf_loc", frozen, get_all)]
pub struct LineUpdates {
    /// NIS of each line at the state it was fused into, shape (N,).
    pub nis: Py<PyArray1<f64>>,
    /// Whether each line passed the gate and was fused, shape (N,).
    pub accepted: Py<PyArray1<bool>>,
}

#[pymethods]
impl LineUpdates {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "LineUpdates(nis={}, accepted={})",
            self.nis.bind(py).repr()?,
            self.accepted.bind(py).repr()?
        ))
    }
}

/// The extended Kalman filter of a differential-drive robot (Hoang et al., with the
/// paper's errata fixed): prediction from wheel speeds (eqs. 1-9) or odometry deltas,
/// compass and laser-line updates in Joseph form with chi-square gates.
///
/// `pose` (x, y, theta) defaults to the origin, `covariance` (3x3, symmetric positive
/// definite) to 1e-4 I. `config` is a dict of the Localizer's config groups; the filter
/// uses `robot` (wheel_radius, track in m; default 0.05, 0.60), `wheel_noise` (delta,
/// floor in (rad/s)^2; default 0.01, 1.296e-3), `odometry_noise`, `laser_mount` (x, y,
/// theta on the robot), `compass` (variance in rad^2, default (2 deg)^2;
/// gate_probability, default 0.999) and `matching.gate_probability` (line gate, 2 dof).
/// `compass.recover_after` is the Localizer's; the bare filter has no lock-out recovery.
/// `gating=False` fuses every measurement.
#[pyclass(module = "ekf_loc")]
pub struct Filter {
    core: Core,
}

#[pymethods]
impl Filter {
    #[new]
    #[pyo3(signature = (pose = None, covariance = None, config = None, *, gating = true))]
    fn new(
        pose: Option<&Bound<'_, PyAny>>,
        covariance: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
        gating: bool,
    ) -> PyResult<Self> {
        let pose = pose.map(|p| pose3(p, "pose")).transpose()?;
        let pose = pose.unwrap_or_else(ekf_core::Pose2::identity);
        let p = match covariance {
            Some(c) => matrix3(c, "covariance")?,
            None => nalgebra::Matrix3::from_diagonal_element(1e-4),
        };
        let config: LocalizerConfig = from_dict(config, "config")?;
        // The Localizer validates every group of the config, naming group and field.
        Localizer::new(config.clone(), pose, p, LineMap::default()).map_err(value_error)?;
        let core = Core::new(&config, pose, p, gating).map_err(value_error)?;
        Ok(Self { core })
    }

    /// The state `[x, y, theta]` (m, m, rad; theta wrapped to (-pi, pi]).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.core.ekf.state().as_slice())
    }

    /// The 3×3 covariance of `(x, y, theta)`.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix3_array(py, self.core.ekf.covariance())
    }

    /// The laser's mounting pose on the robot `(x, y, theta)`.
    #[getter]
    fn laser_mount(&self) -> (f64, f64, f64) {
        let m = self.core.mount;
        (m.x, m.y, m.theta)
    }

    /// Counts of predictions and of accepted and rejected updates so far.
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.core.counts;
        let d = PyDict::new(py);
        d.set_item("predictions", c.predictions)?;
        d.set_item("compass_accepted", c.compass_accepted)?;
        d.set_item("compass_rejected", c.compass_rejected)?;
        d.set_item("lines_accepted", c.lines_accepted)?;
        d.set_item("lines_rejected", c.lines_rejected)?;
        Ok(d)
    }

    /// Replaces the state `pose` (x, y, theta) and the 3x3 `covariance`.
    fn reset(&mut self, pose: &Bound<'_, PyAny>, covariance: &Bound<'_, PyAny>) -> PyResult<()> {
        let pose = pose3(pose, "pose")?;
        let p = matrix3(covariance, "covariance")?;
        self.core.ekf = ekf_core::Ekf::new(pose, p).map_err(value_error)?;
        Ok(())
    }

    /// Prediction from wheel speeds `left`, `right` (rad/s, positive forward) held for
    /// `dt` seconds (> 0): x- = f(x, u), P- = A P A^T + W Q W^T.
    fn predict_wheels(&mut self, left: f64, right: f64, dt: f64) -> PyResult<()> {
        self.core
            .predict_wheels(left, right, dt)
            .map_err(value_error)
    }

    /// Prediction from an odometry delta: `ds` (m) along the mid-angle heading and
    /// `dtheta` (rad), with the odometry noise model.
    fn predict_odometry(&mut self, ds: f64, dtheta: f64) -> PyResult<()> {
        self.core.predict_odometry(ds, dtheta).map_err(value_error)
    }

    /// Fuses a compass heading (rad, map frame) with `variance` (rad^2; default the
    /// config's) if it passes the 1-dof gate; the innovation is wrapped.
    #[pyo3(signature = (heading, variance = None))]
    fn update_compass(&mut self, heading: f64, variance: Option<f64>) -> PyResult<UpdateOutcome> {
        let variance = variance.unwrap_or(self.core.compass_variance);
        self.core
            .update_compass(heading, variance)
            .map(UpdateOutcome::from)
            .map_err(value_error)
    }

    /// Fuses N matched laser lines one at a time, in order: `observed` (N, 2) as (r, psi)
    /// in the laser frame (m, rad), `covariances` (N, 2, 2) of (r, psi), `map_lines`
    /// (N, 2) as (rho, beta) in the world frame. Each line passes the 2-dof gate or is
    /// refused. All or nothing: on an error the filter is left as it was.
    fn update_lines(
        &mut self,
        py: Python<'_>,
        observed: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
        map_lines: &Bound<'_, PyAny>,
    ) -> PyResult<LineUpdates> {
        let observed = real_array::<Ix2>(observed, "observed")?;
        let covariances = real_array::<Ix3>(covariances, "covariances")?;
        let map_lines = real_array::<Ix2>(map_lines, "map_lines")?;
        let (z, r, m) = (
            observed.as_array(),
            covariances.as_array(),
            map_lines.as_array(),
        );
        check_shape(
            "observed",
            z.shape(),
            &[None, Some(2)],
            "(N, 2) as (r, psi)",
        )?;
        let n = z.nrows();
        check_shape(
            "covariances",
            r.shape(),
            &[None, Some(2), Some(2)],
            "(N, 2, 2)",
        )?;
        check_len("covariances", r.shape()[0], n, "observed")?;
        check_shape(
            "map_lines",
            m.shape(),
            &[None, Some(2)],
            "(N, 2) as (rho, beta)",
        )?;
        check_len("map_lines", m.nrows(), n, "observed")?;
        check_finite("observed", &z)?;
        check_finite("covariances", &r)?;
        check_finite("map_lines", &m)?;
        let before = self.core.clone();
        let mut nis = Vec::with_capacity(n);
        let mut accepted = Vec::with_capacity(n);
        for i in 0..n {
            let outcome = self.core.update_line(
                (z[[i, 0]], z[[i, 1]]),
                matrix2(&r.slice(s![i, .., ..])),
                (m[[i, 0]], m[[i, 1]]),
            );
            match outcome {
                Ok(o) => {
                    nis.push(o.nis);
                    accepted.push(o.accepted);
                }
                Err(e) => {
                    self.core = before;
                    return Err(value_error(format!("line {i}: {e}")));
                }
            }
        }
        Ok(LineUpdates {
            nis: new_array(py, nis, Ix1(n))?.unbind(),
            accepted: PyArray1::from_vec(py, accepted).unbind(),
        })
    }

    /// Runs N steps in one native call (the GIL released): each step predicts from
    /// `wheels` (N, 3) as (left, right, dt) or `odometry` (N, 2) as (ds, dtheta), then
    /// fuses `compass` (N,) headings where `compass_mask` (N,) is True (every step without
    /// a mask), then the first `line_counts[k]` (default K) lines of `line_observed`
    /// (N, K, 2), `line_covariances` (N, K, 2, 2), `line_map` (N, K, 2). Unused entries
    /// are never read. Gives exactly the results of the per-call methods. All or nothing:
    /// an error names the step and leaves the filter as it was.
    #[pyo3(signature = (*, wheels = None, odometry = None, compass = None, compass_mask = None,
                        line_observed = None, line_covariances = None, line_map = None,
                        line_counts = None))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        wheels: Option<&Bound<'py, PyAny>>,
        odometry: Option<&Bound<'py, PyAny>>,
        compass: Option<&Bound<'py, PyAny>>,
        compass_mask: Option<&Bound<'py, PyAny>>,
        line_observed: Option<&Bound<'py, PyAny>>,
        line_covariances: Option<&Bound<'py, PyAny>>,
        line_map: Option<&Bound<'py, PyAny>>,
        line_counts: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<batch::BatchResult> {
        let inputs = batch::BatchArgs {
            wheels,
            odometry,
            compass,
            compass_mask,
            line_observed,
            line_covariances,
            line_map,
            line_counts,
        };
        batch::run(py, &mut self.core, &inputs)
    }

    fn __repr__(&self) -> String {
        let x = self.core.ekf.pose();
        format!("Filter(pose=({}, {}, {}))", x.x, x.y, x.theta)
    }
}

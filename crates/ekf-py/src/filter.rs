//! The Python `Filter` class: the EKF one call at a time, plus `run` for a whole sequence
//! in one native call (see `batch`).

use crate::arrays::{
    check_finite, check_len, check_shape, matrix2, matrix3, matrix3_array, new_array, pose3,
    real_array,
};
use crate::batch;
use crate::core::{Core, Counts, Snapshot};
use crate::errors::value_error;
use crate::params::from_dict;
use ekf_core::{ConsideredUpdate, DiffDrive, Ekf, OdometryNoise, Pose2, WheelNoise};
use lrf_lines::{LineMap, Localizer, LocalizerConfig};
use nalgebra::Matrix3;
use numpy::ndarray::s;
use numpy::{Ix1, Ix2, Ix3, PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The outcome of one update: whether the measurement passed its chi-square gate and was
/// fused, its normalised innovation squared (NIS), and, named as in FilterPy's
/// `ExtendedKalmanFilter`, the innovation `y`, its covariance `S` and the gain `K`.
///
/// `y = z - h(x)` (wrapped) and `S = H P H^T + R` are taken at the state before the update,
/// whether or not the gate let it through. `K = P H^T S^-1` is the gain that was applied:
/// zeros if the gate refused the measurement, so that `x+ = x- + K y` holds either way (up
/// to the wrapping of theta).
#[pyclass(module = "ekf_loc", frozen)]
#[derive(Debug, Clone)]
pub struct UpdateOutcome {
    /// True if fused; False if the gate refused it (the state is then unchanged).
    #[pyo3(get)]
    pub accepted: bool,
    /// NIS `yᵀ S⁻¹ y`, chi-square distributed with the measurement's dimension as dof.
    #[pyo3(get)]
    pub nis: f64,
    /// The innovation `y` (a compass heading: 1 entry).
    y: f64,
    /// Its covariance `S` (1×1).
    s: f64,
    /// The gain `K` applied (3×1), zero if refused.
    k: [f64; 3],
}

#[pymethods]
impl UpdateOutcome {
    /// (1,) innovation y = z - h(x) (rad, wrapped), at the state before the update.
    #[getter]
    fn y<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &[self.y])
    }

    /// (1, 1) innovation covariance S = H P H^T + R (rad^2), at the state before the update.
    #[getter(S)]
    fn s<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        new_array(py, vec![self.s], Ix2(1, 1))
    }

    /// (3, 1) gain K = P H^T S^-1 that was applied; zeros if the gate refused the update.
    #[getter(K)]
    fn k<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        new_array(py, self.k.to_vec(), Ix2(3, 1))
    }

    fn __repr__(&self) -> String {
        format!(
            "UpdateOutcome(accepted={}, nis={})",
            if self.accepted { "True" } else { "False" },
            self.nis
        )
    }
}

impl From<ConsideredUpdate<f64, 1>> for UpdateOutcome {
    fn from(u: ConsideredUpdate<f64, 1>) -> Self {
        Self {
            accepted: u.outcome.accepted,
            nis: u.outcome.nis,
            y: u.innovation.y[0],
            s: u.innovation.s[(0, 0)],
            k: [u.gain[0], u.gain[1], u.gain[2]],
        }
    }
}

/// The outcomes of a sequence of line updates, one entry per line in the order fused.
///
/// The lines are fused one after the other, each at the state the lines before it left
/// (for independent line noise this equals the paper's stacked update, eq. 16, up to
/// relinearisation). So `y`, `S` and `K` are per line, as `nis` is: line i's own
/// innovation, its covariance and its gain at the state it was fused into, exactly what
/// FilterPy's `update` leaves in `y`, `S` and `K` when called once per line. They are not
/// the blocks of one stacked 2N-row update's: that gain comes from the covariance before
/// all the lines, line i's from the covariance the lines before it left. A refused
/// line has `K` zeros (nothing applied), and `y`, `S` at the state it was offered to.
#[pyclass(module = "ekf_loc", frozen)]
pub struct LineUpdates {
    /// NIS of each line at the state it was fused into, shape (N,).
    #[pyo3(get)]
    pub nis: Py<PyArray1<f64>>,
    /// Whether each line passed the gate and was fused, shape (N,).
    #[pyo3(get)]
    pub accepted: Py<PyArray1<bool>>,
    /// Per line, row-major: `y` (2 entries), then `S` (4), then `K` (6). One vector for
    /// all three keeps the per-call cost at one allocation.
    reports: Vec<[f64; 12]>,
}

impl LineUpdates {
    /// Entries `range` of every line's report, in order.
    fn column(&self, range: std::ops::Range<usize>) -> Vec<f64> {
        self.reports
            .iter()
            .flat_map(|r| r[range.clone()].iter().copied())
            .collect()
    }
}

#[pymethods]
impl LineUpdates {
    /// (N, 2) innovation y = z - h(x) of each line as (r, psi) (m, rad; psi wrapped), at
    /// the state it was fused into.
    #[getter]
    fn y<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        new_array(py, self.column(0..2), Ix2(self.reports.len(), 2))
    }

    /// (N, 2, 2) innovation covariance S = H P H^T + R of each line, at the state it was
    /// fused into.
    #[getter(S)]
    fn s<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        new_array(py, self.column(2..6), Ix3(self.reports.len(), 2, 2))
    }

    /// (N, 3, 2) gain K = P H^T S^-1 applied for each line; zeros for a refused line.
    #[getter(K)]
    fn k<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        new_array(py, self.column(6..12), Ix3(self.reports.len(), 3, 2))
    }

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

    /// The state `[x, y, theta]` (m, m, rad; theta wrapped to (-pi, pi]), as a new array
    /// (changing it does not change the filter). Assigning three finite numbers replaces
    /// the state (theta wrapped) and keeps the covariance, as FilterPy's `x` does.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.core.ekf.state().as_slice())
    }

    /// Replaces the state; see the getter.
    #[setter]
    fn set_state(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let pose = pose3(value, "state")?;
        self.core.ekf = Ekf::new(pose, *self.core.ekf.covariance()).map_err(value_error)?;
        Ok(())
    }

    /// The 3×3 covariance of `(x, y, theta)`, as a new array. Assigning a 3×3 matrix
    /// replaces it and keeps the state, as FilterPy's `P` does: it must be finite,
    /// symmetric to a relative tolerance of 1.5e-8 (it is then symmetrised, (P + P^T)/2)
    /// and positive definite.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix3_array(py, self.core.ekf.covariance())
    }

    /// Replaces the covariance; see the getter.
    #[setter]
    fn set_covariance(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = symmetric_covariance(value, "covariance")?;
        self.core.ekf = Ekf::new(self.core.ekf.pose(), p).map_err(|e| match e {
            ekf_core::Error::NotPositiveDefinite { .. } => not_positive_definite("covariance", &p),
            e => value_error(e),
        })?;
        Ok(())
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
    /// config's) if it passes the 1-dof gate; the innovation is wrapped. The outcome has
    /// the innovation `y`, `S` and the gain `K` applied (see `UpdateOutcome`).
    #[pyo3(signature = (heading, variance = None))]
    fn update_compass(&mut self, heading: f64, variance: Option<f64>) -> PyResult<UpdateOutcome> {
        let variance = variance.unwrap_or(self.core.compass_variance);
        self.core
            .update_compass::<ConsideredUpdate<f64, 1>>(heading, variance)
            .map(UpdateOutcome::from)
            .map_err(value_error)
    }

    /// Fuses N matched laser lines one at a time, in order: `observed` (N, 2) as (r, psi)
    /// in the laser frame (m, rad), `covariances` (N, 2, 2) of (r, psi), `map_lines`
    /// (N, 2) as (rho, beta) in the world frame. Each line passes the 2-dof gate or is
    /// refused. The result has each line's NIS, gate decision, innovation `y`, `S` and
    /// gain `K` (per line; see `LineUpdates`). All or nothing: on an error the filter is
    /// left as it was.
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
        let mut reports = Vec::with_capacity(n);
        for i in 0..n {
            let outcome: Result<ConsideredUpdate<f64, 2>, _> = self.core.update_line(
                (z[[i, 0]], z[[i, 1]]),
                matrix2(&r.slice(s![i, .., ..])),
                (m[[i, 0]], m[[i, 1]]),
            );
            match outcome {
                Ok(u) => {
                    nis.push(u.outcome.nis);
                    accepted.push(u.outcome.accepted);
                    let (y, s, k) = (&u.innovation.y, &u.innovation.s, &u.gain);
                    reports.push([
                        y[0],
                        y[1],
                        s[(0, 0)],
                        s[(0, 1)],
                        s[(1, 0)],
                        s[(1, 1)],
                        k[(0, 0)],
                        k[(0, 1)],
                        k[(1, 0)],
                        k[(1, 1)],
                        k[(2, 0)],
                        k[(2, 1)],
                    ]);
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
            reports,
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

    /// A copy of the filter (state, covariance, models, gates and counts). A `Filter` shares
    /// nothing mutable, so `copy.copy` is as independent as `copy.deepcopy`.
    fn __copy__(&self) -> Self {
        Self {
            core: self.core.clone(),
        }
    }

    /// A copy of the filter, as `__copy__`.
    fn __deepcopy__(&self, memo: &Bound<'_, PyAny>) -> Self {
        let _ = memo;
        self.__copy__()
    }

    /// Everything the filter holds as a dict of numbers (what pickle stores; version 1):
    /// `state` [x, y, theta], `covariance` 3 rows of 3, `robot` [wheel_radius, track],
    /// `wheel_noise` [delta, floor], `odometry_noise` [a1, b1, a2, b2, a3, a4, b3],
    /// `laser_mount` [x, y, theta], `compass_variance`, `compass_gate` and `line_gate` (NIS
    /// thresholds, None without gating), `counts` [predictions, compass_accepted,
    /// compass_rejected, lines_accepted, lines_rejected]. Floats are stored exactly.
    fn __getstate__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        snapshot_dict(py, &self.core.snapshot())
    }

    /// Replaces everything with a dict from `__getstate__`, validated as the constructor
    /// validates (ValueError otherwise; the filter is then left as it was).
    fn __setstate__(&mut self, state: &Bound<'_, PyAny>) -> PyResult<()> {
        let snapshot = snapshot_from(state)?;
        self.core =
            Core::from_snapshot(&snapshot).map_err(|e| value_error(format!("{STATE}: {e}")))?;
        Ok(())
    }

    /// For pickle: `(Filter, (), state)`, rebuilt with `Filter()` and `__setstate__`, so a
    /// pickled filter continues bit for bit as the original would.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyType>, Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let py = slf.py();
        let state = snapshot_dict(py, &slf.borrow().core.snapshot())?;
        Ok((slf.get_type(), PyTuple::empty(py), state))
    }

    fn __repr__(&self) -> String {
        let x = self.core.ekf.pose();
        format!("Filter(pose=({}, {}, {}))", x.x, x.y, x.theta)
    }
}

/// The version of the dict `Filter.__getstate__` returns.
const STATE_VERSION: u32 = 1;

/// How messages about a pickled state name it.
const STATE: &str = "Filter state";

/// A 3×3 covariance from an array-like: finite, symmetric to a relative tolerance of
/// √ε (the tolerance ekf-core's own check uses) and then symmetrised, `(P + Pᵀ)/2`.
/// Positive definiteness is left to the filter.
fn symmetric_covariance(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Matrix3<f64>> {
    let p = matrix3(obj, name)?;
    let tol = f64::EPSILON.sqrt() * p.amax();
    for i in 0..3 {
        for j in (i + 1)..3 {
            if (p[(i, j)] - p[(j, i)]).abs() > tol {
                return Err(PyValueError::new_err(format!(
                    "{name}: expected a symmetric matrix (to a relative tolerance of 1.5e-8), \
                     got {name}[{i}, {j}] = {} and {name}[{j}, {i}] = {}",
                    p[(i, j)],
                    p[(j, i)]
                )));
            }
        }
    }
    Ok((p + p.transpose()) * 0.5)
}

/// The `ValueError` for a symmetric `p` that is not positive definite, with its
/// eigenvalues.
fn not_positive_definite(name: &str, p: &Matrix3<f64>) -> PyErr {
    let mut eigenvalues: Vec<f64> = p.symmetric_eigenvalues().iter().copied().collect();
    eigenvalues.sort_by(f64::total_cmp);
    let text: Vec<String> = eigenvalues.iter().map(|&v| sci(v)).collect();
    PyValueError::new_err(format!(
        "{name}: expected a positive definite matrix, got eigenvalues {}",
        text.join(", ")
    ))
}

/// `v` in Python's `%.3e` form, e.g. `-1.000e-03`.
fn sci(v: f64) -> String {
    let text = format!("{v:.3e}");
    match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let exponent: i32 = exponent.parse().unwrap_or(0);
            let sign = if exponent < 0 { '-' } else { '+' };
            format!("{mantissa}e{sign}{:02}", exponent.unsigned_abs())
        }
        None => text,
    }
}

/// A [`Snapshot`] as the dict of `Filter.__getstate__`.
fn snapshot_dict<'py>(py: Python<'py>, s: &Snapshot) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let c = s.counts;
    let o = s.odometry_noise;
    d.set_item("version", STATE_VERSION)?;
    d.set_item("state", s.state)?;
    d.set_item("covariance", s.covariance)?;
    d.set_item("robot", [s.robot.wheel_radius, s.robot.track])?;
    d.set_item("wheel_noise", [s.wheel_noise.delta, s.wheel_noise.floor])?;
    d.set_item("odometry_noise", [o.a1, o.b1, o.a2, o.b2, o.a3, o.a4, o.b3])?;
    d.set_item("laser_mount", [s.mount.x, s.mount.y, s.mount.theta])?;
    d.set_item("compass_variance", s.compass_variance)?;
    d.set_item("compass_gate", s.compass_gate)?;
    d.set_item("line_gate", s.line_gate)?;
    let counts = [
        c.predictions,
        c.compass_accepted,
        c.compass_rejected,
        c.lines_accepted,
        c.lines_rejected,
    ];
    d.set_item("counts", counts)?;
    Ok(d)
}

/// The entry `key` of a pickled state, converted with `extract`; a missing key or a value
/// of the wrong form is a `ValueError` naming the key.
fn entry<T>(
    d: &Bound<'_, PyDict>,
    key: &str,
    expected: &str,
    extract: impl FnOnce(&Bound<'_, PyAny>) -> PyResult<T>,
) -> PyResult<T> {
    let value = d
        .get_item(key)?
        .ok_or_else(|| PyValueError::new_err(format!("{STATE}: missing \"{key}\"")))?;
    extract(&value)
        .map_err(|_| PyValueError::new_err(format!("{STATE}: \"{key}\": expected {expected}")))
}

/// A [`Snapshot`] from the dict of `Filter.__getstate__` (not yet validated).
fn snapshot_from(state: &Bound<'_, PyAny>) -> PyResult<Snapshot> {
    let d = state.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{STATE}: expected a dict from Filter.__getstate__, got {}",
            state
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        ))
    })?;
    let version: u32 = entry(d, "version", "an integer", |v| v.extract())?;
    if version != STATE_VERSION {
        return Err(PyValueError::new_err(format!(
            "{STATE}: version {version} is not supported (this ekf_loc reads version {STATE_VERSION})"
        )));
    }
    let floats3 = |v: &Bound<'_, PyAny>| v.extract::<[f64; 3]>();
    let [wheel_radius, track]: [f64; 2] = entry(d, "robot", "2 floats", |v| v.extract())?;
    let [delta, floor]: [f64; 2] = entry(d, "wheel_noise", "2 floats", |v| v.extract())?;
    let [a1, b1, a2, b2, a3, a4, b3]: [f64; 7] =
        entry(d, "odometry_noise", "7 floats", |v| v.extract())?;
    let [mx, my, mtheta] = entry(d, "laser_mount", "3 floats", floats3)?;
    let [predictions, compass_accepted, compass_rejected, lines_accepted, lines_rejected]: [u64;
        5] = entry(d, "counts", "5 integers >= 0", |v| v.extract())?;
    let gate = |key| entry(d, key, "a float or None", |v| v.extract::<Option<f64>>());
    Ok(Snapshot {
        state: entry(d, "state", "3 floats", floats3)?,
        covariance: entry(d, "covariance", "3 rows of 3 floats", |v| v.extract())?,
        robot: DiffDrive {
            wheel_radius,
            track,
        },
        wheel_noise: WheelNoise { delta, floor },
        odometry_noise: OdometryNoise {
            a1,
            b1,
            a2,
            b2,
            a3,
            a4,
            b3,
        },
        mount: Pose2 {
            x: mx,
            y: my,
            theta: mtheta,
        },
        compass_variance: entry(d, "compass_variance", "a float", |v| v.extract())?,
        compass_gate: gate("compass_gate")?,
        line_gate: gate("line_gate")?,
        counts: Counts {
            predictions,
            compass_accepted,
            compass_rejected,
            lines_accepted,
            lines_rejected,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::sci;

    #[test]
    fn sci_is_pythons_percent_3e() {
        for (v, want) in [
            (-1e-3, "-1.000e-03"),
            (0.0, "0.000e+00"),
            (3.0, "3.000e+00"),
            (2.5e-120, "2.500e-120"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(sci(v), want);
        }
    }
}

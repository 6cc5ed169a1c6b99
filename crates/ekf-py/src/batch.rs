//! `Filter.run`: a whole sequence of steps (predict, then compass, then lines) from numpy
//! arrays in one native call, with the GIL released while it runs. All or nothing: an
//! error at any step restores the filter as it was and names the step.

use crate::arrays::{check_len, check_shape, matrix2, new_array, real_array, row_major3};
use crate::core::Core;
use crate::errors::value_error;
use ekf_core::UpdateOutcome;
use numpy::ndarray::{s, ArrayView1, ArrayView2, ArrayView3, ArrayView4};
use numpy::{Ix1, Ix2, Ix3, Ix4, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The keyword arguments of `Filter.run`, as given.
pub struct BatchArgs<'a, 'py> {
    /// (N, 3): `[ω_L, ω_R, Δt]` per step.
    pub wheels: Option<&'a Bound<'py, PyAny>>,
    /// (N, 2): `[Δs, Δθ]` per step.
    pub odometry: Option<&'a Bound<'py, PyAny>>,
    /// (N,): a heading per step.
    pub compass: Option<&'a Bound<'py, PyAny>>,
    /// (N,) bool: which steps have a heading.
    pub compass_mask: Option<&'a Bound<'py, PyAny>>,
    /// (N, K, 2): up to K observed lines `(r, ψ)` per step.
    pub line_observed: Option<&'a Bound<'py, PyAny>>,
    /// (N, K, 2, 2): their covariances.
    pub line_covariances: Option<&'a Bound<'py, PyAny>>,
    /// (N, K, 2): the matched map lines `(ρ, β)`.
    pub line_map: Option<&'a Bound<'py, PyAny>>,
    /// (N,): how many of the K lines each step uses.
    pub line_counts: Option<&'a Bound<'py, PyAny>>,
}

/// What `Filter.run` returns: one row per step, after the step's last update.
#[pyclass(module = "ekf_loc", frozen, get_all)]
pub struct BatchResult {
    /// (N, 3) states `[x, y, theta]`.
    pub states: Py<PyArray2<f64>>,
    /// (N, 3, 3) covariances.
    pub covariances: Py<PyArray3<f64>>,
    /// (N,) compass NIS, NaN at steps without a heading.
    pub compass_nis: Py<PyArray1<f64>>,
    /// (N,) whether the step's heading was fused (False without one).
    pub compass_accepted: Py<PyArray1<bool>>,
    /// (N, K) line NIS, NaN for unused slots.
    pub line_nis: Py<PyArray2<f64>>,
    /// (N, K) whether each line was fused (False for unused slots).
    pub line_accepted: Py<PyArray2<bool>>,
}

/// The motion inputs: one kind per run.
enum Motion<'a> {
    Wheels(ArrayView2<'a, f64>),
    Odometry(ArrayView2<'a, f64>),
}

/// The line inputs with the number of lines used per step.
struct Lines<'a> {
    observed: ArrayView3<'a, f64>,
    covariances: ArrayView4<'a, f64>,
    map: ArrayView3<'a, f64>,
    counts: Vec<usize>,
}

/// Validated views of every input.
struct Inputs<'a> {
    motion: Motion<'a>,
    compass: Option<(ArrayView1<'a, f64>, Option<ArrayView1<'a, bool>>)>,
    lines: Option<Lines<'a>>,
}

/// Outputs filled step by step.
struct Outputs {
    states: Vec<f64>,
    covariances: Vec<f64>,
    compass_nis: Vec<f64>,
    compass_accepted: Vec<bool>,
    line_nis: Vec<f64>,
    line_accepted: Vec<bool>,
}

/// A failed step: its index, the line within it if any, and the filter's message.
struct StepError {
    step: usize,
    line: Option<usize>,
    error: ekf_core::Error,
}

/// Runs the batch on `core` (see the module documentation).
pub fn run(py: Python<'_>, core: &mut Core, args: &BatchArgs<'_, '_>) -> PyResult<BatchResult> {
    let arrays = Arrays::read(args)?;
    let inputs = arrays.inputs()?;
    let n = inputs.steps();
    let k = inputs.lines.as_ref().map_or(0, |l| l.observed.shape()[1]);
    let before = core.clone();
    let result = py.detach(|| steps(core, &inputs, n, k));
    let out = match result {
        Ok(out) => out,
        Err(e) => {
            *core = before;
            let at = match e.line {
                Some(line) => format!("step {}, line {line}", e.step),
                None => format!("step {}", e.step),
            };
            return Err(value_error(format!("{at}: {}", e.error)));
        }
    };
    Ok(BatchResult {
        states: new_array(py, out.states, Ix2(n, 3))?.unbind(),
        covariances: new_array(py, out.covariances, Ix3(n, 3, 3))?.unbind(),
        compass_nis: new_array(py, out.compass_nis, Ix1(n))?.unbind(),
        compass_accepted: PyArray1::from_vec(py, out.compass_accepted).unbind(),
        line_nis: new_array(py, out.line_nis, Ix2(n, k))?.unbind(),
        line_accepted: PyArray1::from_vec(py, out.line_accepted)
            .reshape([n, k])?
            .unbind(),
    })
}

/// The native loop: predict, compass, lines, record.
fn steps(core: &mut Core, inputs: &Inputs<'_>, n: usize, k: usize) -> Result<Outputs, StepError> {
    let mut out = Outputs {
        states: Vec::with_capacity(3 * n),
        covariances: Vec::with_capacity(9 * n),
        compass_nis: vec![f64::NAN; n],
        compass_accepted: vec![false; n],
        line_nis: vec![f64::NAN; n * k],
        line_accepted: vec![false; n * k],
    };
    let variance = core.compass_variance;
    for step in 0..n {
        let fail = |error| StepError {
            step,
            line: None,
            error,
        };
        match &inputs.motion {
            Motion::Wheels(w) => core.predict_wheels(w[[step, 0]], w[[step, 1]], w[[step, 2]]),
            Motion::Odometry(o) => core.predict_odometry(o[[step, 0]], o[[step, 1]]),
        }
        .map_err(fail)?;
        if let Some((headings, mask)) = &inputs.compass {
            if mask.as_ref().is_none_or(|m| m[step]) {
                let o: UpdateOutcome<f64> = core
                    .update_compass(headings[step], variance)
                    .map_err(fail)?;
                out.compass_nis[step] = o.nis;
                out.compass_accepted[step] = o.accepted;
            }
        }
        if let Some(lines) = &inputs.lines {
            let count = lines.counts.get(step).copied().unwrap_or(0);
            for j in 0..count {
                let z = (lines.observed[[step, j, 0]], lines.observed[[step, j, 1]]);
                let m = (lines.map[[step, j, 0]], lines.map[[step, j, 1]]);
                let r = matrix2(&lines.covariances.slice(s![step, j, .., ..]));
                let o: UpdateOutcome<f64> =
                    core.update_line(z, r, m).map_err(|error| StepError {
                        step,
                        line: Some(j),
                        error,
                    })?;
                out.line_nis[step * k + j] = o.nis;
                out.line_accepted[step * k + j] = o.accepted;
            }
        }
        out.states.extend_from_slice(core.ekf.state().as_slice());
        out.covariances
            .extend_from_slice(&row_major3(core.ekf.covariance()));
    }
    Ok(out)
}

/// The borrowed numpy arrays, kept alive while their views are used.
struct Arrays<'py> {
    motion: (bool, PyReadonlyArray<'py, f64, Ix2>),
    compass: Option<PyReadonlyArray<'py, f64, Ix1>>,
    mask: Option<PyReadonlyArray<'py, bool, Ix1>>,
    lines: Option<LineArrays<'py>>,
}

/// `line_observed`, `line_covariances`, `line_map` and `line_counts`.
struct LineArrays<'py> {
    observed: PyReadonlyArray<'py, f64, Ix3>,
    covariances: PyReadonlyArray<'py, f64, Ix4>,
    map: PyReadonlyArray<'py, f64, Ix3>,
    counts: Option<PyReadonlyArray<'py, f64, Ix1>>,
}

impl<'py> Arrays<'py> {
    fn read(args: &BatchArgs<'_, 'py>) -> PyResult<Self> {
        let motion = match (args.wheels, args.odometry) {
            (Some(w), None) => (true, real_array::<Ix2>(w, "wheels")?),
            (None, Some(o)) => (false, real_array::<Ix2>(o, "odometry")?),
            _ => {
                return Err(PyValueError::new_err(
                    "give exactly one of wheels= (N, 3) or odometry= (N, 2)",
                ))
            }
        };
        let compass = args
            .compass
            .map(|c| real_array::<Ix1>(c, "compass"))
            .transpose()?;
        let mask = match (args.compass_mask, &compass) {
            (None, _) => None,
            (Some(_), None) => {
                return Err(PyValueError::new_err("compass_mask given without compass"))
            }
            (Some(m), Some(_)) => Some(
                m.cast::<PyArray1<bool>>()
                    .map_err(|_| {
                        PyTypeError::new_err("compass_mask: expected a 1-dimensional bool array")
                    })?
                    .try_readonly()
                    .map_err(value_error)?,
            ),
        };
        let lines = match (args.line_observed, args.line_covariances, args.line_map) {
            (None, None, None) if args.line_counts.is_none() => None,
            (Some(o), Some(c), Some(m)) => Some(LineArrays {
                observed: real_array::<Ix3>(o, "line_observed")?,
                covariances: real_array::<Ix4>(c, "line_covariances")?,
                map: real_array::<Ix3>(m, "line_map")?,
                counts: args
                    .line_counts
                    .map(|n| real_array::<Ix1>(n, "line_counts"))
                    .transpose()?,
            }),
            _ => {
                return Err(PyValueError::new_err(
                    "lines need all of line_observed=, line_covariances= and line_map=",
                ))
            }
        };
        Ok(Self {
            motion,
            compass,
            mask,
            lines,
        })
    }

    /// Views of the arrays, with every shape and length checked.
    fn inputs(&self) -> PyResult<Inputs<'_>> {
        let (is_wheels, motion) = &self.motion;
        let motion = motion.as_array();
        let n = motion.nrows();
        let motion = if *is_wheels {
            check_shape(
                "wheels",
                motion.shape(),
                &[None, Some(3)],
                "(N, 3) as (left, right, dt)",
            )?;
            Motion::Wheels(motion)
        } else {
            check_shape(
                "odometry",
                motion.shape(),
                &[None, Some(2)],
                "(N, 2) as (ds, dtheta)",
            )?;
            Motion::Odometry(motion)
        };
        let compass = match &self.compass {
            None => None,
            Some(c) => {
                let c = c.as_array();
                check_len("compass", c.len(), n, "the motion")?;
                let mask = self.mask.as_ref().map(|m| m.as_array());
                if let Some(m) = &mask {
                    check_len("compass_mask", m.len(), n, "the motion")?;
                }
                Some((c, mask))
            }
        };
        let lines = match &self.lines {
            None => None,
            Some(arrays) => {
                let o = arrays.observed.as_array();
                let c = arrays.covariances.as_array();
                let m = arrays.map.as_array();
                check_shape(
                    "line_observed",
                    o.shape(),
                    &[Some(n), None, Some(2)],
                    "(N, K, 2)",
                )?;
                let k = o.shape()[1];
                check_shape(
                    "line_covariances",
                    c.shape(),
                    &[Some(n), Some(k), Some(2), Some(2)],
                    "(N, K, 2, 2)",
                )?;
                check_shape(
                    "line_map",
                    m.shape(),
                    &[Some(n), Some(k), Some(2)],
                    "(N, K, 2)",
                )?;
                let counts = match &arrays.counts {
                    None => vec![k; n],
                    Some(counts) => line_counts(&counts.as_array(), n, k)?,
                };
                Some(Lines {
                    observed: o,
                    covariances: c,
                    map: m,
                    counts,
                })
            }
        };
        Ok(Inputs {
            motion,
            compass,
            lines,
        })
    }
}

impl Inputs<'_> {
    fn steps(&self) -> usize {
        match &self.motion {
            Motion::Wheels(m) | Motion::Odometry(m) => m.nrows(),
        }
    }
}

/// The line count of each step: whole numbers in `[0, k]`.
fn line_counts(counts: &ArrayView1<'_, f64>, n: usize, k: usize) -> PyResult<Vec<usize>> {
    check_len("line_counts", counts.len(), n, "the motion")?;
    counts
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            if c.fract() == 0.0 && (0.0..=k as f64).contains(&c) {
                Ok(c as usize)
            } else {
                Err(PyValueError::new_err(format!(
                    "line_counts[{i}] is {c}; expected a whole number from 0 to {k} (K)"
                )))
            }
        })
        .collect()
}

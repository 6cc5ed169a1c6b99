//! Observed laser lines: the `Lines` class (numpy views of `ObservedLine`s) and
//! `extract_lines`, split-and-merge with weighted fits on one scan.

use crate::arrays::{check_finite, check_len, check_shape, new_array, real_array, row_major2};
use crate::errors::value_error;
use crate::params::from_dict;
use ekf_core::Line;
use lrf_lines::{ExtractionParams, LaserScan, LineExtractor, ObservedLine};
use nalgebra::{Matrix2, Point2};
use numpy::{Ix1, Ix2, Ix3, PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;

/// Lines observed in one scan, in the sensor frame: each `x cos psi + y sin psi = r` with
/// `r >= 0`, its 2×2 covariance of `(r, psi)`, and the end points of its segment.
#[pyclass(module = "ekf_loc", frozen)]
#[derive(Debug, Clone, Default)]
pub struct Lines {
    /// The lines.
    pub lines: Vec<ObservedLine>,
}

impl Lines {
    /// Wraps Rust lines.
    pub fn from_vec(lines: Vec<ObservedLine>) -> Self {
        Self { lines }
    }
}

/// End points of each line as an (N, 2) array.
fn points<'py>(
    py: Python<'py>,
    lines: &[ObservedLine],
    point: impl Fn(&ObservedLine) -> Point2<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let v = lines
        .iter()
        .flat_map(|l| {
            let p = point(l);
            [p.x, p.y]
        })
        .collect();
    new_array(py, v, Ix2(lines.len(), 2))
}

#[pymethods]
impl Lines {
    /// Lines from arrays: `lines` (N, 2) as `(r, psi)` (m, rad; a negative `r` is
    /// normalised to `(-r, psi + pi)`), `covariances` (N, 2, 2), `starts` and `ends` (N, 2)
    /// end points in the sensor frame (m), `num_points` (N,) the points each line was fitted
    /// to (default 0). Values must be finite.
    #[new]
    #[pyo3(signature = (lines, covariances, starts, ends, num_points = None))]
    fn new(
        lines: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
        starts: &Bound<'_, PyAny>,
        ends: &Bound<'_, PyAny>,
        num_points: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let l = real_array::<Ix2>(lines, "lines")?;
        let c = real_array::<Ix3>(covariances, "covariances")?;
        let a = real_array::<Ix2>(starts, "starts")?;
        let b = real_array::<Ix2>(ends, "ends")?;
        let (l, c, a, b) = (l.as_array(), c.as_array(), a.as_array(), b.as_array());
        check_shape("lines", l.shape(), &[None, Some(2)], "(N, 2) as (r, psi)")?;
        let n = l.nrows();
        check_shape(
            "covariances",
            c.shape(),
            &[Some(n), Some(2), Some(2)],
            "(N, 2, 2)",
        )?;
        check_shape("starts", a.shape(), &[Some(n), Some(2)], "(N, 2)")?;
        check_shape("ends", b.shape(), &[Some(n), Some(2)], "(N, 2)")?;
        for (name, v) in [("lines", &l), ("starts", &a), ("ends", &b)] {
            check_finite(name, v)?;
        }
        check_finite("covariances", &c)?;
        let counts = match num_points {
            None => vec![0; n],
            Some(obj) => {
                let counts = real_array::<Ix1>(obj, "num_points")?;
                let counts = counts.as_array();
                check_len("num_points", counts.len(), n, "lines")?;
                counts
                    .iter()
                    .map(|&v| {
                        (v >= 0.0 && v.fract() == 0.0)
                            .then_some(v as usize)
                            .ok_or_else(|| value_error(format!("num_points: {v} is not a count")))
                    })
                    .collect::<PyResult<Vec<usize>>>()?
            }
        };
        let lines = (0..n)
            .map(|i| {
                Ok(ObservedLine {
                    line: Line::new(l[[i, 0]], l[[i, 1]]).map_err(value_error)?,
                    covariance: Matrix2::new(
                        c[[i, 0, 0]],
                        c[[i, 0, 1]],
                        c[[i, 1, 0]],
                        c[[i, 1, 1]],
                    ),
                    start: Point2::new(a[[i, 0]], a[[i, 1]]),
                    end: Point2::new(b[[i, 0]], b[[i, 1]]),
                    num_points: counts.get(i).copied().unwrap_or(0),
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Self { lines })
    }

    /// (N, 2) array of `(r, psi)`: distance (m) and normal direction (rad, sensor frame).
    #[getter]
    fn lines<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let v = self
            .lines
            .iter()
            .flat_map(|l| [l.line.rho, l.line.beta])
            .collect();
        new_array(py, v, Ix2(self.lines.len(), 2))
    }

    /// (N, 2, 2) covariances of `(r, psi)` (m², m·rad, rad²).
    #[getter]
    fn covariances<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let v = self
            .lines
            .iter()
            .flat_map(|l| row_major2(&l.covariance))
            .collect();
        new_array(py, v, Ix3(self.lines.len(), 2, 2))
    }

    /// (N, 2) first end points (sensor frame, m), in scan order.
    #[getter]
    fn starts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        points(py, &self.lines, |l| l.start)
    }

    /// (N, 2) last end points (sensor frame, m), in scan order.
    #[getter]
    fn ends<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        points(py, &self.lines, |l| l.end)
    }

    /// (N,) segment lengths (m).
    #[getter]
    fn lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_iter(py, self.lines.iter().map(ObservedLine::length))
    }

    /// (N,) number of scan points each line was fitted to.
    #[getter]
    fn num_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_iter(py, self.lines.iter().map(|l| l.num_points as u64))
    }

    fn __len__(&self) -> usize {
        self.lines.len()
    }

    fn __repr__(&self) -> String {
        format!("Lines({} lines)", self.lines.len())
    }
}

/// The ranges of a scan as `float32` (as a ROS `LaserScan` carries them). NaN, ±inf and
/// out-of-range readings are allowed: they mean "no return" and are skipped.
pub fn ranges_f32(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f32>> {
    if let Ok(a) = obj.cast::<PyArray1<f32>>() {
        return Ok(a.try_readonly().map_err(value_error)?.as_array().to_vec());
    }
    let a = real_array::<Ix1>(obj, "ranges")?;
    Ok(a.as_array().iter().map(|&r| r as f32).collect())
}

/// `range_max` for a [`LaserScan`]: `+inf` (no upper limit) becomes the largest finite
/// value, which the scan header accepts; anything else is passed on to be validated.
pub fn finite_range_max(range_max: f64) -> f64 {
    if range_max == f64::INFINITY {
        f64::MAX
    } else {
        range_max
    }
}

/// Extracts the lines of one laser scan (docs/ARCHITECTURE.md §3): split-and-merge over the valid
/// readings, a weighted least-squares fit per segment with the inverse Fisher information
/// as covariance, and chi-square merging of collinear neighbours.
///
/// `ranges` (m) is a 1-D array (float32 or float64), beam `i` at bearing
/// `angle_min + i * angle_increment` (rad, counter-clockwise in the sensor frame).
/// Readings that are NaN, infinite, `<= range_min` or `>= range_max` are "no return" and
/// skipped (not errors). `range_max = inf` means no upper limit. `params` is a dict of
/// extraction parameters (the `[localizer.extraction]` group of `ekf config`; missing
/// keys take their defaults). Raises `ValueError` on an invalid header or parameter.
#[pyfunction]
#[pyo3(signature = (ranges, angle_min, angle_increment, range_min = 0.0, range_max = f64::INFINITY, params = None))]
pub fn extract_lines(
    py: Python<'_>,
    ranges: &Bound<'_, PyAny>,
    angle_min: f64,
    angle_increment: f64,
    range_min: f64,
    range_max: f64,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<Lines> {
    let ranges = ranges_f32(ranges)?;
    let params: ExtractionParams = from_dict(params, "params")?;
    let mut extractor = LineExtractor::new(params).map_err(value_error)?;
    let scan = LaserScan {
        angle_min,
        angle_increment,
        range_min,
        range_max: finite_range_max(range_max),
        ranges: &ranges,
    };
    let mut out = Vec::new();
    py.detach(|| extractor.extract(&scan, &mut out))
        .map_err(value_error)?;
    Ok(Lines::from_vec(out))
}

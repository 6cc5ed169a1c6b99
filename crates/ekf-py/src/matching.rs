//! `match_lines`: data association of observed lines with map walls at a given state
//! (chi-square gate on the line innovation, segment overlap, each wall at most once).

use crate::arrays::{matrix3, new_array, pose3, row_major2};
use crate::errors::value_error;
use crate::lines::Lines;
use crate::map::LineMap;
use crate::params::from_dict;
use ekf_core::{Ekf, Pose2};
use lrf_lines::{MatchParams, MatchResult, Matcher};
use numpy::{Ix1, Ix2, Ix3, PyArray1, PyArray2, PyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// The association of one scan's lines with the map, at the state matching ran at. Arrays
/// have one entry per match, in the order assigned (increasing NIS).
#[pyclass(module = "ekf_loc", frozen, get_all)]
pub struct Matches {
    /// (M,) index of the observed line.
    pub observed: Py<PyArray1<u64>>,
    /// (M,) index of the map wall.
    pub map: Py<PyArray1<u64>>,
    /// (M,) NIS of the pair.
    pub nis: Py<PyArray1<f64>>,
    /// (M, 2) innovation `(r, psi)` (psi wrapped).
    pub innovations: Py<PyArray2<f64>>,
    /// (M, 2, 2) measurement noise to fuse with: the observed covariance plus the map's.
    pub noise: Py<PyArray3<f64>>,
    /// (M,) overlap of the observed segment with the wall (m).
    pub overlap: Py<PyArray1<f64>>,
    /// Unmatched observed lines as `(index, reason)`, by increasing index.
    pub rejected: Vec<(usize, String)>,
}

#[pymethods]
impl Matches {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.nis.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Matches({} matched, {} rejected)",
            self.__len__(py),
            self.rejected.len()
        )
    }
}

/// Associates observed `lines` (sensor frame) with the walls of `line_map` at the robot
/// state `pose` `(x, y, theta)` with covariance `covariance` (3×3), the laser mounted at
/// `laser_mount` `(x, y, theta)` on the robot. For each pair the innovation of the
/// laser-line model gives `NIS = yᵀ S⁻¹ y`; a pair is a candidate when the NIS passes the
/// chi-square gate (2 dof) and the segments overlap; conflicts are resolved greedily by
/// increasing NIS, each wall used at most once. `params` is a dict of matching parameters
/// (the `[localizer.matching]` group of `ekf config`).
#[pyfunction]
#[pyo3(signature = (lines, line_map, pose, covariance, laser_mount = None, params = None))]
pub fn match_lines(
    py: Python<'_>,
    lines: &Lines,
    line_map: &LineMap,
    pose: &Bound<'_, PyAny>,
    covariance: &Bound<'_, PyAny>,
    laser_mount: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<Matches> {
    let ekf =
        Ekf::new(pose3(pose, "pose")?, matrix3(covariance, "covariance")?).map_err(value_error)?;
    let mount = laser_mount
        .map(|m| pose3(m, "laser_mount"))
        .transpose()?
        .unwrap_or_else(Pose2::identity);
    let params: MatchParams = from_dict(params, "params")?;
    let matcher = Matcher::new(params).map_err(value_error)?;
    let mut result = MatchResult::new();
    matcher.match_lines(&lines.lines, &line_map.map, &ekf, &mount, &mut result);
    let matches = result.matches();
    let m = matches.len();
    let noise = matches.iter().flat_map(|x| row_major2(&x.innovation.r));
    Ok(Matches {
        observed: PyArray1::from_iter(py, matches.iter().map(|x| x.observed as u64)).unbind(),
        map: PyArray1::from_iter(py, matches.iter().map(|x| x.map as u64)).unbind(),
        nis: new_array(
            py,
            matches.iter().map(|x| x.innovation.nis).collect(),
            Ix1(m),
        )?
        .unbind(),
        innovations: new_array(
            py,
            matches
                .iter()
                .flat_map(|x| [x.innovation.y[0], x.innovation.y[1]])
                .collect(),
            Ix2(m, 2),
        )?
        .unbind(),
        noise: new_array(py, noise.collect(), Ix3(m, 2, 2))?.unbind(),
        overlap: new_array(py, matches.iter().map(|x| x.overlap).collect(), Ix1(m))?.unbind(),
        rejected: result
            .rejections()
            .iter()
            .map(|r| (r.observed, r.reason.to_string()))
            .collect(),
    })
}

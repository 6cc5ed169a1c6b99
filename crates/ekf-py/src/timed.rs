//! `TimedLocalizer`: stamped inputs as they arrive, fused in stamp order up to a lag
//! (`ekf_fusion::TimedLocalizer`, the loop `ekf replay` drives).

use crate::arrays::{
    check_finite, check_shape, matrix2, matrix3, matrix3_array, new_array, pose3, real_array,
    row_major3,
};
use crate::errors::value_error;
use crate::map::LineMap;
use crate::params::{from_dict, to_python};
use crate::replay::parse_mode;
use ekf_core::Pose2;
use ekf_fusion::{
    CompassCounts, Fused, Fuser, FusionConfig, GatedCounts, Input, LineCounts, Scan, Skip, Tracking,
};
use lrf_lines::LocalizerConfig;
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use serde::Serialize;

/// What `TimedLocalizer.counts()` returns, keyed as `ekf replay --json` keys it.
#[derive(Serialize)]
struct CountsView<'a> {
    motion_steps: u64,
    wheel_velocities_used: u64,
    too_late: u64,
    skipped: u64,
    lines: &'a LineCounts,
    compass: &'a CompassCounts,
    positions: &'a GatedCounts,
    losses: u64,
    relocalizations: u64,
    scans_lost: u64,
}

/// Inputs with their stamps (ns), pushed as they arrive, fused in stamp order: each is
/// held until one stamped `max_lag` later has been pushed, so a measurement that comes
/// up to `max_lag` late is fused where the robot was when it was made. One later than
/// that is dropped and counted (`counts["too_late"]`; the `add_*` call returns False).
#[pyclass(module = "ekf_loc")]
pub struct TimedLocalizer {
    inner: ekf_fusion::TimedLocalizer<()>,
    /// Readings that could not be used (non-finite, stamps not increasing, impossible
    /// encoder increments, scan headers the extractor refused).
    skipped: u64,
    /// The fused state after each fused input that changed it: stamp, pose, covariance.
    trajectory: Vec<(u64, Pose2<f64>, [f64; 9])>,
}

impl TimedLocalizer {
    /// Pushes `input` and fuses what has become ready; `false` if it came too late.
    fn add(&mut self, t_ns: u64, input: Input) -> PyResult<bool> {
        let kept = self.inner.push(t_ns, input, ()).is_ok();
        while let Some(step) = self.inner.next_ready(&mut ()) {
            let step = step.map_err(value_error)?;
            self.fused(step.stamp_ns, &step.fused);
        }
        Ok(kept)
    }

    /// Notes what fusing one input did.
    fn fused(&mut self, stamp: u64, fused: &Fused) {
        let changed = match fused {
            Fused::Motion { predicted } => *predicted,
            Fused::MotionFromVelocities(_) => true,
            Fused::Heading { .. } | Fused::Position(_) | Fused::Scan(_) => true,
            Fused::Skipped(Skip::First) => false,
            Fused::Skipped(_) | Fused::ScanRefused(_) => {
                self.skipped += 1;
                false
            }
            Fused::Reference(_) | Fused::NotFused | Fused::BeforeStart => false,
        };
        if changed {
            let f = self.inner.fuser().localizer();
            self.trajectory
                .push((stamp, f.pose(), row_major3(f.covariance())));
        }
    }
}

#[pymethods]
impl TimedLocalizer {
    /// A localizer at `pose` `(x, y, theta)` with 3×3 `covariance`, referring to
    /// `start_ns` (motion before it is already in the pose). With `line_map` scans are
    /// matched against it and a lost filter is found again by searching the map
    /// (`global_localization`: from no pose at all); without one the first scan becomes
    /// the map. `config`: the `[localizer]` groups of `ekf config` as a dict. `mode`:
    /// `odometry`, `compass`, `laser` or `laser+compass`. `max_lag`: how late (s) an
    /// input may come and still be fused at its stamp.
    #[new]
    #[pyo3(signature = (pose, covariance, line_map = None, config = None, mode = "laser+compass", max_lag = 0.5, start_ns = 0, global_localization = false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        pose: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
        line_map: Option<&LineMap>,
        config: Option<&Bound<'_, PyAny>>,
        mode: &str,
        max_lag: f64,
        start_ns: u64,
        global_localization: bool,
    ) -> PyResult<Self> {
        let pose = pose3(pose, "pose")?;
        let p = matrix3(covariance, "covariance")?;
        let localizer: LocalizerConfig = from_dict(config, "config")?;
        if !(max_lag.is_finite() && max_lag >= 0.0) {
            return Err(PyValueError::new_err(format!(
                "max_lag: expected a non-negative number of seconds, got {max_lag}"
            )));
        }
        let tracking = match (line_map.is_some(), global_localization) {
            (_, true) => Tracking::Global,
            (true, false) => Tracking::FromInitialPose,
            (false, false) => Tracking::Off,
        };
        let config = FusionConfig {
            localizer,
            mode: parse_mode(mode)?,
            tracking,
            max_lag,
            ..FusionConfig::default()
        };
        let map = line_map.map(|m| m.map.clone());
        let fuser = Fuser::new(&config, pose, p, start_ns, map).map_err(value_error)?;
        Ok(Self {
            inner: ekf_fusion::TimedLocalizer::new(fuser, (max_lag * 1e9).round() as u64),
            skipped: 0,
            trajectory: Vec::new(),
        })
    }

    /// Wheel encoder angles (rad, unwrapped) at `t_ns`: the motion since the previous
    /// wheel reading is their increment. Returns False if it came too late.
    fn add_wheel_angles(&mut self, t_ns: u64, left: f64, right: f64) -> PyResult<bool> {
        let velocities = None;
        self.add(
            t_ns,
            Input::WheelAngles {
                left,
                right,
                velocities,
            },
        )
    }

    /// Wheel speeds (rad/s), held since the previous wheel reading.
    fn add_wheel_speeds(&mut self, t_ns: u64, left: f64, right: f64) -> PyResult<bool> {
        self.add(t_ns, Input::WheelVelocities { left, right })
    }

    /// A pose `(x, y, theta)` of the robot's own odometry: the motion since the previous
    /// one is their relative pose.
    fn add_odometry(&mut self, t_ns: u64, pose: &Bound<'_, PyAny>) -> PyResult<bool> {
        let a = real_array::<numpy::Ix1>(pose, "pose")?;
        let v = a.as_array();
        check_shape("pose", v.shape(), &[Some(3)], "(3,) as (x, y, theta)")?;
        // Not finite: skipped and counted, as `ekf replay` does.
        self.add(t_ns, Input::OdometryPose(Pose2::new(v[0], v[1], v[2])))
    }

    /// A heading (rad, map frame) with `variance` (rad²), or the configured compass
    /// variance.
    #[pyo3(signature = (t_ns, heading, variance = None))]
    fn add_heading(&mut self, t_ns: u64, heading: f64, variance: Option<f64>) -> PyResult<bool> {
        if !heading.is_finite() || variance.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(PyValueError::new_err(format!(
                "heading: expected a finite heading and a positive variance, got {heading} \
                 and {variance:?}"
            )));
        }
        self.add(t_ns, Input::Heading { heading, variance })
    }

    /// A position fix `xy` (m, map frame) with its 2×2 `covariance` (m²), through a 2-dof
    /// gate (0.99).
    fn add_position(
        &mut self,
        t_ns: u64,
        xy: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<bool> {
        let a = real_array::<numpy::Ix1>(xy, "xy")?;
        let v = a.as_array();
        check_shape("xy", v.shape(), &[Some(2)], "(2,) as (x, y)")?;
        check_finite("xy", &v)?;
        let c = real_array::<numpy::Ix2>(covariance, "covariance")?;
        let cv = c.as_array();
        check_shape("covariance", cv.shape(), &[Some(2), Some(2)], "(2, 2)")?;
        check_finite("covariance", &cv)?;
        let input = Input::Position {
            x: v[0],
            y: v[1],
            covariance: matrix2(&cv),
        };
        self.add(t_ns, input)
    }

    /// A laser scan; arguments as for `extract_lines`.
    #[pyo3(signature = (t_ns, ranges, angle_min, angle_increment, range_min = 0.0, range_max = f64::INFINITY))]
    fn add_scan(
        &mut self,
        t_ns: u64,
        ranges: &Bound<'_, PyAny>,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
    ) -> PyResult<bool> {
        let scan = Scan {
            angle_min,
            angle_increment,
            range_min,
            range_max: crate::lines::finite_range_max(range_max),
            ranges: crate::lines::ranges_f32(ranges)?,
        };
        self.add(t_ns, Input::Scan(scan))
    }

    /// Fuses every input still held, in stamp order (when the inputs have ended).
    fn flush(&mut self) -> PyResult<()> {
        while let Some(step) = self.inner.next_held(&mut ()) {
            let step = step.map_err(value_error)?;
            self.fused(step.stamp_ns, &step.fused);
        }
        Ok(())
    }

    /// The pose now: `(t_ns, state (3,), covariance (3, 3))`, the fused state predicted
    /// through the motion readings still held, as fusing them will; None until a motion
    /// reading was fused.
    #[allow(clippy::type_complexity)]
    fn pose_now<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(u64, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>)>> {
        let Some(f) = self.inner.pose_now([]).map_err(value_error)? else {
            return Ok(None);
        };
        let pose = PyArray1::from_slice(py, &[f.pose.x, f.pose.y, f.pose.theta]);
        Ok(Some((f.t_ns, pose, matrix3_array(py, &f.covariance)?)))
    }

    /// The fused state `[x, y, theta]` (it trails the newest input by up to `max_lag`).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = self.inner.fuser().localizer().pose();
        PyArray1::from_slice(py, &[p.x, p.y, p.theta])
    }

    /// The fused state's 3×3 covariance.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix3_array(py, self.inner.fuser().localizer().covariance())
    }

    /// The time the fused state refers to (ns); None until a motion reading was fused.
    #[getter]
    fn t_ns(&self) -> Option<u64> {
        self.inner.fuser().state_ns()
    }

    /// Inputs held, waiting for their turn.
    #[getter]
    fn held(&self) -> usize {
        self.inner.held()
    }

    /// The map (empty until the first scan when built from it).
    #[getter]
    fn line_map(&self) -> LineMap {
        LineMap {
            map: self.inner.fuser().localizer().map().clone(),
        }
    }

    /// What was fused, as `ekf replay --json` counts it: `motion_steps`,
    /// `wheel_velocities_used`, `too_late`, `skipped`, `lines` / `compass` / `positions`
    /// (dicts of counts), `losses`, `relocalizations`, `scans_lost`.
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = self.inner.fuser().counts();
        let view = CountsView {
            motion_steps: c.motion_steps,
            wheel_velocities_used: c.wheel_velocities_used,
            too_late: c.too_late,
            skipped: self.skipped,
            lines: &c.lines,
            compass: &c.compass,
            positions: &c.positions,
            losses: c.tracking.losses,
            relocalizations: c.tracking.relocalizations,
            scans_lost: c.tracking.scans_lost,
        };
        to_python(py, &view)
    }

    /// The fused states since the last call, one after each input that changed the state:
    /// `(t_ns (N,) uint64, states (N, 3), covariances (N, 3, 3))`. Taking them frees
    /// their memory.
    #[allow(clippy::type_complexity)]
    fn take_trajectory<'py>(
        &mut self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyArray1<u64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray3<f64>>,
    )> {
        let rows = std::mem::take(&mut self.trajectory);
        let n = rows.len();
        let t: Vec<u64> = rows.iter().map(|r| r.0).collect();
        let states: Vec<f64> = rows
            .iter()
            .flat_map(|r| [r.1.x, r.1.y, r.1.theta])
            .collect();
        let covs: Vec<f64> = rows.iter().flat_map(|r| r.2).collect();
        Ok((
            PyArray1::from_vec(py, t),
            new_array(py, states, numpy::Ix2(n, 3))?,
            new_array(py, covs, numpy::Ix3(n, 3, 3))?,
        ))
    }
}

//! The simulator's readings as the robot's devices report them (`docs/devices.md`):
//! encoder counts in the base controller's 32-bit registers, the compass as a CMPS03
//! bearing (clockwise from north; the simulator's heading is an ENU yaw, docs/ARCHITECTURE.md §2), the
//! laser's ranges as a sweep the SICK turns into millimetres, and a GPS fix about an
//! origin on the globe, or none.

use super::{GpsReport, Motion, RobotSample};
use crate::devices::sick::device::Sweep;
use ekf_core::angle_diff;
use ekf_sim::{LaserModel, Sample};
use std::time::{Duration, Instant};

/// The CMPS03's bearing (degrees clockwise from north, in `[0, 360)`) of an ENU yaw
/// (rad, counter-clockwise from east), with the map's x axis pointing east.
pub fn bearing_deg(yaw: f64) -> f64 {
    (90.0 - yaw.to_degrees()).rem_euclid(360.0)
}

/// An encoder count as the controller's 32-bit counter holds it (wrapping).
pub fn ticks_register(ticks: i64) -> u32 {
    ticks as u32
}

/// A simulated sweep (metres as `f32`, +∞ no return, NaN an error code) as the
/// scanner sees it.
pub fn sweep(laser: &LaserModel, ranges: &[f32]) -> Sweep {
    Sweep {
        angle_min: laser.angle_min(),
        angle_increment: laser.resolution,
        ranges: ranges.iter().map(|&r| f64::from(r)).collect(),
    }
}

/// What the devices report for simulator step `now`, served at instant `at` and stamped
/// `t_ns` (ns since the Unix epoch, for the GPS clock); the encoders and the compass
/// move on towards step `next` over `dt` (they hold without one).
pub fn robot_sample(
    laser: &LaserModel,
    now: &Sample,
    next: Option<&Sample>,
    at: Instant,
    dt: Duration,
    t_ns: u64,
    gps: Option<GpsReport>,
) -> RobotSample {
    // The compass's noise stays the step's; its heading turns on with the robot.
    let motion = next.map(|n| Motion {
        at,
        duration: dt,
        left_ticks: ticks_register(n.ticks[0]),
        right_ticks: ticks_register(n.ticks[1]),
        bearing_change_deg: -angle_diff(n.truth.theta, now.truth.theta).to_degrees(),
    });
    RobotSample {
        t_ns,
        left_ticks: ticks_register(now.ticks[0]),
        right_ticks: ticks_register(now.ticks[1]),
        bearing_deg: bearing_deg(now.compass.heading),
        motion,
        sweep: now.scan.as_deref().map(|r| sweep(laser, r)),
        gps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::devices::modbus_base::BaseReading;
    use ekf_core::{heading_from_compass_bearing, Pose2};
    use ekf_sim::sensors::CompassReading;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn yaw_and_bearing_follow_design_section_3() {
        // East is yaw 0 and bearing 90°; north yaw π/2 and bearing 0; west bearing 270°.
        assert!((bearing_deg(0.0) - 90.0).abs() < 1e-12);
        assert!(bearing_deg(FRAC_PI_2).abs() < 1e-12);
        assert!((bearing_deg(PI) - 270.0).abs() < 1e-12);
        assert!((bearing_deg(-FRAC_PI_2) - 180.0).abs() < 1e-12);
        // And back, as ekf live reads the register.
        for yaw in [-3.0, -1.2, 0.0, 0.7, 3.1] {
            let b = bearing_deg(yaw).to_radians();
            assert!(angle_diff(heading_from_compass_bearing(b, 0.0, 0.0), yaw).abs() < 1e-12);
        }
    }

    #[test]
    fn counters_wrap() {
        assert_eq!(ticks_register(-1), u32::MAX);
        assert_eq!(ticks_register(1 << 32), 0);
    }

    fn sample(ticks: [i64; 2], theta: f64, heading: f64) -> Sample {
        Sample {
            t_ns: 0,
            truth: Pose2::new(1.0, 2.0, theta),
            ticks,
            compass: CompassReading {
                heading,
                outlier: false,
            },
            scan: Some(vec![1.0, f32::NAN, f32::INFINITY]),
        }
    }

    #[test]
    fn the_base_reads_interpolated_counts_and_bearing_between_steps() {
        let laser = LaserModel::default();
        let at = Instant::now();
        let dt = Duration::from_millis(100);
        // Turning left (yaw up) across ±π, the left wheel backwards past zero.
        let (a, b) = (sample([2, 100], 3.1, 3.1), sample([-8, 120], -3.1, -3.1));
        let s = robot_sample(&laser, &a, Some(&b), at, dt, 0, None);
        assert_eq!(s.sweep.as_ref().unwrap().ranges.len(), 3);
        let (l, r, bearing) = s.base_state_at(at + dt / 2);
        assert_eq!((l, r), (ticks_register(-3), 110));
        let turned = angle_diff(-3.1f64, 3.1).to_degrees() / 2.0;
        assert!(
            (bearing - bearing_deg(3.1) + turned).abs() < 1e-9,
            "{bearing}"
        );
        // After the next step is due, the counts hold at its values.
        let (l, r, _) = s.base_state_at(at + dt * 3);
        assert_eq!((l, r), (ticks_register(-8), 120));
        // The registers carry them as the controller does.
        let reg = BaseReading {
            left_ticks: l,
            right_ticks: r,
            bearing_tenths: 0,
            counter: 0,
        };
        assert_eq!(
            BaseReading::from_registers(&reg.to_registers()).left_ticks,
            l
        );
    }
}

//! The simulator's readings as the robot's devices report them (`docs/devices.md`):
//! encoder counts in the base controller's 32-bit registers, the compass as a CMPS03
//! bearing (clockwise from north; the simulator's heading is an ENU yaw, DESIGN §3), the
//! laser's ranges as a sweep the SICK turns into millimetres, and a GPS fix about an
//! origin on the globe, or none.

use super::{GeoFix, GpsReport, Motion, RobotSample};
use crate::devices::sick::device::Sweep;
use crate::sim::{LaserModel, Sample};
use ekf_core::angle_diff;
use std::time::{Duration, Instant};

/// WGS-84 semi-major axis (m).
const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 first eccentricity squared.
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// Where the simulated room lies on the globe: its frame's origin, x east, y north.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoOrigin {
    /// Latitude (degrees, north positive).
    pub latitude: f64,
    /// Longitude (degrees, east positive).
    pub longitude: f64,
    /// Altitude above mean sea level (m).
    pub altitude: f64,
}

impl GeoOrigin {
    /// The fix at `(east, north)` metres from the origin, on the WGS-84 ellipsoid's
    /// tangent plane there (meridian and prime-vertical radii of curvature; good to
    /// millimetres over a few hundred metres). No receiver noise is modelled.
    pub fn fix_at(&self, east: f64, north: f64) -> GeoFix {
        let phi = self.latitude.to_radians();
        let w = 1.0 - WGS84_E2 * phi.sin().powi(2);
        let meridian = WGS84_A * (1.0 - WGS84_E2) / w.powf(1.5);
        let prime_vertical = WGS84_A / w.sqrt();
        GeoFix {
            latitude: self.latitude + (north / meridian).to_degrees(),
            longitude: self.longitude + (east / (prime_vertical * phi.cos())).to_degrees(),
            altitude: self.altitude,
            hdop: 1.0,
        }
    }
}

impl std::str::FromStr for GeoOrigin {
    type Err = String;

    /// `LAT,LON` or `LAT,LON,ALT` (degrees, degrees, metres).
    fn from_str(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let number = |i: usize, what: &str| -> Result<f64, String> {
            parts[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{what} {:?} is not a number", parts[i]))
        };
        if !(2..=3).contains(&parts.len()) {
            return Err(format!("{text:?}: expected LAT,LON or LAT,LON,ALT"));
        }
        let origin = GeoOrigin {
            latitude: number(0, "latitude")?,
            longitude: number(1, "longitude")?,
            altitude: if parts.len() == 3 {
                number(2, "altitude")?
            } else {
                0.0
            },
        };
        if origin.latitude.abs() > 89.0 || origin.longitude.abs() > 180.0 {
            return Err(format!(
                "{text:?}: expected a latitude within ±89° and a longitude within ±180°"
            ));
        }
        Ok(origin)
    }
}

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
    use crate::sim::sensors::CompassReading;
    use ekf_core::{heading_from_compass_bearing, Pose2};
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
    fn counters_wrap_and_fixes_lie_about_the_origin() {
        assert_eq!(ticks_register(-1), u32::MAX);
        assert_eq!(ticks_register(1 << 32), 0);
        let o = GeoOrigin {
            latitude: 21.0,
            longitude: 105.8,
            altitude: 10.0,
        };
        // One arc minute of latitude is 1845.3 m at 21° N (geodetic tables).
        let f = o.fix_at(0.0, 1845.3);
        assert!(((f.latitude - 21.0) * 60.0 - 1.0).abs() < 1e-4, "{f:?}");
        assert_eq!("21, 105.8,10".parse::<GeoOrigin>(), Ok(o));
        assert!("21".parse::<GeoOrigin>().is_err());
        assert!("95,0"
            .parse::<GeoOrigin>()
            .unwrap_err()
            .contains("latitude"));
        let f = o.fix_at(100.0, 0.0);
        let east = (f.longitude - 105.8).to_radians() * WGS84_A * 21f64.to_radians().cos();
        assert!((east - 100.0).abs() < 0.5, "{east}");
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

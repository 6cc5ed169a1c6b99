//! The `[devices]` section of the configuration: how `ekf live` talks to the robot's
//! devices and turns their raw values into ROS messages.

use ekf_core::setting::{check, Expected, InvalidSetting};
use serde::{Deserialize, Serialize};

/// Serial devices of the paper's robot (docs/ARCHITECTURE.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DevicesConfig {
    /// The laser's frame id in the recorded scans and `/tf_static`.
    pub laser_frame: String,
    /// Laser baud rate after start-up: 38400, or 500000 (falls back to 38400 where the
    /// adapter cannot).
    pub laser_baud: u32,
    /// Laser scanning angle (degrees): 180 or 100.
    pub laser_angle_deg: u16,
    /// Laser angular resolution (degrees): 1, 0.5 or 0.25 (0.25 only with 100°).
    pub laser_resolution_deg: f64,
    /// MODBUS unit id of the base controller.
    pub base_unit_id: u8,
    /// Base controller baud rate.
    pub base_baud: u32,
    /// Encoder ticks per wheel revolution (after quadrature decoding).
    pub ticks_per_revolution: f64,
    /// Fastest a wheel can turn (turns per second): a larger encoder change between two
    /// reads is refused as impossible (a restarted controller, a corrupt read).
    pub max_wheel_turns_per_s: f64,
    /// Polls of the base controller per second (the filter rate).
    pub poll_rate_hz: f64,
    /// GPS baud rate.
    pub gps_baud: u32,
    /// The GPS antenna's frame id in the recorded fixes.
    pub gps_frame: String,
    /// Seconds without usable data before a device counts as silent.
    pub timeout_s: f64,
}

impl Default for DevicesConfig {
    fn default() -> Self {
        Self {
            laser_frame: "laser".into(),
            laser_baud: 38_400,
            laser_angle_deg: 180,
            laser_resolution_deg: 0.5,
            base_unit_id: 1,
            base_baud: 38_400,
            ticks_per_revolution: 500.0,
            max_wheel_turns_per_s: ekf_fusion::DEFAULT_MAX_WHEEL_TURNS_PER_S,
            poll_rate_hz: 10.0,
            gps_baud: 4800,
            gps_frame: "gps".into(),
            timeout_s: 2.0,
        }
    }
}

impl DevicesConfig {
    /// Positive encoder resolution, wheel-speed limit, poll rate, timeout and laser
    /// resolution. Whether the laser can scan the angle and resolution asked for is the
    /// driver's to say, when `ekf live` brings it up.
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        check(
            "ticks_per_revolution",
            self.ticks_per_revolution,
            Expected::Positive,
        )?;
        check(
            "max_wheel_turns_per_s",
            self.max_wheel_turns_per_s,
            Expected::Positive,
        )?;
        check("poll_rate_hz", self.poll_rate_hz, Expected::Positive)?;
        check("timeout_s", self.timeout_s, Expected::Positive)?;
        check(
            "laser_resolution_deg",
            self.laser_resolution_deg,
            Expected::Positive,
        )
    }
}

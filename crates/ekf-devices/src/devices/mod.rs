//! The paper's robot devices on serial lines (docs/ARCHITECTURE.md §5): the SICK LMS 2xx laser, the
//! dsPIC base controller on MODBUS RTU (encoders and the CMPS03 compass), and an NMEA GPS.
//! Each protocol is a sans-I/O part (bytes in, values out) plus a small driver over a
//! [`Link`]; the device side of each protocol, for the emulators, lives next to it.

pub mod arrival_clock;
pub mod error;
pub mod gps;
pub mod link;
pub mod modbus_base;
pub mod sick;

pub use ekf_ros::devices_config::DevicesConfig;
pub use error::DeviceError;
pub use link::{Link, SerialLink};

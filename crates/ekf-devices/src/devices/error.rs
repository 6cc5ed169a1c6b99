//! What can go wrong with a device: it cannot be opened, it went away, it stayed silent,
//! or it refused a request. Every error names the port and the device.

use std::time::Duration;

/// A device failure, naming the port and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// The port could not be opened or configured.
    #[error("{device} on {port}: cannot open: {message}")]
    Open {
        /// The device (`laser`, `base`, `gps`).
        device: &'static str,
        /// The port path.
        port: String,
        /// What the OS or the serial library said.
        message: String,
    },
    /// Reading or writing failed: the device was unplugged or the line hung up.
    #[error("{device} on {port}: {during}: {source}")]
    Io {
        /// The device.
        device: &'static str,
        /// The port path.
        port: String,
        /// What was being done.
        during: &'static str,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Nothing usable arrived in time.
    #[error("{device} on {port}: timeout: nothing usable within {:.1} s; expected {expected}", waited.as_secs_f64())]
    Silent {
        /// The device.
        device: &'static str,
        /// The port path.
        port: String,
        /// How long was waited.
        waited: Duration,
        /// What was expected.
        expected: String,
    },
    /// The device answered but refused or failed the request.
    #[error("{device} on {port}: {message}")]
    Refused {
        /// The device.
        device: &'static str,
        /// The port path.
        port: String,
        /// What was refused.
        message: String,
    },
}

impl DeviceError {
    /// Whether the device went away (unplugged, hung up): worth reopening the port.
    pub fn is_disconnect(&self) -> bool {
        matches!(self, DeviceError::Io { .. } | DeviceError::Open { .. })
    }
}

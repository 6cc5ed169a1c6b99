//! The robot's devices: drivers for the paper's serial devices ([`devices`]), `ekf live`
//! that reads them, runs the localizer and records every reading ([`live`]), and the
//! device emulators the tests drive it against ([`emulate`]). docs/ARCHITECTURE.md §5 and
//! docs/devices.md describe the protocols.

pub mod devices;
pub mod emulate;
pub mod live;

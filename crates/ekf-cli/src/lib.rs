//! The library behind the `ekf` command: ROS 2 MCAP input and output, log importers,
//! trajectory evaluation and plots. `main.rs` only parses arguments and calls in here;
//! nothing in this library prints or exits.

pub mod commands;
pub mod config;
pub mod devices;
pub mod emulate;
pub mod eval;
pub mod geo;
pub mod import;
pub mod live;
pub mod mcap_io;
pub mod plot;
pub mod replay;
pub mod ros2;
pub mod sim;
pub mod trajectory;
pub mod tum;

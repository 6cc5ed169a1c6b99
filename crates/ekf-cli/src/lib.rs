//! The library behind the `ekf` command: one module per subcommand ([`commands`]), log
//! importers ([`import`]) and plots ([`plot`]); the rest comes from the library crates
//! (`ekf-ros`, `ekf-sim`, `ekf-devices`) and is re-exported here under the names the
//! command has always used. `main.rs` only parses arguments and calls in here; nothing in
//! this library prints or exits.

pub mod commands;
pub mod import;
pub mod plot;

pub use ekf_devices::{devices, emulate, live};
pub use ekf_ros::{config, eval, geo, mcap_io, replay, ros2, slam, trajectory, tum};
pub use ekf_sim as sim;

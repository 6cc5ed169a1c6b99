//! ROS 2 logs through the localizer: the messages and their CDR encoding ([`ros2`]),
//! bags in every form rosbag2 writes, read and written ([`mcap_io`]), the configuration
//! file ([`config`]), the replay pipeline that turns messages into the inputs of the
//! time-ordered localizer (`ekf-fusion`) and writes what it did to its sinks — a
//! Foxglove bag, a TUM trajectory, a summary ([`replay`]) — trajectories and their
//! evaluation ([`trajectory`], [`tum`], [`eval`]), and line maps built from a log with a
//! reference ([`map_build`]). docs/ARCHITECTURE.md shows where it sits. Nothing in this
//! library prints or exits.

pub mod config;
pub mod devices_config;
pub mod eval;
pub mod geo;
pub mod grid;
pub mod map_build;
pub mod map_compare;
pub mod map_search;
pub mod mcap_io;
pub mod output_dir;
pub mod replay;
pub mod ros2;
pub mod slam;
pub mod slam_config;
pub mod trajectory;
pub mod tum;

#[cfg(test)]
mod test_support;

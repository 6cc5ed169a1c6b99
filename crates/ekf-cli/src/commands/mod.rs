//! One module per `ekf` subcommand: each takes parsed arguments and returns a report;
//! `main.rs` prints it.

pub mod compare;
pub mod corpus;
pub mod emulate;
pub mod evaluate;
pub mod experiment;
pub mod figures;
pub mod import;
pub mod map_plot;

pub use ekf_ros::grid;
pub use ekf_ros::map_build as map;
pub use ekf_ros::output_dir::create_output_dir;
pub use ekf_sim::simulate;

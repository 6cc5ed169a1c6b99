//! One module per `ekf` subcommand: each takes parsed arguments and returns a report;
//! `main.rs` prints it.

pub mod compare;
pub mod evaluate;
pub mod experiment;
pub mod import;
pub mod map;
pub mod simulate;

//! The simulator (`ekf simulate`, `ekf experiment`): the paper's robot in a room of line
//! segments, driven along a path by a pure-pursuit follower, with the paper's sensors —
//! quadrature encoders behind a speed PID, a compass, a SICK LMS 221 — and optionally
//! the filter in the loop.
//!
//! Every noise source has its own seeded stream ([`rng`]), so a run is reproducible
//! bit for bit and its log ([`log`]) byte for byte.

pub mod log;
pub mod path;
pub mod rng;
pub mod robot;
pub mod room;
pub mod run;
pub mod scenario;
pub mod sensors;
pub mod simulate;
pub mod stepper;

pub use log::LogRecorder;
pub use path::{Path, PurePursuit};
pub use robot::RobotModel;
pub use room::Room;
pub use run::{simulate, Estimator, Feedback, Nees, SimError, SimOptions, SimResult, SimStats};
pub use scenario::{Scenario, ScenarioError, BUILTIN};
pub use sensors::{CompassModel, LaserModel};
pub use stepper::{Sample, Simulator};

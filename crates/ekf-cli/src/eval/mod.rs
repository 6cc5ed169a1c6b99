//! Trajectory evaluation as `evo` defines it: association by time stamp, Umeyama
//! alignment, absolute (APE/ATE) and relative (RPE) pose errors and their statistics.
//!
//! Everything here is planar: a pose is `(x, y, θ)`. For trajectories with `z = 0` and
//! no roll or pitch the numbers equal `evo_ape tum …` / `evo_rpe tum …`
//! (`-r trans_part` and `-r angle_deg`) to rounding; the few places where the planar
//! case differs from `evo`'s SE(3) code are documented where they arise
//! ([`associate`], [`umeyama`]). Results serialize to JSON with serde, with `evo`'s
//! statistic names (`rmse`, `mean`, `median`, `std`, `min`, `max`, `sse`).

mod alignment;
mod ape;
mod association;
mod error;
mod rpe;
mod statistics;

pub use alignment::{align_estimate, umeyama, AlignMode, Alignment, AlignmentOptions};
pub use ape::{ape, Ape, ApeOptions, ApeSummary, PoseError};
pub use association::{associate, AssociationOptions, Matched};
pub use error::EvalError;
pub use rpe::{rpe, RelativeError, Rpe, RpeOptions, RpeSummary};
pub use statistics::Statistics;

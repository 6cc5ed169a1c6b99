//! Trajectory evaluation as `evo` defines it: association by time stamp, Umeyama
//! alignment, absolute (APE/ATE) and relative (RPE) pose errors and their statistics.
//!
//! Everything here is planar: a pose is `(x, y, θ)`. For trajectories with `z = 0` and
//! no roll or pitch the numbers equal `evo_ape tum …` / `evo_rpe tum …`
//! (`-r trans_part` and `-r angle_deg`) to rounding; the few places where the planar
//! case differs from `evo`'s SE(3) code are documented where they arise
//! ([`associate`], [`umeyama`]). Results serialize to JSON with serde, with `evo`'s
//! statistic names (`rmse`, `mean`, `median`, `std`, `min`, `max`, `sse`).
//!
//! ```
//! use ekf_ros::eval::{ape, rpe, AlignMode, ApeOptions, RpeOptions};
//! use ekf_ros::tum::read_tum;
//!
//! let reference = read_tum("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 1 0 0 0 0 1".as_bytes(), "ref")?;
//! let estimate = read_tum("0 0.3 0.4 0 0 0 0 1\n1 1.3 0.4 0 0 0 0 1\n2 2.3 1.4 0 0 0 0 1".as_bytes(), "est")?;
//!
//! let ate = ape(&reference, &estimate, &ApeOptions::default())?;
//! assert!((ate.summary.translation_m.rmse - 0.5).abs() < 1e-12);
//! assert_eq!(ate.summary.matched_poses, 3);
//!
//! let mut aligned = ApeOptions::default();
//! aligned.alignment.mode = AlignMode::Rigid;
//! assert!(ape(&reference, &estimate, &aligned)?.summary.translation_m.rmse < 1e-12);
//!
//! let drift = rpe(&reference, &estimate, &RpeOptions::default())?;
//! assert!(drift.summary.translation_m.max < 1e-12);
//! let json = serde_json::to_string(&drift.summary).unwrap();
//! assert!(json.contains("\"rmse\""));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

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

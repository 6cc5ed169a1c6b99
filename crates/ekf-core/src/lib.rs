//! Extended Kalman filter for differential-drive robots that fuses wheel odometry, a
//! compass and 2-D laser line features (Hoang et al., "Development of an EKF-based
//! Localization Algorithm Using Compass Sensor and LRF"), with the paper's errata fixed.
//!
//! `#![no_std]` unless the default `std` feature is on, and it never allocates: every
//! matrix is fixed-size (nalgebra), so the same code runs on a Cortex-M4F and on a PC.
//! Everything is generic over [`Real`] (`f32` or `f64`).
//!
//! Conventions (ROS REP-103): SI units and radians; the world frame is x east, y north;
//! the robot frame is x forward, y left; the heading θ is counter-clockwise from the
//! world x axis and always wrapped to (−π, π]; the pose covariance is 3×3 in (x, y, θ)
//! order. Every angular innovation is wrapped.
//!
//! # A minimal predict/update loop
//!
//! ```
//! use ekf_core::{
//!     ChiSquareGate, Compass, DiffDrive, Ekf, LaserLine, Line, Pose2, WheelNoise, WheelSpeeds,
//! };
//! use nalgebra::{Matrix2, Matrix3};
//!
//! // The paper's robot: wheel radius 5 cm, track 60 cm, Δt = 0.1 s.
//! let robot = DiffDrive::new(0.05_f64, 0.60)?;
//! let noise = WheelNoise::paper();
//! let mut ekf = Ekf::new(Pose2::new(0.0, 0.0, 0.0), Matrix3::from_diagonal_element(1e-4))?;
//! let gate = ChiSquareGate::from_probability(0.99, 2)?; // 9.21 for a 2-D line innovation
//!
//! // A wall 3 m ahead of the robot: x·cos 0 + y·sin 0 = 3 in the world frame.
//! let wall = Line::new(3.0, 0.0)?;
//! let laser_mount = Pose2::new(0.0, 0.0, 0.0);
//!
//! for _ in 0..10 {
//!     ekf.predict_wheels(&robot, &WheelSpeeds::new(2.0, 2.0, 0.1)?, &noise)?;
//!     ekf.update(&Compass::new(0.0, 1e-4)?, None)?;
//!     // The laser sees the wall at r = 3 − x, ψ = 0 (pretend the robot drove exactly).
//!     let r = 3.0 - ekf.pose().x;
//!     let line = LaserLine::new(Line::new(r, 0.0)?, Matrix2::from_diagonal(&[9e-4, 1e-4].into()), wall, laser_mount)?;
//!     let outcome = ekf.update(&line, Some(&gate))?;
//!     assert!(outcome.accepted);
//! }
//! assert!((ekf.pose().x - 0.1).abs() < 1e-9); // 10 steps × 0.1 s × 2 rad/s × 0.05 m
//! # Ok::<(), ekf_core::Error>(())
//! ```
#![cfg_attr(not(feature = "std"), no_std)]

pub mod angle;
pub mod chi_square;
pub mod ekf;
pub mod error;
pub mod geometry;
pub mod kinematics;
pub mod measurement;
pub mod noise;
pub mod real;
pub mod setting;
mod validate;

pub use angle::{angle_diff, wrap_angle};
pub use chi_square::{chi_square_cdf, chi_square_quantile, ChiSquareGate};
pub use ekf::{Considered, ConsideredUpdate, Ekf, Innovation, UpdateOutcome};
pub use error::Error;
pub use geometry::{Line, Pose2};
pub use kinematics::{DiffDrive, Linearization, Motion, WheelSpeeds};
pub use measurement::{
    heading_from_compass_bearing, Compass, CompassCalibration, LaserLine, Measurement, Position,
};
pub use noise::{OdometryNoise, OdometryTravel, WheelNoise};
pub use real::Real;
pub use setting::{Expected, InvalidSetting};

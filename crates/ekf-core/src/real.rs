//! The scalar type of the filter: `f32` or `f64`.
//!
//! A thin alias over nalgebra's `RealField` so signatures stay short.

use nalgebra::RealField;

/// A floating-point scalar the filter can run on (`f32` on an MCU, `f64` on a PC).
pub trait Real: RealField + Copy {
    /// Converts an `f64` constant (a parameter, π/2, a threshold) to this type.
    #[inline]
    fn lit(v: f64) -> Self {
        nalgebra::convert(v)
    }
}

impl<T: RealField + Copy> Real for T {}

//! Checks of parameters shared by the matcher and the map builder.

use ekf_core::Error;

/// Fails unless every `(value, name)` is finite and ≥ 0 (parameters of the matcher and
/// the map builder).
pub(crate) fn non_negative_params(params: &[(f64, &'static str)]) -> Result<(), Error> {
    for &(v, what) in params {
        if !v.is_finite() {
            return Err(Error::NonFinite { what });
        }
        if v < 0.0 {
            return Err(Error::OutOfRange {
                what,
                expected: ">= 0",
            });
        }
    }
    Ok(())
}

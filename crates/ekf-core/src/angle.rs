//! Angle wrapping to (−π, π] and wrapped differences.
//!
//! Never compare raw angles: every innovation and error goes through [`angle_diff`].

use crate::Real;

/// Wraps an angle to (−π, π].
///
/// `wrap_angle(π) = π`, `wrap_angle(−π) = π`. Non-finite input is returned unchanged
/// (callers validate their inputs).
#[inline]
pub fn wrap_angle<T: Real>(a: T) -> T {
    let pi = T::pi();
    let two_pi = T::two_pi();
    if a > -pi && a <= pi {
        return a;
    }
    // One turn off (sums and differences of wrapped angles): no division needed.
    if a > pi && a <= pi + two_pi {
        return a - two_pi;
    }
    if a <= -pi && a > -pi - two_pi {
        return a + two_pi;
    }
    // r in [0, 2π) for finite a; then shift to (−π, π].
    let mut r = (a + pi) % two_pi;
    if r < T::zero() {
        r += two_pi;
    }
    let w = r - pi;
    if w <= -pi {
        w + two_pi
    } else {
        w
    }
}

/// The wrapped difference `a − b` in (−π, π].
#[inline]
pub fn angle_diff<T: Real>(a: T, b: T) -> T {
    wrap_angle(a - b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;
    use proptest::prelude::*;

    #[test]
    fn boundaries() {
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(0.0_f64), 0.0);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-3.5 * PI) - 0.5 * PI).abs() < 1e-12);
        assert!((angle_diff(PI - 0.1, -PI + 0.1) - (-0.2)).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn wrapped_in_range_and_equivalent(a in -1e4_f64..1e4) {
            let w = wrap_angle(a);
            prop_assert!(w > -PI && w <= PI);
            // Same direction: the difference is a multiple of 2π.
            let k = (a - w) / (2.0 * PI);
            prop_assert!((k - k.round()).abs() < 1e-9);
        }

        #[test]
        fn wrapped_in_range_f32(a in -1e3_f32..1e3) {
            let w = wrap_angle(a);
            prop_assert!(w > -core::f32::consts::PI && w <= core::f32::consts::PI);
        }
    }
}

//! Input checks shared by every public constructor and filter step.

use crate::{Error, Real};
use nalgebra::{Cholesky, SMatrix};

/// Fails with [`Error::NonFinite`] unless `v` is finite.
#[inline]
pub(crate) fn finite<T: Real>(v: T, what: &'static str) -> Result<T, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite { what })
    }
}

/// Fails with [`Error::NonFinite`] unless every entry of `values` is finite.
#[inline]
pub(crate) fn all_finite<T: Real>(values: &[T], what: &'static str) -> Result<(), Error> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite { what })
    }
}

/// Fails unless `v` is finite and ≥ 0.
#[inline]
pub(crate) fn non_negative<T: Real>(v: T, what: &'static str) -> Result<T, Error> {
    finite(v, what)?;
    if v < T::zero() {
        Err(Error::NegativeVariance { what })
    } else {
        Ok(v)
    }
}

/// Fails unless `v` is finite and > 0.
#[inline]
pub(crate) fn positive<T: Real>(v: T, what: &'static str) -> Result<T, Error> {
    finite(v, what)?;
    if v > T::zero() {
        Ok(v)
    } else {
        Err(Error::OutOfRange {
            what,
            expected: "> 0",
        })
    }
}

/// Checks that `m` is a valid process-noise covariance: finite, symmetric and positive
/// *semi*-definite (a motion covariance may be singular, e.g. no lateral noise). Tested as
/// positive definiteness of `m + (ε·max|m_ij| + ε_m²)·I` with `ε_m` the machine epsilon
/// and `ε = √ε_m`, which passes any PSD matrix (rounding leaves its eigenvalues at most
/// about `−ε_m·scale`) and fails one with an eigenvalue below `−ε·scale`, however small
/// its scale; `ε_m²` keeps the zero matrix valid.
pub(crate) fn semi_definite<T: Real, const N: usize>(
    m: &SMatrix<T, N, N>,
    what: &'static str,
) -> Result<(), Error> {
    all_finite(m.as_slice(), what)?;
    let scale = m.amax();
    let eps = T::default_epsilon();
    let tol = eps.sqrt() * (T::one() + scale);
    for i in 0..N {
        for j in (i + 1)..N {
            if (m[(i, j)] - m[(j, i)]).abs() > tol * scale {
                return Err(Error::NotSymmetric { what });
            }
        }
        if m[(i, i)] < T::zero() {
            return Err(Error::NegativeVariance { what });
        }
    }
    let jittered = m + SMatrix::<T, N, N>::identity() * (eps.sqrt() * scale + eps * eps);
    if Cholesky::new(jittered).is_none() {
        return Err(Error::NotPositiveDefinite { what });
    }
    Ok(())
}

/// Whether the symmetric matrix `m` is positive definite: by Sylvester's criterion (all
/// leading principal minors > 0) for N ≤ 3, which is exact and much cheaper than a
/// factorisation at these sizes; by Cholesky above.
pub(crate) fn positive_definite<T: Real, const N: usize>(m: &SMatrix<T, N, N>) -> bool {
    let z = T::zero();
    match N {
        1 => m[(0, 0)] > z,
        2 => m[(0, 0)] > z && m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)] > z,
        3 => {
            let minor2 = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
            m[(0, 0)] > z && minor2 > z && det3(m) > z
        }
        _ => Cholesky::new(*m).is_some(),
    }
}

/// The determinant of the top-left 3×3 block (N ≥ 3).
fn det3<T: Real, const N: usize>(m: &SMatrix<T, N, N>) -> T {
    m[(0, 0)] * (m[(1, 1)] * m[(2, 2)] - m[(1, 2)] * m[(2, 1)])
        - m[(0, 1)] * (m[(1, 0)] * m[(2, 2)] - m[(1, 2)] * m[(2, 0)])
        + m[(0, 2)] * (m[(1, 0)] * m[(2, 1)] - m[(1, 1)] * m[(2, 0)])
}

/// The inverse of a symmetric positive definite `m`, or `None` if it is not positive
/// definite: closed forms for N ≤ 2 (the compass and line innovations), Cholesky above.
pub(crate) fn spd_inverse<T: Real, const N: usize>(
    m: &SMatrix<T, N, N>,
) -> Option<SMatrix<T, N, N>> {
    if !positive_definite(m) {
        return None;
    }
    match N {
        1 => Some(SMatrix::<T, N, N>::from_element(T::one() / m[(0, 0)])),
        2 => {
            let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
            let mut inv = SMatrix::<T, N, N>::zeros();
            inv[(0, 0)] = m[(1, 1)] / det;
            inv[(1, 1)] = m[(0, 0)] / det;
            inv[(0, 1)] = -m[(0, 1)] / det;
            inv[(1, 0)] = -m[(1, 0)] / det;
            Some(inv)
        }
        _ => Cholesky::new(*m).map(|c| c.inverse()),
    }
}

/// Checks that `m` is a valid covariance: finite, symmetric (to a relative tolerance
/// of √ε of its largest entry) and positive definite (Cholesky succeeds).
pub(crate) fn covariance<T: Real, const N: usize>(
    m: &SMatrix<T, N, N>,
    what: &'static str,
) -> Result<(), Error> {
    all_finite(m.as_slice(), what)?;
    let scale = m.amax();
    let tol = T::default_epsilon().sqrt() * scale;
    for i in 0..N {
        for j in (i + 1)..N {
            if (m[(i, j)] - m[(j, i)]).abs() > tol {
                return Err(Error::NotSymmetric { what });
            }
        }
    }
    if !positive_definite(m) {
        return Err(Error::NotPositiveDefinite { what });
    }
    Ok(())
}

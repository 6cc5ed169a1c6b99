//! numpy arrays in: any array-like of real numbers becomes a read-only `float64` array of
//! the expected shape, or a `TypeError`/`ValueError` that names the argument and says what
//! was expected. numpy arrays out: filled from Rust values.

use crate::errors::value_error;
use numpy::ndarray::{ArrayView, Dimension};
use numpy::{PyArray, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

/// numpy's `asarray`, looked up once.
fn asarray(py: Python<'_>) -> PyResult<&Bound<'_, PyAny>> {
    static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    ASARRAY
        .get_or_try_init(py, || {
            Ok::<_, PyErr>(py.import("numpy")?.getattr("asarray")?.unbind())
        })
        .map(|f| f.bind(py))
}

/// `obj` as a read-only `float64` array with `D` dimensions.
///
/// A `float64` ndarray is used as it is (no copy); other array-likes go through
/// `numpy.asarray` and must hold real numbers (float, integer or unsigned dtype): anything
/// else (complex, bool, strings, objects) is a `TypeError`. A wrong number of dimensions
/// is a `ValueError`. `name` is the argument's name in messages.
pub fn real_array<'py, D: Dimension>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArray<'py, f64, D>> {
    if let Ok(a) = obj.cast::<PyArray<f64, D>>() {
        return a.try_readonly().map_err(value_error);
    }
    let py = obj.py();
    let any = asarray(py)?
        .call1((obj,))
        .map_err(|e| PyTypeError::new_err(format!("{name}: not an array of numbers ({e})")))?;
    let array = any
        .cast::<numpy::PyUntypedArray>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: not an array of numbers")))?;
    let dtype = array.dtype();
    let kind = dtype.kind();
    if !matches!(kind, b'f' | b'i' | b'u') {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected real numbers (a float or integer dtype), got dtype {}",
            dtype.str()?
        )));
    }
    let expected = D::NDIM.unwrap_or(0);
    if array.ndim() != expected {
        return Err(PyValueError::new_err(format!(
            "{name}: expected a {expected}-dimensional array, got shape {}",
            shape_text(array.shape())
        )));
    }
    let floats = any.call_method1("astype", ("float64",))?;
    floats
        .cast_into::<PyArray<f64, D>>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: cannot convert to float64")))?
        .try_readonly()
        .map_err(value_error)
}

/// `(3, 2)`-style text of a shape.
pub fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// Fails unless `shape` matches `expected`, where `None` is any length. `what` describes
/// the expected shape in the message, e.g. `(N, 2)`.
pub fn check_shape(
    name: &str,
    shape: &[usize],
    expected: &[Option<usize>],
    what: &str,
) -> PyResult<()> {
    let ok = shape.len() == expected.len()
        && shape
            .iter()
            .zip(expected)
            .all(|(s, e)| e.is_none_or(|e| e == *s));
    if ok {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name}: expected shape {what}, got {}",
            shape_text(shape)
        )))
    }
}

/// Fails unless the first axis of `name` has `n` entries, one per entry of `of`.
pub fn check_len(name: &str, len: usize, n: usize, of: &str) -> PyResult<()> {
    if len == n {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name}: expected {n} rows (one per row of {of}), got {len}"
        )))
    }
}

/// Fails, naming the first offending element, unless every value is finite.
pub fn check_finite<D: Dimension>(name: &str, a: &ArrayView<'_, f64, D>) -> PyResult<()> {
    // `iter` runs in logical (row-major) order whatever the memory layout.
    let Some((flat, v)) = a.iter().enumerate().find(|(_, v)| !v.is_finite()) else {
        return Ok(());
    };
    let mut rest = flat;
    let mut index = vec![0; a.ndim()];
    for (slot, &len) in index.iter_mut().zip(a.shape()).rev() {
        *slot = rest % len.max(1);
        rest /= len.max(1);
    }
    let index: Vec<String> = index.iter().map(usize::to_string).collect();
    Err(PyValueError::new_err(format!(
        "{name}[{}] is {v}; expected a finite number",
        index.join(", ")
    )))
}

/// A pose `(x, y, θ)` from a sequence of three finite numbers.
pub fn pose3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<ekf_core::Pose2<f64>> {
    let a = real_array::<numpy::Ix1>(obj, name)?;
    let v = a.as_array();
    check_shape(name, v.shape(), &[Some(3)], "(3,) as (x, y, theta)")?;
    check_finite(name, &v)?;
    Ok(ekf_core::Pose2::new(v[0], v[1], v[2]))
}

/// A 3×3 matrix from an array-like of shape (3, 3) of finite numbers.
pub fn matrix3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<nalgebra::Matrix3<f64>> {
    let a = real_array::<numpy::Ix2>(obj, name)?;
    let v = a.as_array();
    check_shape(name, v.shape(), &[Some(3), Some(3)], "(3, 3)")?;
    check_finite(name, &v)?;
    Ok(nalgebra::Matrix3::from_fn(|i, j| v[[i, j]]))
}

/// A 2×2 matrix from a row-major view.
pub fn matrix2(v: &ArrayView<'_, f64, numpy::Ix2>) -> nalgebra::Matrix2<f64> {
    nalgebra::Matrix2::new(v[[0, 0]], v[[0, 1]], v[[1, 0]], v[[1, 1]])
}

/// A new `float64` array of `shape` filled row-major from `values`.
pub fn new_array<'py, D: Dimension>(
    py: Python<'py>,
    values: Vec<f64>,
    shape: D,
) -> PyResult<Bound<'py, PyArray<f64, D>>> {
    let flat = numpy::ndarray::Array1::from(values);
    let shaped = flat.into_shape_with_order(shape).map_err(value_error)?;
    Ok(PyArray::from_owned_array(py, shaped))
}

/// A 3×3 matrix as a `(3, 3)` array.
pub fn matrix3_array<'py>(
    py: Python<'py>,
    m: &nalgebra::Matrix3<f64>,
) -> PyResult<Bound<'py, PyArray<f64, numpy::Ix2>>> {
    new_array(py, row_major3(m).to_vec(), numpy::Ix2(3, 3))
}

/// The nine entries of a 3×3 matrix, row by row.
pub fn row_major3(m: &nalgebra::Matrix3<f64>) -> [f64; 9] {
    [
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 0)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 0)],
        m[(2, 1)],
        m[(2, 2)],
    ]
}

/// The four entries of a 2×2 matrix, row by row.
pub fn row_major2(m: &nalgebra::Matrix2<f64>) -> [f64; 4] {
    [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]]
}

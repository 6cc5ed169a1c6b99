//! Parameter groups from Python dicts: the same serde structs (and so the same field names,
//! defaults and "unknown field" errors) as the TOML config file of `ekf config`.

use crate::errors::{file_error, value_error};
use ekf_ros::config::Config;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::PathBuf;

/// Python's `json` module function `name`, looked up once per name.
fn json_fn<'py>(
    py: Python<'py>,
    cell: &'static PyOnceLock<Py<PyAny>>,
    name: &str,
) -> PyResult<&'py Bound<'py, PyAny>> {
    cell.get_or_try_init(py, || {
        Ok::<_, PyErr>(py.import("json")?.getattr(name)?.unbind())
    })
    .map(|f| f.bind(py))
}

/// `T` from a dict (missing fields take their defaults), or the default for `None`.
/// `name` is the argument's name in messages: `params: unknown field ...`.
pub fn from_dict<T: DeserializeOwned + Default>(
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<T> {
    let Some(obj) = obj else {
        return Ok(T::default());
    };
    if obj.is_none() {
        return Ok(T::default());
    }
    let dict = obj
        .cast::<PyDict>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a dict or None")))?;
    static DUMPS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let text: String = json_fn(obj.py(), &DUMPS, "dumps")?
        .call1((dict,))
        .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?
        .extract()?;
    serde_json::from_str(&text).map_err(|e| value_error(format!("{name}: {e}")))
}

/// A serde value as a Python object (dicts, lists, numbers, strings), through JSON.
pub fn to_python<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(value_error)?;
    static LOADS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    json_fn(py, &LOADS, "loads")?.call1((text,))
}

/// The `ekf` configuration: the defaults for `None`, a TOML file for a path (as
/// `--config`), or a dict of the same groups and keys.
pub fn load_config(config: Option<&Bound<'_, PyAny>>) -> PyResult<Config> {
    match config {
        Some(c) if c.is_instance_of::<PyDict>() => from_dict::<Config>(Some(c), "config")?
            .validated("config")
            .map_err(value_error),
        Some(c) if !c.is_none() => {
            let path: PathBuf = c.extract().map_err(|_| {
                PyTypeError::new_err("config: expected a path to a TOML file, a dict or None")
            })?;
            Config::load(&path).map_err(|e| file_error(&e))
        }
        _ => Ok(Config::default()),
    }
}

//! Conversions between Python objects, TOML values and JSON values.
//!
//! A Python value can be anything: nested without end (a list that contains itself), a
//! hundred thousand levels deep, a million items long, or an object whose `tolist()` returns
//! another such object. The conversion walks it with an explicit depth and item budget and
//! a record of the containers on the current path, so it ends with a [`crate::errors::SceneError`]
//! naming the key instead of overflowing the stack (which would kill the interpreter).
//! The TOML and JSON values converted back to Python come from parsed scene files and
//! `summary.json`, whose depth the TOML parser and the limits below already bound.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::key_error;

/// Deepest nesting of a value written into a scene (tables and arrays): a scene file needs
/// at most five levels (`machine.legs.0.anchor.1`), so 32 leaves room and stays far from the
/// stack's limit.
pub const MAX_VALUE_DEPTH: usize = 32;

/// Most items (scalars, tables and arrays together) in one value written into a scene:
/// a long waypoint list has some thousands.
pub const MAX_VALUE_ITEMS: usize = 1_000_000;

/// Walk state: containers on the current path (by identity) and items seen.
struct Walk {
    path: Vec<usize>,
    items: usize,
}

/// A Python value as a TOML value: `bool`, `int` (64-bit), `float`, `str`, `dict` (string
/// keys), `list`/`tuple` and anything with a `tolist()` (NumPy scalars and arrays). `key`
/// names the value in errors.
///
/// # Errors
/// `SceneError` at `key` for an unsupported type, a cycle, nesting deeper than
/// [`MAX_VALUE_DEPTH`] or more than [`MAX_VALUE_ITEMS`] items.
pub fn py_to_toml(value: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    let mut walk = Walk {
        path: Vec::new(),
        items: 0,
    };
    convert(value, key, &mut walk)
}

/// A Python dict with string keys as a TOML table (see [`py_to_toml`]); `prefix` is the
/// dotted key of the dict, empty for a whole scene.
///
/// # Errors
/// As [`py_to_toml`].
pub fn dict_to_table(dict: &Bound<'_, PyDict>, prefix: &str) -> PyResult<toml::Table> {
    let mut walk = Walk {
        path: Vec::new(),
        items: 0,
    };
    match convert(dict.as_any(), prefix, &mut walk)? {
        toml::Value::Table(t) => Ok(t),
        _ => Err(key_error(prefix, "expected a dict".to_string())),
    }
}

fn convert(value: &Bound<'_, PyAny>, key: &str, walk: &mut Walk) -> PyResult<toml::Value> {
    walk.items += 1;
    if walk.items > MAX_VALUE_ITEMS {
        return Err(key_error(
            key,
            format!("holds more than {MAX_VALUE_ITEMS} items; a scene value is far smaller"),
        ));
    }
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.is_truthy()?));
    }
    if value.is_instance_of::<PyInt>() {
        return value
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| {
                key_error(
                    key,
                    format!("the integer {} does not fit in 64 bits", short_repr(value)),
                )
            });
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return value
            .extract::<String>()
            .map(toml::Value::String)
            .map_err(|_| {
                key_error(
                    key,
                    "a string that is not valid Unicode text (lone surrogates)".to_string(),
                )
            });
    }
    let is_dict = value.is_instance_of::<PyDict>();
    let is_seq = value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>();
    let has_tolist = !is_dict && !is_seq && value.hasattr("tolist").unwrap_or(false);
    if !(is_dict || is_seq || has_tolist) {
        return Err(key_error(
            key,
            format!(
                "a value of type {} cannot be written into a scene (expected bool, int, float, str, dict or list)",
                value
                    .get_type()
                    .name()
                    .map_or_else(|_| "?".to_string(), |n| n.to_string())
            ),
        ));
    }
    // A container (or an object standing for one): check the path for a cycle and the depth.
    let id = value.as_ptr() as usize;
    if walk.path.contains(&id) {
        return Err(key_error(
            key,
            "the value contains itself (a cycle); a scene value must be a tree".to_string(),
        ));
    }
    if walk.path.len() >= MAX_VALUE_DEPTH {
        return Err(key_error(
            key,
            format!("nested deeper than {MAX_VALUE_DEPTH} levels; a scene needs at most a few"),
        ));
    }
    walk.path.push(id);
    let out = if is_dict {
        convert_dict(value, key, walk)
    } else if is_seq {
        convert_seq(value, key, walk)
    } else {
        // NumPy scalars and arrays: their plain Python form.
        let plain = value.call_method0("tolist")?;
        if plain.is(value) {
            Err(key_error(
                key,
                "an object whose tolist() returns itself".to_string(),
            ))
        } else {
            convert(&plain, key, walk)
        }
    };
    walk.path.pop();
    out
}

fn convert_dict(value: &Bound<'_, PyAny>, key: &str, walk: &mut Walk) -> PyResult<toml::Value> {
    // A snapshot of the items: converting a value may run Python code (tolist) that
    // changes the dict.
    let items = value.cast::<PyDict>()?.items();
    let mut table = toml::Table::new();
    for item in items.iter() {
        let (k, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract()?;
        let name: String = k.extract().map_err(|_| {
            key_error(
                key,
                format!(
                    "dict keys must be strings, got {}",
                    k.get_type()
                        .name()
                        .map_or_else(|_| "?".to_string(), |n| n.to_string())
                ),
            )
        })?;
        let path = if key.is_empty() {
            name.clone()
        } else {
            format!("{key}.{name}")
        };
        table.insert(name, convert(&v, &path, walk)?);
    }
    Ok(toml::Value::Table(table))
}

fn convert_seq(value: &Bound<'_, PyAny>, key: &str, walk: &mut Walk) -> PyResult<toml::Value> {
    let mut items = Vec::new();
    for (i, item) in value.try_iter()?.enumerate() {
        items.push(convert(&item?, &format!("{key}.{i}"), walk)?);
    }
    Ok(toml::Value::Array(items))
}

/// `repr(value)` cut to 40 characters (a huge integer prints thousands of digits).
fn short_repr(value: &Bound<'_, PyAny>) -> String {
    let text = value
        .repr()
        .map_or_else(|_| "?".to_string(), |r| r.to_string());
    if text.chars().count() > 40 {
        format!("{}...", text.chars().take(37).collect::<String>())
    } else {
        text
    }
}

/// A TOML value as a Python value (tables become dicts, arrays lists, datetimes strings).
pub fn toml_to_py<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        toml::Value::String(s) => PyString::new(py, s).into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(x) => PyFloat::new(py, *x).into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        toml::Value::Array(a) => {
            let list = PyList::empty(py);
            for item in a {
                list.append(toml_to_py(py, item)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(t) => table_to_py(py, t)?.into_any(),
    })
}

/// A TOML table as a Python dict.
pub fn table_to_py<'py>(py: Python<'py>, table: &toml::Table) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (k, v) in table {
        dict.set_item(k, toml_to_py(py, v)?)?;
    }
    Ok(dict)
}

/// A JSON value as a Python value (`null` becomes `None`).
pub fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        serde_json::Value::Null => py.None().into_bound(py),
        serde_json::Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        serde_json::Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any()
            }
        }
        serde_json::Value::String(s) => PyString::new(py, s).into_any(),
        serde_json::Value::Array(a) => {
            let list = PyList::empty(py);
            for item in a {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        serde_json::Value::Object(o) => {
            let dict = PyDict::new(py);
            for (k, v) in o {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// A Python value made of `None`, `bool`, `int`, `float`, `str`, `list` and `dict` (string
/// keys) as a JSON value, exactly (floats keep every bit; the inverse of [`json_to_py`]).
/// Non-finite floats become `null`, as JSON has no other form for them.
///
/// # Errors
/// `ValueError` for another type or nesting deeper than [`MAX_VALUE_DEPTH`].
pub fn py_to_json(value: &Bound<'_, PyAny>, depth: usize) -> PyResult<serde_json::Value> {
    use pyo3::exceptions::PyValueError;
    if depth > MAX_VALUE_DEPTH {
        return Err(PyValueError::new_err(format!(
            "nested deeper than {MAX_VALUE_DEPTH} levels"
        )));
    }
    if value.is_none() {
        return Ok(serde_json::Value::Null);
    }
    if value.is_instance_of::<PyBool>() {
        return Ok(serde_json::Value::Bool(value.is_truthy()?));
    }
    if value.is_instance_of::<PyInt>() {
        if let Ok(i) = value.extract::<i64>() {
            return Ok(i.into());
        }
        return Ok(value.extract::<u64>()?.into());
    }
    if value.is_instance_of::<PyFloat>() {
        let x: f64 = value.extract()?;
        return Ok(serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, Into::into));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(serde_json::Value::String(value.extract()?));
    }
    if let Ok(list) = value.cast::<PyList>() {
        return list
            .iter()
            .map(|item| py_to_json(&item, depth + 1))
            .collect::<PyResult<Vec<_>>>()
            .map(serde_json::Value::Array);
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for item in dict.items().iter() {
            let (k, v): (String, Bound<'_, PyAny>) = item.extract()?;
            map.insert(k, py_to_json(&v, depth + 1)?);
        }
        return Ok(serde_json::Value::Object(map));
    }
    Err(PyValueError::new_err(format!(
        "a value of type {} has no JSON form",
        value
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string())
    )))
}

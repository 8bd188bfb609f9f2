//! `chainbeam.Scene`: a validated scene (the library's [`chainbeam::Scene`]) and the directory its
//! load `series` files are named relative to.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{self, raise};

/// A validated beam scene (the scene file format of `docs/scene-format.md`).
///
/// Build one with `Scene.from_file(path)` or `Scene.from_toml(text)`; `scene.to_toml()` gives the
/// file back (every value explicit) and `scene.replace({"dotted.key": value})` a changed copy.
/// Scenes are immutable, comparable with `==` and picklable (a scene travels as its TOML text and
/// the directory its load `series` files are relative to; the files are read again where it is
/// unpickled).
#[pyclass(module = "chainbeam", frozen, eq)]
#[derive(Clone, PartialEq)]
pub struct Scene {
    /// The scene.
    pub inner: chainbeam::Scene,
    /// The directory relative `series` file names are read from (`None`: the current one).
    pub dir: Option<PathBuf>,
}

impl Scene {
    /// Parses `text` with series files relative to `dir`.
    fn parse(py: Python<'_>, text: &str, dir: Option<PathBuf>) -> PyResult<Self> {
        let parsed = match &dir {
            Some(d) => chainbeam::Scene::from_toml_str_in_dir(text, d),
            None => chainbeam::Scene::from_toml_str(text),
        };
        match parsed {
            Ok(inner) => Ok(Scene { inner, dir }),
            Err(e) => Err(errors::lib(py, e.into())),
        }
    }
}

#[pymethods]
impl Scene {
    /// Reads, parses and validates a scene file; errors name the file and the key. Relative
    /// `series` file names are read from the file's directory.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        match chainbeam::Scene::from_file(&path) {
            Ok(inner) => Ok(Scene {
                inner,
                dir: Some(path.parent().unwrap_or(Path::new("")).to_path_buf()),
            }),
            Err(e) => Err(errors::lib(py, e.into())),
        }
    }

    /// Parses and validates a scene file's text; relative `series` file names are read from
    /// `dir` (default: the current directory).
    #[staticmethod]
    #[pyo3(signature = (text, dir=None))]
    fn from_toml(py: Python<'_>, text: &str, dir: Option<PathBuf>) -> PyResult<Self> {
        Scene::parse(py, text, dir)
    }

    /// The scene as a scene file (TOML), every value explicit:
    /// `Scene.from_toml(s.to_toml()) == s`.
    fn to_toml(&self) -> String {
        self.inner.to_toml_string()
    }

    /// A new scene with the keys of `changes` set: dotted paths into the scene file
    /// (`"loads.drag"`, `"beam.stiffness"`, `"loads.point[0].force"`), values numbers, strings,
    /// booleans, lists or dicts. The result is validated like a file; an error names the key.
    fn replace(&self, py: Python<'_>, changes: &Bound<'_, PyDict>) -> PyResult<Self> {
        let text = self.inner.to_toml_string();
        let mut doc: toml::Table = text
            .parse()
            .map_err(|e| errors::internal(py, &format!("cannot re-read the scene's TOML: {e}")))?;
        for (k, v) in changes.iter() {
            let key: String = k.extract().map_err(|_| {
                scene_error(
                    py,
                    "<key>",
                    "the keys of `changes` must be strings (dotted paths)",
                )
            })?;
            let value = to_toml(py, &key, &v)?;
            set_path(py, &mut doc, &key, value)?;
        }
        Scene::parse(py, &doc.to_string(), self.dir.clone())
    }

    /// Number of pendulums n.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n()
    }

    /// Number of time steps N (`time.steps`).
    #[getter]
    fn steps(&self) -> usize {
        self.inner.time.steps
    }

    /// The time step h in s (`time.step`).
    #[getter]
    fn step(&self) -> f64 {
        self.inner.time.step
    }

    /// Whether the scene needs the spatial model (a load, the current or the control has an x
    /// component).
    #[getter]
    fn is_spatial(&self) -> bool {
        self.inner.is_spatial()
    }

    fn __repr__(&self) -> String {
        format!(
            "chainbeam.Scene(n={}, steps={}, step={}, spatial={})",
            self.inner.n(),
            self.inner.time.steps,
            self.inner.time.step,
            self.inner.is_spatial()
        )
    }

    /// Pickling: the TOML text and the series directory.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("chainbeam._chainbeam")?
            .getattr("_scene_from_state")?;
        let dir = self.dir.as_ref().map(|d| d.display().to_string());
        let args = PyTuple::new(
            py,
            [
                self.inner.to_toml_string().into_pyobject(py)?.into_any(),
                dir.into_pyobject(py)?.into_any(),
            ],
        )?;
        Ok((f, args))
    }
}

/// Unpickles a scene (its TOML text and series directory).
#[pyfunction]
#[pyo3(signature = (text, dir=None))]
pub fn _scene_from_state(py: Python<'_>, text: &str, dir: Option<PathBuf>) -> PyResult<Scene> {
    Scene::parse(py, text, dir)
}

/// `chainbeam.SceneError` naming `key`.
fn scene_error(py: Python<'_>, key: &str, reason: &str) -> PyErr {
    let msg = format!("invalid scene: key `{key}`: {reason}");
    raise(py, "SceneError", &msg, "InvalidValue", Some(key), None)
}

/// A Python value as a TOML value (for the key `key`'s messages).
fn to_toml(py: Python<'_>, key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        let i: i64 = v
            .extract()
            .map_err(|_| scene_error(py, key, "the integer does not fit 64 bits"))?;
        return Ok(toml::Value::Integer(i));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k.extract()?;
            let sub = format!("{key}.{k}");
            t.insert(k, to_toml(py, &sub, &x)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() || v.hasattr("tolist")? {
        // Lists, tuples and numpy arrays or scalars (`tolist()` gives Python numbers).
        let v = if v.hasattr("tolist")? {
            v.call_method0("tolist")?
        } else {
            v.clone()
        };
        if !(v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>()) {
            return to_toml(py, key, &v);
        }
        let mut out = Vec::new();
        for (i, x) in v.try_iter()?.enumerate() {
            out.push(to_toml(py, &format!("{key}[{i}]"), &x?)?);
        }
        return Ok(toml::Value::Array(out));
    }
    let type_name = v.get_type().name()?.to_string();
    Err(scene_error(
        py,
        key,
        &format!("cannot write a Python {type_name} into a scene (numbers, strings, booleans, lists and dicts only)"),
    ))
}

/// One step of a dotted path: a key and, for `name[i]`, an index into an array of tables.
fn split_segment(seg: &str) -> Option<(&str, Option<usize>)> {
    match seg.split_once('[') {
        None => Some((seg, None)),
        Some((name, rest)) => {
            let i = rest.strip_suffix(']')?.parse().ok()?;
            Some((name, Some(i)))
        }
    }
}

/// Sets `value` at the dotted path `key` of `doc`, creating tables on the way.
fn set_path(py: Python<'_>, doc: &mut toml::Table, key: &str, value: toml::Value) -> PyResult<()> {
    let segs: Vec<&str> = key.split('.').collect();
    if key.is_empty() || segs.iter().any(|s| s.is_empty()) {
        return Err(scene_error(
            py,
            key,
            "not a dotted path (e.g. `loads.drag`)",
        ));
    }
    let mut table = doc;
    let mut walked = String::new();
    for (j, seg) in segs.iter().enumerate() {
        let (name, index) = split_segment(seg).ok_or_else(|| {
            scene_error(
                py,
                key,
                &format!("`{seg}` is neither a key nor `name[index]`"),
            )
        })?;
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(seg);
        let last = j + 1 == segs.len();
        match (index, last) {
            (None, true) => {
                table.insert(name.to_string(), value);
                return Ok(());
            }
            (None, false) => {
                let entry = table
                    .entry(name.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                table = entry.as_table_mut().ok_or_else(|| {
                    scene_error(
                        py,
                        &walked,
                        "is a value, not a table: it has no keys below it",
                    )
                })?;
            }
            (Some(i), _) => {
                let arr = table.get_mut(name).and_then(toml::Value::as_array_mut);
                let len = arr.as_ref().map_or(0, |a| a.len());
                let slot = arr.and_then(|a| a.get_mut(i)).ok_or_else(|| {
                    scene_error(
                        py,
                        &walked,
                        &format!("index {i} is out of range (the scene has {len})"),
                    )
                })?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                table = slot.as_table_mut().ok_or_else(|| {
                    scene_error(
                        py,
                        &walked,
                        "is a value, not a table: it has no keys below it",
                    )
                })?;
            }
        }
    }
    Ok(())
}

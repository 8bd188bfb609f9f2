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
    /// booleans, lists or dicts. A dict given for a table is merged into it key by key
    /// (`{"loads": {"drag": 1.0}}` changes `loads.drag` and keeps the table's other keys, as
    /// `{"loads.drag": 1.0}` does); a dict where the scene has a value, or a value where it has
    /// a table, is refused naming the key. A list replaces the whole list (it is the value).
    /// The result is validated like a file; an error names the key.
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

    /// The value at a dotted path of the scene file (`scene["loads.tension"]`,
    /// `scene["beam.stiffness"]`, `scene["loads.point[0].force"]`, `scene["fatigue"]`), every
    /// value explicit as in `to_toml()`: a number, string, boolean, list or dict. A key the
    /// scene does not have raises `KeyError` naming it and the keys that are there.
    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let doc: toml::Table =
            self.inner.to_toml_string().parse().map_err(|e| {
                errors::internal(py, &format!("cannot re-read the scene's TOML: {e}"))
            })?;
        let value = get_path(&doc, key).map_err(pyo3::exceptions::PyKeyError::new_err)?;
        from_toml(py, value)
    }

    /// Whether `key` (a dotted path) is a key of the scene file (`"loads.waves" in scene`).
    fn __contains__(&self, key: &str) -> bool {
        self.inner
            .to_toml_string()
            .parse::<toml::Table>()
            .is_ok_and(|doc| get_path(&doc, key).is_ok())
    }

    /// The pendulum lengths l₁..lₙ \[m\] (from `[beam]` or the `[pipe]`), base first.
    #[getter]
    fn lengths(&self) -> Vec<f64> {
        self.inner.beam.lengths.clone()
    }

    /// The base pendulum's length l₁ \[m\]: the wellhead moment is M_w = M₀·l₁/2
    /// (docs/conventions.md "The wellhead moment M_w").
    #[getter]
    fn l1(&self) -> f64 {
        self.inner.beam.lengths[0]
    }

    /// The beam's length L = Σ lᵢ \[m\].
    #[getter]
    fn length(&self) -> f64 {
        self.inner.beam.lengths.iter().sum()
    }

    /// The run's duration T = N h \[s\] (`time.steps` × `time.step`).
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.time.steps as f64 * self.inner.time.step
    }

    /// The pipe's section and derived values (`[pipe]`; None for a scene given by its beam):
    /// `outer_diameter`, `wall_thickness`, `inner_diameter` \[m\], `steel_area` A_s =
    /// π/4 (D_o² − D_i²) \[m²\], `second_moment` I = π/64 (D_o⁴ − D_i⁴) \[m⁴\],
    /// `bending_stiffness` EI \[N m²\], `mass_per_length` μ = ρ_s A_s + ρ_c A_i + C_a ρ_w A_o
    /// \[kg/m\] and `submerged_weight` w = g (ρ_s A_s + ρ_c A_i − ρ_w A_o) \[N/m\] with the
    /// standard g = 9.80665 m/s² (the library's `Pipe`; the value for `loads.axial_weight`).
    #[getter]
    fn section<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(p) = &self.inner.pipe else {
            return Ok(None);
        };
        let rho_w = self.inner.water.density;
        let d = PyDict::new(py);
        d.set_item("outer_diameter", p.outer_diameter)?;
        d.set_item("wall_thickness", p.wall_thickness)?;
        d.set_item("inner_diameter", p.inner_diameter())?;
        d.set_item("steel_area", p.steel_area())?;
        d.set_item("second_moment", p.second_moment())?;
        d.set_item("bending_stiffness", p.bending_stiffness())?;
        d.set_item("mass_per_length", p.mass_per_length(rho_w))?;
        // Standard gravity: a riser's [loads] has gravity 0, its weight being `axial_weight`.
        d.set_item(
            "submerged_weight",
            p.submerged_weight(rho_w, chainbeam::ocean::STANDARD_GRAVITY),
        )?;
        Ok(Some(d))
    }

    /// Whether the scene has a `[fatigue]` table (what `chainbeam.fatigue` needs).
    #[getter]
    fn has_fatigue(&self) -> bool {
        self.inner.fatigue.is_some()
    }

    /// Whether the scene has an irregular sea (`[loads.waves]`).
    #[getter]
    fn has_waves(&self) -> bool {
        self.inner.loads.waves.is_some()
    }

    fn __repr__(&self) -> String {
        format!(
            "chainbeam.Scene(n={}, steps={}, step={}, duration={} s, length={} m, spatial={})",
            self.inner.n(),
            self.inner.time.steps,
            self.inner.time.step,
            self.duration(),
            self.length(),
            if self.inner.is_spatial() {
                "True"
            } else {
                "False"
            }
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

/// A TOML value as a Python object (integers as `int`, tables as `dict`).
fn from_toml<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(from_toml(py, x)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, from_toml(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// The value at the dotted path `key` of `doc`, or a message naming the key and what is there.
fn get_path<'a>(doc: &'a toml::Table, key: &str) -> Result<&'a toml::Value, String> {
    let mut here: Option<&toml::Value> = None;
    let mut table = Some(doc);
    let mut walked = String::new();
    for seg in key.split('.') {
        let Some((name, index)) = split_segment(seg).filter(|(n, _)| !n.is_empty()) else {
            return Err(format!(
                "scene key `{key}`: `{seg}` is neither a key nor `name[index]`"
            ));
        };
        let Some(t) = table else {
            return Err(format!(
                "scene key `{key}`: `{walked}` is a value, not a table: it has no keys below it"
            ));
        };
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(seg);
        let mut v = t.get(name).ok_or_else(|| {
            let keys: Vec<&str> = t.keys().map(String::as_str).collect();
            format!(
                "scene key `{key}`: the scene has no `{walked}` (keys there: {})",
                keys.join(", ")
            )
        })?;
        if let Some(i) = index {
            let arr = v.as_array().ok_or_else(|| {
                format!("scene key `{key}`: `{name}` is not a list, it has no `[{i}]`")
            })?;
            v = arr.get(i).ok_or_else(|| {
                format!(
                    "scene key `{key}`: index {i} is out of range (the scene has {})",
                    arr.len()
                )
            })?;
        }
        table = v.as_table();
        here = Some(v);
    }
    here.ok_or_else(|| format!("scene key `{key}`: empty"))
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

/// Puts `value` into `slot` (the value at `key`): a table into a table key by key, recursively
/// (so that nothing of the scene's table is dropped); a table into a value, or a value into a
/// table, is refused (the caller meant one or the other, and guessing would drop something).
fn merge(py: Python<'_>, key: &str, slot: &mut toml::Value, value: toml::Value) -> PyResult<()> {
    match (slot, value) {
        (toml::Value::Table(old), toml::Value::Table(new)) => {
            for (k, v) in new {
                let sub = format!("{key}.{k}");
                match old.get_mut(&k) {
                    Some(existing) => merge(py, &sub, existing, v)?,
                    None => {
                        old.insert(k, v);
                    }
                }
            }
            Ok(())
        }
        (toml::Value::Table(_), v) => Err(scene_error(
            py,
            key,
            &format!(
                "is a table of the scene; give a dict of its keys (merged into it) or set them \
                 one by one (`{key}.KEY`), not a {}",
                v.type_str()
            ),
        )),
        (old, toml::Value::Table(_)) => Err(scene_error(
            py,
            key,
            &format!(
                "is a {} of the scene, not a table: a dict cannot be merged into it",
                old.type_str()
            ),
        )),
        (old, v) => {
            *old = v;
            Ok(())
        }
    }
}

/// Sets `value` at the dotted path `key` of `doc`, creating tables on the way; a dict given for
/// an existing table is merged into it ([`merge`]).
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
                match table.get_mut(name) {
                    Some(slot) => merge(py, key, slot, value)?,
                    None => {
                        table.insert(name.to_string(), value);
                    }
                }
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
                    return merge(py, key, slot, value);
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

//! The library's errors as the Python package's exceptions (`python/chainbeam/_errors.py`), with
//! the library's messages: `chainbeam::Error::Scene` → `SceneError` (a `ValueError`, with `.key`
//! and `.file`), the Newton and static solves that did not converge → `ConvergenceError`, the
//! other failures of a computation → `SimulationError`, a trajectory over the memory budget →
//! `TrajectoryTooLargeError` (a `MemoryError`), arguments → `InvalidArgumentError` (a
//! `ValueError`, `.key` the argument). Every exception carries `.kind`, the Rust variant's name.

use chainbeam::Error;
use pyo3::prelude::*;

/// A failure computed on a worker thread, turned into a Python exception once the GIL is held.
#[derive(Debug)]
pub enum Failure {
    /// An error of the library.
    Lib(Error),
    /// An argument of a Python call (its name and what is wrong).
    Argument {
        /// The argument, e.g. `controls`.
        name: String,
        /// The message.
        message: String,
    },
    /// A scene without what the call needs (`SceneError`, `.key` the scene key).
    SceneKey {
        /// The scene key, e.g. `fatigue`.
        key: String,
        /// The message.
        message: String,
    },
    /// A run whose stored trajectory is over the library's memory budget
    /// (`TrajectoryTooLargeError`, `.key` the scene key to change, `time.steps`).
    TooLarge {
        /// The scene key.
        key: String,
        /// The message.
        message: String,
    },
    /// A bug or an operating-system failure.
    Internal(String),
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure::Lib(e)
    }
}

impl Failure {
    /// An argument error.
    pub fn argument(name: &str, message: impl Into<String>) -> Self {
        Failure::Argument {
            name: name.into(),
            message: message.into(),
        }
    }

    /// The Python exception.
    pub fn into_py(self, py: Python<'_>) -> PyErr {
        match self {
            Failure::Lib(e) => lib(py, e),
            Failure::Argument { name, message } => raise(
                py,
                "InvalidArgumentError",
                &message,
                "InvalidArgument",
                Some(&name),
                None,
            ),
            Failure::SceneKey { key, message } => {
                raise(py, "SceneError", &message, "Scene", Some(&key), None)
            }
            Failure::TooLarge { key, message } => raise(
                py,
                "TrajectoryTooLargeError",
                &message,
                "TrajectoryTooLarge",
                Some(&key),
                None,
            ),
            Failure::Internal(m) => internal(py, &m),
        }
    }
}

/// The check a run that stores its trajectory makes first ([`chainbeam::Scene::check_stored_trajectory`]),
/// as the documented `TrajectoryTooLargeError` rather than the scene's error it is in the
/// library (the scene is valid; the run asked of it is too long to keep in memory).
pub fn check_stored(scene: &chainbeam::Scene) -> Result<(), Failure> {
    scene
        .check_stored_trajectory()
        .map_err(|e| Failure::TooLarge {
            key: e.key().unwrap_or("time.steps").to_string(),
            message: e.to_string(),
        })
}

/// `Result<T, Failure>` → `PyResult<T>`.
pub fn check<T>(py: Python<'_>, r: Result<T, Failure>) -> PyResult<T> {
    r.map_err(|f| f.into_py(py))
}

/// An instance of `chainbeam._errors.<class>(message, kind, key, file)` as a `PyErr` (or the
/// error of building it).
pub fn raise(
    py: Python<'_>,
    class: &str,
    message: &str,
    kind: &str,
    key: Option<&str>,
    file: Option<String>,
) -> PyErr {
    let exc = py
        .import("chainbeam._errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call1((message, kind, key, file)));
    match exc {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

/// `chainbeam.ChainbeamError` for a bug or an operating-system failure.
pub fn internal(py: Python<'_>, message: &str) -> PyErr {
    raise(py, "ChainbeamError", message, "Internal", None, None)
}

/// The exception class and variant name of a library error.
fn class_of(e: &Error) -> (&'static str, &'static str) {
    match e {
        Error::Scene(_) => ("SceneError", "Scene"),
        Error::NewtonNotConverged { .. } => ("ConvergenceError", "NewtonNotConverged"),
        Error::StaticNotConverged { .. } => ("ConvergenceError", "StaticNotConverged"),
        Error::Folded { .. } => ("SimulationError", "Folded"),
        Error::SingularSystem { .. } => ("SimulationError", "SingularSystem"),
        Error::NonFinite { .. } => ("SimulationError", "NonFinite"),
        Error::StaticSingular { .. } => ("SimulationError", "StaticSingular"),
        Error::StaticFolded { .. } => ("SimulationError", "StaticFolded"),
        Error::StaticNotIsolated { .. } => ("SimulationError", "StaticNotIsolated"),
        Error::NonFiniteObjective { .. } => ("SimulationError", "NonFiniteObjective"),
        Error::Cancelled => ("ChainbeamError", "Cancelled"),
        Error::TrajectoryTooLarge { .. } => ("TrajectoryTooLargeError", "TrajectoryTooLarge"),
        Error::NeedsSpatialModel { .. } => ("InvalidArgumentError", "NeedsSpatialModel"),
        Error::WrongLength { .. } => ("InvalidArgumentError", "WrongLength"),
        Error::NotFinite { .. } => ("InvalidArgumentError", "NotFinite"),
        Error::NoSuchParameter { .. } => ("InvalidArgumentError", "NoSuchParameter"),
        Error::InvalidStep { .. } => ("InvalidArgumentError", "InvalidStep"),
        Error::NoEffect { .. } => ("InvalidArgumentError", "NoEffect"),
        Error::ControlOutOfRange { .. } => ("InvalidArgumentError", "ControlOutOfRange"),
        Error::Mpc(_) => ("InvalidArgumentError", "Mpc"),
        Error::Ocp(_) => ("InvalidArgumentError", "Ocp"),
        Error::Optimize(_) => ("InvalidArgumentError", "Optimize"),
        Error::Model(_) => ("InvalidArgumentError", "Model"),
        Error::Stepper(_) => ("InvalidArgumentError", "Stepper"),
        Error::Start(_) => ("InvalidArgumentError", "Start"),
        Error::Multistart(_) => ("InvalidArgumentError", "Multistart"),
        Error::EulerBernoulli(_) => ("InvalidArgumentError", "EulerBernoulli"),
        _ => ("ChainbeamError", "Other"),
    }
}

/// The key an error names: a scene key, or the argument's name.
fn key_of(e: &Error) -> Option<String> {
    match e {
        Error::Scene(se) => se.key().map(String::from),
        Error::NeedsSpatialModel { key } => Some(key.clone()),
        other => other.argument().map(String::from),
    }
}

/// A library error as its Python exception, with the library's message.
pub fn lib(py: Python<'_>, e: Error) -> PyErr {
    let (class, kind) = class_of(&e);
    let file = match &e {
        Error::Scene(se) => se.file.as_ref().map(|f| f.display().to_string()),
        _ => None,
    };
    raise(py, class, &e.to_string(), kind, key_of(&e).as_deref(), file)
}

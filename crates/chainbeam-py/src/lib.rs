//! `chainbeam._chainbeam`: the Python extension module of chainbeam (pyo3, abi3 ≥ 3.10).
//!
//! The Python package `chainbeam` (repository folder `python/chainbeam`) wraps this module: its
//! functions return plain dicts of numpy arrays and numbers, which the package turns into result
//! objects, and its errors are raised as the package's exception classes (`chainbeam.SceneError`,
//! `chainbeam.ConvergenceError`, …; [`errors`]). Every computation runs with the GIL released on a
//! worker thread while the calling thread waits for it and checks for Ctrl-C ([`run`]).
//!
//! Module map: [`scene`] the `Scene` class; [`run`] GIL release, interrupts and rayon pools;
//! [`errors`] the library's errors as Python exceptions; [`calls`] simulate and gradient;
//! [`optim`] optimize and mpc; [`fatigue`] the fatigue assessment and studies; [`design`] the design for fatigue.

use pyo3::prelude::*;

mod calls;
mod design;
mod errors;
mod fatigue;
mod optim;
mod run;
mod scene;

/// The extension module. Its names are re-exported, documented and typed by the `chainbeam`
/// package (`python/chainbeam/__init__.py`, `_chainbeam.pyi`).
#[pymodule]
fn _chainbeam(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::Scene>()?;
    m.add_class::<calls::LibraryTrajectory>()?;
    m.add_function(wrap_pyfunction!(scene::_scene_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(calls::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(calls::gradient, m)?)?;
    m.add_function(wrap_pyfunction!(calls::gradient_wrt, m)?)?;
    m.add_function(wrap_pyfunction!(run::_cancel_running, m)?)?;
    m.add_function(wrap_pyfunction!(calls::_time_library_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(optim::optimize, m)?)?;
    m.add_function(wrap_pyfunction!(optim::mpc, m)?)?;
    m.add_function(wrap_pyfunction!(fatigue::_fatigue, m)?)?;
    m.add_function(wrap_pyfunction!(fatigue::_fatigue_cell, m)?)?;
    m.add_function(wrap_pyfunction!(fatigue::_fatigue_combine, m)?)?;
    m.add_function(wrap_pyfunction!(fatigue::_reduced_north_atlantic, m)?)?;
    m.add_function(wrap_pyfunction!(fatigue::_read_scatter, m)?)?;
    m.add_function(wrap_pyfunction!(design::_design, m)?)?;
    m.add_function(wrap_pyfunction!(design::_design_cell, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

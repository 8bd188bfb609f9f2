//! `design`: the command line's `chainbeam design` (the sensitivities at the scene's design, or
//! the bounded L-BFGS design that maximises the wellhead's life over a scatter diagram) on the
//! same library calls, returning the command line's JSON text (the library's
//! [`chainbeam::design::DesignReport`] serialised the same way, so that `json.loads` of it equals
//! `json.load` of the command line's output bit for bit); and [`_design_cell`], one cell of one
//! evaluation, which `chainbeam.design(..., executor=...)` sends to an executor through the
//! runner it gives [`_design`] ([`chainbeam::design::CellRunner`]).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use chainbeam::design::{
    optimise, sensitivities_with, CellGradient, CellRunner, DesignError, DesignIterate,
    DesignOptions, DesignParameter, DesignPoint, DesignReport, DesignStudy, Execution,
    IterateCallback, Want,
};
use chainbeam::fatigue::{ScatterCell, SeaState};
use chainbeam::fatigue_study::{StudyError, PRACTICE_RECORD_S};

use crate::errors::{check, Failure};
use crate::run::{interruptible, with_pool};
use crate::scene::Scene;

/// A scatter cell as Python passes it: (hs, tp, probability, direction or None).
type CellTuple = (f64, f64, f64, Option<f64>);

/// One cell's result as it travels between processes: (probability, damage, duration_s,
/// ∂D_s/∂θ in the order of the names asked for).
type CellResult = (f64, f64, f64, Vec<f64>);

fn cells(cells: &[CellTuple]) -> Vec<ScatterCell> {
    cells
        .iter()
        .map(|&(hs, tp, probability, direction)| ScatterCell {
            sea: SeaState { hs, tp, direction },
            probability,
        })
        .collect()
}

/// A design error as the exception of the argument or scene key at fault (the command line's
/// flags are the Python arguments of the same names).
fn design_error(e: DesignError) -> Failure {
    match e {
        DesignError::Run { source, .. } | DesignError::Optimiser { source } => {
            Failure::Lib(*source)
        }
        e @ (DesignError::NoDesign { .. }
        | DesignError::NotInModel { .. }
        | DesignError::NoGradient { .. }
        | DesignError::NoDamage { .. }) => Failure::SceneKey {
            key: "design".into(),
            message: e.to_string(),
        },
        e @ (DesignError::NoHotSpot { .. }
        | DesignError::HotSpotSpatial { .. }
        | DesignError::HotSpotFolded { .. }) => Failure::SceneKey {
            key: "design.hotspot".into(),
            message: e.to_string(),
        },
        e @ DesignError::NoFatigueSpec => Failure::SceneKey {
            key: "fatigue".into(),
            message: e.to_string(),
        },
        e @ DesignError::Study(StudyError::SpinUp { .. }) => {
            Failure::argument("spin_up", e.to_string())
        }
        e @ DesignError::Study(StudyError::Record { .. }) => {
            Failure::argument("record", e.to_string())
        }
        e @ DesignError::Study(_) => Failure::argument("scatter", e.to_string()),
        e @ DesignError::BadValues { .. } => Failure::argument("design", e.to_string()),
        e => Failure::Internal(e.to_string()),
    }
}

/// The parameters named `names` (the JSON's names).
fn parameters(names: &[String]) -> Result<Vec<DesignParameter>, Failure> {
    names
        .iter()
        .map(|n| {
            DesignParameter::from_name(n).ok_or_else(|| {
                Failure::argument(
                    "design",
                    format!(
                        "unknown design parameter {n:?}; expected one of {}",
                        DesignParameter::names()
                    ),
                )
            })
        })
        .collect()
}

/// The study of a call: the scene, its cells, the record (`None`: 3 hours) and the spin-up.
fn study<'a>(
    scene: &'a chainbeam::Scene,
    cells: Option<&'a [ScatterCell]>,
    record: f64,
    spin_up: f64,
) -> DesignStudy<'a> {
    DesignStudy {
        scene,
        cells,
        record: Some(record),
        spin_up,
    }
}

/// The failure a Python callback (runner or iterate hook) raised, kept to be raised in place of
/// the library's error it caused.
type Raised = Arc<Mutex<Option<PyErr>>>;

/// The runner that calls `runner(names, values, gradient)` (a Python callable returning one
/// [`CellResult`] per cell, in the diagram's order) with the GIL taken on the calling thread.
fn python_runner(runner: Py<PyAny>, raised: Raised) -> CellRunner {
    Arc::new(move |point: &DesignPoint<'_>, want: Want| {
        let names: Vec<String> = point.params.iter().map(|p| p.name().to_string()).collect();
        let values = point.values.to_vec();
        let gradient = want == Want::Gradient;
        let out: PyResult<Vec<CellResult>> = Python::attach(|py| {
            runner
                .bind(py)
                .call1((names, values, gradient))
                .and_then(|r| r.extract())
        });
        match out {
            Ok(list) => Ok(list
                .into_iter()
                .map(|(probability, damage, duration_s, gradient)| CellGradient {
                    probability,
                    damage,
                    duration_s,
                    gradient,
                })
                .collect()),
            Err(e) => {
                let mut slot = raised.lock().unwrap_or_else(|p| p.into_inner());
                slot.get_or_insert(e);
                Err(DesignError::Run {
                    cell: 0,
                    source: Box::new(chainbeam::Error::Cancelled),
                })
            }
        }
    })
}

/// The iterate hook that calls `hook(dict)` with the GIL taken on the calling thread; an
/// exception it raises is kept and cancels the run.
fn python_hook(hook: Py<PyAny>, names: Vec<String>, raised: Raised) -> IterateCallback {
    let token = chainbeam::cancel::current();
    Arc::new(move |it: &DesignIterate| {
        let out = Python::attach(|py| -> PyResult<()> {
            let d = PyDict::new(py);
            d.set_item("iteration", it.iteration)?;
            // Keyed by name in the JSON's (sorted) order.
            let sorted: std::collections::BTreeMap<&String, f64> =
                names.iter().zip(it.values.iter().copied()).collect();
            let design = PyDict::new(py);
            for (n, v) in sorted {
                design.set_item(n, v)?;
            }
            d.set_item("design", design)?;
            d.set_item("damage_per_year", it.damage_per_year)?;
            let finite = |x: f64| x.is_finite().then_some(x);
            d.set_item("life_years", finite(it.life_years))?;
            d.set_item("gradient_norm", finite(it.gradient_norm))?;
            d.set_item("simulations", it.simulations)?;
            d.set_item("adjoint_sweeps", it.adjoint_sweeps)?;
            d.set_item("forward_runs", it.forward_runs)?;
            hook.bind(py).call1((d,))?;
            Ok(())
        });
        if let Err(e) = out {
            let mut slot = raised.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(e);
            if let Some(t) = &token {
                t.cancel();
            }
        }
    })
}

/// `chainbeam design` in one call; see `chainbeam.design`. Returns the command line's JSON text.
/// `runner(names, values, gradient)`, when given, runs the cells of every evaluation (a list of
/// `_design_cell` results in the diagram's order); `on_iterate(dict)` is called with every
/// iterate (both from the worker thread, with the GIL).
#[pyfunction]
#[pyo3(signature = (scene, scatter, sensitivities, record, spin_up, runner=None, on_iterate=None))]
#[allow(clippy::too_many_arguments)]
pub fn _design(
    py: Python<'_>,
    scene: &Scene,
    scatter: Option<Vec<CellTuple>>,
    sensitivities: bool,
    record: Option<f64>,
    spin_up: f64,
    runner: Option<Py<PyAny>>,
    on_iterate: Option<Py<PyAny>>,
) -> PyResult<String> {
    let s = scene.inner.clone();
    let raised: Raised = Arc::default();
    let worker_raised = Arc::clone(&raised);
    let out = interruptible(py, move || -> Result<String, Failure> {
        let cells = scatter.as_deref().map(cells);
        let record = record.unwrap_or(PRACTICE_RECORD_S);
        let study = study(&s, cells.as_deref(), record, spin_up);
        let dff = study.dff().map_err(design_error)?;
        let names: Vec<String> = s
            .design
            .as_ref()
            .map(|t| {
                t.design_choices()
                    .iter()
                    .map(|c| c.0.name().to_string())
                    .collect()
            })
            .unwrap_or_default();
        let options = DesignOptions {
            execution: Execution::Parallel,
            on_iterate: on_iterate.map(|h| python_hook(h, names, Arc::clone(&worker_raised))),
            runner: runner.map(|r| python_runner(r, Arc::clone(&worker_raised))),
        };
        let report = with_pool(|| {
            if sensitivities {
                let started = Instant::now();
                sensitivities_with(&study, &options, &|| {}).map(|(g, t)| {
                    let secs = started.elapsed().as_secs_f64();
                    DesignReport::sensitivities(&study, (&g, &t), dff, record, secs)
                })
            } else {
                optimise(&study, &options).map(|o| DesignReport::optimised(&study, &o, record))
            }
        })
        .map_err(Failure::Internal)?
        .map_err(design_error)?;
        if let Some(v) = report.numbers().iter().find(|v| !v.is_finite()) {
            return Err(Failure::Internal(format!(
                "the design report's sensitivities, design or damage_per_year is not finite \
                 ({v}); nothing was returned"
            )));
        }
        to_json(&report)
    });
    let taken = raised.lock().unwrap_or_else(|p| p.into_inner()).take();
    if let Some(e) = taken {
        return Err(e);
    }
    check(py, out?)
}

/// The report as the command line writes it (`serde_json`'s pretty form; the numbers in the
/// shortest form that reads back as the same double).
fn to_json(report: &DesignReport) -> Result<String, Failure> {
    serde_json::to_string_pretty(report)
        .map_err(|e| Failure::Internal(format!("cannot format the JSON output: {e}")))
}

/// Cell `index` of the diagram at the design `names = values`
/// ([`DesignStudy::run_cell`]): (probability, damage, duration_s, ∂D_s/∂θ in the order of
/// `names`, empty unless `gradient`).
#[pyfunction]
#[pyo3(signature = (scene, scatter, index, names, values, gradient, record, spin_up))]
#[allow(clippy::too_many_arguments)]
pub fn _design_cell(
    py: Python<'_>,
    scene: &Scene,
    scatter: Option<Vec<CellTuple>>,
    index: usize,
    names: Vec<String>,
    values: Vec<f64>,
    gradient: bool,
    record: Option<f64>,
    spin_up: f64,
) -> PyResult<CellResult> {
    let s = scene.inner.clone();
    check(
        py,
        interruptible(py, move || -> Result<CellResult, Failure> {
            let cells = scatter.as_deref().map(cells);
            let study = study(
                &s,
                cells.as_deref(),
                record.unwrap_or(PRACTICE_RECORD_S),
                spin_up,
            );
            if index >= study.n_cells() {
                return Err(Failure::argument(
                    "index",
                    format!("cell {index} of a diagram of {}", study.n_cells()),
                ));
            }
            let params = parameters(&names)?;
            let point = DesignPoint {
                params: &params,
                values: &values,
            };
            let want = if gradient {
                Want::Gradient
            } else {
                Want::Value
            };
            let c = study.run_cell(index, &point, want).map_err(design_error)?;
            Ok((c.probability, c.damage, c.duration_s, c.gradient))
        })?,
    )
}

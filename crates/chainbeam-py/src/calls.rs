//! `simulate` and `gradient`: the same library calls as the command line's `simulate` and
//! `gradient` (src/bin/chainbeam/cmd_simulate.rs, cmd_gradient.rs), on the same floats.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use chainbeam::adjoint::AnyProblem;
use chainbeam::optimize::scene_start;
use chainbeam::{
    simulate as lib_simulate, BendingObjective, ControlKind, ControlMap, ControlProblem,
    ObjectiveKind, Parameter, Parametrisation, PerStepControl, PiecewiseControl, SceneTrajectory,
    SimulateInput,
};

use crate::errors::{check, Failure};
use crate::run::interruptible;
use crate::scene::Scene;

/// Controls given to a call: the z components (or the only ones) and, for a 2-axis control, the
/// x components; one value (a constant force) or N + 1 values u_0..u_N.
pub struct Controls {
    /// u_z (or u) values.
    pub z: Vec<f64>,
    /// u_x values of a 2-axis control.
    pub x: Option<Vec<f64>>,
}

impl Controls {
    /// From the package's normalised arrays (`python/chainbeam/_api.py` splits pairs).
    pub fn from_arrays(
        z: Option<PyReadonlyArray1<'_, f64>>,
        x: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Option<Self>> {
        let Some(z) = z else { return Ok(None) };
        Ok(Some(Controls {
            z: z.to_vec()?,
            x: x.map(|x| x.to_vec()).transpose()?,
        }))
    }

    /// The parametrisation of these values on a scene of N steps: 1 value a constant, N + 1
    /// per-step (the command line's `--controls` without a declared kind), and as many values
    /// as the scene's own `[control]` has a piecewise control of that many pieces: the θ layout
    /// that `gradient` and `optimize` return for the scene, which can be passed back as is.
    pub fn parametrisation(&self, scene: &chainbeam::Scene) -> Result<Parametrisation, Failure> {
        let steps = scene.time.steps;
        if scene.has_two_axis_control() && self.x.is_none() {
            return Err(Failure::argument(
                "controls",
                "the scene's control is 2-axis (`control.values` are pairs [u_x, u_z]) but the \
                 controls hold one number per value: give an array of shape (m, 2) of pairs \
                 [u_x, u_z] ([0, u] for a force along z alone)",
            ));
        }
        if let Some(bad) = self
            .z
            .iter()
            .chain(self.x.iter().flatten())
            .position(|v| !v.is_finite())
        {
            return Err(Failure::argument(
                "controls",
                format!("entry {bad} is not finite"),
            ));
        }
        let pieces = scene
            .control
            .as_ref()
            .filter(|c| c.kind == ControlKind::Piecewise)
            .map(|c| c.values.len());
        match self.z.len() {
            1 => Ok(Parametrisation::Constant),
            got if got == steps + 1 => Ok(Parametrisation::PerStep(PerStepControl { steps })),
            got if Some(got) == pieces => Ok(Parametrisation::Piecewise(PiecewiseControl {
                steps,
                pieces: got,
            })),
            got => Err(Failure::argument(
                "controls",
                format!(
                    "expected N + 1 = {} values u_0..u_N for this scene (time.steps = {steps}), \
                     1 value (a constant force){}, got {got}",
                    steps + 1,
                    match pieces {
                        Some(p) => format!(
                            " or {p} values (one per piece of the scene's piecewise control: \
                             the layout gradient and optimize return)"
                        ),
                        None => String::new(),
                    }
                ),
            )),
        }
    }

    /// θ = (θ_x; θ_z) of these values.
    pub fn theta(&self) -> Vec<f64> {
        let mut t = self.x.clone().unwrap_or_default();
        t.extend(&self.z);
        t
    }
}

/// The trajectory of `scene` under its own control or `controls`.
fn run_simulation(
    scene: &chainbeam::Scene,
    controls: Option<&Controls>,
) -> Result<SceneTrajectory, Failure> {
    Ok(match controls {
        None => lib_simulate(scene)?,
        Some(c) => {
            let map = c.parametrisation(scene)?;
            let expand = |values: &[f64]| {
                let mut u = vec![0.0; scene.time.steps + 1];
                map.controls(values, &mut u);
                u
            };
            match &c.x {
                None => lib_simulate(SimulateInput::new(scene).controls(&expand(&c.z)))?,
                Some(x) => {
                    lib_simulate(SimulateInput::new(scene).controls_xz(&expand(x), &expand(&c.z)))?
                }
            }
        }
    })
}

/// Simulates a scene (RATTLE from its start, `[time] initial`); see `chainbeam.simulate`.
///
/// The columns are built in the trajectory's own memory on the worker thread
/// ([`SceneTrajectory::into_columns`]: one pass over the steps, which also checks that every
/// value is finite, as the command line does before writing) and move into numpy arrays without
/// a copy (`PyArray1::from_vec`; the positions' (N + 1, n, 3) is a reshaped view of the same
/// buffer).
#[pyfunction]
#[pyo3(signature = (scene, controls=None, controls_x=None))]
pub fn simulate<'py>(
    py: Python<'py>,
    scene: &Scene,
    controls: Option<PyReadonlyArray1<'py, f64>>,
    controls_x: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let controls = Controls::from_arrays(controls, controls_x)?;
    let s = scene.inner.clone();
    let (c, eta) = check(
        py,
        interruptible(py, move || -> Result<_, Failure> {
            crate::errors::check_stored(&s)?;
            let eta = wave_elevation(&s)?;
            Ok((run_simulation(&s, controls.as_ref())?.into_columns()?, eta))
        })?,
    )?;
    let d = PyDict::new(py);
    let rows = c.t.len();
    d.set_item("t", PyArray1::from_vec(py, c.t))?;
    d.set_item("energy", PyArray1::from_vec(py, c.energy))?;
    d.set_item("moment", PyArray1::from_vec(py, c.moment))?;
    d.set_item(
        "positions",
        PyArray1::from_vec(py, c.positions).reshape([rows, c.n, 3])?,
    )?;
    d.set_item("control", PyArray1::from_vec(py, c.controls))?;
    if let Some(m) = c.moment_x {
        d.set_item("moment_x", PyArray1::from_vec(py, m))?;
    }
    if let Some(u) = c.controls_x {
        d.set_item("control_x", PyArray1::from_vec(py, u))?;
    }
    if let Some(e) = eta {
        d.set_item("eta", PyArray1::from_vec(py, e))?;
    }
    Ok(d)
}

/// The surface elevation η(t_k) at x = z = 0 of a scene with `[loads.waves]` (the command
/// line's `eta` column: `Scene::wave_elevation`), checked finite where it is made, as the
/// command line does.
fn wave_elevation(scene: &chainbeam::Scene) -> Result<Option<Vec<f64>>, Failure> {
    let eta = scene.wave_elevation().map_err(chainbeam::Error::from)?;
    if let Some(k) = eta
        .as_ref()
        .and_then(|e| e.iter().position(|v| !v.is_finite()))
    {
        return Err(Failure::Lib(chainbeam::Error::NonFinite {
            step: k,
            quantity: "the wave elevation eta (nothing was returned)",
        }));
    }
    Ok(eta)
}

/// The problem of a scene with its own control or `controls`, and θ₀ (the command line's
/// `problem::build` without `--pieces`).
pub fn build_problem(
    scene: &chainbeam::Scene,
    controls: Option<&Controls>,
    effort: f64,
) -> Result<(AnyProblem, Vec<f64>), Failure> {
    if !(effort.is_finite() && effort >= 0.0) {
        return Err(Failure::argument(
            "effort",
            format!("the penalty weight ρ must be finite and non-negative, got {effort}"),
        ));
    }
    // The adjoint stores the trajectory: a run over the budget is the documented error.
    crate::errors::check_stored(scene)?;
    let (map, theta0, two_axis) = match controls {
        None => {
            let (map, theta0) = scene_start(scene)?;
            (map, theta0, scene.has_two_axis_control())
        }
        Some(c) => (c.parametrisation(scene)?, c.theta(), c.x.is_some()),
    };
    let objective = BendingObjective {
        kind: scene.objective.unwrap_or(ObjectiveKind::Final),
        effort,
    };
    Ok((
        ControlProblem::builder(scene)
            .map(map)
            .objective(objective)
            .two_axis(two_axis)
            .build()?,
        theta0,
    ))
}

/// Objective and adjoint gradient; see `chainbeam.gradient`. Returns (objective, gradient θ-
/// shaped flat, two_axis).
#[pyfunction]
#[pyo3(signature = (scene, controls=None, controls_x=None, effort=0.0))]
pub fn gradient<'py>(
    py: Python<'py>,
    scene: &Scene,
    controls: Option<PyReadonlyArray1<'py, f64>>,
    controls_x: Option<PyReadonlyArray1<'py, f64>>,
    effort: f64,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>, bool)> {
    let controls = Controls::from_arrays(controls, controls_x)?;
    let s = scene.inner.clone();
    let (c, g, two_axis) = check(
        py,
        interruptible(py, move || -> Result<_, Failure> {
            let (problem, theta0) = build_problem(&s, controls.as_ref(), effort)?;
            let (c, g) = problem.value_and_gradient(&theta0)?;
            if !c.is_finite() || g.iter().any(|v| !v.is_finite()) {
                return Err(Failure::Lib(chainbeam::Error::NonFiniteObjective {
                    quantity: "objective or gradient",
                }));
            }
            Ok((c, g, problem.is_two_axis()))
        })?,
    )?;
    Ok((c, PyArray1::from_vec(py, g), two_axis))
}

/// A physical parameter by its scene key (`cb.gradient(scene, wrt=[...])`): every
/// [`Parameter`] of the library. A key that sets several values of the model at once
/// (`beam.stiffness`: k₂..kₙ, `beam.mass`: m₁..mₙ, `beam.joint_damping`: every damper) is the
/// derivative with respect to their common value (the sum of the partial derivatives).
pub fn parameter_of(key: &str) -> Option<Parameter> {
    let simple = match key {
        "beam.stiffness" => Some(Parameter::InteriorStiffness),
        "beam.base_stiffness" => Some(Parameter::BaseStiffness),
        "beam.tip_stiffness" => Some(Parameter::TipStiffness),
        "beam.mass" => Some(Parameter::Mass),
        "beam.joint_damping" => Some(Parameter::JointDamping),
        "loads.drag" => Some(Parameter::Drag),
        "loads.tension" => Some(Parameter::Tension),
        "loads.axial_weight" => Some(Parameter::AxialWeight),
        "loads.current.speed" => Some(Parameter::CurrentSpeed),
        _ => None,
    };
    if simple.is_some() {
        return simple;
    }
    // loads.point[i].force, .force[1] (F_z), .force[0] (F_x), .harmonic[j].amplitude|phase
    let rest = key.strip_prefix("loads.point[")?;
    let (i, rest) = rest.split_once(']')?;
    let load: usize = i.parse().ok()?;
    match rest {
        ".force" | ".force[1]" => return Some(Parameter::LoadForce(load)),
        ".force[0]" => return Some(Parameter::LoadForceX(load)),
        _ => {}
    }
    let rest = rest.strip_prefix(".harmonic[")?;
    let (j, field) = rest.split_once(']')?;
    let harmonic: usize = j.parse().ok()?;
    match field {
        ".amplitude" => Some(Parameter::LoadAmplitude { load, harmonic }),
        ".phase" => Some(Parameter::LoadPhase { load, harmonic }),
        _ => None,
    }
}

/// The keys `wrt` accepts (for the error that names an unknown one).
const WRT_KEYS: &str = "\"controls\", \"beam.stiffness\", \"beam.base_stiffness\", \
    \"beam.tip_stiffness\", \"beam.mass\", \"beam.joint_damping\", \"loads.drag\", \
    \"loads.tension\", \"loads.axial_weight\", \"loads.current.speed\", \
    \"loads.point[i].force\" (F_z; also \"force[1]\"), \"loads.point[i].force[0]\" (F_x), \
    \"loads.point[i].harmonic[j].amplitude\", \"loads.point[i].harmonic[j].phase\"";

/// ∂J/∂p for the physical parameters `params` at θ (one adjoint sweep).
fn parameter_gradient(
    problem: &AnyProblem,
    theta: &[f64],
    params: &[Parameter],
) -> chainbeam::Result<Vec<f64>> {
    problem.parameter_gradient(theta, params)
}

/// J and its gradient with respect to the controls (θ) and/or physical parameters by their
/// scene keys; see `chainbeam.gradient(..., wrt=[...])`. Returns (J, ∇_θJ flat or None,
/// [∂J/∂p in `wrt`'s order, the parameters only], two_axis).
#[pyfunction]
#[pyo3(signature = (scene, wrt, controls=None, controls_x=None, effort=0.0))]
#[allow(clippy::type_complexity)] // one tuple for Python to unpack
pub fn gradient_wrt<'py>(
    py: Python<'py>,
    scene: &Scene,
    wrt: Vec<String>,
    controls: Option<PyReadonlyArray1<'py, f64>>,
    controls_x: Option<PyReadonlyArray1<'py, f64>>,
    effort: f64,
) -> PyResult<(f64, Option<Bound<'py, PyArray1<f64>>>, Vec<f64>, bool)> {
    let mut params = Vec::new();
    let mut with_controls = false;
    for key in &wrt {
        if key == "controls" {
            with_controls = true;
            continue;
        }
        match parameter_of(key) {
            Some(p) => params.push(p),
            None => {
                return Err(Failure::argument(
                    "wrt",
                    format!("unknown parameter {key:?}; expected one of {WRT_KEYS}"),
                )
                .into_py(py))
            }
        }
    }
    let controls = Controls::from_arrays(controls, controls_x)?;
    let s = scene.inner.clone();
    let (c, g, dp, two_axis) = check(
        py,
        interruptible(py, move || -> Result<_, Failure> {
            let (problem, theta0) = build_problem(&s, controls.as_ref(), effort)?;
            let (c, g) = if with_controls || params.is_empty() {
                let (c, g) = problem.value_and_gradient(&theta0)?;
                (c, Some(g))
            } else {
                (problem.value(&theta0)?, None)
            };
            let dp = if params.is_empty() {
                Vec::new()
            } else {
                parameter_gradient(&problem, &theta0, &params)?
            };
            let bad = !c.is_finite() || g.iter().flatten().chain(&dp).any(|v| !v.is_finite());
            if bad {
                return Err(Failure::Lib(chainbeam::Error::NonFiniteObjective {
                    quantity: "objective or gradient",
                }));
            }
            Ok((c, g.filter(|_| with_controls), dp, problem.is_two_axis()))
        })?,
    )?;
    Ok((c, g.map(|g| PyArray1::from_vec(py, g)), dp, two_axis))
}

/// A trajectory of the library handed back by [`_time_library_simulate`] so that it is freed
/// when Python drops it, outside the timed call (as `chainbeam.simulate`'s arrays are).
#[pyclass(name = "_LibraryTrajectory", module = "chainbeam._chainbeam", frozen)]
pub struct LibraryTrajectory {
    _trajectory: SceneTrajectory,
}

/// Seconds of the library call `chainbeam::simulate(scene)` alone and the trajectory it returned
/// (freed when Python drops it): the yardstick of `python/benchmarks/overhead.py`, which compares
/// it with `chainbeam.simulate` (same compiled code, plus the columns handed to numpy). It runs
/// on a worker thread like `simulate` ([`interruptible`]), so that both allocate from the same
/// kind of malloc arena (the main thread's and a worker's differ in how they reuse memory).
#[pyfunction]
pub fn _time_library_simulate(py: Python<'_>, scene: &Scene) -> PyResult<(f64, LibraryTrajectory)> {
    let s = scene.inner.clone();
    let (seconds, r) = interruptible(py, move || {
        let t0 = std::time::Instant::now();
        let r = lib_simulate(&s);
        (t0.elapsed().as_secs_f64(), r)
    })?;
    let trajectory = r.map_err(|e| crate::errors::lib(py, e))?;
    Ok((
        seconds,
        LibraryTrajectory {
            _trajectory: trajectory,
        },
    ))
}

//! `simulate` and `gradient`: the same library calls as the command line's `simulate` and
//! `gradient` (src/bin/chainbeam/cmd_simulate.rs, cmd_gradient.rs), on the same floats.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use chainbeam::optimize::{scene_start, AnyProblem, OptimProblem};
use chainbeam::{
    simulate as lib_simulate, simulate_with_controls, simulate_with_controls_xz, BendingObjective,
    ControlMap, ObjectiveKind, Parametrisation, PerStepControl, SceneTrajectory,
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
    /// per-step (the command line's `--controls` without a declared kind).
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
        match self.z.len() {
            1 => Ok(Parametrisation::Constant),
            got if got == steps + 1 => Ok(Parametrisation::PerStep(PerStepControl { steps })),
            got => Err(Failure::argument(
                "controls",
                format!(
                    "expected N + 1 = {} values u_0..u_N for this scene (time.steps = {steps}), \
                     or 1 value (a constant force), got {got}",
                    steps + 1
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

/// The arrays of a trajectory, in the CSV's columns.
struct Arrays {
    t: Vec<f64>,
    energy: Vec<f64>,
    moment: Vec<f64>,
    positions: Vec<f64>,
    control: Vec<f64>,
    moment_x: Option<Vec<f64>>,
    control_x: Option<Vec<f64>>,
    n: usize,
}

/// Copies the trajectory into flat arrays, refusing non-finite values as the command line does.
fn arrays(traj: &SceneTrajectory) -> Result<Arrays, Failure> {
    let (steps, n) = (traj.steps(), traj.n());
    let mut positions = Vec::with_capacity((steps + 1) * n * 3);
    for k in 0..=steps {
        for r in traj.positions(k) {
            positions.extend(r);
        }
    }
    let spatial = traj.is_spatial();
    let a = Arrays {
        t: (0..=steps).map(|k| traj.time(k)).collect(),
        energy: traj.energy().to_vec(),
        moment: traj.moment().to_vec(),
        positions,
        control: traj.controls().to_vec(),
        moment_x: spatial.then(|| traj.moment_x().to_vec()),
        control_x: spatial.then(|| {
            let ux = traj.controls_x();
            (0..=steps)
                .map(|k| ux.get(k).copied().unwrap_or(0.0))
                .collect()
        }),
        n,
    };
    let columns: [(&str, Option<&Vec<f64>>); 7] = [
        ("t", Some(&a.t)),
        ("energy", Some(&a.energy)),
        ("moment", Some(&a.moment)),
        ("positions", Some(&a.positions)),
        ("control", Some(&a.control)),
        ("moment_x", a.moment_x.as_ref()),
        ("control_x", a.control_x.as_ref()),
    ];
    for (name, col) in columns {
        if let Some(i) = col.and_then(|c| c.iter().position(|v| !v.is_finite())) {
            let k = if name == "positions" { i / (3 * n) } else { i };
            return Err(Failure::Lib(chainbeam::Error::NonFinite {
                step: k,
                quantity: "a trajectory value handed to Python (nothing was returned)",
            }));
        }
    }
    Ok(a)
}

/// The trajectory of `scene` under its own control or `controls`.
fn run_simulation(
    scene: &chainbeam::Scene,
    controls: Option<&Controls>,
) -> Result<Arrays, Failure> {
    let traj = match controls {
        None => lib_simulate(scene)?,
        Some(c) => {
            let map = c.parametrisation(scene)?;
            let expand = |values: &[f64]| {
                let mut u = vec![0.0; scene.time.steps + 1];
                map.controls(values, &mut u);
                u
            };
            match &c.x {
                None => simulate_with_controls(scene, &expand(&c.z))?,
                Some(x) => simulate_with_controls_xz(scene, &expand(x), &expand(&c.z))?,
            }
        }
    };
    arrays(&traj)
}

/// Simulates a scene (RATTLE from the straight beam at rest); see `chainbeam.simulate`.
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
    let a = check(
        py,
        interruptible(py, move || run_simulation(&s, controls.as_ref()))?,
    )?;
    let d = PyDict::new(py);
    let steps = a.t.len();
    d.set_item("t", PyArray1::from_vec(py, a.t))?;
    d.set_item("energy", PyArray1::from_vec(py, a.energy))?;
    d.set_item("moment", PyArray1::from_vec(py, a.moment))?;
    d.set_item(
        "positions",
        PyArray1::from_vec(py, a.positions).reshape([steps, a.n, 3])?,
    )?;
    d.set_item("control", PyArray1::from_vec(py, a.control))?;
    if let Some(m) = a.moment_x {
        d.set_item("moment_x", PyArray1::from_vec(py, m))?;
    }
    if let Some(c) = a.control_x {
        d.set_item("control_x", PyArray1::from_vec(py, c))?;
    }
    Ok(d)
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
    Ok((AnyProblem::new(scene, map, objective, two_axis)?, theta0))
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

/// Seconds of the library call `chainbeam::simulate(scene)` alone (the trajectory dropped), with
/// the GIL released: the yardstick of `python/benchmarks/overhead.py`, which compares it with
/// `chainbeam.simulate` (same compiled code, plus the copies into numpy).
#[pyfunction]
pub fn _time_library_simulate(py: Python<'_>, scene: &Scene) -> PyResult<f64> {
    let s = scene.inner.clone();
    let (seconds, r) = py.detach(move || {
        let t0 = std::time::Instant::now();
        let r = lib_simulate(&s).map(drop);
        (t0.elapsed().as_secs_f64(), r)
    });
    r.map_err(|e| crate::errors::lib(py, e))?;
    Ok(seconds)
}

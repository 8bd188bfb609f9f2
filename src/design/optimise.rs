//! The sensitivities of the annual damage at the scene's design, and the bounded L-BFGS design
//! that maximises the wellhead's life (module docs of [`crate::design`], "The optimiser").

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{State, KV};

use super::{DesignError, DesignParameter, DesignStudy, DesignTable, Execution, Role};
use super::{DesignPoint, FreeParameter, ScatterGradient, Want};
use crate::fatigue::life_years;
use crate::optimize::observers::ObservedState;
use crate::optimize::{Method, Minimizer, OptimOptions, OptimProblem};

/// The sensitivity of the annual damage to one parameter at a design.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivity {
    /// The parameter.
    pub parameter: DesignParameter,
    /// Design choice or uncertainty.
    pub role: Role,
    /// Its value at the design, in its unit.
    pub value: f64,
    /// ∂D_y/∂p \[1/year per unit of p\] (the JSON's `sensitivities`).
    pub damage_per_year: f64,
    /// The relative sensitivity of the life, ∂ ln L/∂ ln p = −(p/D_y) · ∂D_y/∂p: the life's
    /// change in % for a 1 % change of p.
    pub relative_life: f64,
}

/// One iterate of the optimiser (the start is iteration 0).
#[derive(Clone, Debug, PartialEq)]
pub struct DesignIterate {
    /// The iteration (0: the scene's own design).
    pub iteration: usize,
    /// The design choices' values, in the `[design]` table's order.
    pub values: Vec<f64>,
    /// D_y \[1/year\].
    pub damage_per_year: f64,
    /// L = 1/(DFF · D_y) \[years\].
    pub life_years: f64,
    /// ∂D_y/∂θ_i of the design choices.
    pub gradient: Vec<f64>,
    /// ‖∇_z ln D_y‖, the optimiser's gradient norm (module docs).
    pub gradient_norm: f64,
    /// Cell runs (adjoint sweeps, each a forward and a reverse pass over a cell's record) so
    /// far.
    pub simulations: usize,
}

/// A callback that receives each iterate ([`DesignOptions::on_iterate`]).
pub type IterateCallback = Arc<dyn Fn(&DesignIterate) + Send + Sync>;

/// A caller's runner of the cells of one evaluation: every cell of the study at the design, by
/// [`DesignStudy::run_cell`] wherever the caller likes (the Python package sends each to an
/// executor: a process pool, a Dask cluster), returned in the diagram's order. The study
/// combines them ([`DesignStudy::combine`]), so the result is the same bit for bit as
/// [`Execution::Serial`]'s when each cell is `run_cell`'s.
pub type CellRunner = Arc<
    dyn Fn(&DesignPoint<'_>, Want) -> Result<Vec<super::CellGradient>, DesignError> + Send + Sync,
>;

/// How the optimiser runs its cells and reports its iterates.
#[derive(Clone, Default)]
pub struct DesignOptions {
    /// Where the cells of every evaluation run (unless `runner` is given).
    pub execution: Execution,
    /// Called with every iterate as it is accepted (the command line prints it to stderr); the
    /// library prints nothing.
    pub on_iterate: Option<IterateCallback>,
    /// The caller's runner of the cells of every evaluation, instead of `execution`.
    pub runner: Option<CellRunner>,
}

impl DesignOptions {
    /// D_y and ∂D_y/∂θ at `point`: the cells by `runner` when given (checked by
    /// [`DesignStudy::check`] first, their number checked after, combined by
    /// [`DesignStudy::combine`]), else [`DesignStudy::evaluate`] on `execution`.
    ///
    /// # Errors
    /// [`DesignStudy::evaluate`]'s, or the runner's; [`DesignError::BadValues`] when the runner
    /// returns another number of cells than the study has.
    pub fn evaluate(
        &self,
        study: &DesignStudy<'_>,
        point: &DesignPoint<'_>,
        want: Want,
        on_cell: &(dyn Fn() + Sync),
    ) -> Result<ScatterGradient, DesignError> {
        let Some(runner) = &self.runner else {
            return study.evaluate(point, want, self.execution, on_cell);
        };
        study.check(point)?;
        let cells = runner(point, want)?;
        if cells.len() != study.n_cells() {
            return Err(DesignError::BadValues {
                reason: format!(
                    "the cell runner returned {} cells for a diagram of {}",
                    cells.len(),
                    study.n_cells()
                ),
            });
        }
        DesignStudy::combine(cells)
    }
}

/// What [`optimise`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignOutcome {
    /// The design choices, in the `[design]` table's order, with their bounds.
    pub parameters: Vec<(DesignParameter, (f64, f64))>,
    /// The optimised values of the design choices.
    pub design: Vec<f64>,
    /// D_y at the optimised design \[1/year\].
    pub damage_per_year: f64,
    /// The life at the optimised design \[years\].
    pub life_years: f64,
    /// The scene's own design (iteration 0).
    pub initial: DesignIterate,
    /// Every iterate, the start first, the last the optimised design.
    pub iterates: Vec<DesignIterate>,
    /// The sensitivities at the scene's own design, of every `[design]` parameter (uncertainties
    /// included).
    pub sensitivities: Vec<Sensitivity>,
    /// Whether the gradient tolerance or the cost-change test stopped the run.
    pub converged: bool,
    /// Why the run stopped.
    pub termination: String,
    /// The cells at the optimised design (their damages: the adjoint sweeps' values that give
    /// `damage_per_year`), in the diagram's order.
    pub cells: Vec<super::CellGradient>,
    /// Cell runs in all (the sensitivities' included).
    pub simulations: usize,
    /// Wall-clock time \[s\].
    pub seconds: f64,
}

/// The design's parameters as `name = value` pairs (for errors).
fn pairs(params: &[DesignParameter], values: &[f64]) -> String {
    params
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{} = {v}", p.name()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The parameters a sensitivity table covers: the `[design]` table's (every role), or every
/// [`DesignParameter`] the scene's model has when it has no `[design]` (the stack-up's flex
/// joints included, those not at an end spring already counted).
fn table_parameters(study: &DesignStudy<'_>) -> Vec<FreeParameter> {
    let scene = study.scene;
    let flex = scene.stackup.iter().flat_map(|st| {
        st.flex_joints
            .iter()
            .map(|f| DesignParameter::FlexJoint(f.name.clone()))
    });
    let mut seen = Vec::new();
    match &study.scene.design {
        Some(t) => t.parameters.clone(),
        None => DesignParameter::ALL
            .into_iter()
            .chain(flex)
            .filter(|p| p.value(scene).is_ok())
            .filter(|p| match p.parameter(scene) {
                Some(q) if !seen.contains(&q) => {
                    seen.push(q);
                    true
                }
                _ => false,
            })
            .map(|parameter| FreeParameter {
                role: parameter.default_role(),
                parameter,
                bounds: None,
            })
            .collect(),
    }
}

/// The sensitivity table of a scatter gradient at the values `values` of `params`.
fn sensitivity_table(
    params: &[FreeParameter],
    values: &[f64],
    g: &ScatterGradient,
) -> Vec<Sensitivity> {
    params
        .iter()
        .zip(values)
        .zip(&g.gradient)
        .map(|((p, &value), &d)| Sensitivity {
            parameter: p.parameter.clone(),
            role: p.role,
            value,
            damage_per_year: d,
            relative_life: -value / g.damage_per_year * d,
        })
        .collect()
}

/// The sensitivities at the scene's own design (module docs): D_y, its gradient with respect to
/// every `[design]` parameter (uncertainties included; every parameter the scene's model has
/// without `[design]`), one adjoint sweep per cell.
///
/// # Errors
/// [`DesignStudy::evaluate`]'s; [`DesignError::NoDesign`] when there is no parameter at all.
pub fn sensitivities(
    study: &DesignStudy<'_>,
    execution: Execution,
    on_cell: &(dyn Fn() + Sync),
) -> Result<(ScatterGradient, Vec<Sensitivity>), DesignError> {
    let options = DesignOptions {
        execution,
        ..DesignOptions::default()
    };
    sensitivities_with(study, &options, on_cell)
}

/// [`sensitivities`] with the cells run as `options` says ([`DesignOptions::evaluate`]: on
/// its `execution` or by its `runner`).
///
/// # Errors
/// As [`sensitivities`]; the runner's.
pub fn sensitivities_with(
    study: &DesignStudy<'_>,
    options: &DesignOptions,
    on_cell: &(dyn Fn() + Sync),
) -> Result<(ScatterGradient, Vec<Sensitivity>), DesignError> {
    let params = table_parameters(study);
    if params.is_empty() {
        return Err(DesignError::NoDesign {
            reason: "the scene's model has none of the design parameters",
        });
    }
    let names: Vec<DesignParameter> = params.iter().map(|p| p.parameter.clone()).collect();
    let values = scene_values(study, &names)?;
    let point = DesignPoint {
        params: &names,
        values: &values,
    };
    let g = options.evaluate(study, &point, Want::Gradient, on_cell)?;
    let table = sensitivity_table(&params, &values, &g);
    Ok((g, table))
}

/// The scene's own values of `params`.
fn scene_values(
    study: &DesignStudy<'_>,
    params: &[DesignParameter],
) -> Result<Vec<f64>, DesignError> {
    params
        .iter()
        .map(|p| {
            p.value(study.scene)
                .map_err(|reason| DesignError::NotInModel {
                    name: p.name(),
                    reason,
                })
        })
        .collect()
}

/// The bound transform of the module docs, anchored at the start: θ_i(z) = θ0_i + (hi_i − lo_i)
/// · (σ(z_i) − σ(z0_i)), clamped to \[lo_i, hi_i\] (the clamp only removes round-off), with
/// σ(z0_i) = (θ0_i − lo_i)/(hi_i − lo_i), so that θ(z0) = θ0 exactly. It is the transform
/// θ = lo + (hi − lo) σ(z) up to round-off, and its derivative is (hi − lo) σ(z)(1 − σ(z)).
#[derive(Clone, Debug)]
struct Transform {
    bounds: Vec<(f64, f64)>,
    theta0: Vec<f64>,
    z0: Vec<f64>,
}

/// The logistic function σ(z) = 1/(1 + e^{−z}).
fn sigmoid(z: f64) -> f64 {
    1.0 / (1.0 + (-z).exp())
}

/// The nearest a start may lie to a bound in the unit interval u = (θ − lo)/(hi − lo): a start on
/// a bound (u = 0 or 1, z = ∓∞) is moved in by this much in z's computation.
const EDGE: f64 = 1e-6;

impl Transform {
    fn new(bounds: Vec<(f64, f64)>, theta0: Vec<f64>) -> Self {
        let z0 = bounds
            .iter()
            .zip(&theta0)
            .map(|(&(lo, hi), &t)| {
                let u = ((t - lo) / (hi - lo)).clamp(EDGE, 1.0 - EDGE);
                (u / (1.0 - u)).ln()
            })
            .collect();
        Transform { bounds, theta0, z0 }
    }

    fn theta(&self, z: &[f64]) -> Vec<f64> {
        (0..z.len())
            .map(|i| {
                let (lo, hi) = self.bounds[i];
                // θ(z0) = θ0 exactly (the start's evaluation is reused), bit for bit.
                if z[i].to_bits() == self.z0[i].to_bits() {
                    return self.theta0[i];
                }
                let t = self.theta0[i] + (hi - lo) * (sigmoid(z[i]) - sigmoid(self.z0[i]));
                t.clamp(lo, hi)
            })
            .collect()
    }

    /// dθ_i/dz_i.
    fn slope(&self, z: &[f64]) -> Vec<f64> {
        (0..z.len())
            .map(|i| {
                let (lo, hi) = self.bounds[i];
                let s = sigmoid(z[i]);
                (hi - lo) * s * (1.0 - s)
            })
            .collect()
    }
}

/// Evaluations shared by the problem and the observer: the designs evaluated with their scatter
/// gradients, the cell runs, the first error.
#[derive(Default)]
struct Shared {
    evaluated: Mutex<Vec<(Vec<f64>, ScatterGradient)>>,
    simulations: AtomicUsize,
    error: Mutex<Option<DesignError>>,
}

impl Shared {
    fn lookup(&self, theta: &[f64]) -> Option<ScatterGradient> {
        let done = self.evaluated.lock().unwrap_or_else(|e| e.into_inner());
        done.iter()
            .find(|(t, _)| t == theta)
            .map(|(_, g)| g.clone())
    }
}

/// ln D_y as a function of z (module docs), for [`Minimizer`].
struct LogDamage<'a> {
    study: &'a DesignStudy<'a>,
    params: Vec<DesignParameter>,
    transform: Transform,
    options: DesignOptions,
    shared: Arc<Shared>,
}

impl LogDamage<'_> {
    fn scatter(&self, theta: &[f64]) -> Result<ScatterGradient, DesignError> {
        if let Some(g) = self.shared.lookup(theta) {
            return Ok(g);
        }
        let point = DesignPoint {
            params: &self.params,
            values: theta,
        };
        let g = self
            .options
            .evaluate(self.study, &point, Want::Gradient, &|| {})?;
        self.shared
            .simulations
            .fetch_add(self.study.n_cells(), Ordering::Relaxed);
        let mut done = self
            .shared
            .evaluated
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        done.push((theta.to_vec(), g.clone()));
        Ok(g)
    }
}

impl OptimProblem for LogDamage<'_> {
    fn n_params(&self) -> usize {
        self.params.len()
    }

    /// ln D_y(θ(z)) and (1/D_y) ∂D_y/∂θ_i · dθ_i/dz_i.
    fn value_and_gradient(&self, z: &[f64]) -> crate::Result<(f64, Vec<f64>)> {
        let theta = self.transform.theta(z);
        let fail = |e: DesignError| {
            let lib = match &e {
                DesignError::Run { source, .. } => (**source).clone(),
                _ => crate::Error::NonFiniteObjective {
                    quantity: "design objective",
                },
            };
            let mut slot = self.shared.error.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(e);
            lib
        };
        let g = self.scatter(&theta).map_err(fail)?;
        if g.damage_per_year <= 0.0 {
            return Err(fail(DesignError::NoDamage {
                values: pairs(&self.params, &theta),
            }));
        }
        let slope = self.transform.slope(z);
        let d = g.damage_per_year;
        let grad = g
            .gradient
            .iter()
            .zip(&slope)
            .map(|(g, s)| g / d * s)
            .collect();
        Ok((d.ln(), grad))
    }
}

/// The observer that turns the solver's iterates into [`DesignIterate`]s.
struct Recorder {
    transform: Transform,
    shared: Arc<Shared>,
    dff: f64,
    iterates: Arc<Mutex<Vec<DesignIterate>>>,
    on_iterate: Option<IterateCallback>,
}

impl Recorder {
    fn record(&mut self, state: &ObservedState) {
        let Some(z) = state.get_param() else {
            return;
        };
        let theta = self.transform.theta(z);
        let Some(g) = self.shared.lookup(&theta) else {
            return;
        };
        let norm = state
            .get_gradient()
            .map_or(f64::NAN, |g| g.iter().map(|x| x * x).sum::<f64>().sqrt());
        let mut list = self.iterates.lock().unwrap_or_else(|e| e.into_inner());
        let it = DesignIterate {
            iteration: list.len(),
            values: theta,
            damage_per_year: g.damage_per_year,
            life_years: life(g.damage_per_year, self.dff),
            gradient: g.gradient,
            gradient_norm: norm,
            simulations: self.shared.simulations.load(Ordering::Relaxed),
        };
        if let Some(f) = &self.on_iterate {
            f(&it);
        }
        list.push(it);
    }
}

impl Observe<ObservedState> for Recorder {
    fn observe_init(
        &mut self,
        _name: &str,
        state: &ObservedState,
        _kv: &KV,
    ) -> Result<(), argmin::core::Error> {
        self.record(state);
        Ok(())
    }
    fn observe_iter(&mut self, state: &ObservedState, _kv: &KV) -> Result<(), argmin::core::Error> {
        self.record(state);
        Ok(())
    }
}

/// L = 1/(DFF · D_y) (+∞ without damage).
fn life(damage_per_year: f64, dff: f64) -> f64 {
    life_years(damage_per_year, dff).unwrap_or(f64::INFINITY)
}

/// The design that maximises the wellhead's life over the diagram (module docs, "The
/// optimiser"): L-BFGS on ln D_y in the bound-transformed variables, from the scene's own design,
/// the `[design]` table's design choices free and its uncertainties at the scene's values. The
/// first evaluation, at the scene's design, also gives the sensitivities of every `[design]`
/// parameter ([`sensitivities`]).
///
/// # Errors
/// [`DesignError::NoDesign`] without a `[design]` table or a design choice in it;
/// [`DesignStudy::evaluate`]'s at the start; [`DesignError::NoDamage`] when the scene's design
/// does no damage; a failed cell's error or [`DesignError::Optimiser`] during the run.
pub fn optimise(
    study: &DesignStudy<'_>,
    options: &DesignOptions,
) -> Result<DesignOutcome, DesignError> {
    let started = Instant::now();
    let table: &DesignTable = study.scene.design.as_ref().ok_or(DesignError::NoDesign {
        reason: "the scene has no [design] table",
    })?;
    let choices = table.design_choices();
    if choices.is_empty() {
        return Err(DesignError::NoDesign {
            reason: "the [design] table has no design choice (role = \"design\") to optimise",
        });
    }
    let dff = study
        .scene
        .fatigue_spec()
        .ok_or(DesignError::NoFatigueSpec)?
        .dff;
    // The start: every [design] parameter's gradient from one sweep per cell.
    let all = table_parameters(study);
    let names: Vec<DesignParameter> = all.iter().map(|p| p.parameter.clone()).collect();
    let values = scene_values(study, &names)?;
    let point = DesignPoint {
        params: &names,
        values: &values,
    };
    let g0 = options.evaluate(study, &point, Want::Gradient, &|| {})?;
    let sens = sensitivity_table(&all, &values, &g0);
    let free: Vec<DesignParameter> = choices.iter().map(|c| c.0.clone()).collect();
    let bounds: Vec<(f64, f64)> = choices.iter().map(|c| c.1).collect();
    let index: Vec<usize> = free
        .iter()
        .map(|p| names.iter().position(|q| q == p).unwrap_or(0))
        .collect();
    let theta0: Vec<f64> = index.iter().map(|&i| values[i]).collect();
    if g0.damage_per_year <= 0.0 {
        return Err(DesignError::NoDamage {
            values: pairs(&free, &theta0),
        });
    }
    let start = ScatterGradient {
        damage_per_year: g0.damage_per_year,
        gradient: index.iter().map(|&i| g0.gradient[i]).collect(),
        cells: g0.cells.clone(),
    };
    let shared = Arc::new(Shared::default());
    shared.simulations.store(study.n_cells(), Ordering::Relaxed);
    shared
        .evaluated
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push((theta0.clone(), start));
    let transform = Transform::new(bounds.clone(), theta0);
    let problem = LogDamage {
        study,
        params: free.clone(),
        transform: transform.clone(),
        options: options.clone(),
        shared: Arc::clone(&shared),
    };
    let iterates = Arc::new(Mutex::new(Vec::new()));
    let recorder = Recorder {
        transform: transform.clone(),
        shared: Arc::clone(&shared),
        dff,
        iterates: Arc::clone(&iterates),
        on_iterate: options.on_iterate.clone(),
    };
    let opts = OptimOptions {
        method: Method::Lbfgs,
        max_iters: table.max_iterations,
        grad_tol: table.tolerance,
        rel_grad_tol: 0.0,
        first_step: 0.5,
        polish_steps: 0,
        ..OptimOptions::default()
    };
    let result = Minimizer::new(&problem, opts)
        .add_observer(recorder, ObserverMode::Always)
        .run(&transform.z0);
    let taken = shared
        .error
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .take();
    let r = match (result, taken) {
        (Ok(r), _) => r,
        (Err(_), Some(e)) => return Err(e),
        (Err(e), None) => {
            return Err(DesignError::Optimiser {
                source: Box::new(e),
            })
        }
    };
    let design = transform.theta(&r.theta);
    let last = problem
        .scatter(&design)
        .map_err(|e| DesignError::Optimiser {
            source: Box::new(crate::Error::NonFiniteObjective {
                quantity: match e {
                    DesignError::Run { .. } => "final design's damage",
                    _ => "final design",
                },
            }),
        })?;
    let iterates = iterates.lock().unwrap_or_else(|e| e.into_inner()).clone();
    let initial = iterates.first().cloned().unwrap_or_else(|| DesignIterate {
        iteration: 0,
        values: design.clone(),
        damage_per_year: last.damage_per_year,
        life_years: life(last.damage_per_year, dff),
        gradient: last.gradient.clone(),
        gradient_norm: f64::NAN,
        simulations: study.n_cells(),
    });
    Ok(DesignOutcome {
        parameters: choices,
        design,
        damage_per_year: last.damage_per_year,
        life_years: life(last.damage_per_year, dff),
        initial,
        iterates,
        sensitivities: sens,
        converged: r.converged,
        termination: r.termination.to_string(),
        cells: last.cells,
        simulations: shared.simulations.load(Ordering::Relaxed),
        seconds: started.elapsed().as_secs_f64(),
    })
}

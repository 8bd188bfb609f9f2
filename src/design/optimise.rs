//! The sensitivities of the annual damage at the scene's design, and the bounded L-BFGS design
//! that maximises the wellhead's life (module docs of [`crate::design`], "The optimiser").

use std::cell::RefCell;
use std::sync::Arc;
use std::time::Instant;

use super::search::{minimise_box, BoxSearch, BoxStep, BoxValue};
use super::{DesignError, DesignParameter, DesignStudy, DesignTable, Execution, Role};
use super::{DesignPoint, FreeParameter, ScatterGradient, Want};
use crate::fatigue::life_years;

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
    /// ‖P(u − ∇_u ln D_y) − u‖_∞, the optimiser's projected gradient norm in the log-scaled
    /// unit box (module docs): 0 where the design is optimal to first order.
    pub gradient_norm: f64,
    /// Cell runs so far: `adjoint_sweeps + forward_runs`.
    pub simulations: usize,
    /// Adjoint sweeps so far (each a forward and a reverse pass over a cell's record).
    pub adjoint_sweeps: usize,
    /// Forward runs so far (a line search's trial that needs the value alone; a hot spot's
    /// history before its adjoint sweep, [`DesignStudy::runs_per_evaluation`]).
    pub forward_runs: usize,
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
    /// Whether the projected gradient's tolerance stopped the run.
    pub converged: bool,
    /// Why the run stopped.
    pub termination: String,
    /// The cells at the optimised design (their damages: the adjoint sweeps' values that give
    /// `damage_per_year`), in the diagram's order.
    pub cells: Vec<super::CellGradient>,
    /// Cell runs in all (the sensitivities' included): `adjoint_sweeps + forward_runs`.
    pub simulations: usize,
    /// Adjoint sweeps in all (each a forward and a reverse pass over a cell's record).
    pub adjoint_sweeps: usize,
    /// Forward runs in all (line-search trials that need the value alone; hot-spot histories).
    pub forward_runs: usize,
    /// The design fatigue factor of the objective's hot spot.
    pub dff: f64,
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

/// The log-scaled unit box of the module docs: u_i = ln(θ_i/lo_i)/ln(hi_i/lo_i), θ_i(u) =
/// lo_i (hi_i/lo_i)^{u_i}; for a signed parameter ([`DesignParameter::is_signed`], the vessel's
/// offset, which may be 0 or negative) the affine u_i = (θ_i − lo_i)/(hi_i − lo_i), θ_i(u) =
/// lo_i + u_i (hi_i − lo_i). Exact at the bounds (u = 0 gives lo, u = 1 gives hi, bit for bit)
/// and at the start (θ(u0) = θ0 bit for bit, so that the start's evaluation is reused).
#[derive(Clone, Debug)]
struct LogBox {
    bounds: Vec<(f64, f64)>,
    /// Whether each parameter is scaled affinely (signed) rather than by logarithms.
    signed: Vec<bool>,
    theta0: Vec<f64>,
    u0: Vec<f64>,
}

impl LogBox {
    fn new(bounds: Vec<(f64, f64)>, signed: Vec<bool>, theta0: Vec<f64>) -> Self {
        let u0 = bounds
            .iter()
            .zip(&theta0)
            .zip(&signed)
            .map(|((&(lo, hi), &t), &affine)| {
                if affine {
                    ((t - lo) / (hi - lo)).clamp(0.0, 1.0)
                } else {
                    ((t / lo).ln() / (hi / lo).ln()).clamp(0.0, 1.0)
                }
            })
            .collect();
        LogBox {
            bounds,
            signed,
            theta0,
            u0,
        }
    }

    fn theta(&self, u: &[f64]) -> Vec<f64> {
        (0..u.len())
            .map(|i| {
                let (lo, hi) = self.bounds[i];
                if u[i].to_bits() == self.u0[i].to_bits() {
                    self.theta0[i]
                } else if u[i] <= 0.0 {
                    lo
                } else if u[i] >= 1.0 {
                    hi
                } else if self.signed[i] {
                    (lo + u[i] * (hi - lo)).clamp(lo, hi)
                } else {
                    (lo.ln() + u[i] * (hi / lo).ln()).exp().clamp(lo, hi)
                }
            })
            .collect()
    }

    /// dθ_i/du_i = θ_i ln(hi_i/lo_i) (hi_i − lo_i for a signed parameter).
    fn slope(&self, theta: &[f64]) -> Vec<f64> {
        theta
            .iter()
            .zip(&self.bounds)
            .zip(&self.signed)
            .map(
                |((t, (lo, hi)), &affine)| {
                    if affine {
                        hi - lo
                    } else {
                        t * (hi / lo).ln()
                    }
                },
            )
            .collect()
    }
}

/// L = 1/(DFF · D_y) (+∞ without damage).
fn life(damage_per_year: f64, dff: f64) -> f64 {
    life_years(damage_per_year, dff).unwrap_or(f64::INFINITY)
}

/// The cell runs of the evaluations so far: adjoint sweeps and forward runs.
#[derive(Clone, Copy, Debug, Default)]
struct Runs {
    adjoint: usize,
    forward: usize,
}

impl Runs {
    fn add(&mut self, study: &DesignStudy<'_>, want: Want) {
        let (a, f) = study.runs_per_evaluation(want);
        self.adjoint += a;
        self.forward += f;
    }
}

/// The design that maximises the wellhead's life over the diagram (module docs, "The
/// optimiser"): the projected L-BFGS of [`super::minimise_box`] on ln D_y in the log-scaled
/// unit box, from the scene's own design, the `[design]` table's design choices free and its
/// uncertainties at the scene's values. The first evaluation, at the scene's design, also gives
/// the sensitivities of every `[design]` parameter ([`sensitivities`]).
///
/// # Errors
/// [`DesignError::NoDesign`] without a `[design]` table or a design choice in it;
/// [`DesignStudy::evaluate`]'s at the start; [`DesignError::NoDamage`] when a design evaluated
/// does no damage; a failed cell's error during the run.
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
    let dff = study.dff()?;
    // The start: every [design] parameter's gradient from one sweep per cell.
    let all = table_parameters(study);
    let names: Vec<DesignParameter> = all.iter().map(|p| p.parameter.clone()).collect();
    let values = scene_values(study, &names)?;
    let point = DesignPoint {
        params: &names,
        values: &values,
    };
    let g0 = options.evaluate(study, &point, Want::Gradient, &|| {})?;
    let mut runs = Runs::default();
    runs.add(study, Want::Gradient);
    let sens = sensitivity_table(&all, &values, &g0);
    let free: Vec<DesignParameter> = choices.iter().map(|c| c.0.clone()).collect();
    let bounds: Vec<(f64, f64)> = choices.iter().map(|c| c.1).collect();
    let index: Vec<usize> = free
        .iter()
        .map(|p| names.iter().position(|q| q == p).unwrap_or(0))
        .collect();
    let theta0: Vec<f64> = index.iter().map(|&i| values[i]).collect();
    let signed: Vec<bool> = free.iter().map(DesignParameter::is_signed).collect();
    let scaled = LogBox::new(bounds, signed, theta0.clone());
    // ln D_y and its gradient in u (module docs) from a scatter evaluation at θ(u).
    let in_box = |theta: &[f64], g: &ScatterGradient| -> Result<BoxValue, DesignError> {
        if g.damage_per_year <= 0.0 {
            return Err(DesignError::NoDamage {
                values: pairs(&free, theta),
            });
        }
        let d = g.damage_per_year;
        let gradient = g
            .gradient
            .iter()
            .zip(scaled.slope(theta))
            .map(|(g, s)| g / d * s)
            .collect();
        Ok(BoxValue {
            value: d.ln(),
            gradient,
        })
    };
    let start = ScatterGradient {
        damage_per_year: g0.damage_per_year,
        gradient: index.iter().map(|&i| g0.gradient[i]).collect(),
        cells: g0.cells.clone(),
    };
    let first = in_box(&theta0, &start)?;
    // Every evaluation, for the iterates' records and the result's cells.
    let evaluated: RefCell<Vec<(Vec<f64>, ScatterGradient)>> = RefCell::new(vec![(theta0, start)]);
    let mut eval = |u: &[f64], want: Want| -> Result<BoxValue, DesignError> {
        let theta = scaled.theta(u);
        let point = DesignPoint {
            params: &free,
            values: &theta,
        };
        let g = options.evaluate(study, &point, want, &|| {})?;
        runs.add(study, want);
        let r = if want == Want::Gradient {
            in_box(&theta, &g)?
        } else if g.damage_per_year > 0.0 {
            BoxValue {
                value: g.damage_per_year.ln(),
                gradient: Vec::new(),
            }
        } else {
            return Err(DesignError::NoDamage {
                values: pairs(&free, &theta),
            });
        };
        let mut done = evaluated.borrow_mut();
        // A gradient evaluation replaces a value's at the same design (same D_y, bit for bit).
        done.retain(|(t, _)| *t != theta);
        done.push((theta, g));
        Ok(r)
    };
    let per_gradient = study.runs_per_evaluation(Want::Gradient);
    let per_value = study.runs_per_evaluation(Want::Value);
    let mut iterates: Vec<DesignIterate> = Vec::new();
    let mut on_step = |s: &BoxStep| {
        let theta = scaled.theta(&s.u);
        // The evaluation the search accepted, with its gradient (the point's last).
        let (d, gradient) = evaluated
            .borrow()
            .iter()
            .find(|(t, g)| *t == theta && !g.gradient.is_empty())
            .map(|(_, g)| (g.damage_per_year, g.gradient.clone()))
            .unwrap_or((s.value.exp(), Vec::new()));
        // Each evaluation of the study runs every cell; the start's (every [design]
        // parameter's gradient, for the sensitivities) is the search's first.
        let adjoint_sweeps = s.gradient_evaluations * per_gradient.0;
        let forward_runs =
            s.gradient_evaluations * per_gradient.1 + s.value_evaluations * per_value.1;
        let it = DesignIterate {
            iteration: s.iteration,
            values: theta,
            damage_per_year: d,
            life_years: life(d, dff),
            gradient,
            gradient_norm: s.projected_gradient_norm,
            simulations: adjoint_sweeps + forward_runs,
            adjoint_sweeps,
            forward_runs,
        };
        if let Some(f) = &options.on_iterate {
            f(&it);
        }
        iterates.push(it);
    };
    let settings = BoxSearch {
        max_iterations: table.max_iterations,
        tolerance: table.tolerance,
        ..BoxSearch::default()
    };
    let u0 = scaled.u0.clone();
    let outcome = minimise_box(&mut eval, &u0, Some(first), settings, &mut on_step)?;
    let last = outcome.last();
    let design = scaled.theta(&last.u);
    let cells = evaluated
        .borrow()
        .iter()
        .find(|(t, _)| *t == design)
        .map(|(_, g)| g.cells.clone())
        .unwrap_or_default();
    let initial = iterates[0].clone();
    let final_ = iterates[iterates.len() - 1].clone();
    Ok(DesignOutcome {
        parameters: choices,
        design,
        damage_per_year: final_.damage_per_year,
        life_years: final_.life_years,
        initial,
        iterates,
        sensitivities: sens,
        converged: outcome.termination.converged(),
        termination: outcome.termination.to_string(),
        cells,
        simulations: runs.adjoint + runs.forward,
        adjoint_sweeps: runs.adjoint,
        forward_runs: runs.forward,
        dff,
        seconds: started.elapsed().as_secs_f64(),
    })
}

//! The report of a design run (`chainbeam design`'s JSON, Python's `chainbeam.design`): one
//! serialisable structure built from the library's results, so that the command line and the
//! Python package give the same fields and the same numbers.

use std::collections::BTreeMap;

use serde::Serialize;

use super::{DesignOutcome, DesignParameter, DesignStudy, ScatterGradient, Sensitivity};
use crate::fatigue::life_years;

/// The report (the command line's `design --help` lists the fields).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DesignReport {
    /// ∂D_y/∂p at the scene's design \[1/year per unit of p\], keyed by parameter name.
    pub sensitivities: BTreeMap<String, f64>,
    /// ∂ ln L/∂ ln p = −(p/D_y) ∂D_y/∂p at the scene's design, keyed by parameter name.
    pub relative_sensitivities: BTreeMap<String, f64>,
    /// `design` or `uncertainty`, keyed by parameter name.
    pub roles: BTreeMap<String, &'static str>,
    /// The scene's own design: its values, D_y and life.
    pub scene_design: ReportPoint,
    /// The optimised values of the design choices (absent without an optimisation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub design: Option<BTreeMap<String, f64>>,
    /// D_y at the optimised design (the scene's without an optimisation) \[1/year\].
    pub damage_per_year: f64,
    /// L = 1/(DFF · D_y) there \[years\] (`None`: no damage, an infinite life).
    pub life_years: Option<f64>,
    /// Every iterate, the start first (absent without an optimisation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterates: Option<Vec<ReportIterate>>,
    /// Whether the optimiser converged (absent without an optimisation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    /// Why the optimiser stopped (absent without an optimisation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub termination: Option<String>,
    /// Cell runs in all: `adjoint_sweeps + forward_runs`.
    pub simulations: usize,
    /// Adjoint sweeps in all (each a forward and a reverse pass over a cell's record).
    pub adjoint_sweeps: usize,
    /// Forward runs in all (line-search trials that need the value alone).
    pub forward_runs: usize,
    /// Wall-clock time \[s\].
    pub seconds: f64,
    /// The record counted after the spin-up in every cell \[s\].
    pub record_s: f64,
    /// The spin-up left out of every record \[s\].
    pub spin_up_s: f64,
    /// The hot spot whose damage is the objective (`[design] hotspot`).
    pub hot_spot: ReportHotSpot,
    /// The cells at the reported design, in the diagram's order.
    pub cells: Vec<ReportCell>,
}

/// A design and its damage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportPoint {
    /// The parameters' values, keyed by name.
    pub values: BTreeMap<String, f64>,
    /// D_y \[1/year\].
    pub damage_per_year: f64,
    /// The life \[years\] (`None`: infinite).
    pub life_years: Option<f64>,
}

/// The hot spot whose damage is the objective.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportHotSpot {
    /// The `[[fatigue.hotspot]]`'s name; `None` (JSON `null`): the chain's base, the wellhead
    /// moment M_w = M₀ l₁/2 (the default objective).
    pub name: Option<String>,
    /// Its elevation above the chain's base \[m\] (0 for the chain's base).
    pub elevation: f64,
    /// The joints (0-based, joint 0 the base spring) whose torques its moment interpolates,
    /// lower and upper (the same joint when it lies on one; `[0, 0]` for the chain's base).
    pub joints: [usize; 2],
    /// The upper joint's weight w in M = (1 − w) M_lower + w M_upper.
    pub weight: f64,
    /// Its design fatigue factor (the life's L = 1/(DFF · D_y)).
    pub dff: f64,
}

impl ReportHotSpot {
    /// The objective's hot spot of `study` with the design fatigue factor `dff`.
    pub fn of(study: &DesignStudy<'_>, dff: f64) -> Self {
        match study.hot_spot().ok().flatten() {
            Some(h) => {
                let w =
                    crate::hotspots::interpolation_joints(&study.scene.beam.lengths, h.elevation);
                ReportHotSpot {
                    name: Some(h.name.clone()),
                    elevation: h.elevation,
                    joints: [w.lower, w.upper],
                    weight: w.weight,
                    dff,
                }
            }
            None => ReportHotSpot {
                name: None,
                elevation: 0.0,
                joints: [0, 0],
                weight: 0.0,
                dff,
            },
        }
    }
}

/// One iterate of the optimiser.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportIterate {
    /// The iteration (0: the scene's design).
    pub iteration: usize,
    /// The design choices' values, keyed by name.
    pub design: BTreeMap<String, f64>,
    /// D_y \[1/year\].
    pub damage_per_year: f64,
    /// The life \[years\] (`None`: infinite).
    pub life_years: Option<f64>,
    /// The projected gradient's norm ‖P(u − ∇_u ln D_y) − u‖_∞ in the log-scaled unit box
    /// (`None` when not finite).
    pub gradient_norm: Option<f64>,
    /// Cell runs so far: `adjoint_sweeps + forward_runs`.
    pub simulations: usize,
    /// Adjoint sweeps so far.
    pub adjoint_sweeps: usize,
    /// Forward runs so far.
    pub forward_runs: usize,
}

/// One cell at the reported design.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportCell {
    /// H_s \[m\] (absent without a diagram).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hs: Option<f64>,
    /// T_p \[s\] (absent without a diagram).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tp: Option<f64>,
    /// The waves' direction \[deg\] (absent when the cell gives none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction: Option<f64>,
    /// p_s.
    pub probability: f64,
    /// D_s over the counted record.
    pub damage: f64,
    /// T_s \[s\].
    pub duration_s: f64,
}

/// `name → value` of parameters and values in the same order.
fn by_name<'a, T: Copy>(
    names: impl IntoIterator<Item = &'a DesignParameter>,
    values: impl IntoIterator<Item = T>,
) -> BTreeMap<String, T> {
    names
        .into_iter()
        .map(|p| p.name().to_string())
        .zip(values)
        .collect()
}

/// A life as the report has it: `None` for an infinite one.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// L = 1/(DFF · D_y), `None` without damage.
fn life(damage_per_year: f64, dff: f64) -> Option<f64> {
    life_years(damage_per_year, dff).ok().and_then(finite)
}

impl DesignReport {
    /// The sensitivity fields of a table at the scene's design: (sensitivities, relative, roles,
    /// values).
    #[allow(clippy::type_complexity)]
    fn table(
        s: &[Sensitivity],
    ) -> (
        BTreeMap<String, f64>,
        BTreeMap<String, f64>,
        BTreeMap<String, &'static str>,
        BTreeMap<String, f64>,
    ) {
        let names: Vec<&DesignParameter> = s.iter().map(|x| &x.parameter).collect();
        (
            by_name(names.iter().copied(), s.iter().map(|x| x.damage_per_year)),
            by_name(names.iter().copied(), s.iter().map(|x| x.relative_life)),
            by_name(names.iter().copied(), s.iter().map(|x| x.role.name())),
            by_name(names.iter().copied(), s.iter().map(|x| x.value)),
        )
    }

    /// The cells of `g` with the diagram's sea states.
    fn cells(study: &DesignStudy<'_>, g: &[super::CellGradient]) -> Vec<ReportCell> {
        g.iter()
            .enumerate()
            .map(|(s, c)| {
                let sea = study.cells.map(|cs| cs[s].sea);
                ReportCell {
                    hs: sea.map(|x| x.hs),
                    tp: sea.map(|x| x.tp),
                    direction: sea.and_then(|x| x.direction),
                    probability: c.probability,
                    damage: c.damage,
                    duration_s: c.duration_s,
                }
            })
            .collect()
    }

    /// The report of the sensitivities at the scene's design ([`super::sensitivities`]'s
    /// result), `dff` the hot spot's design fatigue factor, `record` the counted record \[s\]
    /// and `seconds` the wall time.
    pub fn sensitivities(
        study: &DesignStudy<'_>,
        (g, s): (&ScatterGradient, &[Sensitivity]),
        dff: f64,
        record: f64,
        seconds: f64,
    ) -> Self {
        let (sens, rel, roles, values) = Self::table(s);
        let life = life(g.damage_per_year, dff);
        let runs = study.runs_per_evaluation(super::Want::Gradient);
        DesignReport {
            sensitivities: sens,
            relative_sensitivities: rel,
            roles,
            scene_design: ReportPoint {
                values,
                damage_per_year: g.damage_per_year,
                life_years: life,
            },
            design: None,
            damage_per_year: g.damage_per_year,
            life_years: life,
            iterates: None,
            converged: None,
            termination: None,
            simulations: runs.0 + runs.1,
            adjoint_sweeps: runs.0,
            forward_runs: runs.1,
            seconds,
            record_s: record,
            spin_up_s: study.spin_up,
            hot_spot: ReportHotSpot::of(study, dff),
            cells: Self::cells(study, &g.cells),
        }
    }

    /// The report of an optimisation ([`super::optimise`]'s outcome), `record` the counted
    /// record \[s\].
    pub fn optimised(study: &DesignStudy<'_>, o: &DesignOutcome, record: f64) -> Self {
        let (sens, rel, roles, values) = Self::table(&o.sensitivities);
        let names: Vec<&DesignParameter> = o.parameters.iter().map(|(p, _)| p).collect();
        let iterates = o
            .iterates
            .iter()
            .map(|it| ReportIterate {
                iteration: it.iteration,
                design: by_name(names.iter().copied(), it.values.iter().copied()),
                damage_per_year: it.damage_per_year,
                life_years: finite(it.life_years),
                gradient_norm: finite(it.gradient_norm),
                simulations: it.simulations,
                adjoint_sweeps: it.adjoint_sweeps,
                forward_runs: it.forward_runs,
            })
            .collect();
        DesignReport {
            sensitivities: sens,
            relative_sensitivities: rel,
            roles,
            scene_design: ReportPoint {
                values,
                damage_per_year: o.initial.damage_per_year,
                life_years: finite(o.initial.life_years),
            },
            design: Some(by_name(names.iter().copied(), o.design.iter().copied())),
            damage_per_year: o.damage_per_year,
            life_years: finite(o.life_years),
            iterates: Some(iterates),
            converged: Some(o.converged),
            termination: Some(o.termination.clone()),
            simulations: o.simulations,
            adjoint_sweeps: o.adjoint_sweeps,
            forward_runs: o.forward_runs,
            seconds: o.seconds,
            record_s: record,
            spin_up_s: study.spin_up,
            hot_spot: ReportHotSpot::of(study, o.dff),
            cells: Self::cells(study, &o.cells),
        }
    }

    /// The report's numbers that must be finite (sensitivities, relative sensitivities, the
    /// damage per year, the design): the command line and the package refuse to return a report
    /// with a non-finite one.
    pub fn numbers(&self) -> Vec<f64> {
        let mut numbers: Vec<f64> = self.sensitivities.values().copied().collect();
        numbers.extend(self.relative_sensitivities.values());
        numbers.push(self.damage_per_year);
        if let Some(d) = &self.design {
            numbers.extend(d.values());
        }
        numbers
    }
}

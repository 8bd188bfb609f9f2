//! The expected annual damage over a scatter diagram and its exact design gradient (module docs
//! of [`crate::design`]): one adjoint sweep per cell, the cells combined in the diagram's order.

#[cfg(feature = "parallel")]
use rayon::prelude::*;

use super::hotspot::hot_spot_sweep;
use super::tangents::node_tangents;
use super::{DesignError, DesignParameter};
use crate::adjoint::{ControlProblem, History, Objective, Stage};
use crate::base::Scalar;
use crate::fatigue::SECONDS_PER_YEAR;
use crate::fatigue::{combine_scatter, CellDamage, DamageGradient, ScatterCell, WellheadDamage};
use crate::fatigue_study::{
    cell_scene, spin_up_steps, with_record, ControlSettings, ControllerKind, StudyError,
};
use crate::hotspots::HotSpotSpec;
use crate::optimize::any::scene_start;
use crate::scene::{Scene, ValidScene};

/// Where the cells of [`DesignStudy::evaluate`] run. The result is the same bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Execution {
    /// One after the other, on the calling thread.
    Serial,
    /// On rayon's thread pool (with the `parallel` feature; serially without it).
    #[default]
    Parallel,
}

/// A scatter-diagram study of a scene's design: the scene (its `[control]` applied as written,
/// its `[fatigue]` table or its `[pipe]`'s section at the wellhead), the diagram, and the record
/// of every cell (as `chainbeam fatigue --scatter`: each cell sets `[loads.waves]` hs, tp and
/// direction and keeps the seed).
#[derive(Clone, Copy, Debug)]
pub struct DesignStudy<'a> {
    /// The scene (its own values are the design's start).
    pub scene: &'a Scene,
    /// The scatter diagram; `None`: the scene's own sea, probability 1.
    pub cells: Option<&'a [ScatterCell]>,
    /// Seconds counted after the spin-up in every cell (each run is spin-up + record long);
    /// `None`: the scene's own `[time]`.
    pub record: Option<f64>,
    /// The first seconds of every record left out of the count (the start-up from rest).
    pub spin_up: f64,
}

/// A design: values of some [`DesignParameter`]s (the others at the scene's values).
#[derive(Clone, Copy, Debug)]
pub struct DesignPoint<'a> {
    /// The parameters set.
    pub params: &'a [DesignParameter],
    /// Their values, in their units.
    pub values: &'a [f64],
}

/// What an evaluation computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    /// The damage alone, by forward runs (no gradient).
    Value,
    /// The damage and its gradient with respect to every parameter of the design, by adjoint
    /// sweeps.
    Gradient,
}

/// One cell's damage and its design gradient.
#[derive(Clone, Debug, PartialEq)]
pub struct CellGradient {
    /// p_s.
    pub probability: f64,
    /// Miner's sum D_s over the counted record.
    pub damage: f64,
    /// T_s, the counted record's duration \[s\].
    pub duration_s: f64,
    /// ∂D_s/∂θ_i, in the order of the design's parameters (empty for [`Want::Value`]).
    pub gradient: Vec<f64>,
}

/// The expected annual damage over the diagram and its gradient.
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterGradient {
    /// D_y = Σ_s p_s · D_s · Y/T_s \[1/year\].
    pub damage_per_year: f64,
    /// ∂D_y/∂θ_i = Σ_s p_s · ∂D_s/∂θ_i · Y/T_s, in the order of the parameters asked for.
    pub gradient: Vec<f64>,
    /// The cells, in the diagram's order.
    pub cells: Vec<CellGradient>,
}

/// The fatigue objective of a design cell: the wellhead's rainflow damage of the record after
/// its first `skip` samples (the spin-up), J = D(M₀(t_skip), …, M₀(t_N)), which is
/// `chainbeam fatigue`'s damage of the same counted record ([`WellheadDamage`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct CountedDamage {
    damage: WellheadDamage,
    skip: usize,
}

impl Objective for CountedDamage {
    /// No stage cost: D is the history term.
    fn stage<D: Scalar>(&self, _s: Stage<'_, D>) -> D {
        D::zero()
    }
    fn has_history(&self) -> bool {
        true
    }
    /// D of M₀(t_skip..=t_N) and its gradient there (zero on the spin-up's samples).
    fn history<D: Scalar>(&self, h: History<'_, D>) -> crate::Result<D> {
        let k = self.skip.min(h.moment.len());
        let spatial = !h.moment_x.is_empty();
        let grad_x: &mut [D] = if spatial { &mut h.grad_x[k..] } else { &mut [] };
        let out = DamageGradient {
            grad: &mut h.grad[k..],
            grad_x,
        };
        let mx = spatial.then(|| &h.moment_x[k..]);
        Ok(self.damage.value_and_gradient(&h.moment[k..], mx, out)?)
    }
    fn power_proxy(&self) -> Option<f64> {
        Some(self.damage.exponent())
    }
}

/// D and ∂D/∂θ (or D alone, by a forward run, when `params` is `None`) on `scene` in the model
/// `DIM`: the library's parameters `params` and the buoyancy diameters of the stack-up's
/// segments `segments` from the same adjoint sweep (their node tangents,
/// [`node_tangents`]).
/// Returns (D, ∂D/∂params, ∂D/∂D_b per segment).
fn cell_sweep<const DIM: usize>(
    scene: &ValidScene,
    objective: CountedDamage,
    params: Option<&[crate::Parameter]>,
    segments: &[usize],
) -> crate::Result<(f64, Vec<f64>, Vec<f64>)> {
    let (map, theta0) = scene_start(scene)?;
    let two_axis = scene.has_two_axis_control();
    let problem = ControlProblem::builder(scene)
        .map(map)
        .objective(objective)
        .two_axis(two_axis)
        .build_in::<DIM>()?;
    let Some(params) = params else {
        return Ok((problem.value(&theta0)?, Vec::new(), Vec::new()));
    };
    if segments.is_empty() {
        let r = problem.adjoint(&theta0, params)?;
        return Ok((r.value, r.parameter_gradient, Vec::new()));
    }
    let nodes = node_tangents::<DIM>(scene, segments)?;
    let (r, buoyancy) = problem.adjoint_with_nodes(&theta0, params, nodes)?;
    Ok((r.value, r.parameter_gradient, buoyancy))
}

impl DesignStudy<'_> {
    /// The number of cells (1 without a diagram).
    pub fn n_cells(&self) -> usize {
        self.cells.map_or(1, <[ScatterCell]>::len)
    }

    /// The cell runs of one evaluation ([`DesignStudy::evaluate`]): (adjoint sweeps, forward
    /// runs). [`Want::Gradient`]: one adjoint sweep per cell (a forward and a reverse pass over
    /// its record); [`Want::Value`]: one forward run per cell.
    ///
    /// At a named hot spot ([`DesignStudy::hot_spot`]) an evaluation with the gradient also
    /// runs the forward run that gives the hot spot's moment history and its damage's gradient
    /// before the adjoint sweep (module docs of `design::hotspot`): one adjoint sweep and one
    /// forward run per cell.
    ///
    /// A segment's buoyancy diameter ([`DesignParameter::is_node_quantity`]) adds no run: its
    /// derivative comes from the same adjoint sweep (per step, a few O(n) evaluations of the
    /// terms in `Dual64`, module docs of [`crate::adjoint`] "Per-node quantities").
    pub fn runs_per_evaluation(&self, want: Want) -> (usize, usize) {
        let n = self.n_cells();
        let at_hot_spot = matches!(self.hot_spot(), Ok(Some(_)));
        match want {
            Want::Gradient if at_hot_spot => (n, n),
            Want::Gradient => (n, 0),
            Want::Value => (0, n),
        }
    }

    /// The `[[fatigue.hotspot]]` the objective reads (`[design] hotspot`), `None` for the
    /// chain's base (the wellhead moment M_w = M₀ l₁/2 of the adjoint's history term, the
    /// default).
    ///
    /// # Errors
    /// [`DesignError::NoHotSpot`] when the scene has no hot spot of the name asked for.
    pub fn hot_spot(&self) -> Result<Option<&HotSpotSpec>, DesignError> {
        let Some(name) = self.scene.design.as_ref().and_then(|d| d.hotspot.as_ref()) else {
            return Ok(None);
        };
        self.scene
            .hotspots
            .iter()
            .find(|h| &h.name == name)
            .map(Some)
            .ok_or_else(|| DesignError::NoHotSpot { name: name.clone() })
    }

    /// The design fatigue factor of the objective's hot spot (its `[[fatigue.hotspot]]`'s, else
    /// the `[fatigue]` table's or the `[pipe]`'s default), for the life L = 1/(DFF · D_y).
    ///
    /// # Errors
    /// [`DesignError::NoFatigueSpec`]; [`DesignStudy::hot_spot`]'s.
    pub fn dff(&self) -> Result<f64, DesignError> {
        if let Some(h) = self.hot_spot()? {
            return Ok(h.spec.dff);
        }
        Ok(self
            .scene
            .fatigue_spec()
            .ok_or(DesignError::NoFatigueSpec)?
            .dff)
    }

    /// Checks the request before any run: the diagram (cells, their number, the probabilities),
    /// the record and spin-up, the section, and the parameters (each one the scene's model has,
    /// once, with finite values).
    ///
    /// # Errors
    /// [`DesignError`] naming what is wrong.
    pub fn check(&self, point: &DesignPoint<'_>) -> Result<(), DesignError> {
        if self.scene.time.initial == crate::scene::Initial::Static {
            return Err(DesignError::StaticStart);
        }
        let (params, values) = (point.params, point.values);
        if params.len() != values.len() {
            return Err(DesignError::BadValues {
                reason: format!("{} values for {} parameters", values.len(), params.len()),
            });
        }
        let mut lib = Vec::with_capacity(params.len());
        for (i, (p, v)) in params.iter().zip(values).enumerate() {
            p.value(self.scene)
                .map_err(|reason| DesignError::NotInModel {
                    name: p.name(),
                    reason,
                })?;
            // A parameter without a library parameter (a segment's buoyancy diameter) is
            // differentiated through the adjoint sweep's node tangents.
            if !p.is_node_quantity() {
                let q = p
                    .parameter(self.scene)
                    .ok_or_else(|| DesignError::NotInModel {
                        name: p.name(),
                        reason: "the scene's model has no such parameter",
                    })?;
                if lib.contains(&q) {
                    return Err(DesignError::BadValues {
                        reason: format!(
                            "{} is the same spring as another parameter of the design",
                            p.name()
                        ),
                    });
                }
                lib.push(q);
            }
            if !v.is_finite() {
                return Err(DesignError::BadValues {
                    reason: format!("{} = {v} is not finite", p.name()),
                });
            }
            if params[..i].contains(p) {
                return Err(DesignError::BadValues {
                    reason: format!("{} is given twice", p.name()),
                });
            }
        }
        if self.scene.fatigue_spec().is_none() {
            return Err(DesignError::NoFatigueSpec);
        }
        self.hot_spot()?;
        match self.cells {
            Some([]) => return Err(StudyError::NoCells.into()),
            Some(cells) if cells.len() > crate::fatigue_study::MAX_SCATTER_CELLS => {
                return Err(StudyError::TooManyCells { cells: cells.len() }.into())
            }
            Some(cells) => {
                let dummy: Vec<CellDamage> = cells
                    .iter()
                    .map(|c| CellDamage {
                        probability: c.probability,
                        damage: 0.0,
                        duration_s: 1.0,
                    })
                    .collect();
                combine_scatter(&dummy).map_err(StudyError::from)?;
            }
            None => {}
        }
        match self.record {
            Some(record) => {
                with_record(self.scene, &self.settings(), ControllerKind::Scene, record)?;
            }
            None => {
                spin_up_steps(self.scene, self.spin_up)?;
            }
        }
        Ok(())
    }

    fn settings(&self) -> ControlSettings {
        ControlSettings {
            spin_up: self.spin_up,
            record: self.record,
            ..ControlSettings::default()
        }
    }

    /// The scene of cell `cell` with the design `point` set: the cell's sea state, then its
    /// record.
    ///
    /// # Errors
    /// The study's (the sea state or the record the scene refuses, naming the key).
    pub fn cell_scene(
        &self,
        cell: usize,
        point: &DesignPoint<'_>,
    ) -> Result<ValidScene, DesignError> {
        let mut scene = self.scene.clone();
        // The run needs no `[design]` (whose bounds a design being evaluated, e.g. a finite
        // difference's, may leave).
        scene.design = None;
        for (p, &v) in point.params.iter().zip(point.values) {
            p.set(&mut scene, v).map_err(|e| DesignError::Run {
                cell,
                source: Box::new(e.into()),
            })?;
        }
        // Validated once for the design, the sea state and the record together.
        let sea = self.cells.map(|cells| (&cells[cell].sea, cell));
        let settings = self.settings();
        let record = self.record.map(|r| (&settings, ControllerKind::Scene, r));
        Ok(match (sea, record) {
            (None, None) => scene.into_valid().map_err(|e| DesignError::Run {
                cell,
                source: Box::new(e.into()),
            })?,
            _ => cell_scene(&scene, sea, record)?,
        })
    }

    /// Cell `cell` (0-based, in the diagram's order) at the design `point`: its damage D_s, by
    /// one adjoint sweep with ∂D_s/∂θ for every parameter of the design ([`Want::Gradient`]) or
    /// by a forward run ([`Want::Value`]). Its numbers do not depend on the thread or machine it
    /// ran on.
    ///
    /// # Errors
    /// [`DesignError::Run`] for a failed run (or a cancelled one), the study's errors for the
    /// cell's scene, [`DesignError::NoFatigueSpec`].
    pub fn run_cell(
        &self,
        cell: usize,
        point: &DesignPoint<'_>,
        want: Want,
    ) -> Result<CellGradient, DesignError> {
        let run_err = |source: crate::Error| DesignError::Run {
            cell,
            source: Box::new(source),
        };
        crate::cancel::check().map_err(run_err)?;
        if want == Want::Gradient {
            self.refuse_no_gradient(point)?;
        }
        let scene = self.cell_scene(cell, point)?;
        let skip = spin_up_steps(&scene, self.spin_up)?;
        let spec = scene.fatigue_spec().ok_or(DesignError::NoFatigueSpec)?;
        let damage =
            WellheadDamage::new(&spec, scene.moment_measure()).map_err(StudyError::from)?;
        let objective = CountedDamage { damage, skip };
        // The library's parameters, for a gradient only (a value needs none: a segment's
        // buoyancy diameter, which has none, is evaluated through the cell's scene and
        // differentiated by the same adjoint sweep through its node tangents).
        let lib = match want {
            Want::Gradient => Some(
                point
                    .params
                    .iter()
                    .filter(|p| !p.is_node_quantity())
                    .map(|p| p.parameter(&scene))
                    .collect::<Option<Vec<crate::Parameter>>>()
                    .ok_or_else(|| DesignError::NotInModel {
                        name: point
                            .params
                            .iter()
                            .find(|p| p.parameter(&scene).is_none())
                            .map(DesignParameter::name)
                            .unwrap_or_default(),
                        reason: "the scene's model has no such parameter",
                    })?,
            ),
            Want::Value => None,
        };
        let lib = lib.as_deref();
        // The buoyancy diameters' segments, for a gradient only.
        let segments = match lib {
            Some(_) => node_segments(point, &scene)?,
            None => Vec::new(),
        };
        let (damage, adjoint, buoyancy) = if let Some(h) = self.hot_spot()? {
            hot_spot_sweep(&scene, h, skip, lib, &segments)
                .map_err(|e| e.into_design(cell, &h.name))?
        } else if scene.is_spatial() {
            cell_sweep::<3>(&scene, objective, lib, &segments).map_err(run_err)?
        } else {
            cell_sweep::<2>(&scene, objective, lib, &segments).map_err(run_err)?
        };
        let gradient = match lib {
            Some(_) => in_design_order(point.params, adjoint, buoyancy),
            None => Vec::new(),
        };
        let h = scene.time.step;
        Ok(CellGradient {
            probability: self.cells.map_or(1.0, |c| c[cell].probability),
            damage,
            duration_s: scene.time.steps as f64 * h - skip as f64 * h,
            gradient,
        })
    }

    /// Combines the cells (in the diagram's order, as given): D_y = Σ_s p_s · D_s · Y/T_s by
    /// [`combine_scatter`] (the same arithmetic as `chainbeam fatigue --scatter`), and
    /// ∂D_y/∂θ_i = Σ_s p_s · (∂D_s/∂θ_i · Y/T_s) summed in the same order.
    ///
    /// # Errors
    /// The combination's [`crate::fatigue::FatigueError`] (a probability outside \[0, 1\], a sum
    /// over 1, a non-finite damage); [`DesignError::BadValues`] for cells whose gradients differ
    /// in length or are not finite.
    pub fn combine(cells: Vec<CellGradient>) -> Result<ScatterGradient, DesignError> {
        let damages: Vec<CellDamage> = cells
            .iter()
            .map(|c| CellDamage {
                probability: c.probability,
                damage: c.damage,
                duration_s: c.duration_s,
            })
            .collect();
        let total = combine_scatter(&damages).map_err(StudyError::from)?;
        let m = cells.first().map_or(0, |c| c.gradient.len());
        let mut gradient = vec![0.0; m];
        for (s, c) in cells.iter().enumerate() {
            if c.gradient.len() != m || c.gradient.iter().any(|g| !g.is_finite()) {
                return Err(DesignError::BadValues {
                    reason: format!(
                        "cell {s}: its gradient has {} values (expected {m}) or one that is \
                         not finite",
                        c.gradient.len()
                    ),
                });
            }
            for (g, dc) in gradient.iter_mut().zip(&c.gradient) {
                *g += c.probability * (dc * SECONDS_PER_YEAR / c.duration_s);
            }
        }
        Ok(ScatterGradient {
            damage_per_year: total.damage_per_year,
            gradient,
            cells,
        })
    }

    /// D_y and ∂D_y/∂θ (with [`Want::Gradient`]) at the design `point` (module docs): every
    /// cell by [`DesignStudy::run_cell`] on `execution`, combined by [`DesignStudy::combine`].
    /// `on_cell` is called after each cell, from the thread that ran it (a progress bar).
    ///
    /// # Errors
    /// [`DesignStudy::check`]'s; the first failed cell's error in the diagram's order; the
    /// combination's.
    pub fn evaluate(
        &self,
        point: &DesignPoint<'_>,
        want: Want,
        execution: Execution,
        on_cell: &(dyn Fn() + Sync),
    ) -> Result<ScatterGradient, DesignError> {
        self.check(point)?;
        if want == Want::Gradient {
            self.refuse_no_gradient(point)?;
        }
        let job = |s: usize| {
            let r = self.run_cell(s, point, want);
            on_cell();
            r
        };
        let n = self.n_cells();
        let results: Vec<Result<CellGradient, DesignError>> = match execution {
            #[cfg(feature = "parallel")]
            Execution::Parallel => (0..n).into_par_iter().map(job).collect(),
            _ => (0..n).map(job).collect(),
        };
        let cells = results.into_iter().collect::<Result<Vec<_>, _>>()?;
        Self::combine(cells)
    }
}

/// The stack-up segment of every buoyancy diameter of the design `params`
/// ([`DesignParameter::is_node_quantity`]), in their order, on the cell's `scene`.
fn node_segments(point: &DesignPoint<'_>, scene: &Scene) -> Result<Vec<usize>, DesignError> {
    point
        .params
        .iter()
        .filter(|p| p.is_node_quantity())
        .map(|p| {
            p.segment(scene).ok_or_else(|| DesignError::NotInModel {
                name: p.name(),
                reason: "the scene has no [[stackup.segment]] of that name",
            })
        })
        .collect()
}

/// The gradient in the design's order `params`: the library's parameters' (`adjoint`, in their
/// order) and the buoyancy diameters' (`buoyancy`, in theirs), both from the cell's one adjoint
/// sweep.
fn in_design_order(params: &[DesignParameter], adjoint: Vec<f64>, buoyancy: Vec<f64>) -> Vec<f64> {
    let mut from_adjoint = adjoint.into_iter();
    let mut from_nodes = buoyancy.into_iter();
    params
        .iter()
        .map(|p| {
            let g = if p.is_node_quantity() {
                from_nodes.next()
            } else {
                from_adjoint.next()
            };
            g.unwrap_or(f64::NAN)
        })
        .collect()
}

impl DesignStudy<'_> {
    /// [`DesignError::NoGradient`] for the first parameter of `point` that moves the chain's
    /// per-node quantities (a segment's buoyancy diameter, [`DesignParameter::is_node_quantity`])
    /// in a study whose adjoint sweep has no node tangents for it: a scene with a `[control]` (a
    /// driven tip's mass has no node-by-node partials), the momentum drag (its constant comes
    /// from the masses in real arithmetic), joint damping (its M⁻¹ has no node-by-node partials,
    /// refused by the sweep itself). The objective at a `[design] hotspot` carries them as the
    /// chain's base does.
    fn refuse_no_gradient(&self, point: &DesignPoint<'_>) -> Result<(), DesignError> {
        let Some(p) = point.params.iter().find(|p| p.is_node_quantity()) else {
            return Ok(());
        };
        let reason = if self.scene.control.is_some() {
            Some("in a scene with a [control]")
        } else if self
            .scene
            .stackup
            .as_ref()
            .is_some_and(|st| st.drag_model != crate::scene::DragModel::Morison)
        {
            Some("with the momentum drag (stackup.drag_model = \"morison\" needed)")
        } else {
            None
        };
        match reason {
            Some(reason) => Err(DesignError::NoGradient {
                name: p.name(),
                reason,
            }),
            None => Ok(()),
        }
    }
}

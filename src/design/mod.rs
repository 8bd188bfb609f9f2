//! Design for fatigue: the exact gradient of the wellhead's expected annual damage over a
//! scatter diagram with respect to physical design parameters, and the bounded design that
//! maximises the wellhead's life (`chainbeam design`, Python's `chainbeam.design`).
//!
//! # The objective
//! For the design θ (the values of the [`DesignParameter`]s) and cell s of the diagram
//! (probability p_s, a record of T_s seconds counted after the spin-up, Miner's sum D_s(θ) of the
//! wellhead stress over it), the expected damage per year and the life are
//! ```text
//! D_y(θ) = Σ_s p_s · D_s(θ) · Y/T_s,      L(θ) = 1/(DFF · D_y(θ)) years,
//! ∂D_y/∂θ_i = Σ_s p_s · (∂D_s/∂θ_i) · Y/T_s,
//! ```
//! Y = 365.25 · 86400 s: the combination of `chainbeam fatigue --scatter`
//! ([`crate::fatigue::combine_scatter`]), the cells in the diagram's order. D_s is the rainflow
//! damage at the wellhead that `chainbeam fatigue` reports for the same record (the fatigue
//! objective's history term, [`crate::FatigueObjective`]; the spin-up's samples are left out of
//! the count as there), and ∂D_s/∂θ_i comes from one adjoint sweep of the cell's record
//! ([`crate::ControlProblem::adjoint`] with the physical parameters): every parameter's
//! derivative from one forward and one reverse pass, whatever their number. The damage is
//! piecewise smooth in θ (docs of [`crate::fatigue::damage`]): the gradient is that of the
//! rainflow pairing at θ, exact there; a pairing change is a kink.
//!
//! # The hot spot
//! By default the hot spot is the chain's base, the wellhead, whose moment M_w = M₀ · l₁/2 the
//! adjoint's objectives read (its history term). `[design] hotspot = "NAME"` makes it a
//! `[[fatigue.hotspot]]` instead: D_s is then the rainflow damage of that hot spot's moment,
//! interpolated in elevation between the two joints around it ([`crate::hotspots`]), with its
//! own section, SCF, S-N curve and DFF, the damage `chainbeam fatigue` reports for it. Its
//! gradient comes from the damage linearised at the run's rainflow pairing, J = Σ_k g_k M(t_k)
//! with g_k = ∂D_s/∂M(t_k) from a forward run, whose adjoint seed is the blend of the two joints'
//! seeds (`design::hotspot`): a forward run and an adjoint sweep per cell, in the planar model.
//! A segment's buoyancy diameter is differentiated there by the same sweep's node tangents, as
//! at the chain's base.

//! # The parameters ([`DesignParameter`])
//! The top tension T (`loads.tension`), the lower flex joint's rotational stiffness (the base
//! spring k₁, `beam.base_stiffness`, which is also the k₁ of the wellhead moment), the upper
//! flex joint's (the tip spring, `beam.tip_stiffness`), and the soil's p-y modulus at the mudline
//! (`soil.modulus`), an uncertainty by default ([`Role::Uncertainty`]): its sensitivity is
//! reported, it is not optimised; the vessel's mean offset Z₀ (`vessel.offset`, with
//! `support = "vessel"`), which the top's prescribed motion Z(t) = ρ(t)(Z₀ + d_z X_w(t)) reads
//! (and the prescribed part of a vessel under thrust): its adjoint is that of the top's
//! constraint, the cotangents of Z(t_k) and Ż(t_k) times ∂Z/∂Z₀ = ρ(t_k), ∂Ż/∂Z₀ = ρ̇(t_k);
//! and, in a scene with a `[stackup]`, the rotational stiffness
//! of each named flex joint (`stackup.flex_joint.<name>.stiffness`: the joint spring where it
//! sits, base, tip or interior). Each maps to one [`crate::Parameter`] whose exact adjoint
//! gradient the library has; the scene's value is the model's value (the chain is built from
//! the scene with the parameter set).
//!
//! The buoyancy modules' outer diameter D_b of a named stack-up segment
//! (`stackup.segment.<name>.buoyancy_diameter`, [`DesignParameter::BuoyancyDiameter`]) moves
//! every node of the segment: its mass with added mass, its submerged weight (the effective
//! tension), its Morison drag coefficient and its waves' inertia coefficient (the last three and
//! the added mass through D_h = D_b unless the segment gives `hydrodynamic_diameter`). No
//! library parameter carries these: its gradient comes from the cell's one adjoint sweep,
//! the same as the other parameters', through the node tangents of the chain
//! ([`crate::adjoint::adjoint_gradient_with_nodes`], module docs of [`crate::adjoint`]
//! "Per-node quantities"). The reverse step adds the per-node masses' hand-written partials of
//! RATTLE's drift and projection (θ̄ += h q̄′ᵀ(∂M⁻¹/∂D_b)p½ − (Ĝᵀŷ)ᵀ(∂M⁻¹/∂D_b)p′) and the
//! terms' contractions w·∂F/∂D_b at the recorded state, each one evaluation of the terms on
//! the chain in `Dual64` with every node quantity x_k seeded as x_k + ε ∂x_k/∂D_b, the
//! derivatives exact ([`crate::scene::Stackup::buoyancy_tangents`]: the layout is linear in
//! the segment's per-length quantities, which are polynomials in D_b), the waves' series W
//! and G (linear in the nodes' masses and inertia coefficients) with their derivative parts
//! ([`crate::Chain::set_node_quantities`]). ∂D_s/∂D_b is exact to round-off (it equals the
//! derivative part of the cell's run in `Dual64` with the same seeds, forward mode, to
//! 10⁻¹²: tests/design/design_buoyancy.rs). Counting the runs: one adjoint sweep per cell
//! for all the parameters, where the forward mode took one more run in dual numbers per cell
//! and per buoyancy parameter; each buoyancy parameter adds per step two `Dual64`
//! evaluations of the conservative terms and two of Morison's drag (O(n), no Newton solve)
//! to the sweep. The objective at a `[design] hotspot` carries the same node tangents through
//! its adjoint sweep of the linearised damage J = Σ_k g_k M(t_k) (its stage cost reads the
//! nodes' positions alone, so D_b enters through the chain;
//! tests/design/design_buoyancy_hotspot.rs: equal to the forward mode to 10⁻¹²). It needs the node-by-node Morison drag, a scene without
//! a control and no joint damping; elsewhere a gradient is refused ([`DesignError::NoGradient`],
//! or the sweep's [`crate::model::ModelError::NodeQuantities`] for joint damping) and the values
//! alone are evaluated.
//!
//! # Cells and executors
//! The cells are independent: [`DesignStudy::evaluate`] runs them serially or on rayon's pool
//! ([`Execution`]), and [`DesignStudy::run_cell`] runs one (the Python package sends these to a
//! Dask cluster). Each cell's numbers do not depend on where it ran, and
//! [`DesignStudy::combine`] sums them in the diagram's order, so the damage and its gradient are
//! the same bit for bit on any executor.
//!
//! # The optimiser ([`optimise`])
//! A projected L-BFGS with an active set ([`minimise_box`], in the manner of L-BFGS-B) on ln D_y,
//! the scaled objective (a damage spans orders of magnitude; its logarithm's gradient does not),
//! in the design choices scaled by the logarithms of their bounds to the unit box,
//! ```text
//! u_i = ln(θ_i/lo_i) / ln(hi_i/lo_i) ∈ [0, 1],      θ_i = lo_i · (hi_i/lo_i)^{u_i},
//! ∂ ln D_y/∂u_i = (1/D_y) · ∂D_y/∂θ_i · θ_i ln(hi_i/lo_i),
//! ```
//! so that a unit of u is a parameter's whole range whatever its unit, and a stiffness spanning
//! decades moves by factors (every bound is positive, `[design]`). A signed parameter (the
//! vessel's offset, whose value may be 0 or negative: [`DesignParameter::is_signed`]) is
//! scaled affinely instead,
//! ```text
//! u_i = (θ_i − lo_i)/(hi_i − lo_i),   θ_i = lo_i + u_i (hi_i − lo_i),
//! ∂ ln D_y/∂u_i = (1/D_y) · ∂D_y/∂θ_i · (hi_i − lo_i).
//! ``` A bound is reached exactly: a
//! step that would leave the box lands on the bound, and a variable on a bound whose gradient
//! pushes outward is held there (active) while the others move. The first step is the steepest
//! descent scaled so that its longest component spans its variable's whole range (a damage
//! monotone in a parameter sends it to its bound in one step); later steps are L-BFGS steps on
//! the free variables, each accepted by Armijo's condition along the projected path. It starts
//! at the scene's own design and stops, converged, when the projected gradient's norm
//! ‖P(u − ∇_u ln D_y) − u‖_∞ (zero exactly at a first-order optimum, bounds included) is at most
//! `tolerance` (`[design] tolerance`), or after `max_iterations`, or when no trial decreases ln D_y
//! (a kink of the rainflow pairing).
//!
//! # Counting the simulations
//! An evaluation with the gradient runs one adjoint sweep per cell: a forward pass over the
//! cell's record and a reverse pass back over it (counted as one cell run, `adjoint_sweeps`);
//! a line-search trial that needs the value alone runs one forward pass per cell (counted as one
//! cell run, `forward_runs`). The reports give both and their sum, `simulations`.

mod hotspot;
mod optimise;
mod report;
mod scatter;
mod search;
mod tangents;

pub use optimise::{
    optimise, sensitivities, sensitivities_with, CellRunner, DesignIterate, DesignOptions,
    DesignOutcome, IterateCallback, Sensitivity,
};
pub use report::{DesignReport, ReportCell, ReportHotSpot, ReportIterate, ReportPoint};
pub use scatter::{CellGradient, DesignPoint, DesignStudy, Execution, ScatterGradient, Want};
pub use search::{
    minimise_box, projected_gradient_norm, BoxOutcome, BoxSearch, BoxStep, BoxTermination, BoxValue,
};

use thiserror::Error;

use crate::fatigue_study::StudyError;
pub use crate::scene::{DesignParameter, DesignTable, FreeParameter, Role};

/// Why a design could not be evaluated or optimised; each names the key, cell or parameter.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum DesignError {
    /// The scene has no `[design]` table (or none with a design choice, for an optimisation).
    #[error("{reason} (docs/scene-format.md \"[design]\")")]
    NoDesign {
        /// What is missing.
        reason: &'static str,
    },
    /// The scene has neither a `[fatigue]` table nor a `[pipe]` whose section could serve.
    #[error("the scene has no [fatigue] table (nor a [pipe] whose section could serve)")]
    NoFatigueSpec,
    /// A parameter of the request is not one the scene's model has.
    #[error("{name}: {reason}")]
    NotInModel {
        /// The parameter's name.
        name: String,
        /// Why.
        reason: &'static str,
    },
    /// A gradient was asked for with respect to a segment's buoyancy diameter in a study whose
    /// adjoint sweep has no node tangents for it ([`DesignParameter::is_node_quantity`]): its
    /// values D_y alone can be evaluated there.
    #[error(
        "{name}: its design gradient (adjoint, node by node) is not available {reason}; \
         its damage can be evaluated at given values, not optimised nor tabulated in \
         --sensitivities"
    )]
    NoGradient {
        /// The parameter's name.
        name: String,
        /// Where it is not available.
        reason: &'static str,
    },
    /// A scene that starts from its static equilibrium (`[time] initial = "static"`): the start
    /// depends on the design, H dq₀/dθ = −∂(∇U)/∂θ (H the statics' Hessian), a derivative the
    /// adjoint does not carry, so a design study refuses it.
    #[error(
        "time.initial = \"static\": the start then depends on the design (dq₀/dθ, by the statics' \
         Hessian), which the design gradient does not carry; set `[time] initial = \"rest\"` \
         for a design study (docs/scene-format.md \"[time]\")"
    )]
    StaticStart,
    /// A design vector of the wrong length or with a value that is not finite.
    #[error("design values: {reason}")]
    BadValues {
        /// What is wrong.
        reason: String,
    },
    /// The study's own errors (the diagram, a cell's sea state, the record, the spin-up).
    #[error(transparent)]
    Study(#[from] StudyError),
    /// A cell's run (its adjoint sweep) failed.
    #[error("cell {cell}: {source}")]
    Run {
        /// The cell (0-based, in the diagram's order).
        cell: usize,
        /// The library's error.
        source: Box<crate::Error>,
    },
    /// The design does no damage (D_y = 0): its life is infinite and ln D_y, the optimiser's
    /// objective, is not defined.
    #[error(
        "the design {values} does no damage over the diagram (an infinite life): nothing to \
         optimise"
    )]
    NoDamage {
        /// The design, as `name = value` pairs.
        values: String,
    },
    /// The `[design] hotspot` names no `[[fatigue.hotspot]]` of the scene.
    #[error(
        "design.hotspot = {name:?}: the scene has no [[fatigue.hotspot]] of that name \
         (docs/scene-format.md \"[design]\")"
    )]
    NoHotSpot {
        /// The name asked for.
        name: String,
    },
    /// The objective at a hot spot needs the planar model (a cell's sea or the scene made the
    /// run spatial, where a joint's torque has two components).
    #[error(
        "design.hotspot = {name:?}: the objective at a hot spot needs a planar run (no load, \
         current, wave direction or control along x)"
    )]
    HotSpotSpatial {
        /// The hot spot.
        name: String,
    },
    /// A pendulum around the hot spot stopped pointing upward (its angle from the vertical
    /// reached 90°), where the hot spot's joint angles are no longer those the adjoint reads.
    #[error(
        "design.hotspot = {name:?}: cell {cell}: a pendulum around the hot spot does not point \
         upward at step {step} (a folded chain)"
    )]
    HotSpotFolded {
        /// The hot spot.
        name: String,
        /// The cell (0-based, in the diagram's order).
        cell: usize,
        /// The step.
        step: usize,
    },
    /// The optimiser's own error (its options, a failed line search that could not restart).
    #[error("optimiser: {source}")]
    Optimiser {
        /// The library's error.
        source: Box<crate::Error>,
    },
}

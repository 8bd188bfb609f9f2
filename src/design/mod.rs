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
//! The hot spot is the wellhead, whose moment M_w = M₀ · l₁/2 the adjoint's objectives read. The
//! `[[fatigue.hotspot]]` entries at other joints are not part of this objective: their joint
//! torques are not a history term of the adjoint.
//!
//! # The parameters ([`DesignParameter`])
//! The top tension T (`loads.tension`), the lower flex joint's rotational stiffness (the base
//! spring k₁, `beam.base_stiffness`, which is also the k₁ of the wellhead moment), the upper
//! flex joint's (the tip spring, `beam.tip_stiffness`), and the soil's p-y modulus at the mudline
//! (`soil.modulus`), an uncertainty by default ([`Role::Uncertainty`]): its sensitivity is
//! reported, it is not optimised; and, in a scene with a `[stackup]`, the rotational stiffness
//! of each named flex joint (`stackup.flex_joint.<name>.stiffness`: the joint spring where it
//! sits, base, tip or interior). Each maps to one [`crate::Parameter`] whose exact adjoint
//! gradient the library has; the scene's value is the model's value (the chain is built from
//! the scene with the parameter set).
//!
//! # Cells and executors
//! The cells are independent: [`DesignStudy::evaluate`] runs them serially or on rayon's pool
//! ([`Execution`]), and [`DesignStudy::run_cell`] runs one (the Python package sends these to a
//! Dask cluster). Each cell's numbers do not depend on where it ran, and
//! [`DesignStudy::combine`] sums them in the diagram's order, so the damage and its gradient are
//! the same bit for bit on any executor.
//!
//! # The optimiser ([`optimise`])
//! L-BFGS (argmin's, through [`crate::optimize::minimize`]) on ln D_y, the scaled objective (a
//! damage spans orders of magnitude; its logarithm's gradient does not), in unbounded variables
//! z with the bounds by a smooth transform,
//! ```text
//! θ_i = lo_i + (hi_i − lo_i) · σ(z_i),   σ(z) = 1/(1 + e^{−z}),
//! ∂ ln D_y/∂z_i = (1/D_y) · ∂D_y/∂θ_i · (hi_i − lo_i) σ(z_i)(1 − σ(z_i)),
//! ```
//! so every iterate lies within its bounds, and z is O(1) over the box whatever the parameter's
//! unit. It starts at the scene's own design and stops when ‖∇_z ln D_y‖ ≤ `tolerance`
//! (`[design] tolerance`), after `max_iterations`, or when a step no longer changes ln D_y.

mod optimise;
mod report;
mod scatter;

pub use optimise::{
    optimise, sensitivities, sensitivities_with, CellRunner, DesignIterate, DesignOptions,
    DesignOutcome, IterateCallback, Sensitivity,
};
pub use report::{DesignReport, ReportCell, ReportIterate, ReportPoint};
pub use scatter::{CellGradient, DesignPoint, DesignStudy, Execution, ScatterGradient, Want};

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
    /// The optimiser's own error (its options, a failed line search that could not restart).
    #[error("optimiser: {source}")]
    Optimiser {
        /// The library's error.
        source: Box<crate::Error>,
    },
}

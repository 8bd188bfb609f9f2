//! Errors of setting up a stepper or handing it a state ([`crate::steppers`]).

use thiserror::Error;

/// An input a stepper refuses before it steps.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StepperError {
    /// The method does not implement the reaction-force tip's rheonomic constraint (eq. 3.2.1):
    /// only RATTLE does, and RATTLE's control half-kick does not apply to it either.
    #[error(
        "invalid argument `tip condition`: {method} does not support the reaction-force tip; \
         use RATTLE"
    )]
    ReactionTipUnsupported {
        /// The method, e.g. `SHAKE`.
        method: &'static str,
    },
    /// RATTLE's control half-kick of a force on the riser does not apply when the control is
    /// the thrust on the vessel (`[vessel]` thrust keys): the thrust moves the top's constraint
    /// instead.
    #[error(
        "invalid argument `control`: {method} needs a control force on the riser, and the \
         control of this scene is the thrust on the vessel"
    )]
    ThrustControlUnsupported {
        /// What was asked, e.g. `a control half-kick`.
        method: &'static str,
    },
    /// The method does not implement the vessel's prescribed tip (`support = "vessel"`): only
    /// RATTLE does.
    #[error(
        "invalid argument `tip condition`: {method} does not support a tip held by the vessel \
         (support = \"vessel\"); use RATTLE"
    )]
    PrescribedTipUnsupported {
        /// The method, e.g. `SHAKE`.
        method: &'static str,
    },
    /// The method does not implement Morison's drag node by node (`[pipe] drag_model =
    /// "morison"`): only RATTLE does.
    #[error(
        "invalid argument `drag model`: {method} does not implement Morison's drag node by node \
         (drag_model = \"morison\"); use RATTLE"
    )]
    NodeDragUnsupported {
        /// The method, e.g. `SHAKE`.
        method: &'static str,
    },
    /// The time step h is not positive and finite.
    #[error("invalid argument `h`: the step must be positive and finite, got {h}")]
    StepNotPositive {
        /// The step given \[s\].
        h: f64,
    },
    /// A state with another number of pendulums than the stepper's chain.
    #[error("invalid argument `state`: the state has {got} blocks, the chain {expected}")]
    StateSize {
        /// The state's number of blocks qᵢ.
        got: usize,
        /// The chain's n.
        expected: usize,
    },
    /// The comparison integrators ([`crate::integrators`]) take a finite control only.
    #[error("invalid argument `u`: the control must be finite, got {u}")]
    NonFiniteControl {
        /// The control given (its real part).
        u: f64,
    },
    /// The comparison integrators ([`crate::integrators::Integrator::new`]) take a scene with a
    /// constant control only.
    #[error(
        "invalid argument `control`: the comparison integrators support a constant control only"
    )]
    NonConstantControl,
    /// The method's step does not end with the control's half-kick
    /// ([`crate::steppers::Stepper::control_kick`]): only RATTLE's does.
    #[error("invalid argument `method`: {method} has no closing control half-kick; use RATTLE")]
    ControlKickUnsupported {
        /// The method's type.
        method: &'static str,
    },
}

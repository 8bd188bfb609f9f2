//! Errors of building and configuring a [`Chain`](crate::model::Chain).

use thiserror::Error;

/// A chain's configuration a caller asked for that the model cannot take.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ModelError {
    /// The reaction-force tip (eq. 3.2.1) moves the tip node by the control, so the control must
    /// act at the tip node n (`control.node`).
    #[error(
        "invalid argument `control.node`: the reaction-force variant moves the tip: the control \
         must act at node {n}, not {node}"
    )]
    ReactionTipControlNode {
        /// The control node given.
        node: usize,
        /// The number of pendulums n (the tip node).
        n: usize,
    },
    /// A control node outside 1..=n ([`Chain::set_control_node`](crate::model::Chain::set_control_node)).
    #[error("invalid argument `control node`: must be in 1..={n}, got {node}")]
    ControlNodeOutOfRange {
        /// The node given.
        node: usize,
        /// The number of pendulums n.
        n: usize,
    },
    /// x components of a control ([`Chain::set_control_x`](crate::model::Chain::set_control_x))
    /// for a chain without a control node.
    #[error("invalid argument `control_x`: the model has no control node")]
    NoControlNode,
    /// The model has a term the structured optimal-control solvers (Riccati, condensed) and so
    /// MPC do not take yet: the node-by-node Morison drag (simulations, statics, forward-mode
    /// derivatives and the discrete adjoint take it).
    #[error(
        "invalid argument `model`: the structured solvers (Riccati, condensed) and MPC do not take \
         the {term} yet; use L-BFGS on the adjoint gradient, or `drag_model = \"momentum\"`"
    )]
    NoAdjoint {
        /// The term, e.g. `node-by-node Morison drag`.
        term: &'static str,
    },
    /// Per-node quantities ([`Chain::set_node_quantities`](crate::model::Chain::set_node_quantities))
    /// the chain cannot take: of the wrong length, or for a term whose constants need them
    /// otherwise (the momentum drag's, computed from the masses once).
    #[error("invalid argument `node quantities`: {reason}")]
    NodeQuantities {
        /// Why.
        reason: &'static str,
    },
    /// A static start ([`Chain::set_static_start`](crate::model::Chain::set_static_start)) of
    /// the wrong count, or with an attitude that is not a unit vector.
    #[error(
        "invalid argument `time.initial`: the static start needs {n} unit attitudes, got {got}{}",
        pendulum.map_or(String::new(), |j| format!(" (pendulum {j}'s is not a unit vector)"))
    )]
    StartSize {
        /// The number of pendulums n.
        n: usize,
        /// The number of attitudes given.
        got: usize,
        /// The first pendulum (1-based) whose attitude is not a finite unit vector.
        pendulum: Option<usize>,
    },
    /// A fold limit outside (0°, 180°) ([`Chain::set_fold_limit_deg`](crate::model::Chain::set_fold_limit_deg)).
    #[error("invalid argument `fold limit`: must be in (0, 180) degrees, got {deg}")]
    FoldLimitOutOfRange {
        /// The limit given \[°\].
        deg: f64,
    },
}

//! Errors of the Euler-Bernoulli reference beam: its own enum (the beam is a reference model
//! apart from the chain, and imports nothing of the crate), wrapped into [`crate::Error`] by
//! `#[from]` for callers that mix it with the chain.

use thiserror::Error;

use super::EbSupport;

/// An argument of [`EulerBernoulli`](crate::euler_bernoulli::EulerBernoulli) out of its range.
/// [`EulerBernoulliError::argument`] names the argument.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum EulerBernoulliError {
    /// `length`, `ei`, `mass_per_node` or `h` is not positive and finite.
    #[error("invalid argument `{name}`: must be positive and finite, got {value}")]
    NotPositive {
        /// The argument.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// Fewer than 2 segments: the five-point stencil with its ghost nodes needs nodes 0..=2.
    #[error(
        "invalid argument `n_segments`: the five-point stencil with ghost nodes needs at least 2 \
         segments, got {n_segments}"
    )]
    TooFewSegments {
        /// The number given.
        n_segments: usize,
    },
    /// More than [`MAX_SEGMENTS`](crate::euler_bernoulli::MAX_SEGMENTS) segments.
    #[error(
        "invalid argument `n_segments`: at most {max} segments are supported, got {n_segments}"
    )]
    TooManySegments {
        /// The number given.
        n_segments: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// The stiffness scale EI/d³ (or 16 EI/(d³ m)) is not a finite positive number.
    #[error(
        "invalid argument `ei`: the stiffness scale EI/d³ = {scale:e} (d = {d:e}) is not a usable \
         finite positive number"
    )]
    StiffnessScale {
        /// EI/d³.
        scale: f64,
        /// The segment width d = L/n.
        d: f64,
    },
    /// A load's node is outside 0..=n.
    #[error("invalid argument `loads`: load node {node} is outside the nodes 0..={n}")]
    LoadNodeOutside {
        /// The load's node.
        node: usize,
        /// The number of segments n.
        n: usize,
    },
    /// A load's node is held by the support (z = 0 there, so the load would have no effect).
    #[error(
        "invalid argument `loads`: load node {node} is held by the {support:?} support (z = 0 \
         there); loads must act on the free nodes 1..={last}"
    )]
    LoadNodeHeld {
        /// The load's node.
        node: usize,
        /// The support.
        support: EbSupport,
        /// The last free node.
        last: usize,
    },
    /// A load's force is not finite.
    #[error("invalid argument `loads`: the force at node {node} is not finite ({force})")]
    NonFiniteForce {
        /// The load's node.
        node: usize,
        /// The force.
        force: f64,
    },
    /// The forces at one node add up to a non-finite value.
    #[error("invalid argument `loads`: the forces at node {node} add up to a non-finite value")]
    NonFiniteForceSum {
        /// The node.
        node: usize,
    },
    /// `z` or `v` of [`EulerBernoulli::energy`](crate::euler_bernoulli::EulerBernoulli::energy)
    /// does not hold n + 1 node values.
    #[error("invalid argument `{name}`: expected {expected} node values, got {got}")]
    WrongNodeCount {
        /// `z` or `v`.
        name: &'static str,
        /// n + 1.
        expected: usize,
        /// The number given.
        got: usize,
    },
    /// A time step at or beyond Störmer–Verlet's stability limit h < 2/√λ_max.
    #[error(
        "invalid argument `h`: Störmer–Verlet is unstable for h ≥ 2/√λ_max; h = {h} exceeds the \
         limit {limit:.6e} (Gershgorin bound λ_max ≤ {lambda_max:.6e})"
    )]
    Unstable {
        /// The step given \[s\].
        h: f64,
        /// The limit 2/√λ_max.
        limit: f64,
        /// The Gershgorin bound on λ_max.
        lambda_max: f64,
    },
    /// `steps` + 1 overflows.
    #[error("invalid argument `steps`: {steps} steps overflow the row count")]
    StepsOverflow {
        /// The number of steps given.
        steps: usize,
    },
    /// The allocator refused the `steps` + 1 rows of node values.
    #[error("invalid argument `steps`: cannot allocate {rows} rows of node values")]
    RowsNotAllocated {
        /// The number of rows.
        rows: usize,
    },
}

impl EulerBernoulliError {
    /// The argument the error is about: `n_segments`, `length`, `ei`, `mass_per_node`, `loads`,
    /// `z`, `v`, `h` or `steps`.
    pub fn argument(&self) -> &'static str {
        match self {
            Self::NotPositive { name, .. } | Self::WrongNodeCount { name, .. } => name,
            Self::TooFewSegments { .. } | Self::TooManySegments { .. } => "n_segments",
            Self::StiffnessScale { .. } => "ei",
            Self::LoadNodeOutside { .. }
            | Self::LoadNodeHeld { .. }
            | Self::NonFiniteForce { .. }
            | Self::NonFiniteForceSum { .. } => "loads",
            Self::Unstable { .. } => "h",
            Self::StepsOverflow { .. } | Self::RowsNotAllocated { .. } => "steps",
        }
    }
}

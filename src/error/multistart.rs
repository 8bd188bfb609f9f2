//! Errors of the multistart, the second-order certificate and the landscapes
//! ([`crate::multistart`]).

use thiserror::Error;

/// An input of [`crate::multistart`] out of its range.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MultistartError {
    /// A start box ([`StartDesign`](crate::multistart::StartDesign)) without finite lo < hi.
    #[error("invalid argument `design`: the box needs finite lo < hi, got [{lo}, {hi}]")]
    EmptyBox {
        /// The lower end.
        lo: f64,
        /// The upper end.
        hi: f64,
    },
    /// A perturbation center without n finite values.
    #[error(
        "invalid argument `design`: the center needs {expected} finite values, got {got} values"
    )]
    BadCenter {
        /// The number of parameters n.
        expected: usize,
        /// The center's length.
        got: usize,
    },
    /// A perturbation radius that is negative or not finite.
    #[error("invalid argument `design`: the radius must be finite and >= 0, got {radius}")]
    BadRadius {
        /// The radius given.
        radius: f64,
    },
    /// More threads than [`MAX_THREADS`](crate::multistart::MAX_THREADS).
    #[error("invalid argument `threads`: at most {max} threads, got {threads}")]
    TooManyThreads {
        /// The threads asked for.
        threads: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// The thread pool could not be built (the message of rayon's error).
    #[error("invalid argument `threads`: {message}")]
    ThreadPool {
        /// What rayon reported.
        message: String,
    },
    /// `starts = 0`.
    #[error("invalid argument `starts`: at least one start is needed")]
    NoStarts,
    /// A certificate of a problem without Hessian-vector products.
    #[error(
        "invalid argument `problem`: a certificate needs Hessian-vector products \
         (OptimProblem::hessian)"
    )]
    NoHessian,
    /// A certificate of more parameters than
    /// [`MAX_CERTIFICATE_PARAMS`](crate::multistart::MAX_CERTIFICATE_PARAMS).
    #[error(
        "invalid argument `theta`: a certificate needs a dense {n} x {n} Hessian; at most {max} \
         parameters are supported"
    )]
    CertificateTooLarge {
        /// The number of parameters.
        n: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// A landscape range that is not finite, or no points.
    #[error(
        "invalid argument `{name}`: needs a finite range and at least one point, got {range:?}, \
         {points}"
    )]
    BadGrid {
        /// The argument, e.g. `range`.
        name: &'static str,
        /// The range given.
        range: (f64, f64),
        /// The number of points given.
        points: usize,
    },
    /// A landscape's center or direction without n finite values.
    #[error("invalid argument `{name}`: needs {expected} finite values, got {got}")]
    BadVector {
        /// The argument, e.g. `center`.
        name: &'static str,
        /// The number of parameters n.
        expected: usize,
        /// Its length.
        got: usize,
    },
}

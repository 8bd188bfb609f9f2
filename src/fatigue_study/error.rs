//! Why a fatigue study could not be run ([`StudyError`]): each error names the controller, the
//! cell or the key at fault.

use super::*;

/// Why a study could not be run; each names the controller, the cell or the key at fault.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StudyError {
    /// The assessment's own error (the `[fatigue]` table, a non-finite moment, a probability).
    #[error(transparent)]
    Fatigue(#[from] FatigueError),
    /// Not a controller name.
    #[error("unknown controller `{name}` (one of none, constant, pd, mpc)")]
    UnknownController {
        /// The name given.
        name: String,
    },
    /// A controller named twice.
    #[error("controller `{name}` is named twice")]
    DuplicateController {
        /// The name.
        name: String,
    },
    /// An empty list of controllers.
    #[error("no controller named (give a comma list of none, constant, pd, mpc)")]
    NoControllers,
    /// A scatter diagram without cells.
    #[error("the scatter diagram has no cells")]
    NoCells,
    /// More cells than [`MAX_SCATTER_CELLS`].
    #[error("the scatter diagram has {cells} cells, more than {MAX_SCATTER_CELLS}")]
    TooManyCells {
        /// The number of cells.
        cells: usize,
    },
    /// The control acts at a node the supports lock: it cannot change the moment.
    #[error(
        "controller `{controller}` cannot act: its force is at node {node}, the tip of a \
         {support} beam, which the supports lock (set `control.node` to a free node)"
    )]
    ControlCannotAct {
        /// The controller.
        controller: &'static str,
        /// The control node (`control.node`, default the tip n).
        node: usize,
        /// The support (`beam.support`).
        support: &'static str,
    },
    /// A cell's sea state cannot be set on the scene (e.g. it has no `[loads.waves]`).
    #[error("scatter cell {cell}: {reason}")]
    SeaState {
        /// Index of the cell (0-based, in the diagram's order).
        cell: usize,
        /// Why.
        reason: String,
    },
    /// A spin-up window that is negative, not finite, or not shorter than the record.
    #[error(
        "spin_up = {spin_up} s: the window not counted must be finite, ≥ 0 and shorter than the \
         record ({duration_s} s)"
    )]
    SpinUp {
        /// The window given \[s\].
        spin_up: f64,
        /// The record's duration N h \[s\].
        duration_s: f64,
    },
    /// A record to count that is not positive and finite, or whose run the scene cannot hold.
    #[error("record = {record} s: {reason}")]
    Record {
        /// The record given \[s\].
        record: f64,
        /// Why.
        reason: String,
    },
    /// Seeds per cell that are not in 1..=[`MAX_SEEDS`], more than one on a scene without a sea
    /// to draw, or a seed past the largest.
    #[error("seeds = {seeds}: {reason}")]
    Seeds {
        /// The number of seeds given.
        seeds: usize,
        /// Why.
        reason: String,
    },
    /// A cell index past the diagram's last ([`run_study_cell`]).
    #[error("scatter cell {cell}: the diagram has {cells} cells")]
    CellIndex {
        /// The index given (0-based).
        cell: usize,
        /// The number of cells.
        cells: usize,
    },
    /// Runs to combine that are not one per (cell, seed, controller) ([`combine_study`]).
    #[error("{got} runs to combine where the study has {expected} (cell, seed, controller) runs")]
    RunCount {
        /// Cells × seeds × controllers.
        expected: usize,
        /// The runs given.
        got: usize,
    },
    /// A run failed (a RATTLE step, a solve, settings that do not fit the scene).
    #[error("controller `{controller}`, cell {cell}: {source}")]
    Run {
        /// The controller.
        controller: &'static str,
        /// Index of the cell.
        cell: usize,
        /// The library's error (boxed: it is large, and this is the cold path).
        source: Box<crate::Error>,
    },
}

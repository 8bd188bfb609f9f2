//! The Table 3.4 problems as the tests use them (declared with `#[path]` next to `mod thesis` in a
//! test crate's `main.rs`).

use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};

/// Row `node` of Table 3.4: the thesis riser with the control at `node`, per-step controls over
/// N = 10 steps, c_sum without effort; and the bound the `tables` example gives it, the
/// largest |u_k| of the thesis's printed row (examples/tables/thesis.rs).
pub fn row(node: usize) -> (ControlProblem, f64) {
    let p = ControlProblem::builder(&catalogue::riser(node))
        .map(Parametrisation::PerStep(PerStepControl { steps: 10 }))
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .unwrap();
    let bound = super::thesis::TABLE_3_4[node - 1]
        .0
        .iter()
        .fold(0.0f64, |m, u| m.max(u.abs()));
    (p, bound)
}

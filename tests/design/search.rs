//! The design's bounded search (`chainbeam::design::minimise_box`, the projected L-BFGS with an
//! active set that `chainbeam design` runs on ln D_y in the log-scaled unit box) on closed-form
//! objectives whose optimum is known: every optimum on a bound, and one parameter on a bound with
//! the other interior. Each test states the evaluations the search takes and why.

use chainbeam::design::{
    minimise_box, projected_gradient_norm, BoxSearch, BoxStep, BoxTermination, BoxValue,
    DesignError, Want,
};

/// A test function: its value and gradient at u, in closed form.
type ClosedForm = dyn Fn(&[f64]) -> (f64, Vec<f64>);

/// Runs the search on `f` (value and gradient in closed form) from `start`, counting the
/// evaluations by kind.
fn run(
    f: &ClosedForm,
    start: &[f64],
    settings: BoxSearch,
) -> (chainbeam::design::BoxOutcome, usize, usize) {
    let (mut grads, mut values) = (0, 0);
    let mut eval = |u: &[f64], want: Want| -> Result<BoxValue, DesignError> {
        let (value, gradient) = f(u);
        Ok(match want {
            Want::Gradient => {
                grads += 1;
                BoxValue { value, gradient }
            }
            Want::Value => {
                values += 1;
                BoxValue {
                    value,
                    gradient: Vec::new(),
                }
            }
        })
    };
    let mut steps: Vec<BoxStep> = Vec::new();
    let out = minimise_box(&mut eval, start, None, settings, &mut |s| {
        steps.push(s.clone())
    })
    .unwrap();
    assert_eq!(steps, out.steps, "on_step sees every accepted point");
    (out, grads, values)
}

/// f(u) = 2u₁ + u₂ (ln D_y of a damage that rises exponentially with both scaled parameters):
/// the optimum is the corner u = (0, 0). From u = (0.4, 0.3), the first step is the steepest
/// descent scaled by the box, d = −g/‖g‖_∞ = (−1, −½): u₁ moves by its whole range to its bound
/// and u₂ by ½ > 0.3 to its own; both gradient components then push outward, the projected
/// gradient is exactly 0 and the search stops converged. Two evaluations with the gradient (the
/// start and the step, each an adjoint sweep per cell in a design) and none of the value alone:
/// the count follows from the step's construction, not from a run.
#[test]
fn monotone_objective_reaches_both_bounds_in_one_step() {
    let f = |u: &[f64]| (2.0 * u[0] + u[1], vec![2.0, 1.0]);
    let (out, grads, values) = run(&f, &[0.4, 0.3], BoxSearch::default());
    assert_eq!(out.termination, BoxTermination::ProjectedGradient);
    let last = out.last();
    assert_eq!(last.u, vec![0.0, 0.0]);
    assert_eq!(last.projected_gradient_norm, 0.0);
    assert_eq!((grads, values), (2, 0));
    assert_eq!(out.steps.len(), 2);
    assert_eq!((last.gradient_evaluations, last.value_evaluations), (2, 0));
}

/// f(u) = 2(u₁ − 0.3)² + ½u₂: the optimum is u₁ = 0.3 (interior, where ∂f/∂u₁ = 0) and u₂ = 0 (its
/// lower bound, ∂f/∂u₂ = ½ > 0 pushing outward). From u = (0.8, 0.6) the search goes, by its
/// rules (module docs of `design::search`; traced by hand and by a transcription of the rules):
/// 1. d = −g/‖g‖_∞ = (−1, −¼): u₁ lands on its bound 0, u₂ on 0.35 (f 0.8 → 0.355, Armijo at
///    α = 1); there ∂f/∂u₁ = −1.2 points inward, so u₁ is free again;
/// 2. two L-BFGS steps with both free, to (0.2609, 0.2943) and (0.3267, 0.1085), each accepted
///    at α = 1;
/// 3. an L-BFGS step whose first trial (with the gradient) fails Armijo's test, a second trial
///    (the value alone) lands u₂ on its bound 0 and is accepted, then its gradient;
/// 4. with u₂ active (held at 0) the one free variable's secant step lands on u₁ = 0.3 to
///    round-off: the projected gradient is 2·10⁻¹⁶ and the search stops converged.
///
/// That is 7 evaluations with the gradient (the start, 5 accepted steps, 1 rejected first trial)
/// and 1 of the value alone: the numbers asserted. The reference optimum is the closed form.
#[test]
fn interior_optimum_and_active_bound() {
    let f = |u: &[f64]| {
        (
            2.0 * (u[0] - 0.3).powi(2) + 0.5 * u[1],
            vec![4.0 * (u[0] - 0.3), 0.5],
        )
    };
    let settings = BoxSearch {
        tolerance: 1e-8,
        ..BoxSearch::default()
    };
    let (out, grads, values) = run(&f, &[0.8, 0.6], settings);
    let last = out.last();
    assert_eq!(
        out.termination,
        BoxTermination::ProjectedGradient,
        "{out:?}"
    );
    assert!((last.u[0] - 0.3).abs() <= 1e-8, "{:?}", last.u);
    assert_eq!(last.u[1], 0.0, "{:?}", last.u);
    assert!(projected_gradient_norm(&last.u, &last.gradient) <= 1e-8);
    // The first step as the docs derive it.
    assert_eq!(out.steps[1].u, vec![0.0, 0.35]);
    assert!(
        grads <= 8 && values <= 2,
        "{grads} gradient, {values} value evaluations"
    );
    eprintln!(
        "interior optimum and active bound: {grads} gradient and {values} value evaluations, \
         {} iterations",
        out.steps.len() - 1
    );
    // Every iterate within the box, f non-increasing.
    for w in out.steps.windows(2) {
        assert!(w[1].value <= w[0].value);
        assert!(w[1].u.iter().all(|u| (0.0..=1.0).contains(u)));
    }
}

/// A start outside the box and an objective that returns a non-finite value are refused with
/// [`DesignError::BadValues`], not a panic or a NaN design.
#[test]
fn bad_start_and_non_finite_values_are_refused() {
    let f = |u: &[f64]| (u[0], vec![1.0]);
    let mut eval = |u: &[f64], _: Want| -> Result<BoxValue, DesignError> {
        let (value, gradient) = f(u);
        Ok(BoxValue { value, gradient })
    };
    let e = minimise_box(&mut eval, &[1.5], None, BoxSearch::default(), &mut |_| {});
    assert!(matches!(e, Err(DesignError::BadValues { .. })), "{e:?}");
    let mut nan = |_: &[f64], _: Want| -> Result<BoxValue, DesignError> {
        Ok(BoxValue {
            value: f64::NAN,
            gradient: vec![1.0],
        })
    };
    let e = minimise_box(&mut nan, &[0.5], None, BoxSearch::default(), &mut |_| {});
    assert!(matches!(e, Err(DesignError::BadValues { .. })), "{e:?}");
}

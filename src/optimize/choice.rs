//! The automatic choice of method ([`Method::Auto`], the default of [`OptimOptions`]):
//! [`choose_method`] reads the problem's [`ProblemShape`](super::ProblemShape) and picks the
//! structured condensed or Riccati solver, or L-BFGS; [`Minimizer::run`] then runs it behind a
//! guard, so that the automatic choice is never worse than L-BFGS, the former default: a
//! structured run that fails or stops short of convergence is followed by L-BFGS from the same
//! start, and the better of the two results is kept ([`Fallback`]).
//! A converged condensed run is followed by the Riccati solver from the same start and the lower
//! converged objective kept (`companion`): the two end in different local minima on some
//! nonconvex problems (Table 3.4 rows 3 and 6 against rows 1 and 10).

use std::fmt;

use super::{Method, Minimizer, OptimOptions, OptimProblem, OptimResult, Termination};
use crate::error::Result;

/// The automatic choice of method ([`choose_method`]) and what came of it: the method, the
/// reason, e.g. `condensed: a planar control problem with 11 parameters …`, and the L-BFGS
/// fallback if the structured solver chosen did not converge.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MethodChoice {
    /// The method chosen.
    pub method: Method,
    /// Why, in words (reported by the command line's JSON `method_choice` and `--progress`).
    pub reason: String,
    /// The L-BFGS run that followed a structured run that failed or did not converge; `None`
    /// when the method chosen converged (or was L-BFGS itself).
    pub fallback: Option<Fallback>,
}

/// The guard of [`Method::Auto`]: a structured run (condensed or Riccati) that returned an
/// error or did not converge is followed by L-BFGS from the same θ₀ (exactly the former
/// default's run), and [`Minimizer::run`] returns, in this order of preference, a converged
/// L-BFGS result, the lower objective of two results that did not converge (the structured one
/// on a tie), whichever of the two runs returned a result, or L-BFGS's error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fallback {
    /// What the structured run came to: its termination, or its error.
    pub why: String,
    /// The method whose result was kept: [`Method::Lbfgs`], or the structured run's method
    /// (its `method`, e.g. [`Method::TrustRegion`] after a trust-region finish).
    pub kept: Method,
}

impl fmt::Display for MethodChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.method, self.reason)?;
        if let Some(fb) = &self.fallback {
            write!(
                f,
                "; {}, so lbfgs ran from the same start; kept the {} result",
                fb.why, fb.kept
            )?;
        }
        Ok(())
    }
}

/// The largest number of parameters for which [`Method::Auto`] takes the condensed solver,
/// 4(2n + 1) for n pendulums (the threshold `mpc --solver auto` uses, measured there): the
/// condensed solver's iteration costs N·P forward dual sweeps (P parameters, N steps) and a dense
/// P × P QP, the Riccati solver's O(N) stage Jacobians of size 2n; below this the condensed one
/// is the faster (Table 3.4: 11 parameters, n = 10: 14–18 ms against 29–31 ms, and L-BFGS 126
/// ms — `Method::Condensed`'s docs), above it the Riccati one.
pub fn condensed_max_params(pendulums: usize) -> usize {
    4 * (2 * pendulums + 1)
}

/// The condensed solver's sensitivity storage, 16·(N + 1)·P bytes, above which [`Method::Auto`]
/// takes the Riccati solver whatever P (256 MiB: a tenth of the condensed solver's own refusal
/// limit is far below it, so the choice never reaches that refusal).
const CONDENSED_AUTO_BYTES: u128 = 256 << 20;

/// The choice [`Method::Auto`] makes for `problem` under `opts` (a method other than `Auto` in
/// `opts` is returned as given, reason "given"):
///
/// 1. a control problem the structured solvers take ([`ProblemShape::structured`](super::ProblemShape::structured): an
///    objective in Gauss-Newton form, a free tip, per-step, piecewise or constant controls):
///    [`Method::Condensed`] when its parameters P are at most
///    [`condensed_max_params`]`(n)` = 4(2n + 1) and its sensitivities 16·(N + 1)·P bytes fit 256
///    MiB, else [`Method::Riccati`] (cost linear in N per iteration), in the planar and the
///    spatial model alike;
/// 2. anything else (another objective, a locked tip, a problem that is not a
///    control problem): [`Method::Lbfgs`], the cheapest per iteration (one adjoint sweep per
///    line-search trial).
///
/// A finite [`OptimOptions::target_cost`], which only the argmin solvers test, also takes
/// [`Method::Lbfgs`]. Bounds do not move the choice: every method keeps the box exactly (the
/// structured solvers by interior-point QPs, the others by the bounded map). The structured
/// solvers are fast but not safe everywhere (from u = 0 on the unbounded per-step c_sum of the
/// riser, loaded at node 5, the beam folds within a few steps), so [`Minimizer::run`] runs the
/// structured solver chosen behind the L-BFGS guard of [`Fallback`].
pub fn choose_method<Q: OptimProblem + ?Sized>(problem: &Q, opts: &OptimOptions) -> MethodChoice {
    if opts.method != Method::Auto {
        return MethodChoice {
            method: opts.method,
            reason: "given".into(),
            fallback: None,
        };
    }
    if opts.target_cost > f64::NEG_INFINITY {
        return MethodChoice {
            method: Method::Lbfgs,
            reason: "a target cost, which only the argmin solvers test".into(),
            fallback: None,
        };
    }
    let Some(shape) = problem.shape() else {
        return MethodChoice {
            method: Method::Lbfgs,
            reason: "not a control problem".into(),
            fallback: None,
        };
    };
    let p = shape.params;
    if !shape.structured {
        let why = "an objective, tip or control node the structured solvers do not take";
        return MethodChoice {
            method: Method::Lbfgs,
            reason: format!("{why}, {p} parameters"),
            fallback: None,
        };
    }
    let limit = condensed_max_params(shape.pendulums);
    let bytes = 16 * (shape.steps as u128 + 1) * p as u128;
    let model = if shape.dim == 3 { "spatial" } else { "planar" };
    if p <= limit && bytes <= CONDENSED_AUTO_BYTES {
        MethodChoice {
            method: Method::Condensed,
            reason: format!(
                "a {model} control problem with {p} parameters over N = {} steps, at most \
                 4(2n + 1) = {limit} for n = {}",
                shape.steps, shape.pendulums
            ),
            fallback: None,
        }
    } else {
        MethodChoice {
            method: Method::Riccati,
            reason: format!(
                "a {model} control problem with {p} parameters over N = {} steps, more than \
                 4(2n + 1) = {limit} for n = {} (or sensitivities over 256 MiB)",
                shape.steps, shape.pendulums
            ),
            fallback: None,
        }
    }
}

/// [`Minimizer::run`] with [`Method::Auto`]: the method [`choose_method`] picks, behind the
/// guard of [`Fallback`], the choice recorded in the result ([`OptimResult::choice`]). The start
/// checks of every method come first (their errors are returned as they are: L-BFGS would
/// refuse the same start). The result's `seconds` are those of the whole call.
pub(super) fn run_auto<Q: OptimProblem + ?Sized>(
    m: &Minimizer<'_, Q>,
    theta0: &[f64],
) -> Result<OptimResult> {
    let clock = std::time::Instant::now();
    let mut choice = choose_method(m.problem, &m.opts);
    let lbfgs = OptimOptions {
        method: Method::Lbfgs,
        ..m.opts.clone()
    };
    if choice.method == Method::Lbfgs {
        return m.run_with(&lbfgs, theta0).map(|mut r| {
            r.choice = Some(choice);
            r
        });
    }
    let structured = OptimOptions {
        method: choice.method,
        ..m.opts.clone()
    };
    // The checks L-BFGS would make (options, θ₀, box, range, no effect); an error here is the
    // former default's error too.
    structured.validate()?;
    super::check_start(m.problem, theta0)?;
    super::riccati::check_start_point(m.problem, theta0, &structured)?;
    let first = super::riccati::run(m, theta0, &structured);
    if let Ok(r) = &first {
        // An observer that stopped the run stops the call: no fallback, no companion.
        if r.converged || matches!(r.termination, Termination::Observer { .. }) {
            let mut kept = first.expect("checked Ok");
            let planar = m.problem.shape().is_some_and(|s| s.dim == 2);
            if choice.method == Method::Condensed && planar && kept.converged {
                kept = companion(m, theta0, kept, &mut choice);
            }
            kept.seconds = clock.elapsed().as_secs_f64();
            kept.choice = Some(choice);
            return Ok(kept);
        }
    }
    let why = match &first {
        Ok(r) if r.method == choice.method => format!("{}: {}", r.method, r.termination),
        Ok(r) => format!(
            "{} (finished by {}): {}",
            choice.method, r.method, r.termination
        ),
        Err(e) => format!("{} failed: {e}", choice.method),
    };
    let second = m.run_with(&lbfgs, theta0);
    let mut kept = match (first, second) {
        (_, Ok(b)) if b.converged => b,
        (Ok(a), Ok(b)) => {
            if b.objective < a.objective {
                b
            } else {
                a
            }
        }
        (Ok(a), Err(_)) => a,
        (Err(_), Ok(b)) => b,
        (Err(_), Err(e)) => return Err(e),
    };
    choice.fallback = Some(Fallback {
        why,
        kept: kept.method,
    });
    kept.seconds = clock.elapsed().as_secs_f64();
    kept.choice = Some(choice);
    Ok(kept)
}

/// The second structured run of a converged condensed choice: the Riccati solver from the same
/// θ₀ (a few ms at the condensed solver's sizes, P ≤ 4(2n + 1)). The two reach different local
/// minima on some problems (Table 3.4: condensed lower on rows 1, 9, 10, Riccati lower on rows 3
/// and 6, both equal to L-BFGS or below on every row), so the lower converged objective is kept,
/// the condensed one unless Riccati's is lower by more than round-off (relative 1e-12). Recorded
/// in the choice's reason.
fn companion<Q: OptimProblem + ?Sized>(
    m: &Minimizer<'_, Q>,
    theta0: &[f64],
    condensed: OptimResult,
    choice: &mut MethodChoice,
) -> OptimResult {
    let opts = OptimOptions {
        method: Method::Riccati,
        ..m.opts.clone()
    };
    let other = super::riccati::run(m, theta0, &opts);
    let (kept, note) = match other {
        Ok(r) if r.converged && r.objective < condensed.objective * (1.0 - 1e-12) => {
            let note = format!(
                "riccati also ran from the same start and reached a lower objective ({:e} < {:e}): kept riccati",
                r.objective, condensed.objective
            );
            (r, note)
        }
        Ok(r) => (
            condensed,
            format!(
                "riccati also ran from the same start ({}): kept condensed",
                r.termination
            ),
        ),
        Err(e) => (
            condensed,
            format!("riccati also ran and failed ({e}): kept condensed"),
        ),
    };
    choice.reason = format!("{}; {note}", choice.reason);
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::{Method, OptimOptions};
    use crate::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};

    fn per_step(scene: &crate::Scene) -> ControlProblem {
        let map = Parametrisation::PerStep(PerStepControl {
            steps: scene.time.steps,
        });
        ControlProblem::builder(scene)
            .map(map)
            .objective(BendingObjective::summed_moment())
            .build_in::<2>()
            .unwrap()
    }

    /// [`choose_method`] follows its documented rule: Table 3.4's 11 per-step parameters on the
    /// n = 10 riser (≤ 4(2n + 1) = 84) go to the condensed solver, the long horizon's 1001 to the
    /// Riccati solver, a constant control to the condensed one, a method given stays as given.
    #[test]
    fn the_automatic_choice_follows_the_shape() {
        let opts = OptimOptions::default();
        assert_eq!(opts.method, Method::Auto);
        let table = per_step(&catalogue::riser(5));
        assert_eq!(choose_method(&table, &opts).method, Method::Condensed);
        let long = per_step(&catalogue::long_horizon());
        assert_eq!(choose_method(&long, &opts).method, Method::Riccati);
        let constant = ControlProblem::builder(&catalogue::riser(5))
            .map(Parametrisation::Constant)
            .objective(BendingObjective::summed_moment())
            .build_in::<2>()
            .unwrap();
        assert_eq!(choose_method(&constant, &opts).method, Method::Condensed);
        let given = OptimOptions {
            method: Method::TrustRegion,
            ..OptimOptions::default()
        };
        assert_eq!(choose_method(&table, &given).method, Method::TrustRegion);
        assert_eq!(condensed_max_params(10), 84);
    }
}

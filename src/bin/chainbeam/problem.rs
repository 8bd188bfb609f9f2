//! The control problem a command works on: the scene's `[control]` and `[objective]`, changed by
//! `--pieces`, `--effort` and `--controls`, in the model the scene needs ([`AnyProblem`]: the
//! planar model unless a load, the current or the control has an x component).

use std::path::Path;

use clap::Args;
use serde::Serialize;

use chainbeam::{
    BendingObjective, ControlMap, ControlProblem, ObjectiveKind, Parametrisation, PiecewiseControl,
    ValidScene,
};

use crate::controls_io::ControlsFile;
use crate::{lib_error, CliError};

/// Flags that change the objective or the control parametrisation (gradient, optimize, explore).
#[derive(Args, Clone, Debug)]
pub struct ProblemArgs {
    /// Piecewise-constant control with P pieces (1 ≤ P ≤ N = time.steps) instead of the scene's
    /// control kind; the start values are the scene's forces averaged over each piece (each
    /// component of a 2-axis control).
    #[arg(long, value_name = "P")]
    pub pieces: Option<usize>,
    /// Adds the control-effort penalty ρ·h·Σ_{k=0..N} |u_k|² to the objective (ρ ≥ 0, in
    /// m²/s: the penalty is then in N²m² like the objective).
    #[arg(long, value_name = "RHO", allow_hyphen_values = true)]
    pub effort: Option<f64>,
}

/// The problem in the model the scene needs and the JSON layout of θ live in the library (shared
/// with the Python bindings).
pub use chainbeam::adjoint::AnyProblem;
pub use chainbeam::optimize::Values;

/// The control problem of a scene and the parameters θ₀ to evaluate it at (or start from).
pub struct SceneProblem {
    /// The problem, in the model the scene (and the controls) need.
    pub problem: AnyProblem,
    /// θ₀: the scene's `control.values` (or one constant 0 at the tip without a `[control]`),
    /// averaged over pieces with `--pieces`, or the `--controls` file's values; for a 2-axis
    /// control θ₀ = (θ_x; θ_z), the x components first.
    pub theta0: Vec<f64>,
    /// The node the control acts at.
    pub control_node: usize,
    /// The objective (kind and effort).
    pub objective: BendingObjective,
}

/// How the parametrisation is reported in the JSON: `control_kind` and, for piecewise controls,
/// `pieces`.
#[derive(Serialize)]
pub struct KindReport {
    /// "constant", "per-step" or "piecewise".
    pub control_kind: &'static str,
    /// The number of pieces of a piecewise control.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pieces: Option<usize>,
}

/// The name of a parametrisation in the JSON.
pub fn kind_report(p: &Parametrisation) -> KindReport {
    match p {
        Parametrisation::Constant => KindReport {
            control_kind: "constant",
            pieces: None,
        },
        Parametrisation::PerStep(_) => KindReport {
            control_kind: "per-step",
            pieces: None,
        },
        Parametrisation::Piecewise(pc) => KindReport {
            control_kind: "piecewise",
            pieces: Some(pc.pieces),
        },
    }
}

/// The problem as the JSON of `gradient` and `optimize` ends: model, objective_kind,
/// objective_exponent (kind "power" only), effort, control_kind, pieces (piecewise only),
/// control_node.
#[derive(Serialize)]
pub struct ProblemReport {
    model: &'static str,
    objective_kind: &'static str,
    /// p of kind "power".
    #[serde(skip_serializing_if = "Option::is_none")]
    objective_exponent: Option<f64>,
    effort: f64,
    #[serde(flatten)]
    kind: KindReport,
    control_node: usize,
}

impl ProblemReport {
    /// The report of `sp`.
    pub fn of(sp: &SceneProblem) -> Self {
        ProblemReport {
            model: sp.problem.model_name(),
            objective_kind: objective_name(sp.objective.kind),
            objective_exponent: objective_exponent(sp.objective.kind),
            effort: sp.objective.effort,
            kind: kind_report(sp.problem.map()),
            control_node: sp.control_node,
        }
    }
}

/// The name of an objective kind in the JSON.
pub fn objective_name(kind: ObjectiveKind) -> &'static str {
    kind.name()
}

/// The exponent p of an objective of kind "power" (JSON `objective_exponent`).
pub fn objective_exponent(kind: ObjectiveKind) -> Option<f64> {
    match kind {
        ObjectiveKind::Power { exponent } => Some(exponent),
        _ => None,
    }
}

/// Checks `--effort` (finite, ≥ 0).
pub fn check_effort(effort: Option<f64>) -> Result<f64, CliError> {
    match effort {
        None => Ok(0.0),
        Some(r) if r.is_finite() && r >= 0.0 => Ok(r),
        Some(r) => Err(CliError::msg(format!(
            "--effort: the penalty weight ρ must be finite and non-negative, got {r}"
        ))),
    }
}

/// The scene's own parametrisation and θ₀ (θ₀ = (θ_x; θ_z) for a 2-axis control).
fn scene_parametrisation(
    path: &Path,
    scene: &ValidScene,
) -> Result<(Parametrisation, Vec<f64>), CliError> {
    chainbeam::optimize::scene_start(scene).map_err(|e| lib_error(path, e))
}

/// θ of a piecewise control whose pieces hold the means of `u` over them.
fn piece_means(pc: PiecewiseControl, u: &[f64]) -> Vec<f64> {
    let mut sum = vec![0.0; pc.pieces];
    let mut count = vec![0.0; pc.pieces];
    pc.transpose(u, &mut sum);
    pc.transpose(&vec![1.0; u.len()], &mut count);
    sum.iter()
        .zip(&count)
        .map(|(s, c)| if *c > 0.0 { s / c } else { 0.0 })
        .collect()
}

/// θ of `--pieces P`: the means over each piece of the forces of θ under `map`, component by
/// component for a 2-axis θ = (θ_x; θ_z).
fn pieces_theta(
    path: &Path,
    steps: usize,
    p: usize,
    (map, theta, two_axis): (Parametrisation, &[f64], bool),
) -> Result<(Parametrisation, Vec<f64>), CliError> {
    if p == 0 || p > steps {
        return Err(CliError::msg(format!(
            "--pieces: the number of pieces must be between 1 and N = {steps} (time.steps of \
             {}), got {p}",
            path.display()
        )));
    }
    let pc = PiecewiseControl { steps, pieces: p };
    let blocks = if two_axis { 2 } else { 1 };
    let mut out = Vec::with_capacity(blocks * p);
    for block in theta.chunks(theta.len() / blocks) {
        let mut u = vec![0.0; steps + 1];
        map.controls(block, &mut u);
        out.extend(piece_means(pc, &u));
    }
    Ok((Parametrisation::Piecewise(pc), out))
}

/// Builds the problem: the scene's control and objective, `args`' changes, and (if given) the
/// parametrisation and values of a `--controls` file, in the model they need.
pub fn build(
    path: &Path,
    scene: &ValidScene,
    args: Option<&ProblemArgs>,
    controls: Option<&ControlsFile>,
) -> Result<SceneProblem, CliError> {
    let effort = check_effort(args.and_then(|a| a.effort))?;
    let steps = scene.time.steps;
    let (mut map, mut theta0) = scene_parametrisation(path, scene)?;
    let mut two_axis = scene.has_two_axis_control();
    if let Some(p) = args.and_then(|a| a.pieces) {
        (map, theta0) = pieces_theta(path, steps, p, (map, &theta0, two_axis))?;
    }
    if let Some(c) = controls {
        c.check_axes(scene)?;
        map = c.parametrisation(steps)?;
        theta0 = c.theta();
        two_axis = c.is_two_axis();
    }
    let objective = BendingObjective {
        kind: scene.objective.unwrap_or(ObjectiveKind::Final),
        effort,
    };
    let problem = ControlProblem::builder(scene)
        .map(map)
        .objective(objective)
        .two_axis(two_axis)
        .build()
        .map_err(|e| lib_error(path, e))?;
    let control_node = scene.control.as_ref().map_or(scene.n(), |c| c.node);
    Ok(SceneProblem {
        problem,
        theta0,
        control_node,
        objective,
    })
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Piece means of a ramp u_k = k: each piece's mean is the mean of the k it covers, whatever
    /// the library's convention (computed here from the same map's u).
    #[test]
    fn piece_means_average_each_piece() {
        let pc = PiecewiseControl {
            steps: 9,
            pieces: 3,
        };
        let u: Vec<f64> = (0..10).map(f64::from).collect();
        let theta = piece_means(pc, &u);
        for (j, t) in theta.iter().enumerate() {
            // The steps piece j covers: where the unit vector e_j maps to 1.
            let mut e = vec![0.0; 3];
            e[j] = 1.0;
            let mut back = vec![0.0; 10];
            pc.controls(&e, &mut back);
            let ks: Vec<f64> = (0..10)
                .filter(|&k| back[k] > 0.5)
                .map(|k| k as f64)
                .collect();
            let mean = ks.iter().sum::<f64>() / ks.len() as f64;
            assert!((t - mean).abs() < 1e-12, "{theta:?}");
        }
        // A constant is kept exactly.
        let theta = piece_means(pc, &[2.5; 10]);
        assert_eq!(theta, [2.5, 2.5, 2.5]);
    }
}

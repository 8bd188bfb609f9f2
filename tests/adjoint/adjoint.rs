//! The discrete adjoint is the exact derivative of the discrete RATTLE map.
//!
//! References: forward-mode dual numbers through the same simulation (the adjoint must agree to
//! ~1e-12 relative, round-off), and central finite differences of whole simulations (to ~1e-6,
//! limited by the difference quotient). Every case starts from the exactly straight beam.

use chainbeam::adjoint::{adjoint_gradient, forward_value, NodeDisplacementObjective};
use chainbeam::catalogue;
use chainbeam::*;
use num_dual::Dual64;

use crate::gradient_check;
use gradient_check::Tolerance;

/// A thesis riser scene (docs/conventions.md) with another support, drag and horizon. The vessel
/// support moves its top: a 2 cm offset ramped in over 0.08 s of the 0.12 s horizon.
fn scene(support: Support, load_node: usize, drag: f64, steps: usize) -> Scene {
    let mut s = catalogue::riser(load_node);
    s.beam.support = support;
    if support == Support::Vessel {
        s.vessel = Some(Vessel {
            offset: 0.02,
            ramp: 0.08,
            rao: None,
            ..Vessel::default()
        });
    }
    s.loads.drag = drag;
    s.time.steps = steps;
    s
}

fn start(map: &Parametrisation, steps: usize) -> Vec<f64> {
    let np = map.n_params();
    (0..np)
        .map(|j| -1.5 + 0.4 * ((j as f64) * 0.9 + 0.3 * steps as f64).sin())
        .collect()
}

/// The shared helper: adjoint gradient vs forward mode to 1e-12 relative to the gradient's largest
/// component (the two sum the same terms in different orders; the largest deviation seen over all
/// cases is 2e-13 of it), and vs central finite differences to 1e-6 of it; physical parameters
/// against forward mode to 5e-12 relative (the largest seen: 1.4e-12, on a tip-stiffness
/// derivative of size 4e-6).
fn check<O: Objective + Clone>(
    label: &str,
    s: &Scene,
    control_node: usize,
    map: Parametrisation,
    obj: O,
) {
    let mut s = s.clone();
    s.control = Some(Control {
        node: control_node,
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    let steps = s.time.steps;
    let theta = start(&map, steps);
    let mut params = vec![
        Parameter::InteriorStiffness,
        Parameter::LoadForce(0),
        Parameter::Mass,
    ];
    if s.beam.support != Support::PinnedPinned {
        params.push(Parameter::BaseStiffness);
    }
    if s.beam.support.end_springs().1 {
        params.push(Parameter::TipStiffness);
    }
    if s.loads.drag > 0.0 {
        params.push(Parameter::Drag);
    }
    let prob = ControlProblem::builder(&s)
        .map(map)
        .objective(obj.clone())
        .build_in::<2>()
        .unwrap();
    let adj = prob.adjoint(&theta, &params).unwrap();
    let (worst_fwd, worst_fd, ng) = check_controls(label, &prob, map, &obj, &theta, &adj);
    // physical parameters: forward mode
    let fwd = gradient_check::forward_parameter_gradient(
        &prob,
        &theta,
        &params,
        s.loads.drag,
        s.time.step,
        &obj,
    );
    gradient_check::assert_close(
        &format!("{label}: dJ/d{params:?}, adjoint"),
        &adj.parameter_gradient,
        &fwd,
        "forward-mode Dual64",
        Tolerance::relative(5e-12).plus(1e-300),
    );
    println!("{label}: {ng} controls, worst |adjoint - forward|/max(|forward_j|, max|g|) {worst_fwd:.1e}, worst FD {worst_fd:.1e}");
}

/// The controls' part of [`check`]: the adjoint's ∂J/∂θ (`adj` at `theta`) against forward-mode
/// Dual64 (1e-12 of max|g|) and central differences (1e-6 of it). Returns the worst deviations
/// and the number of controls.
fn check_controls<O: Objective + Clone>(
    label: &str,
    prob: &ControlProblem<Parametrisation, O, 2>,
    map: Parametrisation,
    obj: &O,
    theta: &[f64],
    adj: &chainbeam::adjoint::AdjointResult<f64>,
) -> (f64, f64, usize) {
    let steps = prob.steps();
    let mut g = vec![0.0; map.n_params()];
    map.transpose(&adj.control_gradient, &mut g);
    let scale = g.iter().fold(0.0f64, |a, b| a.max(b.abs()));

    // forward mode and finite differences, control parameters
    let chain_d = prob.chain_as::<Dual64>();
    let (mut fwd, mut fd) = (Vec::new(), Vec::new());
    for j in 0..map.n_params() {
        let th: Vec<Dual64> = theta
            .iter()
            .enumerate()
            .map(|(i, &t)| Dual64::new(t, f64::from(u8::from(i == j))))
            .collect();
        let mut u = vec![Dual64::from(0.0); steps + 1];
        map.controls(&th, &mut u);
        fwd.push(
            forward_value(&chain_d, prob.time_step(), steps, &u, obj)
                .unwrap()
                .eps,
        );
        let eps = 1e-5 * theta[j].abs().max(1.0);
        let at = |x: f64| {
            let mut t = theta.to_vec();
            t[j] = x;
            prob.value(&t).unwrap()
        };
        fd.push(gradient_check::central(&at, theta[j], eps));
    }
    let worst_fwd = gradient_check::assert_close(
        &format!("{label}: dJ/dtheta, adjoint"),
        &g,
        &fwd,
        "forward-mode Dual64",
        Tolerance::at_least(1e-12, scale),
    );
    let worst_fd = gradient_check::assert_close(
        &format!("{label}: dJ/dtheta, central difference (step 1e-5 max(|theta_j|, 1))"),
        &fd,
        &g,
        "the adjoint",
        Tolerance::of_scale(1e-6, scale.max(1e-300)),
    );
    (worst_fwd, worst_fd, g.len())
}

/// A riser in a 0.3 m/s current with its top held by a vessel at a 2 cm offset, started from
/// the static equilibrium (`[time] initial = "static"`, the vessel's offset held in full): the
/// start does not depend on the controls, so the adjoint's ∂J/∂θ is the exact derivative of
/// this run too (forward-mode Dual64 from the same start to 1e-12 of max|g|, central
/// differences to 1e-6, as [`check`]). Physical parameters are refused naming `time.initial`:
/// the start depends on them (dq₀/dθ), a term the adjoint does not carry.
#[test]
fn static_start_control_gradient_is_exact() {
    let steps = 12;
    let mut s = scene(Support::Vessel, 5, 10.0, steps);
    s.loads.current = Some(Current::uniform(0.3, [0.0, 1.0]));
    s.time.initial = Initial::Static;
    s.control = Some(Control {
        node: 7,
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    for map in [
        Parametrisation::Constant,
        Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 4 }),
    ] {
        let obj = BendingObjective::summed_moment().with_effort(0.5);
        let prob = ControlProblem::builder(&s)
            .map(map)
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        // The start is the static one (the top at the offset), not the straight beam.
        let q0 = prob.chain().start_attitudes().unwrap();
        let top: f64 = q0
            .iter()
            .zip(prob.chain().lengths())
            .map(|(q, l)| q[1] * l)
            .sum();
        assert!((top - 0.02).abs() < 1e-12, "top z {top}");
        let theta = start(&map, steps);
        let adj = prob.adjoint(&theta, &[]).unwrap();
        let label = format!("static start {map:?}");
        let (worst_fwd, worst_fd, ng) = check_controls(&label, &prob, map, &obj, &theta, &adj);
        println!("{label}: {ng} controls, worst forward {worst_fwd:.1e}, worst FD {worst_fd:.1e}");
        let e = prob.adjoint(&theta, &[Parameter::Drag]).unwrap_err();
        assert!(matches!(e, Error::StaticStartRefused { .. }), "{e}");
        assert!(e.to_string().contains("time.initial"), "{e}");
    }
}

/// Every support x objective (final, sum, with and without effort) x parametrisation x drag
/// (0, 10) x load node. Pinned-pinned beams have no base spring, so M₀ ≡ 0 there: they are checked
/// with the displacement of node 3 instead. Held tips absorb a tip control, so fixed-fixed,
/// pinned-pinned and vessel are controlled at node 7.
#[test]
fn adjoint_matches_forward_mode_and_finite_differences() {
    let steps = 12;
    let maps = [
        Parametrisation::Constant,
        Parametrisation::PerStep(PerStepControl { steps }),
        Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 4 }),
    ];
    for support in [
        Support::Cantilever,
        Support::Riser,
        Support::FixedFixed,
        Support::PinnedPinned,
        Support::Vessel,
    ] {
        let control_node = if support.holds_tip() { 7 } else { 10 };
        for drag in [0.0, 10.0] {
            for load_node in [3, 5, 9] {
                let s = scene(support, load_node, drag, steps);
                for map in maps {
                    let label = format!("{support:?} D={drag} load@{load_node} {map:?}");
                    if support == Support::PinnedPinned {
                        for kind in [ObjectiveKind::Final, ObjectiveKind::Sum] {
                            check(
                                &label,
                                &s,
                                control_node,
                                map,
                                NodeDisplacementObjective { node: 3, kind },
                            );
                        }
                        continue;
                    }
                    for obj in [
                        BendingObjective::final_moment(),
                        BendingObjective::summed_moment(),
                        BendingObjective::final_moment().with_effort(0.5),
                        BendingObjective::summed_moment().with_effort(0.5),
                    ] {
                        check(&format!("{label} {obj:?}"), &s, control_node, map, obj);
                    }
                }
            }
        }
    }
}

/// The reaction-force variant (thesis §3.2) moves the tip by the control: its gradient too.
#[test]
fn adjoint_reaction_force_variant() {
    for drag in [0.0, 10.0] {
        let mut s = scene(Support::FixedFixed, 5, drag, 12);
        s.beam.reaction_force = true;
        check(
            &format!("reaction D={drag}"),
            &s,
            10,
            Parametrisation::PerStep(PerStepControl { steps: 12 }),
            BendingObjective::summed_moment(),
        );
    }
}

/// Checkpointing changes the memory, not the arithmetic: bit-for-bit the same gradient.
#[test]
fn checkpointing_is_bit_for_bit() {
    let s = scene(Support::Riser, 5, 10.0, 97);
    let map = Parametrisation::PerStep(PerStepControl { steps: 97 });
    let theta = start(&map, 97);
    let base = ControlProblem::builder(&s)
        .map(map)
        .objective(BendingObjective::summed_moment())
        .checkpointing(Checkpointing::StoreAll)
        .build_in::<2>()
        .unwrap();
    let reference = base.adjoint(&theta, &[Parameter::Drag]).unwrap();
    for c in [
        Checkpointing::Sqrt,
        Checkpointing::Every(1),
        Checkpointing::Every(5),
        Checkpointing::Every(97),
        Checkpointing::Auto,
    ] {
        let r = ControlProblem::builder(&s)
            .map(map)
            .objective(BendingObjective::summed_moment())
            .checkpointing(c)
            .build_in::<2>()
            .unwrap()
            .adjoint(&theta, &[Parameter::Drag])
            .unwrap();
        assert!(r.value.to_bits() == reference.value.to_bits());
        for (a, b) in r.control_gradient.iter().zip(&reference.control_gradient) {
            assert!(a.to_bits() == b.to_bits(), "{c:?}");
        }
        assert!(r.parameter_gradient[0].to_bits() == reference.parameter_gradient[0].to_bits());
    }
}

/// Hessian-vector products (forward-over-adjoint) equal central differences of adjoint gradients
/// to 1e-6, and the Hessian is symmetric: vᵀH w = wᵀH v to 1e-10.
#[test]
fn hessian_vector_products() {
    for (support, drag) in [
        (Support::Riser, 0.0),
        (Support::Riser, 10.0),
        (Support::FixedFixed, 10.0),
    ] {
        let s = scene(support, 5, drag, 15);
        let node = if support == Support::FixedFixed {
            7
        } else {
            10
        };
        let mut s2 = s.clone();
        s2.control = Some(Control {
            node,
            kind: ControlKind::Constant,
            values: vec![0.0],
            values_x: None,
        });
        let map = Parametrisation::PerStep(PerStepControl { steps: 15 });
        let prob = ControlProblem::builder(&s2)
            .map(map)
            .objective(BendingObjective::summed_moment().with_effort(0.1))
            .build_in::<2>()
            .unwrap();
        let theta = start(&map, 15);
        let v: Vec<f64> = (0..16).map(|j| ((j * 7 % 5) as f64 - 2.0) * 0.3).collect();
        let w: Vec<f64> = (0..16).map(|j| ((j * 3 % 7) as f64 - 3.0) * 0.2).collect();
        let hv = prob.hessian_vec(&theta, &v).unwrap();
        let hw = prob.hessian_vec(&theta, &w).unwrap();
        let eps = 1e-5;
        let shift = |d: f64| {
            theta
                .iter()
                .zip(&v)
                .map(|(t, x)| t + d * x)
                .collect::<Vec<f64>>()
        };
        let gp = prob.gradient(&shift(eps)).unwrap();
        let gm = prob.gradient(&shift(-eps)).unwrap();
        let scale = hv.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for j in 0..16 {
            let fd = (gp[j] - gm[j]) / (2.0 * eps);
            assert!(
                (fd - hv[j]).abs() <= 1e-6 * scale,
                "{support:?}: Hv_{j} {} vs FD {fd}",
                hv[j]
            );
        }
        let vhw: f64 = v.iter().zip(&hw).map(|(a, b)| a * b).sum();
        let whv: f64 = w.iter().zip(&hv).map(|(a, b)| a * b).sum();
        println!("{support:?} D={drag}: v'Hw = {vhw:e}, w'Hv = {whv:e}");
        assert!((vhw - whv).abs() <= 1e-10 * vhw.abs().max(whv.abs()));
    }
}

/// A 10⁵-step horizon (n = 10, h = 0.01, D = 10, load at node 5): the checkpointed gradient is
/// finite, matches central finite differences, and keeps O(n √N) states in memory.
#[test]
fn long_horizon_gradient_with_checkpointing() {
    let steps = 100_000;
    let s = scene(Support::Riser, 5, 10.0, steps);
    let map = Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 5 });
    let prob = ControlProblem::builder(&s)
        .map(map)
        .objective(BendingObjective::summed_moment())
        .checkpointing(Checkpointing::Sqrt)
        .build_in::<2>()
        .unwrap();
    let theta = vec![-1.5, -1.4, -1.6, -1.5, -1.45];
    let r = prob.adjoint(&theta, &[]).unwrap();
    let mut g = vec![0.0; 5];
    map.transpose(&r.control_gradient, &mut g);
    assert!(g.iter().all(|x| x.is_finite()));
    let scale = g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    for j in [0, 2] {
        let eps = 1e-4;
        let (mut tp, mut tm) = (theta.clone(), theta.clone());
        tp[j] += eps;
        tm[j] -= eps;
        let fd = (prob.value(&tp).unwrap() - prob.value(&tm).unwrap()) / (2.0 * eps);
        println!("long horizon dJ/dtheta_{j}: adjoint {:e}, FD {fd:e}", g[j]);
        assert!((fd - g[j]).abs() <= 1e-6 * scale);
    }
    // One stored state: q, p (n × 2 each), λ, μ (n each), the tip target (2), and, because the
    // scene has drag, the tape's record of the step into it: p_{k+1/2} and W (n × 2 each).
    let state = (4 * 10 * 2 + 2 * 10 + 2) * 8;
    let sqrt_n = (steps as f64).sqrt();
    println!(
        "checkpointed state memory: {} bytes = {:.1} states (sqrt(N) = {sqrt_n:.0}); storing all: {} bytes",
        r.state_bytes,
        r.state_bytes as f64 / state as f64,
        (steps + 1) * state
    );
    assert!((r.state_bytes as f64) <= 2.5 * sqrt_n * state as f64);
}

/// Bad arguments are typed errors.
#[test]
fn bad_arguments_are_errors() {
    let s = scene(Support::Riser, 5, 0.0, 10);
    let prob = ControlProblem::builder(&s)
        .map(Parametrisation::Constant)
        .objective(BendingObjective::final_moment())
        .build_in::<2>()
        .unwrap();
    assert!(matches!(
        prob.gradient(&[1.0, 2.0]),
        Err(Error::WrongLength {
            name: "theta",
            expected: 1,
            got: 2
        })
    ));
    assert!(matches!(
        prob.gradient(&[f64::NAN]),
        Err(Error::NotFinite {
            name: "theta",
            index: 0
        })
    ));
    assert!(matches!(
        prob.parameter_gradient(&[0.0], &[Parameter::Drag]),
        Err(Error::NoSuchParameter {
            parameter: Parameter::Drag,
            ..
        })
    ));
    let ch = prob.chain().clone();
    let r = adjoint_gradient(
        &ch,
        0.01,
        10,
        &[0.0; 3],
        &BendingObjective::final_moment(),
        &[],
        Checkpointing::Auto,
    );
    assert!(matches!(
        r,
        Err(Error::WrongLength {
            name: "controls",
            expected: 11,
            got: 3
        })
    ));
}

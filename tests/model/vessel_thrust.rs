//! The vessel as the actuator (`[vessel]` `mass`, `added_mass`, `damping`, `thrust_bound`,
//! `thrust_rate_bound`): the control is the thrust F on the vessel, whose surge x_v obeys
//! (m + m_a) ẍ_v = F − c ẋ_v, and the riser's top follows Z = P(t) + x_v.
//!
//! References: the adjoint gradient with respect to the thrust against forward-mode dual
//! numbers through the same simulation (to 1e-12 of the gradient's largest component, round-off)
//! and central finite differences of whole simulations (to 1e-6, the difference quotient), as in
//! tests/adjoint/adjoint.rs; the vessel's discrete surge against the closed-form solution of the linear
//! ODE under a constant thrust (an order-2 scheme: the error falls 4× per halved step).

use crate::gradient_check::{assert_close, central, forward_parameter_gradient, Tolerance};
use chainbeam::adjoint::{forward_value, BendingObjective, Objective};
use chainbeam::catalogue;
use chainbeam::*;
use num_dual::Dual64;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, h = 0.01 s) held by a vessel of the thesis's
/// scale (m + m_a = 0.6 kg, c = 2 N·s/m, so that a thrust of 1 N moves the top by centimetres
/// over the 0.12 s horizon), a 2 cm offset ramped in over 0.08 s, the thrust as the control.
fn scene(drag: f64, steps: usize) -> Scene {
    let mut s = catalogue::riser(5);
    s.beam.support = Support::Vessel;
    s.vessel = Some(Vessel {
        offset: 0.02,
        ramp: 0.08,
        mass: Some(0.5),
        added_mass: Some(0.1),
        damping: Some(2.0),
        ..Vessel::default()
    });
    s.loads.drag = drag;
    s.time.steps = steps;
    s
}

/// The relative step of the central differences. The final moment J = M₀(t_N)² of the
/// thrust-driven riser carries a noise of about 4e-12 (the RATTLE Newton's tolerance, 1e-14 on
/// the constraint residuals): on D = 10, per-step thrusts, the difference quotient missed the
/// adjoint (which Dual64 confirms to 1e-12) by 1.45e-7 with a step of 1.5e-5 and by 1.46e-6 with
/// 1.5e-6, noise/(2·step) both times. A step of 1e-4 keeps that noise below 1e-7 of the gradient
/// while the truncation error, O(step²), stays below it too; the test prints the worst deviation.
const FD_STEP: f64 = 1e-4;

fn start(n: usize, steps: usize) -> Vec<f64> {
    (0..n)
        .map(|j| -1.5 + 0.4 * ((j as f64) * 0.9 + 0.3 * steps as f64).sin())
        .collect()
}

/// Adjoint vs Dual64 (thrust seeded as dual) to 1e-12 and vs central differences to 1e-6 of the
/// gradient's largest component; the riser's parameters against Dual64 to 5e-12 (as
/// tests/adjoint/adjoint.rs). The round-off is relative to the terms the gradient sums: with an effort
/// weight ρ the scale is also that of the effort's own gradient 2ρh u (mapped to θ), which the
/// moment's part nearly cancels at these thrusts (a sum 80 times smaller than either part, seen
/// with ρ = 0.5). Every comparison goes through the one gradient check
/// (tests/common/gradient_check.rs: `central`, `assert_close`) with the tolerances above: the
/// thrust's gradient within 1e-12 · max(|forward|, scale) of forward mode and 1e-6 · scale of the
/// central difference (step 1e-4 · max(|θ_j|, 1)), the parameters' within 5e-12 |forward| +
/// 1e-300. Returns the worst deviations (forward: over max(|forward_j|, scale), FD: over scale).
fn check<O: Objective + Clone>(
    label: &str,
    s: &Scene,
    map: Parametrisation,
    (obj, effort): (O, f64),
) -> (f64, f64) {
    let mut s = s.clone();
    s.control = Some(Control {
        node: s.n(),
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    let steps = s.time.steps;
    let theta = start(map.n_params(), steps);
    let mut params = vec![
        Parameter::InteriorStiffness,
        Parameter::LoadForce(0),
        Parameter::Mass,
        Parameter::BaseStiffness,
        Parameter::TipStiffness,
    ];
    if s.loads.drag > 0.0 {
        params.push(Parameter::Drag);
    }
    let prob = ControlProblem::builder(&s)
        .map(map)
        .objective(obj.clone())
        .build_in::<2>()
        .unwrap();
    let adj = prob.adjoint(&theta, &params).unwrap();
    let mut g = vec![0.0; map.n_params()];
    map.transpose(&adj.control_gradient, &mut g);
    let scale = g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(scale > 0.0, "{label}: the thrust must move the objective");
    let u_effort: Vec<f64> = prob
        .controls(&theta)
        .unwrap()
        .iter()
        .map(|u| 2.0 * effort * s.time.step * u)
        .collect();
    let mut g_effort = vec![0.0; map.n_params()];
    map.transpose(&u_effort, &mut g_effort);
    let scale = g_effort.iter().fold(scale, |a, b| a.max(b.abs()));

    let chain_d = prob.chain_as::<Dual64>();
    let fwd: Vec<f64> = (0..map.n_params())
        .map(|j| {
            let th: Vec<Dual64> = theta
                .iter()
                .enumerate()
                .map(|(i, &t)| Dual64::new(t, f64::from(u8::from(i == j))))
                .collect();
            let mut u = vec![Dual64::from(0.0); steps + 1];
            map.controls(&th, &mut u);
            forward_value(&chain_d, s.time.step, steps, &u, &obj)
                .unwrap()
                .eps
        })
        .collect();
    let worst_fwd = assert_close(
        &format!("{label}: dJ/dF, adjoint"),
        &g,
        &fwd,
        "forward-mode Dual64 with the thrust seeded",
        Tolerance::at_least(1e-12, scale),
    );
    let fd: Vec<f64> = (0..map.n_params())
        .map(|j| {
            let at = |x: f64| {
                let mut t = theta.clone();
                t[j] = x;
                prob.value(&t).unwrap()
            };
            central(&at, theta[j], FD_STEP * theta[j].abs().max(1.0))
        })
        .collect();
    let worst_fd = assert_close(
        &format!("{label}: dJ/dF, adjoint against central differences"),
        &g,
        &fd,
        "central differences, step 1e-4 max(|θ_j|, 1)",
        Tolerance::of_scale(1e-6, scale),
    );
    let fwd = forward_parameter_gradient(&prob, &theta, &params, s.loads.drag, s.time.step, &obj);
    assert_close(
        &format!("{label}: dJ/d{params:?}, adjoint"),
        &adj.parameter_gradient,
        &fwd,
        "forward-mode Dual64 with the parameter seeded",
        Tolerance::relative(5e-12).plus(1e-300),
    );
    (worst_fwd, worst_fd)
}

/// The gradient with respect to the thrust is exact: every parametrisation × objective × drag.
#[test]
fn thrust_gradient_matches_forward_mode_and_finite_differences() {
    let steps = 12;
    let maps = [
        Parametrisation::Constant,
        Parametrisation::PerStep(PerStepControl { steps }),
        Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 4 }),
    ];
    let (mut fwd, mut fd): (f64, f64) = (0.0, 0.0);
    for drag in [0.0, 10.0] {
        let s = scene(drag, steps);
        for map in maps {
            for obj in [
                BendingObjective::final_moment(),
                BendingObjective::summed_moment(),
                BendingObjective::summed_moment().with_effort(0.5),
            ] {
                let label = format!("D={drag} {map:?} {obj:?}");
                let (a, b) = check(&label, &s, map, (obj, obj.effort));
                fwd = fwd.max(a);
                fd = fd.max(b);
            }
        }
    }
    println!("worst |adjoint - forward|/max|g| {fwd:.1e}, worst |FD - adjoint|/max|g| {fd:.1e}");
}

/// Without damping the same check (the Störmer–Verlet limit of the drive).
#[test]
fn thrust_gradient_without_vessel_damping() {
    let mut s = scene(10.0, 12);
    if let Some(v) = s.vessel.as_mut() {
        v.damping = Some(0.0);
    }
    check(
        "c = 0",
        &s,
        Parametrisation::PerStep(PerStepControl { steps: 12 }),
        (BendingObjective::summed_moment(), 0.0),
    );
}

/// With station keeping (`position_stiffness` k = 4 N/m: √(k/M) = 2.6 rad/s, a spring the
/// 0.12 s horizon feels) the same check: the spring's kicks and their transpose
/// (model::ThrustDrive::reverse) against Dual64 and central differences.
#[test]
fn thrust_gradient_with_station_keeping() {
    for damping in [2.0, 0.0] {
        let mut s = scene(10.0, 12);
        if let Some(v) = s.vessel.as_mut() {
            v.position_stiffness = Some(4.0);
            v.damping = Some(damping);
        }
        for map in [
            Parametrisation::PerStep(PerStepControl { steps: 12 }),
            Parametrisation::Piecewise(PiecewiseControl {
                steps: 12,
                pieces: 4,
            }),
        ] {
            check(
                &format!("k = 4, c = {damping}, {map:?}"),
                &s,
                map,
                (BendingObjective::summed_moment(), 0.0),
            );
        }
    }
}

/// Station keeping against the closed form of the damped oscillator M ẍ = F − c ẋ − k x from
/// rest under a constant thrust F: x(t) = F/k (1 − e^{−ζω t}(cos ω_d t + ζω/ω_d sin ω_d t)),
/// ω = √(k/M), ζ = c/(2Mω), ω_d = ω√(1 − ζ²). Order 2 (the error at t = 1 s falls by 4 ± 10 %
/// per halved step), and the top settles at F/k: the station keeping holds the vessel where a
/// constant thrust puts it (after 30 s, 9 decay times 2M/c, to 1e-9 of F/k).
#[test]
fn station_keeping_against_the_damped_oscillator() {
    let (mass, damping, stiffness, force) = (0.6, 2.0, 4.0, 0.5);
    let top = |h: f64, end: f64| {
        let mut s = catalogue::riser(5);
        s.beam.support = Support::Vessel;
        s.vessel = Some(Vessel {
            mass: Some(mass),
            added_mass: Some(0.0),
            damping: Some(damping),
            position_stiffness: Some(stiffness),
            ..Vessel::default()
        });
        s.time.step = h;
        s.time.steps = (end / h).round() as usize;
        s.control = Some(Control {
            node: s.n(),
            kind: ControlKind::Constant,
            values: vec![force],
            values_x: None,
        });
        *simulate(&s).unwrap().tip_target().last().unwrap()
    };
    let w = (stiffness / mass).sqrt();
    let zeta = damping / (2.0 * mass * w);
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let exact =
        force / stiffness * (1.0 - (-zeta * w).exp() * (wd.cos() + zeta * w / wd * wd.sin()));
    let error = |h: f64| (top(h, 1.0) - exact).abs();
    let (e1, e2, e3) = (error(0.01), error(0.005), error(0.0025));
    println!("station-keeping surge error at t = 1 s: {e1:.3e}, {e2:.3e}, {e3:.3e}");
    for r in [e1 / e2, e2 / e3] {
        assert!((3.6..=4.4).contains(&r), "order-2 ratio expected, got {r}");
    }
    let settled = top(0.01, 30.0);
    assert!(
        (settled - force / stiffness).abs() <= 1e-9 * force / stiffness,
        "settled at {settled}, F/k = {}",
        force / stiffness
    );
}

/// The top's surge under a constant thrust F from rest against the closed form of
/// M ẍ = F − c ẋ: x(t) = (F/c)(t − τ(1 − e^{−t/τ})), τ = M/c. The riser's top follows the vessel
/// (one-way coupling), so the top's z minus the prescribed offset is x_v. The scheme is of
/// order 2: the error at t = 1 s falls by 4 (±10 %) per halved step.
#[test]
fn vessel_surge_is_second_order_against_the_closed_form() {
    let (mass, damping, force) = (0.6, 2.0, 0.5);
    let error = |h: f64| {
        let mut s = catalogue::riser(5);
        s.beam.support = Support::Vessel;
        s.vessel = Some(Vessel {
            mass: Some(mass),
            added_mass: Some(0.0),
            damping: Some(damping),
            ..Vessel::default()
        });
        s.time.step = h;
        s.time.steps = (1.0 / h).round() as usize;
        s.control = Some(Control {
            node: s.n(),
            kind: ControlKind::Constant,
            values: vec![force],
            values_x: None,
        });
        let tr = simulate(&s).unwrap();
        let z = *tr.tip_target().last().unwrap();
        let tau = mass / damping;
        let exact = force / damping * (1.0 - tau * (1.0 - (-1.0 / tau).exp()));
        (z - exact).abs()
    };
    let (e1, e2, e3) = (error(0.01), error(0.005), error(0.0025));
    println!("surge error at t = 1 s: {e1:.3e}, {e2:.3e}, {e3:.3e}");
    for r in [e1 / e2, e2 / e3] {
        assert!((3.6..=4.4).contains(&r), "order-2 ratio expected, got {r}");
    }
}

/// The thrust keys are checked by name and quantity.
#[test]
fn bad_thrust_keys_are_refused_by_name() {
    for (key, set) in [
        (
            "vessel.mass",
            (|v: &mut Vessel| v.mass = Some(-1.0)) as fn(&mut Vessel),
        ),
        ("vessel.added_mass", |v| v.added_mass = Some(f64::NAN)),
        ("vessel.damping", |v| v.damping = Some(-2.0)),
        ("vessel.thrust_bound", |v| v.thrust_bound = Some(0.0)),
        ("vessel.thrust_rate_bound", |v| {
            v.thrust_rate_bound = Some(f64::INFINITY)
        }),
        ("vessel.position_stiffness", |v| {
            v.position_stiffness = Some(-1.0)
        }),
    ] {
        let mut s = scene(0.0, 12);
        set(s.vessel.as_mut().unwrap());
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
    // The thrust acts at the top, within its bound and its rate.
    let mut s = scene(0.0, 12);
    s.control = Some(Control {
        node: 7,
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("control.node"), "{e}");
    s.control = Some(Control {
        node: 10,
        kind: ControlKind::Constant,
        values: vec![4e6],
        values_x: None,
    });
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("thrust_bound"), "{e}");
    s.vessel.as_mut().unwrap().thrust_rate_bound = Some(10.0);
    let mut values = vec![0.0; 13];
    values[5] = 0.2; // 0.2 N in 0.01 s: 20 N/s > 10 N/s
    s.control = Some(Control {
        node: 10,
        kind: ControlKind::PerStep,
        values,
        values_x: None,
    });
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("thrust_rate_bound"), "{e}");
}

/// A PD law that asks for more than the thrusters give: the plant applies at most
/// `thrust_bound` and changes the thrust by at most `thrust_rate_bound` · h per step, asserted
/// over every step of the closed loop; both limits bind in this run (so the check is not
/// vacuous: the commanded law jumps by up to 2 N at each decision).
#[test]
fn closed_loop_thrust_respects_its_bound_and_rate_at_every_step() {
    let (bound, rate) = (1.0, 5.0);
    let mut s = scene(10.0, 300);
    if let Some(v) = s.vessel.as_mut() {
        v.thrust_bound = Some(bound);
        v.thrust_rate_bound = Some(rate);
    }
    let mut pd = mpc::PdLaw {
        kp: 50.0,
        kd: 5.0,
        bound: 2.0, // the law's own clamp, above the thrusters' bound
        ..mpc::PdLaw::default()
    };
    let r = mpc::run_closed_loop(&s, 0.05, &mut pd).unwrap();
    let h = s.time.step;
    let (mut at_bound, mut at_rate) = (false, false);
    assert_eq!(r.control.len(), s.time.steps + 1);
    assert!(
        r.control[0].abs() <= rate * h * (1.0 + 1e-12),
        "from 0 at t = 0"
    );
    for (k, f) in r.control.iter().enumerate() {
        assert!(f.abs() <= bound, "step {k}: |F| = {f} > {bound}");
        at_bound |= f.abs() == bound;
    }
    for (k, w) in r.control.windows(2).enumerate() {
        let change = (w[1] - w[0]).abs();
        assert!(
            change <= rate * h * (1.0 + 1e-12),
            "step {k}: |ΔF| = {change} > {}",
            rate * h
        );
        at_rate |= change >= rate * h * (1.0 - 1e-12);
    }
    assert!(at_bound && at_rate, "the limits must bind in this run");
    // The decisions asked for more than the plant applied.
    let asked = r
        .decisions
        .iter()
        .fold(0.0f64, |m, d| m.max(d.control.abs()));
    assert!(asked > bound, "largest command {asked}");
}

/// The best constant thrust (by the adjoint gradient, the structured solvers refusing the
/// vessel's tip) lowers c_sum below no thrust on a riser pushed by a point load; the
/// receding-horizon controller in the spatial model refuses the thrust with a typed error.
#[test]
fn constant_thrust_lowers_the_moment_and_spatial_mpc_refuses_typed() {
    let s = scene(10.0, 100);
    let (c, r) = mpc::ConstantForce::best_thrust(&s, 3.0, 0.0).unwrap();
    let problem = ControlProblem::builder(&s)
        .map(PiecewiseControl {
            steps: 100,
            pieces: 1,
        })
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .unwrap();
    let none = problem.value(&[0.0]).unwrap();
    println!(
        "best constant thrust {} N: J {} vs {none} without",
        c.u.z, r.objective
    );
    assert!(r.objective < none, "J {} vs {none}", r.objective);
    assert!(c.u.z.abs() <= 3.0);
    // MPC plans through the thrust in the planar model (tests/mpc/mpc_vessel.rs); the spatial
    // model's is refused, typed.
    let e = mpc::Mpc::spatial(&s, 0.05, mpc::MpcOptions::default()).map(|_| ());
    assert!(
        matches!(e, Err(Error::Mpc(mpc::MpcError::ThrustSpatial))),
        "{e:?}"
    );
}

/// `chainbeam fatigue`'s thrust report: a PD law (given gains, no tuning) run as a fatigue
/// controller on a thrust scene reports (rms, peak) of the thrust the plant applied, the same
/// numbers as the closed loop's own record (recomputed here from its per-step thrusts), within
/// the bound; `none` reports zero thrust, and a scene whose control is a force reports none.
#[test]
fn fatigue_controllers_report_the_thrust_they_applied() {
    use chainbeam::fatigue_study::{run_controller, thrust_stats, ControlSettings, ControllerKind};
    let (bound, rate) = (1.0, 5.0);
    let mut s = scene(10.0, 300);
    if let Some(v) = s.vessel.as_mut() {
        v.thrust_bound = Some(bound);
        v.thrust_rate_bound = Some(rate);
    }
    let settings = ControlSettings {
        interval: 0.05,
        pd_gains: Some([0.0, 50.0, 5.0]),
        ..ControlSettings::default()
    };
    let pd = run_controller(&s, ControllerKind::Pd, &settings).unwrap();
    let [rms, peak] = pd.thrust.expect("a thrust scene reports its thrust");
    // The same loop by hand: the PD law clamps at the thrust bound (control_bound).
    let mut law = mpc::PdLaw {
        kp: 50.0,
        kd: 5.0,
        bound,
        ..mpc::PdLaw::default()
    };
    let r = mpc::run_closed_loop(&s, 0.05, &mut law).unwrap();
    let [rms_ref, peak_ref] = thrust_stats(&r.control);
    let direct = (r.control.iter().map(|f| f * f).sum::<f64>() / r.control.len() as f64).sqrt();
    assert_eq!([rms, peak], [rms_ref, peak_ref]);
    assert!((rms - direct).abs() <= 1e-15 * direct);
    assert!(
        rms > 0.0 && peak <= bound && rms <= peak,
        "rms {rms}, peak {peak}"
    );
    let none = run_controller(&s, ControllerKind::None, &settings).unwrap();
    assert_eq!(none.thrust, Some([0.0, 0.0]));
    let force = catalogue::riser(5);
    let none = run_controller(&force, ControllerKind::None, &settings).unwrap();
    assert_eq!(none.thrust, None);
    println!("pd thrust rms {rms} N, peak {peak} N");
}

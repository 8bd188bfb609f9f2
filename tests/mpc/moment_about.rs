//! MPC on the hot spot's moment about the plan's own mean (`[mpc] moment_about = "mean"`):
//! J = h Σ_k |M_k − M̄|^m + ρ h Σ_k F_k², M̄ = (1/(N+1)) Σ_k M_k ([`HotSpotObjective`], "About
//! the plan's mean"), its exact gradient through the vessel's thrust, MPC planning on it, the
//! default `"zero"` unchanged and the refusals.
//!
//! References: forward-mode Dual64 through the same simulation (which differentiates J's value
//! itself, not the hand-written gradient of the history term) and a five-point central
//! difference (tests/common/gradient_check.rs) for the gradient; for J's value, the hot spot's
//! moment recomputed by an independent path, the joint torques of
//! [`hotspots::joint_moment_history`] (atan2 of the attitudes, blended by
//! [`hotspots::interpolation_joints`]); for the history term alone, its invariance under a
//! constant shift of M (the definition: M − M̄ does not change), hence Σ_j ∂J/∂M_j = 0.

use crate::gradient_check::{assert_close, Tolerance};
use chainbeam::adjoint::{History, HotSpotObjective, Objective};
use chainbeam::fatigue::{MomentMeasure, WellheadDamage};
use chainbeam::hotspots::{self, HotSpotSpec};
use chainbeam::mpc::planning::planning_scene;
use chainbeam::mpc::{run_closed_loop, Horizon, MomentAbout, Mpc, MpcError, MpcOptions};
use chainbeam::scene::MpcTable;
use chainbeam::*;
use num_dual::Dual64;

/// examples/scenes/riser_300m_system.toml with the vessel's thrust as the control, its stack-up
/// rebuilt with 20 pendulums at h = 0.008 s (the reduced system scene of tests/mpc/hotspot.rs),
/// run for `seconds`.
fn system(seconds: f64) -> Scene {
    let mut scene = Scene::from_file(system_path()).unwrap();
    scene.vessel.as_mut().unwrap().mass = Some(chainbeam::scene::DEFAULT_VESSEL_MASS);
    let mut s = planning_scene(&scene, 20, 0.008).unwrap();
    s.time.steps = (seconds / s.time.step).round() as usize;
    s
}

fn system_path() -> &'static str {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m_system.toml"
    )
}

/// The scene's hot spot "conductor below mudline" (between two joints of the 20-pendulum chain).
fn conductor(s: &Scene) -> HotSpotSpec {
    s.hotspots
        .iter()
        .find(|h| h.name == "conductor below mudline")
        .expect("the system scene's hot spot")
        .clone()
}

/// The S-N curve's first slope m of a hot spot (3 for the conductor's F1 weld).
fn exponent(spot: &HotSpotSpec) -> f64 {
    WellheadDamage::new(&spot.spec, MomentMeasure::Wellhead)
        .unwrap()
        .exponent()
}

/// h Σ_k |M_k − M̄|^m + ρ h Σ_k F_k² of the scene `s` run with the per-step thrusts `thrusts`
/// from rest, its moment from the joint torques of [`hotspots::joint_moment_history`] (the
/// independent path), with the mean M̄ and the std of M about it. The thrust's rate bound is
/// lifted for the run (it only validates a per-step control; the adjoint's piecewise thrusts
/// jump between pieces, as a [`ControlProblem`] allows).
fn recomputed(s: &Scene, spot: &HotSpotSpec, thrusts: &[f64], effort: f64) -> (f64, f64, f64) {
    let mut s = s.clone();
    s.vessel.as_mut().unwrap().thrust_rate_bound = Some(1e9);
    s.time.steps = thrusts.len() - 1;
    s.control = Some(Control {
        node: s.n(),
        kind: ControlKind::PerStep,
        values: thrusts.to_vec(),
        values_x: None,
    });
    let w = hotspots::interpolation_joints(&s.beam.lengths, spot.elevation);
    let history = hotspots::joint_moment_history(&s, &[w.lower, w.upper]).unwrap();
    let moment: Vec<f64> = history.moment[0]
        .iter()
        .zip(&history.moment[1])
        .map(|(&a, &b)| w.blend(a, b))
        .collect();
    let n = moment.len() as f64;
    let mean = moment.iter().sum::<f64>() / n;
    let std = (moment.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / n).sqrt();
    let (h, m) = (s.time.step, exponent(spot));
    let j = moment
        .iter()
        .zip(thrusts)
        .map(|(&mk, &f)| (mk - mean).abs().powf(m) * h + effort * h * f * f)
        .sum();
    (j, mean, std)
}

/// dJ/dθ_j of the mean objective through the vessel's thrust, F held over 4 pieces of 2 s, on
/// the reduced system scene in its sea: the adjoint equals forward-mode Dual64 (which
/// differentiates J's value, M̄ included, through the simulation) to 1e-11 and a five-point
/// central difference (step 10³ N, against thrusts of 10⁶ N) equals it to 1e-6, both of the
/// gradient's largest component (the tolerances of tests/mpc/hotspot.rs's gradient test on the
/// same scene and thrusts, whose objective differs only in the mean). J's value equals the
/// independent recomputation from the joint torques to 1e-9 (the two paths differ in the angle,
/// asin against atan2: tests/mpc/hotspot.rs measures 1e-9). Measured, of each component: the
/// adjoint 2·10⁻¹² – 5·10⁻¹¹ from Dual64, the difference 7·10⁻⁸ – 1·10⁻⁵ (the smaller components
/// carry the larger's rounding); J to the recomputation 10⁻¹⁶ (M̄ = 2.4·10⁵ N m against a std of
/// 1.1·10⁵ N m over these 8 s from rest).
#[test]
fn gradient_about_the_mean_is_exact() {
    let s = system(8.0);
    let spot = conductor(&s);
    let m = exponent(&spot);
    assert_eq!(m, 3.0, "F1's first slope");
    let effort = 0.01;
    let objective = HotSpotObjective::new(&s, spot.elevation, m, effort)
        .unwrap()
        .with_about(MomentAbout::Mean);
    let steps = s.time.steps;
    let problem = ControlProblem::builder(&s)
        .map(PiecewiseControl { steps, pieces: 4 })
        .objective(objective)
        .build_in::<2>()
        .unwrap();
    let theta = [1.0e6, -0.5e6, 1.5e6, 0.5e6];
    let (j, adjoint) = problem.value_and_gradient(&theta).unwrap();
    let u = problem.controls(&theta).unwrap();
    let (want, mean, std) = recomputed(&s, &spot, &u, effort);
    println!("J = {j:.6e}, recomputed {want:.6e}; M̄ = {mean:.4e} N m, std {std:.4e} N m");
    assert!(((j - want) / want).abs() < 1e-9, "J {j} vs {want}");
    // The case this objective is for: a mean that is not small against the fluctuation.
    assert!(mean.abs() > 0.1 * std, "mean {mean} std {std}");
    let (forward, central) = super::hotspot::dual_and_central(&problem, steps, theta, &adjoint);
    let scale = forward.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    let source = "forward-mode Dual64";
    assert_close(
        "dJ/dθ about the mean, adjoint",
        &adjoint,
        &forward,
        source,
        Tolerance::of_scale(1e-11, scale),
    );
    assert_close(
        "dJ/dθ about the mean, five-point central difference (step 10³ N)",
        &central,
        &forward,
        source,
        Tolerance::of_scale(1e-6, scale),
    );
}

/// The history term alone, on a synthetic moment history M_k = 7·10⁵ + 10⁵ sin(0.3 k) + 3·10⁴
/// cos(1.1 k) (a mean seven times the fluctuation, as the conductor's): ∂H/∂M_j equals Dual64
/// of H to 1e-12 relative (per component, of the largest), H and its gradient do not change
/// when a constant is added to every M_k (to 1e-12 relative: M − M̄ is the same up to rounding),
/// and Σ_j ∂H/∂M_j = 0 (to 1e-12 of Σ_j |∂H/∂M_j|); for m = 2 and m = 3.
#[test]
fn the_history_term_sees_only_the_fluctuation() {
    let s = system(0.1);
    let spot = conductor(&s);
    let moment: Vec<f64> = (0..41)
        .map(|k| {
            let k = k as f64;
            7.0e5 + 1.0e5 * (0.3 * k).sin() + 3.0e4 * (1.1 * k).cos()
        })
        .collect();
    for m in [2.0, 3.0] {
        let o = HotSpotObjective::new(&s, spot.elevation, m, 0.0)
            .unwrap()
            .with_about(MomentAbout::Mean);
        assert!(o.has_history());
        let eval = |moment: &[f64]| {
            let mut grad = vec![0.0; moment.len()];
            let v = o
                .history(History {
                    moment,
                    moment_x: &[],
                    grad: &mut grad,
                    grad_x: &mut [],
                    h: 0.008,
                })
                .unwrap();
            (v, grad)
        };
        let (v, grad) = eval(&moment);
        let scale = grad.iter().fold(0.0f64, |a, g| a.max(g.abs()));
        for (j, &gj) in grad.iter().enumerate() {
            let md: Vec<Dual64> = moment
                .iter()
                .enumerate()
                .map(|(k, &x)| Dual64::new(x, if k == j { 1.0 } else { 0.0 }))
                .collect();
            let mut gd = vec![Dual64::from(0.0); md.len()];
            let vd = o
                .history(History {
                    moment: &md,
                    moment_x: &[],
                    grad: &mut gd,
                    grad_x: &mut [],
                    h: 0.008,
                })
                .unwrap();
            assert!((vd.re - v).abs() <= 1e-15 * v, "m = {m}: value");
            assert!(
                (vd.eps - gj).abs() <= 1e-12 * scale,
                "m = {m}, j = {j}: {gj} vs Dual64 {}",
                vd.eps
            );
        }
        let shifted: Vec<f64> = moment.iter().map(|x| x - 6.5e5).collect();
        let (vs, gs) = eval(&shifted);
        println!("m = {m}: H = {v:.6e}, shifted by −6.5e5 N m: {vs:.6e}");
        assert!(((vs - v) / v).abs() < 1e-12, "m = {m}: {vs} vs {v}");
        for (a, b) in gs.iter().zip(&grad) {
            assert!((a - b).abs() < 1e-12 * scale, "m = {m}: {a} vs {b}");
        }
        let sum: f64 = grad.iter().sum();
        let abs: f64 = grad.iter().map(|g| g.abs()).sum();
        assert!(sum.abs() < 1e-12 * abs, "m = {m}: Σ ∂H/∂M = {sum}");
    }
}

/// MPC with `moment_about = Mean` plans on the mean objective: the first plan's J (from rest at
/// t = 0, one decision of 0.4 s, a horizon of 1.6 s, a perfect forecast) equals h Σ_k |M_k −
/// M̄|^m + ρ h Σ_k F_k² recomputed from the plan's per-step thrusts by the joint torques (1e-9,
/// as tests/mpc/hotspot.rs's plan test), and the plan acts.
#[test]
fn mpc_plans_on_the_moment_about_its_mean() {
    let s = system(0.4);
    let spot = conductor(&s);
    let effort = 0.01;
    let options = MpcOptions {
        horizon: Horizon::Seconds(1.6),
        effort,
        first_iterations: 5,
        hotspot: Some(spot.clone()),
        moment_about: MomentAbout::Mean,
        ..MpcOptions::default()
    };
    let mut mpc = Mpc::new(&s, 0.4, options).unwrap();
    run_closed_loop(&s, 0.4, &mut mpc).unwrap();
    let plan = mpc.last_thrust_plan().expect("a plan").clone();
    assert_eq!(plan.start, 0.0, "the first plan, from rest");
    let peak = plan.thrusts.iter().fold(0.0f64, |a, f| a.max(f.abs()));
    let (want, _, _) = recomputed(&s, &spot, &plan.thrusts, effort);
    let rel = (plan.objective - want).abs() / want;
    println!(
        "plan: J = {:.6e}, recomputed {want:.6e} ({rel:.1e}); peak thrust {peak:.3e} N",
        plan.objective
    );
    assert!(peak > 0.0, "the plan acts");
    assert!(rel < 1e-9, "plan J {} vs {want}", plan.objective);
}

/// `"zero"` is the objective as before bit for bit: the default of the objective, of
/// [`MpcOptions`] and of the `[mpc]` table's resolution, and an explicit `with_about(Zero)` gives
/// the same J and gradient bits as the objective built without it; and "mean" differs (the
/// mean matters on this scene).
#[test]
fn zero_is_the_objective_as_before() {
    let s = system(2.0);
    let spot = conductor(&s);
    assert_eq!(MpcOptions::default().moment_about, MomentAbout::Zero);
    assert_eq!(
        MpcTable::default().resolve(None).moment_about,
        MomentAbout::Zero
    );
    let before = HotSpotObjective::new(&s, spot.elevation, 3.0, 0.01).unwrap();
    assert_eq!(before.about, MomentAbout::Zero);
    assert!(!before.has_history());
    let explicit = before.clone().with_about(MomentAbout::Zero);
    let mean = before.clone().with_about(MomentAbout::Mean);
    let steps = s.time.steps;
    let theta = [1.0e6, -0.5e6];
    let run = |o: HotSpotObjective| {
        ControlProblem::builder(&s)
            .map(PiecewiseControl { steps, pieces: 2 })
            .objective(o)
            .build_in::<2>()
            .unwrap()
            .value_and_gradient(&theta)
            .unwrap()
    };
    let (j0, g0) = run(before);
    let (j1, g1) = run(explicit);
    assert_eq!(j0.to_bits(), j1.to_bits());
    for (a, b) in g0.iter().zip(&g1) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
    let (jm, _) = run(mean);
    println!("J about zero {j0:.6e}, about the mean {jm:.6e}");
    assert!(jm < 0.5 * j0, "the mean dominates J about zero here");
}

/// A bad `moment_about` in the scene file is refused naming `mpc.moment_about`; "mean" without
/// a hot spot is refused naming `moment_about` (by the settings' resolution and by MPC); the
/// names read back.
#[test]
fn bad_moment_about_is_refused_by_name() {
    let text = std::fs::read_to_string(system_path()).unwrap();
    let dir = std::path::Path::new(system_path()).parent().unwrap();
    for bad in ["\"median\"", "\"Mean\"", "1"] {
        let e = Scene::from_toml_str_in_dir(&format!("{text}\n[mpc]\nmoment_about = {bad}\n"), dir)
            .unwrap_err();
        println!("{bad}: {e}");
        assert!(e.to_string().contains("mpc.moment_about"), "{bad}: {e}");
    }
    let ok = Scene::from_toml_str_in_dir(
        &format!("{text}\n[mpc]\nhotspot = \"conductor below mudline\"\nmoment_about = \"mean\"\n"),
        dir,
    )
    .unwrap();
    let table = ok.mpc.clone().unwrap();
    assert_eq!(table.moment_about, Some(MomentAbout::Mean));
    // The flag's value overrides the table's (MpcTable::resolve).
    let flags = MpcTable {
        moment_about: Some(MomentAbout::Zero),
        ..MpcTable::default()
    };
    assert_eq!(flags.resolve(Some(&table)).moment_about, MomentAbout::Zero);
    let settings = MpcTable::default().resolve(Some(&table));
    assert_eq!(
        settings.hotspot_spec(&ok).unwrap().unwrap().name,
        "conductor below mudline"
    );
    // "mean" without a hot spot.
    let lone = MpcTable {
        moment_about: Some(MomentAbout::Mean),
        ..MpcTable::default()
    }
    .resolve(None);
    let e = lone.hotspot_spec(&ok).unwrap_err();
    assert!(matches!(e, MpcError::MomentAboutNeedsHotSpot), "{e:?}");
    assert_eq!(e.argument(), "moment_about");
    let s = system(0.4);
    let e = Mpc::new(
        &s,
        0.4,
        MpcOptions {
            horizon: Horizon::Seconds(1.6),
            moment_about: MomentAbout::Mean,
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::Mpc(MpcError::MomentAboutNeedsHotSpot)),
        "{e:?}"
    );
    assert_eq!(e.argument_fault().unwrap().0, "moment_about");
    assert!(e.to_string().contains("moment_about"), "{e}");
}

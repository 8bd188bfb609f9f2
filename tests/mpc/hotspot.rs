//! Controllers that act on a hot spot's moment (`[mpc] hotspot`): the objective h Σ|M|^m + ρ h Σ u²
//! at a named elevation ([`HotSpotObjective`]), its exact gradient through the vessel's thrust,
//! and MPC planning on it.
//!
//! References: forward-mode Dual64 through the same simulation and a five-point central
//! difference (tests/common/gradient_check.rs) for the gradient; for the plan's objective, the
//! hot spot's moment recomputed from the plan's thrusts by an independent path, the joint
//! torques of [`hotspots::joint_moment_history`] (atan2 of the attitudes, blended by
//! [`hotspots::interpolation_joints`]), which the fatigue study's `hotspots` assess.

use crate::gradient_check::{assert_close, five_point, Tolerance};
use chainbeam::adjoint::{forward_value, HotSpotObjective};
use chainbeam::fatigue::{MomentMeasure, WellheadDamage};
use chainbeam::hotspots::{self, HotSpotSpec};
use chainbeam::mpc::planning::planning_scene;
use chainbeam::mpc::{run_closed_loop, Horizon, Mpc, MpcError, MpcOptions};
use chainbeam::*;
use num_dual::Dual64;

/// examples/scenes/riser_300m_system.toml with the vessel's thrust as the control, its stack-up
/// rebuilt with 20 pendulums at h = 0.008 s (the reduced system scene of tests/mpc/observe.rs),
/// run for `seconds`.
fn system(seconds: f64) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m_system.toml"
    );
    let mut scene = Scene::from_file(path).unwrap();
    scene.vessel.as_mut().unwrap().mass = Some(chainbeam::scene::DEFAULT_VESSEL_MASS);
    let mut s = planning_scene(&scene, 20, 0.008).unwrap();
    s.time.steps = (seconds / s.time.step).round() as usize;
    s
}

/// The scene's hot spot "conductor below mudline" (elevation 57 m: between two joints of the
/// 20-pendulum chain, so the moment is a blend of two joint torques).
fn conductor(s: &Scene) -> HotSpotSpec {
    let spot = s
        .hotspots
        .iter()
        .find(|h| h.name == "conductor below mudline")
        .expect("the system scene's hot spot")
        .clone();
    let w = hotspots::interpolation_joints(&s.beam.lengths, spot.elevation);
    assert!(w.weight > 0.0 && w.upper == w.lower + 1, "{w:?}: a blend");
    spot
}

/// The S-N curve's first slope m of a hot spot (3 for the F1 curve of the conductor's weld).
fn exponent(spot: &HotSpotSpec) -> f64 {
    WellheadDamage::new(&spot.spec, MomentMeasure::Wellhead)
        .unwrap()
        .exponent()
}

/// dJ/dθ_j of J = h Σ|M|^m + ρ h Σ F² through the vessel's thrust, F held over 4 pieces of 2 s,
/// on the reduced system scene in its sea: the adjoint equals forward-mode Dual64 to 1e-11 and a
/// five-point central difference (step 10³ N, against thrusts of 10⁶ N) equals it to 1e-6, both
/// of the gradient's largest component (the components span a factor 1300, and the smaller ones
/// carry the rounding of the larger: measured, of the component itself, 8·10⁻¹⁴ and 7·10⁻⁸ on
/// the largest, up to 8·10⁻¹¹ and 7·10⁻⁵ on the smallest; of the largest, at most 2·10⁻¹² for
/// the adjoint). The thrusts are large and the pieces long so that the thrust moves
/// the 5·10⁷ kg vessel by decimetres and J by a share of itself: over 0.4 s pieces of 10⁵ N the
/// derivative is 10⁻⁷ of J per newton·θ, below the RATTLE Newton solve's tolerance seen through
/// a difference (measured: 1.5·10⁻³ relative difference then).
#[test]
fn gradient_through_the_thrust_is_exact() {
    let s = system(8.0);
    let spot = conductor(&s);
    let m = exponent(&spot);
    assert_eq!(m, 3.0, "F1's first slope");
    let objective = HotSpotObjective::new(&s, spot.elevation, m, 0.01).unwrap();
    let steps = s.time.steps;
    let problem = ControlProblem::builder(&s)
        .map(PiecewiseControl { steps, pieces: 4 })
        .objective(objective)
        .build_in::<2>()
        .unwrap();
    let theta = [1.0e6, -0.5e6, 1.5e6, 0.5e6];
    let (j, adjoint) = problem.value_and_gradient(&theta).unwrap();
    println!("J = {j:.6e}");
    assert!(j.is_finite() && j > 0.0);
    let (forward, central) = dual_and_central(&problem, steps, theta, &adjoint);
    let scale = forward.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    let source = "forward-mode Dual64";
    assert_close(
        "dJ/dθ, adjoint",
        &adjoint,
        &forward,
        source,
        Tolerance::of_scale(1e-11, scale),
    );
    let fd = "dJ/dθ, five-point central difference (step 10³ N)";
    assert_close(
        fd,
        &central,
        &forward,
        source,
        Tolerance::of_scale(1e-6, scale),
    );
}

/// With `hotspot` set, MPC's plan minimises the hot spot's objective: the first plan's J (from
/// rest at t = 0, one decision of 0.4 s, a horizon of 1.6 s) equals h Σ_k |M(t_k)|^m + ρ h Σ_k
/// F_k² recomputed from the plan's per-step thrusts by the joint torques of
/// [`hotspots::joint_moment_history`] on the same scene (the plan's model is the plant's: a
/// perfect forecast). The two paths differ in the angle (asin of the attitude's z from the
/// node positions against atan2 of the attitudes) and in the wave kinematics' tabulation (the
/// plan's chain tabulates the sea over the run and a horizon beyond), so they agree to rounding,
/// not bit for bit: 1e-9 relative. And the plan moved the thrust off zero (it acted).
#[test]
fn mpc_plans_on_the_hot_spots_moment() {
    let mut s = system(0.4);
    let spot = conductor(&s);
    let m = exponent(&spot);
    let effort = 0.01;
    let options = MpcOptions {
        horizon: Horizon::Seconds(1.6),
        effort,
        first_iterations: 5,
        hotspot: Some(spot.clone()),
        ..MpcOptions::default()
    };
    let mut mpc = Mpc::new(&s, 0.4, options).unwrap();
    run_closed_loop(&s, 0.4, &mut mpc).unwrap();
    let plan = mpc.last_thrust_plan().expect("a plan").clone();
    assert_eq!(plan.start, 0.0, "the first plan, from rest");
    let peak = plan.thrusts.iter().fold(0.0f64, |a, f| a.max(f.abs()));
    println!("plan: J = {:.6e}, peak thrust {peak:.3e} N", plan.objective);
    assert!(peak > 0.0, "the plan acts");
    // The plan's trajectory: the scene over the horizon with the plan's thrusts per step.
    let steps = plan.thrusts.len() - 1;
    s.time.steps = steps;
    s.control = Some(Control {
        node: s.n(),
        kind: ControlKind::PerStep,
        values: plan.thrusts.clone(),
        values_x: None,
    });
    let w = hotspots::interpolation_joints(&s.beam.lengths, spot.elevation);
    let history = hotspots::joint_moment_history(&s, &[w.lower, w.upper]).unwrap();
    let h = s.time.step;
    let recomputed: f64 = history.moment[0]
        .iter()
        .zip(&history.moment[1])
        .zip(&plan.thrusts)
        .map(|((&a, &b), &f)| w.blend(a, b).abs().powf(m) * h + effort * h * f * f)
        .sum();
    let rel = (plan.objective - recomputed).abs() / recomputed;
    println!("recomputed J = {recomputed:.6e}: relative difference {rel:.1e}");
    assert!(rel < 1e-9, "plan J {} vs {recomputed}", plan.objective);
    // The hot spot's moment is not the base moment: the base's objective differs.
    let base: f64 = history
        .base_moment
        .iter()
        .map(|&b| (b * s.beam.lengths[0] / 2.0).abs().powf(m) * h)
        .sum();
    assert!((base - recomputed).abs() > 0.1 * recomputed);
}

/// The moment the objective reads from the node positions is the joint-torque blend of the hot
/// spots' assessment on a run (the angles of [`hotspots::joint_moment`]), to 1e-9 of its peak.
#[test]
fn the_objectives_moment_is_the_hot_spots() {
    let mut s = system(2.0);
    s.control = None;
    let spot = conductor(&s);
    let objective = HotSpotObjective::new(&s, spot.elevation, 3.0, 0.0).unwrap();
    let w = hotspots::interpolation_joints(&s.beam.lengths, spot.elevation);
    let history = hotspots::joint_moment_history(&s, &[w.lower, w.upper]).unwrap();
    let run = simulate(&s).unwrap();
    let traj = run.as_planar().expect("planar");
    let peak = history.moment[0]
        .iter()
        .zip(&history.moment[1])
        .fold(0.0f64, |p, (&a, &b)| p.max(w.blend(a, b).abs()));
    assert!(peak > 1e4, "the conductor bends: {peak}");
    let mut worst = 0.0f64;
    for k in 0..=s.time.steps {
        let got = objective.moment_of_attitudes(traj.q(k));
        let want = w.blend(history.moment[0][k], history.moment[1][k]);
        worst = worst.max((got - want).abs() / peak);
    }
    println!("peak |M| {peak:.4e} N m: worst difference {worst:.1e} of it");
    assert!(worst < 1e-9);
}

/// A hot spot for MPC on a force-controlled scene (its plans take the base moment's
/// Gauss-Newton form), an exponent below 2 and the spatial model are refused, naming `hotspot`.
#[test]
fn refusals_name_hotspot() {
    let s = system(0.4);
    let spot = conductor(&s);
    let options = MpcOptions {
        hotspot: Some(spot.clone()),
        ..MpcOptions::default()
    };
    let mut force = catalogue::riser(5);
    force.hotspots = vec![HotSpotSpec {
        elevation: 2.5,
        ..spot.clone()
    }];
    let e = Mpc::new(&force, 0.1, options.clone()).unwrap_err();
    assert!(
        matches!(e, Error::Mpc(MpcError::HotSpotNeedsThrust)),
        "{e:?}"
    );
    assert!(e.to_string().contains("hotspot"), "{e}");
    let e = HotSpotObjective::new(&force, 2.5, 1.0, 0.0).unwrap_err();
    assert!(
        matches!(e, Error::Mpc(MpcError::HotSpotExponent { .. })),
        "{e:?}"
    );
    // A force along x makes the scene spatial.
    let mut spatial = force.clone();
    spatial.loads.points[0].force_x = 1.0;
    assert!(spatial.is_spatial());
    let e = HotSpotObjective::new(&spatial, 2.5, 3.0, 0.0).unwrap_err();
    assert!(matches!(e, Error::Mpc(MpcError::HotSpotSpatial)), "{e:?}");
    let e = Mpc::spatial(
        &spatial,
        0.1,
        MpcOptions {
            hotspot: Some(spot),
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, Error::Mpc(MpcError::HotSpotSpatial)), "{e:?}");
}

/// A fatigue study of MPC through the thrust with `hotspot` reports the hot spot's damage: each
/// controller's cell damage is positive and its totals (damage per year, life) are the hot spot's
/// `hotspots` entry, bit for bit (the same Miner sum of the same replayed moment with the hot
/// spot's DFF: docs/cli.md "The moment the controllers act on").
#[test]
fn a_study_reports_the_hot_spots_damage() {
    use chainbeam::fatigue_study::{run_study, ControlSettings, ControllerKind, StudyInput};
    let s = system(0.8);
    let spot = conductor(&s);
    let index = s.hotspots.iter().position(|h| h.name == spot.name).unwrap();
    let spec = s.fatigue_spec().unwrap();
    let settings = ControlSettings {
        interval: 0.4,
        mpc: MpcOptions {
            horizon: Horizon::Seconds(1.6),
            first_iterations: 3,
            thrust_iterations: 2,
            hotspot: Some(spot.clone()),
            ..MpcOptions::default()
        },
        ..ControlSettings::default()
    };
    let controllers = [ControllerKind::None, ControllerKind::Mpc];
    let study = run_study(
        &StudyInput {
            scene: &s,
            spec: &spec,
            cells: None,
            controllers: &controllers,
            settings: &settings,
        },
        &|| {},
    )
    .unwrap();
    for c in &study.controllers {
        let entry = &c.hotspots[index];
        println!(
            "{:?}: cell damage {:.4e}, life {:.4e} y ({} {:.4e} y)",
            c.kind, c.cells[0].damage, c.life_years, entry.name, entry.life_years
        );
        assert!(c.cells[0].damage > 0.0);
        assert_eq!(c.life_years.to_bits(), entry.life_years.to_bits());
        assert_eq!(c.damage_per_year.to_bits(), entry.damage_per_year.to_bits());
    }
}

/// The references of a thrust problem's gradient at θ (four pieces): per component, the
/// forward-mode Dual64 run of the whole horizon seeded along that piece's controls, and the
/// five-point central difference of J (step 10³ N); each printed against the adjoint's.
pub(crate) fn dual_and_central(
    problem: &ControlProblem<PiecewiseControl, HotSpotObjective, 2>,
    steps: usize,
    theta: [f64; 4],
    adjoint: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let u = problem.controls(&theta).unwrap();
    let (h, chain) = (problem.time_step(), problem.chain().lift::<Dual64>());
    let (mut forward, mut central) = (Vec::new(), Vec::new());
    for (i, &g) in adjoint.iter().enumerate() {
        let mut e = [0.0; 4];
        e[i] = 1.0;
        let dir = problem.controls(&e).unwrap();
        let ud: Vec<Dual64> = u
            .iter()
            .zip(&dir)
            .map(|(&x, &d)| Dual64::new(x, d))
            .collect();
        let fwd = forward_value(&chain, h, steps, &ud, problem.objective())
            .unwrap()
            .eps;
        let at = |x: f64| {
            let mut t = theta;
            t[i] = x;
            problem.value(&t).unwrap()
        };
        let fd = five_point(&at, theta[i], 1e3);
        println!(
            "dJ/dtheta_{i} = {fwd:.12e}: |adjoint − forward| {:.1e}, |FD − forward| {:.1e} \
             (of the component)",
            (g - fwd).abs() / fwd.abs(),
            (fd - fwd).abs() / fwd.abs()
        );
        assert!(fwd.abs() > 0.0, "theta_{i} acts");
        forward.push(fwd);
        central.push(fd);
    }
    (forward, central)
}

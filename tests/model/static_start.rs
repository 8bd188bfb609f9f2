//! The static start (`[time] initial = "static"`, docs/conventions.md "The start of a run"): a
//! run of the calm sea started there stays there, the vessel's offset is held in full, and a
//! path that cannot start there refuses naming `time.initial`.
//!
//! Reference: the statics' own Newton solution (`chainbeam::statics::static_equilibrium_at`, an
//! independent solver: the equilibrium of the energy's gradient, not a time stepper) of the
//! scene without waves at t = 0 with the control 0.

use chainbeam::scene::{Current, Initial, Vessel};
use chainbeam::statics::{calm_scene, static_equilibrium_at};
use chainbeam::steppers::Stepper;
use chainbeam::{catalogue, simulate, Chain, Error, Rattle, Scene, Support};

/// examples/scenes/riser_1000m_system.toml (90 pendulums, h = 0.004 s, the 10 m offset, the
/// 0.5 m/s current, Morison's drag, the soil) without its waves, `steps` steps, with `initial`.
fn riser_1000m_calm(initial: Initial, steps: usize) -> Scene {
    let path = format!(
        "{}/examples/scenes/riser_1000m_system.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut s = Scene::from_file(&path).unwrap();
    s.loads.waves = None;
    s.time.steps = steps;
    s.time.initial = initial;
    s
}

/// The largest distance |r_i(t_k) − r_i*| over nodes and the steps of a run (r* the statics').
fn largest_departure(scene: &Scene, reference: &[[f64; 3]]) -> f64 {
    let traj = simulate(scene).unwrap();
    let mut worst = 0.0f64;
    for k in 0..=scene.time.steps {
        for (r, r0) in traj.positions(k).iter().zip(reference) {
            let d = (0..3).map(|c| (r[c] - r0[c]).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d);
        }
    }
    worst
}

/// The 1000 m system in a calm sea, started static, 500 steps (2 s) for a vessel that holds the
/// top (prescribed) and one under thrust (x_v = 0, thrust 0): every node stays within 1e-9 m of
/// the statics' positions (measured: 1.4e-12 m with either vessel, round-off). The
/// same scene started from rest moves metres away (the offset is 10 m): the check can fail.
#[test]
fn a_calm_run_from_the_static_start_stays_there() {
    let steps = 500;
    for thrust in [false, true] {
        let mut s = riser_1000m_calm(Initial::Static, steps);
        if thrust {
            s.vessel.as_mut().unwrap().damping = Some(7.0e5);
        }
        let eq = static_equilibrium_at(&calm_scene(&s), 0.0, 0.0).unwrap();
        let reference = eq.positions_xyz();
        let top = reference.last().unwrap()[2];
        assert!((top - 10.0).abs() < 1e-9, "the top at the offset: {top}");
        let worst = largest_departure(&s, &reference);
        println!(
            "thrust {thrust}: largest departure from the statics over {steps} steps {worst:.2e} m"
        );
        assert!(worst < 1e-9, "thrust {thrust}: {worst:e} m");
        let rest = largest_departure(&riser_1000m_calm(Initial::Rest, steps), &reference);
        assert!(rest > 1.0, "from rest: {rest} m");
    }
}

/// With `initial = "static"` the vessel's offset is not ramped: the tip's prescribed Z(t) is Z₀
/// from t = 0 (without waves), where the rest start ramps it in by ρ(t) (½(1 − cos(π t/20))
/// at t = 1 s: 0.0062).
#[test]
fn the_static_start_holds_the_offset_in_full() {
    for (initial, want) in [
        (Initial::Static, 10.0),
        (
            Initial::Rest,
            10.0 * 0.5 * (1.0 - (std::f64::consts::PI / 20.0).cos()),
        ),
    ] {
        let s = riser_1000m_calm(initial, 10);
        let chain = Chain::<f64, 2>::from_scene(&s).unwrap();
        let [z, zd] = chain.prescribed_tip(1.0).unwrap();
        assert!(
            (z - want).abs() < 1e-12 && zd.abs() < 1.0,
            "{initial:?}: Z(1) = {z}"
        );
    }
}

/// A chain of a static scene built without its start refuses to start (never silently
/// straight), naming `time.initial`; `set_static_start` gives it its start.
#[test]
fn a_chain_without_its_static_start_refuses_to_start() {
    let s = riser_1000m_calm(Initial::Static, 10);
    let chain = Chain::<f64, 2>::from_scene(&s).unwrap();
    let mut r = Rattle::new(chain.clone(), s.time.step).unwrap();
    let e = r.initial_state(0.0).unwrap_err();
    assert!(matches!(e, Error::StaticStartRefused { .. }), "{e}");
    assert!(e.to_string().contains("time.initial"), "{e}");
    let mut chain = chain;
    chainbeam::statics::set_static_start(&mut chain, &s).unwrap();
    let mut r = Rattle::new(chain, s.time.step).unwrap();
    let st = r.initial_state(0.0).unwrap();
    assert!(
        st.q.iter().any(|q| (q[0] - 1.0).abs() > 1e-6),
        "not straight"
    );
}

/// A static start the statics cannot solve is an error naming `time.initial`, not a panic: a
/// pinned-pinned beam in a current across the plane (spatial) turns freely about z and has no
/// isolated equilibrium.
#[test]
fn an_unsolvable_static_start_names_time_initial() {
    let mut s = catalogue::riser(5);
    s.beam.support = Support::PinnedPinned;
    s.loads.drag = 10.0;
    s.loads.current = Some(Current::uniform(0.2, [1.0, 0.0]));
    s.time.initial = Initial::Static;
    let e = simulate(&s).unwrap_err();
    assert!(matches!(e, Error::StaticStart { .. }), "{e}");
    assert!(e.to_string().contains("time.initial"), "{e}");
    // The vessel scene of the same beam is solvable: the error is the statics', not the key's.
    s.beam.support = Support::Vessel;
    s.control = None;
    s.loads.current = Some(Current::uniform(0.2, [0.0, 1.0]));
    s.vessel = Some(Vessel {
        offset: 0.05,
        ..Vessel::default()
    });
    simulate(&s).unwrap();
}

/// `vessel.ramp = 0` with the 10 m offset: accepted from the static start (the offset is held
/// from t = 0, nothing jumps: the calm run stays within 1e-9 m as above), refused from rest
/// (the top would jump to Z₀ at t = 0) and, with a RAO, refused either way (the surge would
/// start at t = 0 on a riser at rest), each naming `vessel.ramp`.
#[test]
fn a_held_offset_needs_no_ramp() {
    let mut s = riser_1000m_calm(Initial::Static, 100);
    s.vessel.as_mut().unwrap().ramp = 0.0;
    let with_rao = s.clone();
    s.vessel.as_mut().unwrap().rao = None;
    let eq = static_equilibrium_at(&calm_scene(&s), 0.0, 0.0).unwrap();
    let worst = largest_departure(&s, &eq.positions_xyz());
    assert!(worst < 1e-9, "{worst:e} m");
    let refused = |scene: &Scene| {
        let e = Chain::<f64, 2>::from_scene(scene).unwrap_err().to_string();
        assert!(e.contains("vessel.ramp"), "{e}");
    };
    refused(&with_rao);
    s.time.initial = Initial::Rest;
    refused(&s);
}

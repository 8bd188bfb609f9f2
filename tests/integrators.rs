//! The alternative integrators of `chainbeam::integrators` (SHAKE, projected RK4) against RATTLE:
//! agreement, convergence order, energy behaviour, stability and typed failures.

use chainbeam::catalogue;
use chainbeam::integrators::{integrate, Integrator, Method};
use chainbeam::Error;

fn tip(it: &Integrator) -> [f64; 2] {
    *it.positions().last().unwrap()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

#[test]
fn shake_positions_equal_rattle_positions_without_drag() {
    let scene = catalogue::thesis_cantilever();
    let mut r = Integrator::new(&scene, Method::Rattle, 0.01).unwrap();
    let mut s = Integrator::new(&scene, Method::Shake, 0.01).unwrap();
    for _ in 0..300 {
        r.step().unwrap();
        s.step().unwrap();
    }
    let d = r
        .positions()
        .iter()
        .zip(s.positions())
        .map(|(a, b)| dist(*a, b))
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "SHAKE and RATTLE positions differ by {d}");
    assert!(s.constraint_residual() < 1e-12);
}

#[test]
fn rattle_matches_library_simulation() {
    let mut scene = catalogue::thesis_cantilever();
    scene.time.steps = 100;
    let traj = chainbeam::simulate(&scene).unwrap();
    let it = integrate(&scene, Method::Rattle, 0.01, 100, 100, |_| {}).unwrap();
    let a = traj.positions(100).last().unwrap()[2];
    assert!((a - tip(&it)[1]).abs() < 1e-13);
}

/// Tip position error at T = 0.5 s against a fine projected-RK4 reference.
fn error_at(method: Method, h: f64) -> f64 {
    let scene = catalogue::thesis_cantilever();
    let t = 0.5;
    let reference = integrate(&scene, Method::ProjectedRk4, 1.0e-4, 5000, 5000, |_| {}).unwrap();
    let steps = (t / h).round() as usize;
    let it = integrate(&scene, method, h, steps, steps, |_| {}).unwrap();
    dist(tip(&it), tip(&reference))
}

#[test]
fn convergence_orders() {
    let e1 = error_at(Method::Rattle, 0.004);
    let e2 = error_at(Method::Rattle, 0.002);
    let p = (e1 / e2).log2();
    assert!((1.7..2.4).contains(&p), "RATTLE order {p}");
    // Pre-asymptotic at these steps: the measured ratio climbs from 8 toward 16 as h shrinks.
    let e1 = error_at(Method::ProjectedRk4, 0.001);
    let e2 = error_at(Method::ProjectedRk4, 0.0005);
    let p = (e1 / e2).log2();
    assert!(p > 3.2, "projected RK4 order {p} ({e1:e}, {e2:e})");
}

#[test]
fn rattle_energy_bounded_where_explicit_method_drifts() {
    // 10⁵ steps at h = 0.01: RATTLE's (and SHAKE's) energy error oscillates within a bound that
    // does not grow; the explicit method's drifts away (RK4 damps the fast modes) and ends far
    // beyond that bound.
    let scene = catalogue::thesis_cantilever();
    let h = 0.01;
    let steps = 100_000;
    let run = |m: Method| {
        let mut e = Vec::new();
        integrate(&scene, m, h, steps, 100, |it| e.push(it.energy())).unwrap();
        let de: Vec<f64> = e.iter().map(|x| (x - e[0]).abs()).collect();
        let half = de.len() / 2;
        let first = de[..half].iter().cloned().fold(0.0, f64::max);
        let second = de[half..].iter().cloned().fold(0.0, f64::max);
        (first, second, de[half], *de.last().unwrap())
    };
    for m in [Method::Rattle, Method::Shake] {
        let (first, second, _, _) = run(m);
        assert!(second < 1e-4, "{}: energy error {second}", m.name());
        assert!(second <= 1.5 * first, "{}: {first} then {second}", m.name());
    }
    let (_, second_r, _, _) = run(Method::Rattle);
    let (_, _, mid, end) = run(Method::ProjectedRk4);
    assert!(
        end >= mid,
        "explicit energy error not one-sided: {mid} then {end}"
    );
    assert!(
        end > 3.0 * second_r,
        "explicit drift {end} vs RATTLE {second_r}"
    );
}

#[test]
fn explicit_method_fails_with_typed_error_beyond_its_stability_limit() {
    let scene = catalogue::thesis_cantilever();
    // The explicit method is linearly stable to h ≈ 0.021 on this beam; at 0.03 it blows up.
    let res = integrate(&scene, Method::ProjectedRk4, 0.03, 2000, 2000, |_| {});
    match res {
        Err(Error::NonFinite { .. })
        | Err(Error::Folded { .. })
        | Err(Error::NewtonNotConverged { .. })
        | Err(Error::SingularSystem { .. }) => {}
        other => panic!("expected a typed failure, got {other:?}"),
    }
}

#[test]
fn folding_is_a_typed_error_for_every_method() {
    // A soft chain under a huge tip load folds over: θ → π must be an error, not garbage.
    let scene = catalogue::scaled_cantilever(10, 10.0, 10.0, 10.0, 2.0);
    let mut scene = scene;
    scene.loads.points[0].force = 500.0;
    for m in Method::ALL {
        let res = integrate(&scene, m, 0.001, 20_000, 20_000, |_| {});
        match res {
            Err(Error::Folded { angle_deg, .. }) => assert!(angle_deg > 170.0),
            Err(Error::NewtonNotConverged { .. })
            | Err(Error::NonFinite { .. })
            | Err(Error::SingularSystem { .. }) => {}
            Ok(it) => panic!(
                "{}: no error, max joint angle {}",
                m.name(),
                it.chain().max_joint_angle(it.q()).to_degrees()
            ),
            Err(e) => panic!("{}: unexpected error {e}", m.name()),
        }
    }
}

#[test]
fn locked_tip_and_drag_are_supported() {
    let scene = catalogue::dissipative_fixed_fixed(10.0);
    let h = 0.005;
    let r = integrate(&scene, Method::Rattle, h, 200, 200, |_| {}).unwrap();
    for m in [Method::Shake, Method::ProjectedRk4] {
        let it = integrate(&scene, m, h, 200, 200, |_| {}).unwrap();
        assert!(it.constraint_residual() < 1e-12, "{}", m.name());
        let d = r
            .positions()
            .iter()
            .zip(it.positions())
            .map(|(a, b)| dist(*a, b))
            .fold(0.0, f64::max);
        assert!(d < 1e-3, "{}: differs from RATTLE by {d}", m.name());
    }
}

#[test]
fn reaction_tip_and_bad_step_are_rejected() {
    let mut scene = catalogue::fixed_fixed();
    scene.beam.reaction_force = true;
    assert!(matches!(
        Integrator::new(&scene, Method::Shake, 0.01),
        Err(Error::InvalidArgument { .. })
    ));
    assert!(Integrator::new(&scene, Method::Rattle, 0.01).is_ok());
    assert!(matches!(
        Integrator::new(&catalogue::thesis_cantilever(), Method::ProjectedRk4, -1.0),
        Err(Error::InvalidArgument { .. })
    ));
}

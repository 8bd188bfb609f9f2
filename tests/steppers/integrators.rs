//! The alternative integrators of `chainbeam::integrators` (SHAKE, projected RK4) against RATTLE:
//! agreement, convergence order, energy behaviour, stability and typed failures; and every
//! stepper of `chainbeam::steppers` generic over the dimension and the scalar, without
//! allocating per step.

use chainbeam::catalogue;
use chainbeam::integrators::{integrate, Integrator, IntegratorMethod};
use chainbeam::steppers::{ProjectedRk4, Rattle, Shake, Stepper, StepperError};
use chainbeam::{Chain, Error, Parameter, Scalar, Scene};
use num_dual::Dual64;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Counts the allocations of the current thread (tests run in parallel threads).
struct CountingAlloc;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_allocation() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

// SAFETY: forwards to the system allocator; the counter is a const-initialised thread-local
// without a destructor, so counting neither allocates nor re-enters the allocator.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_allocation();
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_allocation();
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: CountingAlloc = CountingAlloc;

fn tip(it: &Integrator) -> [f64; 2] {
    *it.positions().last().unwrap()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

#[test]
fn shake_positions_equal_rattle_positions_without_drag() {
    let scene = catalogue::thesis_cantilever();
    let mut r = Integrator::new(&scene, IntegratorMethod::Rattle, 0.01).unwrap();
    let mut s = Integrator::new(&scene, IntegratorMethod::Shake, 0.01).unwrap();
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
    let it = integrate(&scene, IntegratorMethod::Rattle, 0.01, 100, 100, |_| {}).unwrap();
    let a = traj.positions(100).last().unwrap()[2];
    assert!((a - tip(&it)[1]).abs() < 1e-13);
}

/// Tip position error at T = 0.5 s against a fine projected-RK4 reference.
fn error_at(method: IntegratorMethod, h: f64) -> f64 {
    let scene = catalogue::thesis_cantilever();
    let t = 0.5;
    let reference = integrate(
        &scene,
        IntegratorMethod::ProjectedRk4,
        1.0e-4,
        5000,
        5000,
        |_| {},
    )
    .unwrap();
    let steps = (t / h).round() as usize;
    let it = integrate(&scene, method, h, steps, steps, |_| {}).unwrap();
    dist(tip(&it), tip(&reference))
}

#[test]
fn convergence_orders() {
    let e1 = error_at(IntegratorMethod::Rattle, 0.004);
    let e2 = error_at(IntegratorMethod::Rattle, 0.002);
    let p = (e1 / e2).log2();
    assert!((1.7..2.4).contains(&p), "RATTLE order {p}");
    // Pre-asymptotic at these steps: the measured ratio climbs from 8 toward 16 as h shrinks.
    let e1 = error_at(IntegratorMethod::ProjectedRk4, 0.001);
    let e2 = error_at(IntegratorMethod::ProjectedRk4, 0.0005);
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
    let run = |m: IntegratorMethod| {
        let mut e = Vec::new();
        integrate(&scene, m, h, steps, 100, |it| e.push(it.energy())).unwrap();
        let de: Vec<f64> = e.iter().map(|x| (x - e[0]).abs()).collect();
        let half = de.len() / 2;
        let first = de[..half].iter().cloned().fold(0.0, f64::max);
        let second = de[half..].iter().cloned().fold(0.0, f64::max);
        (first, second, de[half], *de.last().unwrap())
    };
    for m in [IntegratorMethod::Rattle, IntegratorMethod::Shake] {
        let (first, second, _, _) = run(m);
        assert!(second < 1e-4, "{}: energy error {second}", m.name());
        assert!(second <= 1.5 * first, "{}: {first} then {second}", m.name());
    }
    let (_, second_r, _, _) = run(IntegratorMethod::Rattle);
    let (_, _, mid, end) = run(IntegratorMethod::ProjectedRk4);
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
    let res = integrate(
        &scene,
        IntegratorMethod::ProjectedRk4,
        0.03,
        2000,
        2000,
        |_| {},
    );
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
    for m in IntegratorMethod::ALL {
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
    let r = integrate(&scene, IntegratorMethod::Rattle, h, 200, 200, |_| {}).unwrap();
    for m in [IntegratorMethod::Shake, IntegratorMethod::ProjectedRk4] {
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
        Integrator::new(&scene, IntegratorMethod::Shake, 0.01),
        Err(Error::Stepper(StepperError::ReactionTipUnsupported {
            method: "SHAKE"
        }))
    ));
    assert!(Integrator::new(&scene, IntegratorMethod::Rattle, 0.01).is_ok());
    assert!(matches!(
        Integrator::new(
            &catalogue::thesis_cantilever(),
            IntegratorMethod::ProjectedRk4,
            -1.0
        ),
        Err(Error::Stepper(StepperError::StepNotPositive { h: -1.0 }))
    ));
}

/// The three steppers, for tests that run each through the generic [`Stepper`] interface.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Rattle,
    Shake,
    Rk4,
}

const KINDS: [Kind; 3] = [Kind::Rattle, Kind::Shake, Kind::Rk4];

/// Runs `stepper` from its initial state for `u.len() − 1` steps with the controls u_k and
/// returns the final (q, p) as one vector of blocks.
fn run<D: Scalar, const DIM: usize, S: Stepper<D, DIM>>(mut stepper: S, u: &[D]) -> Vec<[D; DIM]> {
    let mut state = stepper.initial_state(u[0]).unwrap();
    for k in 0..u.len() - 1 {
        stepper.step(&mut state, k, u[k], u[k + 1]).unwrap();
    }
    let mut out = stepper.q(&state).to_vec();
    out.extend_from_slice(stepper.p(&state));
    out
}

/// [`run`] with the stepper of `kind` (one generic function per stepper type: each gets its own
/// state).
fn run_kind<D: Scalar, const DIM: usize>(
    kind: Kind,
    chain: Chain<D, DIM>,
    h: f64,
    u: &[D],
) -> Vec<[D; DIM]> {
    match kind {
        Kind::Rattle => run(Rattle::new(chain, h).unwrap(), u),
        Kind::Shake => run(Shake::new(chain, h).unwrap(), u),
        Kind::Rk4 => run(ProjectedRk4::new(chain, h).unwrap(), u),
    }
}

/// What a test case differentiates with respect to.
#[derive(Clone, Copy)]
enum Seed {
    Parameter(Parameter),
    /// The amplitude a of the controls u_k = a (1 + ½ sin(3 t_k)) (varying, so that projected
    /// RK4's midpoint control is exercised).
    Control,
}

/// A scene, the seeded quantity and its value, the step and the number of steps.
struct Case {
    name: &'static str,
    scene: Scene,
    seed: Seed,
    value: f64,
    h: f64,
    steps: usize,
}

/// The free cantilever, the locked tip with drag (every branch: tip row, drag), and the riser
/// with a large time-varying control at its tip (deflections of several degrees per joint).
fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "cantilever, k",
            scene: catalogue::thesis_cantilever(),
            seed: Seed::Parameter(Parameter::InteriorStiffness),
            value: 1000.0,
            h: 0.01,
            steps: 100,
        },
        Case {
            name: "fixed-fixed with drag, D",
            scene: catalogue::dissipative_fixed_fixed(10.0),
            seed: Seed::Parameter(Parameter::Drag),
            value: 10.0,
            h: 0.005,
            steps: 200,
        },
        Case {
            name: "riser, u",
            scene: catalogue::riser(5),
            seed: Seed::Control,
            value: -30.0,
            h: 0.01,
            steps: 100,
        },
    ]
}

impl Case {
    /// The chain over `D` with the seeded quantity set to `v`, and the controls u_0..u_N.
    fn setup<D: Scalar, const DIM: usize>(&self, v: D) -> (Chain<D, DIM>, Vec<D>) {
        let mut chain = Chain::<D, DIM>::from_scene(&self.scene).unwrap();
        let u = match self.seed {
            Seed::Parameter(p) => {
                chain.set_parameter(p, v).unwrap();
                vec![D::zero(); self.steps + 1]
            }
            Seed::Control => (0..=self.steps)
                .map(|k| v * (1.0 + 0.5 * (3.0 * k as f64 * self.h).sin()))
                .collect(),
        };
        (chain, u)
    }

    fn run<D: Scalar, const DIM: usize>(&self, kind: Kind, v: D) -> Vec<[D; DIM]> {
        let (chain, u) = self.setup::<D, DIM>(v);
        run_kind(kind, chain, self.h, &u)
    }
}

#[test]
fn every_stepper_in_three_dimensions_equals_the_planar_model_on_a_planar_scene() {
    // Every load acts along z and the beam starts along +y, so the spatial model's x components
    // stay exactly 0, and its (y, z) arithmetic is the planar model's plus exact products with
    // those zeros (0·a + b = b): the model docs promise (and tests/model/core.rs asserts for RATTLE)
    // that the planar model reproduces the spatial one exactly, so the comparison is exact.
    for case in cases() {
        for kind in KINDS {
            let planar = case.run::<f64, 2>(kind, case.value);
            let spatial = case.run::<f64, 3>(kind, case.value);
            for (i, (a, b)) in planar.iter().zip(&spatial).enumerate() {
                assert_eq!(
                    [b[0].to_bits(), b[1].to_bits(), b[2].to_bits()],
                    [0.0f64.to_bits(), a[0].to_bits(), a[1].to_bits()],
                    "{} {kind:?}: block {i} spatial {b:?} vs planar {a:?}",
                    case.name
                );
            }
        }
    }
}

#[test]
fn every_stepper_runs_in_dual_numbers_with_the_f64_real_parts_and_exact_derivatives() {
    // Real parts: the same code path in Dual64 performs the f64 run's arithmetic on its real
    // parts (divisions by f64 only, derivative-only Newton updates after convergence), so they
    // are bit-identical. Derivative parts: against central finite differences of the f64 run,
    // whose error is O(δ²): measured 2.5e-5, 2.5e-7, 2.5e-9 of the largest derivative at
    // δ = 1e-3, 1e-4, 1e-5 relative (cantilever, k), i.e. the dual parts are exact.
    for case in cases() {
        let delta = 1e-5 * case.value.abs();
        for kind in KINDS {
            let dual = case.run::<Dual64, 2>(kind, Dual64::new(case.value, 1.0));
            let real = case.run::<f64, 2>(kind, case.value);
            let plus = case.run::<f64, 2>(kind, case.value + delta);
            let minus = case.run::<f64, 2>(kind, case.value - delta);
            let mut scale: f64 = 0.0;
            let mut err: f64 = 0.0;
            for i in 0..dual.len() {
                for d in 0..2 {
                    let x = dual[i][d];
                    assert_eq!(
                        x.re.to_bits(),
                        real[i][d].to_bits(),
                        "{} {kind:?}: real part {} vs f64 {} at block {i}",
                        case.name,
                        x.re,
                        real[i][d]
                    );
                    let fd = (plus[i][d] - minus[i][d]) / (2.0 * delta);
                    scale = scale.max(fd.abs());
                    err = err.max((x.eps - fd).abs());
                }
            }
            assert!(scale > 0.0, "{} {kind:?}: no sensitivity", case.name);
            assert!(
                err <= 1e-6 * scale,
                "{} {kind:?}: derivative differs from central FD by {err:e} (scale {scale:e})",
                case.name
            );
        }
    }
}

/// Allocations of `steps` steps of `stepper` after the initial state and one warm-up step.
fn allocations_per_run<S: Stepper<f64, 2>>(mut stepper: S, steps: usize) -> usize {
    let mut state = stepper.initial_state(0.0).unwrap();
    stepper.step(&mut state, 0, 0.0, 0.0).unwrap();
    let before = allocations();
    for k in 1..=steps {
        stepper.step(&mut state, k, 0.0, 0.0).unwrap();
    }
    allocations() - before
}

#[test]
fn steppers_do_not_allocate_per_step() {
    // Counted by the test binary's global allocator, per thread.
    for (name, scene) in [
        ("cantilever", catalogue::thesis_cantilever()),
        (
            "fixed-fixed with drag",
            catalogue::dissipative_fixed_fixed(10.0),
        ),
    ] {
        let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
        let h = 0.005;
        let counts = [
            allocations_per_run(Rattle::new(chain.clone(), h).unwrap(), 50),
            allocations_per_run(Shake::new(chain.clone(), h).unwrap(), 50),
            allocations_per_run(ProjectedRk4::new(chain, h).unwrap(), 50),
        ];
        assert_eq!(
            counts,
            [0, 0, 0],
            "{name}: allocations of RATTLE, SHAKE, RK4"
        );
    }
}

#[test]
fn a_state_of_another_chain_is_a_typed_error() {
    let ten = Chain::<f64, 2>::from_scene(&catalogue::thesis_cantilever()).unwrap();
    let five =
        Chain::<f64, 2>::from_scene(&catalogue::scaled_cantilever(5, 10.0, 1000.0, 10.0, 2.0))
            .unwrap();
    let mut shake5 = Shake::new(five.clone(), 0.01).unwrap();
    let mut state10 = Shake::new(ten.clone(), 0.01)
        .unwrap()
        .initial_state(0.0)
        .unwrap();
    assert!(matches!(
        shake5.step(&mut state10, 0, 0.0, 0.0),
        Err(Error::Stepper(StepperError::StateSize {
            got: 10,
            expected: 5
        }))
    ));
    let mut rk5 = ProjectedRk4::new(five, 0.01).unwrap();
    let mut state10 = ProjectedRk4::new(ten, 0.01)
        .unwrap()
        .initial_state(0.0)
        .unwrap();
    assert!(matches!(
        rk5.step(&mut state10, 0, 0.0, 0.0),
        Err(Error::Stepper(StepperError::StateSize {
            got: 10,
            expected: 5
        }))
    ));
}

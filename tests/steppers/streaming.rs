//! The streaming simulation (`simulate_streaming`, `moment_history`: a 3-hour record in O(n) memory) against the
//! stored trajectory of `simulate` on the same scene. Reference: `simulate` itself, the
//! library's tested path (thesis scenes, the wave riser, spatial scenes); a streamed run takes
//! the same RATTLE steps from the same state and evaluates the same formulas, so every number
//! must agree bit for bit (`==` on f64, not a tolerance).

use chainbeam::*;

/// Every state a streamed run shows, in the trajectory's layout.
#[derive(Default)]
struct Recorder {
    k: Vec<usize>,
    t: Vec<f64>,
    q: Vec<f64>,
    p: Vec<f64>,
    lambda: Vec<f64>,
    mu: Vec<f64>,
    energy: Vec<f64>,
    moment: Vec<f64>,
    moment_x: Vec<f64>,
    positions: Vec<[f64; 3]>,
    control: Vec<f64>,
    control_x: Vec<f64>,
    iterations: usize,
}

impl StepObserver for Recorder {
    type Error = std::convert::Infallible;
    fn observe<const DIM: usize>(&mut self, s: &mut StepView<'_, DIM>) -> Result<(), Self::Error> {
        self.k.push(s.k());
        self.t.push(s.time());
        self.q.extend(s.q().iter().flatten());
        self.p.extend(s.p().iter().flatten());
        self.lambda.extend(s.lambda());
        self.mu.extend(s.mu());
        self.energy.push(s.energy());
        let [mx, mz] = s.moment_vector();
        self.moment.push(mz);
        self.moment_x.push(mx);
        let mut r = vec![[0.0; 3]; s.n()];
        s.positions(&mut r);
        self.positions.extend(r);
        self.control.push(s.control());
        self.control_x.push(s.control_x());
        self.iterations += s.stats().map_or(0, |st| st.iterations);
        Ok(())
    }
}

fn flat<const DIM: usize>(x: &[[f64; DIM]]) -> impl Iterator<Item = f64> + '_ {
    x.iter().flatten().copied()
}

/// The streamed run equals the stored trajectory bit for bit.
fn assert_same<const DIM: usize>(rec: &Recorder, traj: &Trajectory<f64, DIM>, what: &str) {
    let steps = traj.steps();
    assert_eq!(
        rec.k,
        (0..=steps).collect::<Vec<_>>(),
        "{what}: every k once"
    );
    let (mut q, mut p, mut lambda, mut mu, mut r) = (vec![], vec![], vec![], vec![], vec![]);
    for k in 0..=steps {
        assert_eq!(rec.t[k], traj.time(k), "{what}: t_{k}");
        q.extend(flat(traj.q(k)));
        p.extend(flat(traj.p(k)));
        lambda.extend_from_slice(traj.lambda(k));
        mu.extend_from_slice(traj.mu(k));
        r.extend(traj.positions(k));
    }
    assert_eq!(rec.q, q, "{what}: q");
    assert_eq!(rec.p, p, "{what}: p");
    assert_eq!(rec.lambda, lambda, "{what}: λ");
    assert_eq!(rec.mu, mu, "{what}: μ");
    assert_eq!(rec.positions, r, "{what}: node positions");
    assert_eq!(rec.energy, traj.energy, "{what}: energy");
    assert_eq!(rec.moment, traj.moment, "{what}: M₀");
    if DIM == 3 {
        assert_eq!(rec.moment_x, traj.moment_x, "{what}: M₀ₓ");
    } else {
        assert!(rec.moment_x.iter().all(|&m| m == 0.0), "{what}: planar M₀ₓ");
    }
    assert_eq!(rec.control, traj.controls, "{what}: u");
    if !traj.controls_x.is_empty() {
        assert_eq!(rec.control_x, traj.controls_x, "{what}: u_x");
    }
    assert_eq!(
        rec.iterations,
        traj.newton_iterations(),
        "{what}: Newton iterations"
    );
}

fn check_scene(scene: &Scene, what: &str) {
    let traj = simulate(scene).unwrap();
    let mut rec = Recorder::default();
    let summary = simulate_streaming(scene, StreamControls::Scene, &mut rec).unwrap();
    assert_eq!(summary.steps, traj.steps());
    assert_eq!(summary.spatial, traj.is_spatial(), "{what}: model");
    assert_eq!(summary.newton_iterations, traj.newton_iterations());
    match (traj.as_planar(), traj.as_spatial()) {
        (Some(t), _) => assert_same(&rec, t, what),
        (_, Some(t)) => assert_same(&rec, t, what),
        _ => unreachable!("a trajectory is planar or spatial"),
    }
    let hist = moment_history(scene).unwrap();
    assert_eq!(hist.moment, traj.moment(), "{what}: moment_history M₀");
    assert_eq!(
        hist.moment_x.as_deref(),
        traj.is_spatial().then(|| traj.moment_x()),
        "{what}: moment_history M₀ₓ"
    );
    assert_eq!(hist.h, traj.h());
    assert_eq!(hist.duration(), traj.steps() as f64 * traj.h());
}

/// Every catalogue scene (thesis cantilever, risers, dissipative, piecewise and per-step
/// controls, spatial, waves, currents), shortened where long.
#[test]
fn every_catalogue_scene_streams_bit_for_bit() {
    for (name, mut scene) in catalogue::all() {
        if scene.time.steps > 400 {
            // Keep the run short; a per-step control keeps its own length.
            let per_step = scene
                .control
                .as_ref()
                .is_some_and(|c| c.kind == scene::ControlKind::PerStep);
            if !per_step {
                scene.time.steps = 400;
                if scene.validate().is_err() {
                    continue;
                }
            }
        }
        check_scene(&scene, name);
    }
}

/// The shipped 300 m riser (pipe, tension, current and a JONSWAP sea) for 400 steps.
#[test]
fn the_real_scale_riser_streams_bit_for_bit() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let mut scene = Scene::from_file(path).unwrap();
    scene.time.steps = 400;
    check_scene(&scene, "riser_300m");
}

/// Explicit controls, 1-axis and 2-axis, as `simulate` with `SimulateInput::controls(_xz)`.
#[test]
fn given_controls_stream_bit_for_bit() {
    let scene = catalogue::riser(5);
    let n1 = scene.time.steps + 1;
    let u: Vec<f64> = (0..n1).map(|k| 0.3 * (k as f64 * 0.05).sin()).collect();
    let ux: Vec<f64> = (0..n1).map(|k| -0.2 * (k as f64 * 0.03).cos()).collect();

    let traj = simulate(SimulateInput::new(&scene).controls(&u)).unwrap();
    let mut rec = Recorder::default();
    simulate_streaming(&scene, StreamControls::Given(&u), &mut rec).unwrap();
    assert_same(&rec, traj.as_planar().unwrap(), "riser(5), given u");

    let traj = simulate(SimulateInput::new(&scene).controls_xz(&ux, &u)).unwrap();
    let mut rec = Recorder::default();
    let s = simulate_streaming(&scene, StreamControls::GivenXz { x: &ux, z: &u }, &mut rec);
    assert!(s.unwrap().spatial);
    assert_same(&rec, traj.as_spatial().unwrap(), "riser(5), given (u_x, u)");

    // Wrong lengths are the same typed errors as simulate's.
    let short = &u[..n1 - 1];
    let e = simulate_streaming(
        &scene,
        StreamControls::Given(short),
        &mut Recorder::default(),
    );
    assert!(matches!(
        e,
        Err(StreamError::Simulation(Error::WrongLength {
            name: "controls",
            ..
        }))
    ));
    let e = simulate_streaming(
        &scene,
        StreamControls::GivenXz { x: short, z: &u },
        &mut Recorder::default(),
    );
    assert!(matches!(
        e,
        Err(StreamError::Simulation(Error::WrongLength { .. }))
    ));
}

/// An observer's error stops the run at once, and is returned as the observer's.
#[test]
fn an_observer_error_stops_the_run() {
    struct StopAt(usize, usize);
    impl StepObserver for StopAt {
        type Error = String;
        fn observe<const DIM: usize>(&mut self, s: &mut StepView<'_, DIM>) -> Result<(), String> {
            self.1 += 1;
            if s.k() == self.0 {
                return Err(format!("stop at {}", s.k()));
            }
            Ok(())
        }
    }
    let scene = catalogue::thesis_cantilever();
    let mut stop = StopAt(7, 0);
    let e = simulate_streaming(&scene, StreamControls::Scene, &mut stop).unwrap_err();
    assert!(matches!(&e, StreamError::Observer(m) if m == "stop at 7"));
    assert_eq!(stop.1, 8, "k = 0..=7 observed, nothing after");
}

//! Benchmarks of one RATTLE step and of whole simulations (docs/conventions.md).
//!
//! Groups:
//! - `step_f64_planar`: one planar `f64` step for n = 10, 100, 1000, with
//!   `Throughput::Elements(n)` so the report reads as time per pendulum-step;
//! - `step_scalar`: `f64` vs `Dual64` (derivative seeded in the interior stiffness), n = 100;
//! - `step_dim`: planar (DIM = 2) vs spatial (DIM = 3) on the same in-plane cantilever, `f64`,
//!   n = 10, 100, 1000 (the ratio spatial/planar per pendulum-step);
//! - `step_current`: the cost of a current, n = 100 with drag D = 10: still water vs a linear
//!   shear vs a table (planar), and still water vs a current at 45° (spatial);
//! - `simulate_riser`: `chainbeam::simulate` of the thesis riser scene for N = 10 and N = 1000;
//! - `force_jvp`: the springs' stiffness product K·v (K = ∂²U/∂q², planar `f64`, at the bent state)
//!   for n = 10, 100, 1000: `override` is the hand-written [`ForceTerm::force_jvp`] of
//!   [`Springs`](chainbeam::model::Springs), `dual_default` the trait's dual-number default
//!   (one `Dual64` evaluation of the springs' force at q + εv) through a wrapper that delegates
//!   everything else to the springs. The ratio is what the override saves the adjoint, which
//!   calls K·v twice per reverse step.
//! - `step_pipe_drag`: riser_300m's pipe in its current, the momentum drag against Morison's
//!   drag node by node, n = 100 and 1000 (time per pendulum-step: both O(n));
//! - `joint_damping`: one planar `f64` step of the cantilever with a joint damper beside every
//!   spring (c = 0.01 s · k), n = 20, 80, 320: the coupled half step's band solve. Measured
//!   (load ≈ 15 on 2 cores, back-to-back): 22 µs, 100 µs, 129 µs; the dense LU it replaced took
//!   104 µs, 4.1 ms, 31 ms (h shrinks like 1/n², so the rows need not take the same Newton
//!   iterations per step).
//!
//! The step benchmarks first advance the straight beam by [`PRE_STEPS`] steps so the state is
//! bent and the Newton predictor is the multiplier of a real previous step, then keep stepping the
//! same state forward inside the timed closure. Without drag RATTLE conserves energy, so the
//! oscillation stays bounded however many steps criterion runs.
//!
//! Run with
//! `cargo bench --bench step -- --warm-up-time 1 --measurement-time 3`.

#[path = "common/cantilever.rs"]
mod cantilever;

use std::hint::black_box;
use std::time::Duration;

use cantilever::scaled_cantilever;
use chainbeam::model::{Ctx, DualScratch, Embed, ForceTerm, TermVisitor};
use chainbeam::{catalogue, Chain, Current, Parameter, Rattle, Scalar, Scene, State};
use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput,
};
use num_dual::Dual64;

/// Steps taken outside the timed closure to reach a representative (bent) state.
const PRE_STEPS: usize = 50;

/// Samples per benchmark (criterion's default of 100 makes the run needlessly long).
const SAMPLES: usize = 20;

/// The scaled cantilever (benches/common/cantilever.rs) with base spring k and only the
/// [`PRE_STEPS`] steps the bench takes.
fn cantilever(n: usize) -> Scene {
    scaled_cantilever(n, 1.0, PRE_STEPS)
}

/// The thesis riser (n = 10, l = 1, m = 1, k = 1000, base/tip 2000, F = 2 at node 5, D = 0,
/// h = 0.01) with `steps` steps.
fn riser(steps: usize) -> Scene {
    let mut s = catalogue::riser(5);
    s.control = None;
    s.objective = None;
    s.time.steps = steps;
    s
}

/// An integrator for `chain` on `scene`'s step, with the state after [`PRE_STEPS`] steps and the
/// index of the next step.
fn prepared<D: Scalar, const DIM: usize>(scene: &Scene, chain: Chain<D, DIM>) -> Prepared<D, DIM> {
    let mut rattle = Rattle::new(chain, scene.time.step).expect("valid step");
    let mut state = rattle.straight_state();
    let u = D::from(0.0);
    for k in 0..PRE_STEPS {
        rattle
            .step(&mut state, k, u, u)
            .unwrap_or_else(|e| panic!("n = {}: pre-step {k} failed: {e}", scene.n()));
    }
    (rattle, state, PRE_STEPS)
}

/// Integrator, state and next step index, as returned by [`prepared`].
type Prepared<D, const DIM: usize> = (Rattle<D, DIM>, State<D, DIM>, usize);

/// Times one step from a copy of `prep`, stepping forward (k increasing) on every iteration.
/// Criterion calls this once per sample, so every sample starts from the same bent state.
fn bench_steps<D: Scalar, const DIM: usize>(
    b: &mut criterion::Bencher<'_>,
    prep: &Prepared<D, DIM>,
) {
    let (mut rattle, mut state, mut k) = prep.clone();
    let u = D::from(0.0);
    b.iter(|| {
        let stats = rattle
            .step(black_box(&mut state), k, u, u)
            .expect("RATTLE step failed");
        k += 1;
        black_box(stats)
    });
}

fn planar_f64(scene: &Scene) -> Chain<f64, 2> {
    Chain::from_scene(scene).expect("valid scene")
}

fn step_f64_planar(c: &mut Criterion) {
    let mut group = c.benchmark_group("step_f64_planar");
    group.sample_size(SAMPLES);
    for n in [10usize, 100, 1000] {
        let scene = cantilever(n);
        group.throughput(Throughput::Elements(n as u64));
        let prep = prepared(&scene, planar_f64(&scene));
        group.bench_function(BenchmarkId::from_parameter(n), |b| bench_steps(b, &prep));
    }
    group.finish();
}

fn step_scalar(c: &mut Criterion) {
    let n = 100;
    let scene = cantilever(n);
    let mut group = c.benchmark_group("step_scalar");
    group.sample_size(SAMPLES);
    group.throughput(Throughput::Elements(n as u64));
    let real = prepared(&scene, planar_f64(&scene));
    let mut chain = Chain::<Dual64, 2>::from_scene(&scene).expect("valid scene");
    let k = scene.beam.stiffness[0];
    chain
        .set_parameter(Parameter::InteriorStiffness, Dual64::new(k, 1.0))
        .expect("interior stiffness exists");
    let dual = prepared(&scene, chain);
    group.bench_function(BenchmarkId::new("f64", n), |b| bench_steps(b, &real));
    group.bench_function(BenchmarkId::new("Dual64", n), |b| bench_steps(b, &dual));
    group.finish();
}

fn step_dim(c: &mut Criterion) {
    let mut group = c.benchmark_group("step_dim");
    group.sample_size(SAMPLES);
    for n in [10usize, 100, 1000] {
        let scene = cantilever(n);
        group.throughput(Throughput::Elements(n as u64));
        let planar = prepared(&scene, planar_f64(&scene));
        let spatial = prepared(
            &scene,
            Chain::<f64, 3>::from_scene(&scene).expect("valid scene"),
        );
        group.bench_function(BenchmarkId::new("planar", n), |b| bench_steps(b, &planar));
        group.bench_function(BenchmarkId::new("spatial", n), |b| bench_steps(b, &spatial));
    }
    group.finish();
}

/// riser_300m.toml's pipe in its 0.5 m/s current (no waves) as `n` pendulums at a step stable
/// for that n (h = 0.0125 (80/n)² s: the fastest bending mode scales like n²), with the
/// momentum drag (`"momentum"`, its D for that n) or Morison's drag node by node (`"morison"`).
fn pipe_riser(n: usize, model: &str) -> Scene {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    ))
    .expect("riser_300m.toml");
    let text = text.split("\n[mpc]\n").next().expect("scene");
    let (a, b) = (
        text.find("\n[loads.waves]\n").expect("waves"),
        text.find("\n[time]\n").expect("time"),
    );
    let h = 0.0125 * (80.0 / n as f64).powi(2);
    let mut text = format!("{}{}", &text[..a], &text[b..])
        .replace("pendulums = 80", &format!("pendulums = {n}"))
        .replace("step = 0.0125", &format!("step = {h}"))
        .replace("steps = 48000 ", &format!("steps = {PRE_STEPS} "));
    if model == "morison" {
        text = text
            .replace(
                "added_mass_coefficient = 1.0\n",
                "added_mass_coefficient = 1.0\ndrag_model = \"morison\"\n",
            )
            .replace("drag = 4.0020e-7 ", "# drag ");
    } else {
        let d = 4.0020e-7 * 80.0 / n as f64;
        text = text.replace("drag = 4.0020e-7 ", &format!("drag = {d:e} "));
    }
    Scene::from_toml_str(&text).expect("valid scene")
}

/// The cost of Morison's drag node by node against the momentum drag it replaces, one planar
/// `f64` step of riser_300m's pipe in its current, n = 100 and 1000: both O(n) (the node drag's
/// half step is a root per node and two bidiagonal passes, its Newton matrix tridiagonal), so
/// the time per pendulum-step is flat in n for both.
fn step_pipe_drag(c: &mut Criterion) {
    let mut group = c.benchmark_group("step_pipe_drag");
    group.sample_size(SAMPLES);
    for n in [100, 1000] {
        group.throughput(Throughput::Elements(n as u64));
        for model in ["momentum", "morison"] {
            let scene = pipe_riser(n, model);
            let prep = prepared(&scene, planar_f64(&scene));
            group.bench_function(BenchmarkId::new(model, n), |b| bench_steps(b, &prep));
        }
    }
    group.finish();
}

/// [`cantilever`]`(n)` with drag D = 10 and, if given, a current (the drag then acts relative
/// to it).
fn with_current(n: usize, current: Option<Current>) -> Scene {
    let mut s = cantilever(n);
    s.loads.drag = 10.0;
    s.loads.current = current;
    s.validate().expect("valid scene");
    s
}

/// The cost of a current: one planar step with the still-water drag, with a linear shear and
/// with a tabulated current (the profile is evaluated once, when the model is built, so both
/// cost the same per step), and the spatial step with a current at 45°.
fn step_current(c: &mut Criterion) {
    let n = 100;
    let mut group = c.benchmark_group("step_current");
    group.sample_size(SAMPLES);
    group.throughput(Throughput::Elements(n as u64));
    let cases = [
        ("still_water", None),
        ("linear", Some(Current::linear(0.5, 0.1, [0.0, 1.0]))),
        (
            "table",
            Some(Current::table(vec![
                [0.0, 0.5, 0.0],
                [5.0, 0.3, 0.0],
                [10.0, 0.1, 0.0],
            ])),
        ),
    ];
    for (name, current) in cases {
        let scene = with_current(n, current);
        let prep = prepared(&scene, planar_f64(&scene));
        group.bench_function(BenchmarkId::new(name, n), |b| bench_steps(b, &prep));
    }
    for (name, current) in [
        ("spatial_still_water", None),
        ("spatial_45deg", Some(Current::linear(0.5, 0.1, [1.0, 1.0]))),
    ] {
        let scene = with_current(n, current);
        let prep = prepared(
            &scene,
            Chain::<f64, 3>::from_scene(&scene).expect("valid scene"),
        );
        group.bench_function(BenchmarkId::new(name, n), |b| bench_steps(b, &prep));
    }
    group.finish();
}

fn simulate_riser(c: &mut Criterion) {
    let mut group = c.benchmark_group("simulate_riser");
    group.sample_size(SAMPLES);
    for steps in [10usize, 1000] {
        let scene = riser(steps);
        chainbeam::simulate(&scene).expect("riser simulates");
        group.bench_function(BenchmarkId::new("N", steps), |b| {
            b.iter(|| chainbeam::simulate(black_box(&scene)).expect("riser simulates"))
        });
    }
    group.finish();
}

/// A force term with the dual-number default K·v: energy, force and parameters are the wrapped
/// term's, and [`ForceTerm::force_jvp`] is *not* overridden, so it differentiates the term's
/// `force` in `Dual<D>`.
#[derive(Clone, Debug)]
struct DualDefault<T>(T);

impl<D: Scalar, const DIM: usize, T: ForceTerm<D, DIM>> ForceTerm<D, DIM> for DualDefault<T> {
    fn name(&self) -> &'static str {
        "dual default"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        self.0.energy(q, ctx)
    }

    fn force<E: Embed<D>>(
        &self,
        q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> chainbeam::Result<()> {
        self.0.force(q, ctx, out)
    }

    fn depends_on_configuration(&self) -> bool {
        self.0.depends_on_configuration()
    }

    fn depends_on_control(&self) -> bool {
        self.0.depends_on_control()
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        self.0.has_parameter(p)
    }
}

/// Times `term`'s K·v into `out` (zeroed on every iteration, as the solvers accumulate into a
/// cleared buffer).
fn bench_jvp<T: ForceTerm<f64, 2>>(
    b: &mut criterion::Bencher<'_>,
    term: &T,
    (q, v): (&[[f64; 2]], &[[f64; 2]]),
) {
    let ctx = Ctx::new(0.0, 0.0, 0);
    let mut out = vec![[0.0; 2]; q.len()];
    let mut scratch = DualScratch::new(q.len());
    b.iter(|| {
        out.iter_mut().for_each(|o| *o = [0.0; 2]);
        term.force_jvp(
            black_box(q),
            black_box(v),
            &ctx,
            1.0,
            &mut out,
            &mut scratch,
        )
        .expect("K v");
        black_box(&out);
    });
}

/// Finds the springs among the chain's terms and benches their K·v, hand-written against the
/// dual default (after checking the two agree).
struct SpringsJvp<'a, 'g> {
    group: &'a mut BenchmarkGroup<'g, WallTime>,
    q: &'a [[f64; 2]],
    v: &'a [[f64; 2]],
    found: bool,
}

impl TermVisitor<f64, 2> for SpringsJvp<'_, '_> {
    fn visit<T: ForceTerm<f64, 2>>(&mut self, term: &T) -> chainbeam::Result<()> {
        if term.name() != "springs" {
            return Ok(());
        }
        self.found = true;
        let n = self.q.len();
        let dual = DualDefault(term.clone());
        let ctx = Ctx::new(0.0, 0.0, 0);
        let mut scratch = DualScratch::new(n);
        let (mut hand, mut derived) = (vec![[0.0; 2]; n], vec![[0.0; 2]; n]);
        term.force_jvp(self.q, self.v, &ctx, 1.0, &mut hand, &mut scratch)?;
        dual.force_jvp(self.q, self.v, &ctx, 1.0, &mut derived, &mut scratch)?;
        let scale = hand.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for (h, d) in hand.iter().flatten().zip(derived.iter().flatten()) {
            assert!(
                (h - d).abs() <= 1e-12 * scale,
                "n = {n}: override {h} vs dual default {d}"
            );
        }
        let qv = (self.q, self.v);
        self.group
            .bench_function(BenchmarkId::new("override", n), |b| bench_jvp(b, term, qv));
        self.group
            .bench_function(BenchmarkId::new("dual_default", n), |b| {
                bench_jvp(b, &dual, qv)
            });
        Ok(())
    }
}

fn force_jvp(c: &mut Criterion) {
    let mut group = c.benchmark_group("force_jvp");
    group.sample_size(SAMPLES);
    for n in [10usize, 100, 1000] {
        let scene = cantilever(n);
        let (rattle, state, _) = prepared(&scene, planar_f64(&scene));
        // A direction with every component non-zero, of unit size.
        let v: Vec<[f64; 2]> = (0..n)
            .map(|i| [(0.7 * i as f64).sin(), (0.3 * i as f64 + 0.5).cos()])
            .collect();
        group.throughput(Throughput::Elements(n as u64));
        let mut visitor = SpringsJvp {
            group: &mut group,
            q: &state.q,
            v: &v,
            found: false,
        };
        rattle
            .chain()
            .visit_terms(&mut visitor)
            .expect("springs K v");
        assert!(visitor.found, "the chain has no springs term");
    }
    group.finish();
}

/// [`cantilever`]`(n)` with a joint damper beside every spring, c_j = α k_j with α = 0.01 s
/// (stiffness-proportional damping, ζ = α ω / 2 per mode; docs/conventions.md "Joint damping").
fn damped_cantilever(n: usize) -> Scene {
    let mut s = cantilever(n);
    let (base, k) = (s.beam.base_stiffness, &s.beam.stiffness);
    // c₁..c_{n+1}: the base spring, the interior springs, no tip spring (cantilever).
    let mut c = vec![0.01 * base];
    c.extend(k.iter().map(|k| 0.01 * k));
    c.push(0.0);
    s.beam.joint_damping = c;
    s.validate()
        .unwrap_or_else(|e| panic!("bench damped cantilever n = {n} is invalid: {e}"));
    s
}

/// One planar `f64` RATTLE step of [`damped_cantilever`] for n = 20, 80, 320: the cost of the
/// joint damping's implicit half step and Newton solve (`steppers/coupled.rs`), with
/// `Throughput::Elements(n)`. Compare with `step_f64_planar`, the same beam without dampers.
fn joint_damping(c: &mut Criterion) {
    let mut group = c.benchmark_group("joint_damping");
    group.sample_size(SAMPLES.min(10));
    for n in [20usize, 80, 320] {
        let scene = damped_cantilever(n);
        group.throughput(Throughput::Elements(n as u64));
        let prep = prepared(&scene, planar_f64(&scene));
        group.bench_function(BenchmarkId::from_parameter(n), |b| bench_steps(b, &prep));
    }
    group.finish();
}

/// Short defaults so a plain `cargo bench` stays quick; `--warm-up-time` / `--measurement-time` on
/// the command line override them (the groups set only the sample size).
fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
}

criterion_group! {
    name = benches;
    config = config();
    targets = step_f64_planar, step_scalar, step_dim, step_current, simulate_riser, force_jvp,
        joint_damping, step_pipe_drag
}
criterion_main!(benches);

//! A 3-hour sea state on the real-scale riser: `chainbeam::simulate` of
//! `examples/scenes/riser_300m.toml`'s riser and sea for 3 hours (the model's wave record by
//! inverse FFT, then the RATTLE run with the wellhead moment history), the streamed
//! `moment_history` of the same run (no stored trajectory), and the wave record alone
//! (`Chain::from_scene`: the sea, the per-pendulum amplitudes and the FFTs), at the coarse
//! discretisation n = 30, h = 0.05 s (216 000 steps; the file's cell lumping of the waves; with
//! node lumping it was 2 % off in the mean moment and 24 % in its standard deviation,
//! docs/scene-format.md "Real-scale risers").
//!
//! The converged n = 60, h = 0.0125 s (the scene file's) is 864 000 steps for 3 hours. Group
//! `riser_300m_converged` times the shipped file's own run three ways, each in flat sampling
//! (ten samples of one run each, whatever the machine's speed, so the group takes about
//! 10 × (0.3 + 0.6 + 6) s plus one warm-up run each on an idle core): its wave record alone
//! (`wave_record`: the whole 3-hour repeat period, as for any run), `moment_history` of the
//! file's 600 s (`moment_history_600s`, 48 000 steps) and `moment_history` of 3 hours
//! (`moment_history_3h`, 864 000 steps: the figure that matters for fatigue, the run that
//! `chainbeam simulate examples/scenes/riser_300m.toml --columns t,moment --every 16` makes with
//! `time.steps = 864000`). The 3-hour time is also wave record + 18 × (600 s run − wave
//! record) to the sampling noise, a check on the split (docs/scene-format.md "Real-scale
//! risers").
//!
//! Group `wave_setup_10s` times the set-up of a 10 s run of the same sea (`wave_setup`).
//! Group `riser_300m_system_3h` times 3 hours of the riser system held by its vessel
//! (`examples/scenes/riser_300m_system.toml`, `riser_system`).
//!
//! Run with `cargo bench --bench sea_state` (ten samples each; the report's time per iteration
//! is the time of one whole run; target for 3 hours ≤ 10 s, ≥ 1000× real time). One group:
//! `cargo bench --bench sea_state -- riser_300m_converged`.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use chainbeam::{moment_history, simulate, Chain, Scene};
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};

/// The shipped scene at n = 30, h = 0.05 s for 3 hours, D re-derived for n = 30
/// (D = ½ ρ_w C_d D_o / (l μ² L), the scene file's comments).
fn riser_300m() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_300m.toml");
    let mut s = Scene::from_file(path).expect("the shipped scene");
    let pipe = s.pipe.expect("a pipe");
    let rho = s.water.density;
    let n = 30;
    s.beam = pipe.beam(n, s.beam.support, rho, (None, None)).unwrap();
    let (l, mu) = (pipe.length / n as f64, pipe.mass_per_length(rho));
    s.loads.drag = pipe.drag_per_length(rho) / (l * mu * mu * pipe.length);
    s.time.step = 0.05;
    s.time.steps = 216_000;
    s.validate().unwrap();
    s
}

fn sea_state(c: &mut Criterion) {
    let scene = riser_300m();
    assert_eq!(scene.time.steps as f64 * scene.time.step, 10_800.0);
    let mut g = c.benchmark_group("riser_300m_3h");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(1));
    g.measurement_time(Duration::from_secs(30));
    g.bench_function("wave_record", |b| {
        b.iter(|| black_box(Chain::<f64, 2>::from_scene(black_box(&scene)).unwrap()))
    });
    g.bench_function("simulate", |b| {
        b.iter(|| {
            let t = simulate(black_box(&scene)).unwrap();
            black_box(t.moment().len())
        })
    });
    g.bench_function("moment_history", |b| {
        b.iter(|| black_box(moment_history(black_box(&scene)).unwrap().moment.len()))
    });
    g.finish();

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_300m.toml");
    let shipped = Scene::from_file(path).expect("the shipped scene");
    assert_eq!(shipped.time.steps, 48_000);
    let mut three_hours = shipped.clone();
    three_hours.time.steps = 864_000;
    assert_eq!(
        three_hours.time.steps as f64 * three_hours.time.step,
        10_800.0
    );
    let mut g = c.benchmark_group("riser_300m_converged");
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(1));
    // Below ten runs' time for all three: one run per sample (the flat mode's count is
    // ⌈measurement time / (10 × one run)⌉).
    g.measurement_time(Duration::from_secs(1));
    g.bench_function("wave_record", |b| {
        b.iter(|| black_box(Chain::<f64, 2>::from_scene(black_box(&shipped)).unwrap()))
    });
    g.bench_function("moment_history_600s", |b| {
        b.iter(|| black_box(moment_history(black_box(&shipped)).unwrap().moment.len()))
    });
    g.bench_function("moment_history_3h", |b| {
        b.iter(|| {
            black_box(
                moment_history(black_box(&three_hours))
                    .unwrap()
                    .moment
                    .len(),
            )
        })
    });
    g.finish();
}

/// The set-up of a short wave run: `examples/scenes/riser_300m.toml` for 10 s (800 steps of
/// 0.0125 s), its sea the same 3-hour realisation (M = 864 000 grid points per repeat period).
/// `chain_from_scene`: the model as built now (the sea, the amplitudes and, per pendulum, the
/// cheaper of the full inverse FFT and the zoom transform of the run's 801 times;
/// `Sea::synthesis_rows`); `full_fft_record`: the per-pendulum transforms as they were built
/// before, the repeat period's full inverse FFT of length M for each of the n + 1 series
/// (`Sea::synthesis_every(1)`), the cost that made every wave scene take ~2.4 s before its
/// first step whatever its length; `zoom_record`: the same n + 1 series by the zoom transform.
/// `cargo bench --bench sea_state -- wave_setup_10s`.
fn wave_setup(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_300m.toml");
    let mut scene = Scene::from_file(path).expect("the shipped scene");
    scene.time.steps = 800;
    assert_eq!(scene.time.steps as f64 * scene.time.step, 10.0);
    scene.validate().unwrap();
    let w = scene.loads.waves.expect("a sea");
    let sea = chainbeam::ocean::Sea::new(
        &w.sea_spec(scene.wave_depth()).unwrap(),
        scene.time.step,
        10.0,
    )
    .unwrap();
    let amplitudes = vec![chainbeam::ocean::Complex::new(1.0, 0.5); sea.frequencies().len()];
    let rows = scene.time.steps + 1;
    let series = |plan: &mut chainbeam::ocean::Synthesis| {
        let mut sum = 0.0;
        for _ in 0..=scene.n() {
            sea.synthesize((&amplitudes, &amplitudes), rows, plan, |_, x, y| {
                sum += x + y
            });
        }
        sum
    };
    let mut g = c.benchmark_group("wave_setup_10s");
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(1));
    g.measurement_time(Duration::from_secs(1));
    g.bench_function("chain_from_scene", |b| {
        b.iter(|| black_box(Chain::<f64, 2>::from_scene(black_box(&scene)).unwrap()))
    });
    g.bench_function("full_fft_record", |b| {
        b.iter(|| black_box(series(&mut sea.synthesis_every(1))))
    });
    g.bench_function("zoom_record", |b| {
        b.iter(|| black_box(series(&mut sea.synthesis_rows(1, rows))))
    });
    g.finish();
}

/// The riser system as an engineer runs it (`examples/scenes/riser_300m_system.toml`: the
/// stack-up from the conductor in the soil to the vessel, Morison's drag node by node, the
/// file's converged n and h) for 3 hours after its start: `moment_history` (streamed, the run
/// that `chainbeam simulate riser_300m_system.toml --columns t,moment --every 100` makes with
/// `time.steps` = 3 h / h; docs/riser-system.md "Speed"). Flat sampling, ten runs.
/// `cargo bench --bench sea_state -- riser_300m_system_3h`.
fn riser_system(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_300m_system.toml");
    let mut scene = Scene::from_file(path).expect("the shipped scene");
    scene.time.steps = (10_800.0 / scene.time.step).round() as usize;
    scene.validate().unwrap();
    let mut g = c.benchmark_group("riser_300m_system_3h");
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(1));
    g.measurement_time(Duration::from_secs(1));
    g.bench_function("moment_history_3h", |b| {
        b.iter(|| black_box(moment_history(black_box(&scene)).unwrap().moment.len()))
    });
    g.finish();
}

criterion_group!(benches, sea_state, wave_setup, riser_system);
criterion_main!(benches);

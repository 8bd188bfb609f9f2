//! The thesis's scenes, ready to simulate (their identification: docs/conventions.md).
//!
//! Every constructor returns a validated [`Scene`]. The parameter-free ones cannot fail; the
//! parametrised ones panic on parameters that cannot make a valid scene (documented under
//! *Panics*), like slice indexing does. All of them start at rest from the straight beam along +y
//! (docs/conventions.md), with loads in the thesis sign (+F z in H: F > 0 pushes toward −z). Unless stated
//! otherwise: n = 10, lᵢ = 1 m, mᵢ = 1 kg, interior springs k = 1000 Nm/rad, no gravity, no drag,
//! h = 0.01 s. The time grid can be changed freely afterwards (`scene.time.steps = ...`); a
//! per-step control must then be resized to N + 1 values.
//!
//! [`all`] lists every scene under a stable name.

use crate::scene::{
    ControlKind, Current, Harmonic, LoadSeries, ObjectiveKind, PointLoad, Scene, SceneBuilder,
    Support,
};

/// The standard chain of the thesis: n = 10, l = 1, m = 1, k = 1000, h = 0.01.
fn thesis_chain() -> SceneBuilder {
    Scene::builder(10)
        .length(1.0)
        .mass(1.0)
        .stiffness(1000.0)
        .step(0.01)
}

/// Builds a catalogue scene. The parameter-free scenes are fixed data that the tests validate, and
/// the parametrised ones check their parameters first, so a failure here is a bug in this module.
fn known_good(builder: SceneBuilder, name: &str) -> Scene {
    builder
        .build()
        .unwrap_or_else(|e| panic!("catalogue scene `{name}` is invalid: {e}"))
}

fn assert_drag(drag: f64, name: &str) {
    assert!(
        drag.is_finite() && drag >= 0.0,
        "catalogue::{name}: drag must be finite and non-negative, got {drag}"
    );
}

/// The conservative cantilever of thesis §2.2.4 (Fig. 2.5-2.8): n = 10, l = 1 m, m = 1 kg,
/// k = 1000 Nm/rad for every spring including the base spring k₁ = 1000 (§2.2.4 uses one k), free
/// tip, F = 2 N at node 10 (the tip), no drag, h = 0.01 s, N = 1000 (t ∈ [0, 10] s). No control,
/// no objective. (RATTLE's Newton solve fails on this beam at h = 0.02, as the thesis's did.)
pub fn thesis_cantilever() -> Scene {
    known_good(
        thesis_chain()
            .support(Support::Cantilever)
            .base_stiffness(1000.0)
            .point_load(10, 2.0)
            .steps(1000),
        "thesis_cantilever",
    )
}

/// The riser builder shared by [`riser`], [`riser_dissipative`] and [`long_horizon`]:
/// k₁ = k₁₁ = 2000, F = 2 at `load_node`.
fn riser_chain(load_node: usize, name: &str) -> SceneBuilder {
    assert!(
        (1..=10).contains(&load_node),
        "catalogue::{name}: load_node must be in 1..=10, got {load_node}"
    );
    riser_chain_without_load().point_load(load_node, 2.0)
}

/// The optimal-control scene of thesis §3.3.1 (Tables 3.1-3.4, "system i" = `load_node`), as
/// identified by re-computing the tables (docs/conventions.md, "Thesis errata corrected"): riser
/// support (cantilever with a tip spring, tip free), n = 10, l = 1 m, m = 1 kg, interior
/// k = 1000 Nm/rad, k₁ = k₁₁ = 2000 Nm/rad, **no drag** (D = 0), F = 2 N at
/// `load_node`, control at node 10 (constant, initial value 0), objective c = M₀(t_N)²
/// (eq. 3.3.2; set `scene.objective` to [`ObjectiveKind::Sum`] for Tables 3.2/3.4), h = 0.01 s,
/// N = 10 (T = 0.1 s).
///
/// # Panics
/// If `load_node` is not in 1..=10.
pub fn riser(load_node: usize) -> Scene {
    known_good(
        riser_chain(load_node, "riser")
            .control_constant(10, 0.0)
            .objective(ObjectiveKind::Final)
            .steps(10),
        "riser",
    )
}

/// The manually controlled riser of thesis §3.1 (Fig. 3.1-3.2): [`riser`] with drag D = 10 kg/m
/// and N = 1000 (t ∈ [0, 10] s). The control (node 10, constant) starts at 0; the thesis's manual
/// values are u = −[0.37 0.72 1.01 1.28 1.50 1.68 1.83 1.93 1.99 2] N for `load_node` 1..10 (with
/// u = −1.5 and the load at node 5 the tip settles near z ≈ 0.042, thesis §3.2).
///
/// # Panics
/// If `load_node` is not in 1..=10.
pub fn riser_dissipative(load_node: usize) -> Scene {
    known_good(
        riser_chain(load_node, "riser_dissipative")
            .drag(10.0)
            .control_constant(10, 0.0)
            .objective(ObjectiveKind::Final)
            .steps(1000),
        "riser_dissipative",
    )
}

/// The fixed-fixed beam of thesis §2.4.2 (Fig. 2.12-2.13 left): n = 10, l = 1 m, m = 1 kg,
/// k = 1000 Nm/rad, end springs k₁ = k₁₁ = 2000 Nm/rad (the values that match Euler-Bernoulli),
/// tip z locked, F = 2 N at the central node 5, no drag, h = 0.01 s, N = 1000 (t ∈ [0, 10] s).
pub fn fixed_fixed() -> Scene {
    known_good(fixed_fixed_builder(0.0), "fixed_fixed")
}

fn fixed_fixed_builder(drag: f64) -> SceneBuilder {
    thesis_chain()
        .support(Support::FixedFixed)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(drag)
        .point_load(5, 2.0)
        .steps(1000)
}

/// The pinned-pinned beam of thesis §2.4.2 (Fig. 2.13 right): as [`fixed_fixed`] without end
/// springs (k₁ = k₁₁ = 0, stored as 0), tip z locked, F = 2 N at node 5, no drag, N = 1000.
pub fn pinned_pinned() -> Scene {
    known_good(pinned_pinned_builder(0.0), "pinned_pinned")
}

fn pinned_pinned_builder(drag: f64) -> SceneBuilder {
    thesis_chain()
        .support(Support::PinnedPinned)
        .base_stiffness(0.0)
        .tip_stiffness(0.0)
        .drag(drag)
        .point_load(5, 2.0)
        .steps(1000)
}

/// The dissipative cantilever of thesis §2.4.4 (Fig. 2.14-2.16, D = 10 and 100 kg/m in the
/// thesis): n = 10, l = 1 m, m = 1 kg, k = 1000 Nm/rad, base spring k₁ = 2000 Nm/rad (the
/// static formula 2.4.5 with EI = k·l matches when the base spring is 2000), F = 2 N at node 10,
/// drag D = `drag`, h = 0.01 s, N = 1000 (lengthen `time.steps` to let it settle).
///
/// # Panics
/// If `drag` is negative or not finite.
pub fn dissipative_cantilever(drag: f64) -> Scene {
    assert_drag(drag, "dissipative_cantilever");
    known_good(
        thesis_chain()
            .support(Support::Cantilever)
            .base_stiffness(2000.0)
            .drag(drag)
            .point_load(10, 2.0)
            .steps(1000),
        "dissipative_cantilever",
    )
}

/// [`fixed_fixed`] with drag D = `drag` (thesis §2.4.4, Fig. 2.14-2.15, static formula 2.4.6).
///
/// # Panics
/// If `drag` is negative or not finite.
pub fn dissipative_fixed_fixed(drag: f64) -> Scene {
    assert_drag(drag, "dissipative_fixed_fixed");
    known_good(fixed_fixed_builder(drag), "dissipative_fixed_fixed")
}

/// [`pinned_pinned`] with drag D = `drag` (thesis §2.4.4, Fig. 2.14-2.15, static formula 2.4.7).
///
/// # Panics
/// If `drag` is negative or not finite.
pub fn dissipative_pinned_pinned(drag: f64) -> Scene {
    assert_drag(drag, "dissipative_pinned_pinned");
    known_good(pinned_pinned_builder(drag), "dissipative_pinned_pinned")
}

/// A cantilever of total length L, flexural rigidity EI and total mass M discretised by `n`
/// pendulums, for convergence studies (the open question at the end of thesis §2.4.4):
/// l = L/n, interior springs k = EI/l, base spring k₁ = `base_factor`·k (2 matches the static
/// formula 2.4.5), m = M/n, F = 2 N at the tip (node n), no drag, t ∈ [0, 10] s with
/// h = 0.01 s · min(1, (10/n)²): the fastest mode's frequency grows like n² and RATTLE's Newton
/// solve needs h·ω_max bounded (thesis: it fails at h = 0.02 for n = 10). The time grid is thus
/// N = 1000 for n ≤ 10 and grows like n² beyond; a stored trajectory then exceeds
/// [`crate::scene::MAX_TRAJECTORY_BYTES`] from n ≈ 260 on (a streamed run,
/// [`crate::simulate_streaming`], does not store it): use [`scaled_cantilever_steps`] for a
/// shorter horizon. `scaled_cantilever(10, 10.0, 1000.0, 10.0, 2.0)` is [`dissipative_cantilever`]
/// without drag.
///
/// # Panics
/// If `n` is 0 or above [`crate::scene::MAX_PENDULUMS`], or `total_length`, `ei`, `total_mass`
/// are not positive and finite, or `base_factor` is negative or not finite, or the scene is
/// invalid (outside the valid ranges of docs/scene-format.md).
pub fn scaled_cantilever(
    n: usize,
    total_length: f64,
    ei: f64,
    total_mass: f64,
    base_factor: f64,
) -> Scene {
    let h = scaled_step(n);
    scaled_cantilever_steps(
        n,
        total_length,
        ei,
        total_mass,
        base_factor,
        (10.0 / h).round() as usize,
    )
}

/// h = 0.01 s · min(1, (10/n)²), the step of [`scaled_cantilever`].
fn scaled_step(n: usize) -> f64 {
    0.01 * (10.0 / n as f64).powi(2).min(1.0)
}

/// [`scaled_cantilever`] with `steps` steps of the same h (t ∈ [0, steps·h]), for large n
/// (benchmarks: n = 1000 with 100 steps).
///
/// # Panics
/// As [`scaled_cantilever`], and if `steps` is 0.
pub fn scaled_cantilever_steps(
    n: usize,
    total_length: f64,
    ei: f64,
    total_mass: f64,
    base_factor: f64,
    steps: usize,
) -> Scene {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    assert!(
        (1..=crate::scene::MAX_PENDULUMS).contains(&n),
        "catalogue::scaled_cantilever: n must be in 1..={}, got {n}",
        crate::scene::MAX_PENDULUMS
    );
    assert!(
        positive(total_length) && positive(ei) && positive(total_mass),
        "catalogue::scaled_cantilever: total_length, ei and total_mass must be positive and \
         finite, got {total_length}, {ei}, {total_mass}"
    );
    assert!(
        base_factor.is_finite() && base_factor >= 0.0,
        "catalogue::scaled_cantilever: base_factor must be finite and non-negative, got \
         {base_factor}"
    );
    let l = total_length / n as f64;
    let k = ei / l;
    let h = scaled_step(n);
    known_good(
        Scene::builder(n)
            .length(l)
            .mass(total_mass / n as f64)
            .stiffness(k)
            .base_stiffness(base_factor * k)
            .support(Support::Cantilever)
            .point_load(n, 2.0)
            .step(h)
            .steps(steps),
        "scaled_cantilever",
    )
}

/// The longer-horizon optimal-control problem the thesis leaves for future work (end of §3.3,
/// Fig. 3.12): the riser (k₁ = k₁₁ = 2000) with drag D = 10 kg/m, F = 2 N at node 5 from t = 0,
/// per-step control at node 10 (N + 1 = 1001 zeros as the initial guess), objective
/// c_sum = Σ M₀(t_k)² (eq. 3.3.4), h = 0.01 s, N = 1000 (t ∈ [0, 10] s).
pub fn long_horizon() -> Scene {
    let steps = 1000;
    known_good(
        riser_chain(5, "long_horizon")
            .drag(10.0)
            .control_per_step(10, vec![0.0; steps + 1])
            .objective(ObjectiveKind::Sum)
            .steps(steps),
        "long_horizon",
    )
}

/// A load out of the yz-plane (docs/scene-format.md): the thesis riser (k₁ = k₁₁ = 2000, no drag)
/// with F = 2 N at node 5 at 45° between x and z, `force = [√2, √2]`, h = 0.01 s, N = 1000
/// (t ∈ [0, 10] s). Spatial: [`crate::simulate()`] runs the spatial model, and by the model's
/// rotational symmetry about y the deflection is the in-plane one of [`riser`]`(5)`'s load turned
/// by 45° (tests/model/loads.rs). No control (a 2-axis control on the same load: [`oblique_control`]).
pub fn oblique_riser() -> Scene {
    let f = std::f64::consts::SQRT_2;
    known_good(
        riser_chain_without_load()
            .point_load_vector(5, [f, f])
            .steps(1000),
        "oblique_riser",
    )
}

/// A 2-axis control on an oblique load: [`oblique_riser`] (F = 2 N at node 5 at 45° between x
/// and z, no drag, h = 0.01 s, N = 1000) with a 2-axis piecewise control [u_x, u_z] at node 10 of
/// 10 pieces of 1 s (initial guess 0) and the objective c_sum = Σ |M₀(t_k)|². Spatial; by the
/// rotational symmetry about y its optimal control points along the load.
pub fn oblique_control() -> Scene {
    let f = std::f64::consts::SQRT_2;
    known_good(
        riser_chain_without_load()
            .point_load_vector(5, [f, f])
            .control_two_axis(10, ControlKind::Piecewise, &[[0.0, 0.0]; 10])
            .objective(ObjectiveKind::Sum)
            .steps(1000),
        "oblique_control",
    )
}

/// Period of the waves of [`wave_riser`] and [`wave_series`] \[s\].
pub const WAVE_PERIOD: f64 = 8.0;

/// A regular wave's force on the riser: the thesis riser (k₁ = k₁₁ = 2000) with drag
/// D = 10 kg/m and a harmonic load F_z(t) = 2 N · sin(2π t/8 s) at node 5, ramped in over the
/// first period (8 s), h = 0.01 s, N = 3200 (t ∈ [0, 32] s, four periods). Piecewise control at
/// node 10 with 32 pieces of 1 s (initial guess 0), objective c_sum = Σ M₀(t_k)²: planar, so
/// `chainbeam optimize` computes the control that counters the wave.
pub fn wave_riser() -> Scene {
    let wave = Harmonic {
        amplitude: 2.0,
        period: WAVE_PERIOD,
        phase: 0.0,
    };
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .load(PointLoad::harmonic(5, [0.0, 1.0], vec![wave]).ramped(WAVE_PERIOD))
            .control_piecewise(10, vec![0.0; 32])
            .objective(ObjectiveKind::Sum)
            .steps(3200),
        "wave_riser",
    )
}

/// The irregular sea of [`mpc_riser`] and [`spatial_mpc_riser`] at node 5:
/// 2 N · sin(2π t/8 s) + 0.5 N · sin(2π t/5.3 s + 1).
fn mpc_sea() -> Vec<Harmonic> {
    vec![
        Harmonic {
            amplitude: 2.0,
            period: WAVE_PERIOD,
            phase: 0.0,
        },
        Harmonic {
            amplitude: 0.5,
            period: 5.3,
            phase: 1.0,
        },
    ]
}

/// The closed-loop scene of receding-horizon control ([`crate::mpc`]): [`wave_riser`]'s riser
/// and drag (D = 10 kg/m) under an irregular sea at node 5, F_z(t) = 2 N · sin(2π t/8 s) +
/// 0.5 N · sin(2π t/5.3 s + 1), ramped in over the first 8 s, h = 0.01 s, N = 6000
/// (t ∈ [0, 60] s), in a sheared current along +z, 0.1 m/s at the surface falling linearly to
/// 0.02 m/s at the seabed (its steady drag bends the riser one way, a mean base moment of about
/// 28 Nm, which a constant force of about 2.9 N cancels within the bound |u| ≤ 5 N of
/// `chainbeam mpc`; [`sheared_current`]'s 0.3 m/s would need more than 5 N). Control at node 10 (the platform; the `[control]` value 0 is only the
/// open-loop default, `chainbeam mpc` decides it every control interval), objective
/// c_sum = Σ M₀(t_k)².
pub fn mpc_riser() -> Scene {
    let sea = mpc_sea();
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .load(PointLoad::harmonic(5, [0.0, 1.0], sea).ramped(WAVE_PERIOD))
            .current(Current::linear(0.1, 0.02, [0.0, 1.0]))
            .control_constant(10, 0.0)
            .objective(ObjectiveKind::Sum)
            .steps(6000),
        "mpc_riser",
    )
}

/// The spatial closed-loop scene (MPC with a 2-axis control): [`mpc_riser`]'s riser, drag and
/// current (along +z, 0.1 m/s at the surface falling linearly to 0.02 m/s at the seabed) with its sea
/// at node 5 coming from another direction, 60° from +z toward +x (F(t) = (2 N sin(2π t/8 s) +
/// 0.5 N sin(2π t/5.3 s + 1)) (sin 60°, cos 60°), ramped in over 8 s), h = 0.01 s, N = 3000
/// (t ∈ [0, 30] s); a 2-axis control at node 10 (the platform; a spatial closed loop,
/// [`crate::mpc::run_closed_loop`] in the spatial model, decides (u_x, u_z)
/// every interval), objective c_sum = Σ |M₀(t_k)|². Spatial: the loads have x components.
pub fn spatial_mpc_riser() -> Scene {
    let sea = mpc_sea();
    let (s, c) = 60f64.to_radians().sin_cos();
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .load(PointLoad::harmonic(5, [s, c], sea).ramped(WAVE_PERIOD))
            .current(Current::linear(0.1, 0.02, [0.0, 1.0]))
            .control_two_axis(10, ControlKind::Constant, &[[0.0, 0.0]])
            .objective(ObjectiveKind::Sum)
            .steps(3000),
        "spatial_mpc_riser",
    )
}

/// The controller's *wrong* model of [`mpc_riser`] (the mismatch case of `examples/mpc.rs` and
/// the `mpc_moment` figure): the drag underestimated by 30 % (D = 7 instead of 10 kg/m), the
/// current overestimated by 20 % (0.12 → 0.024 m/s), and a forecast of the sea that misses its
/// 5.3 s component and underestimates the 8 s wave by 20 % (1.6 N). Use it as the `model` of
/// [`crate::mpc::Mpc::new`] with [`mpc_riser`] as the plant (`chainbeam mpc --model`).
pub fn mpc_riser_wrong_model() -> Scene {
    let mut model = mpc_riser();
    model.loads.drag *= 0.7;
    if let Some(c) = model.loads.current.as_mut() {
        c.profile = crate::scene::CurrentProfile::Linear {
            speed: 0.12,
            bottom_speed: 0.024,
        };
    }
    let sea = &mut model.loads.points[0].harmonics;
    sea.truncate(1);
    sea[0].amplitude *= 0.8;
    model
}

/// The rows of [`wave_series`]'s file `wave_series.csv`: every 0.1 s over [0, 32] s, an oblique
/// sea with F_x = 0.8 sin(2π t/8) and F_z = 2 sin(2π t/8 + 0.5) + 0.5 sin(2π t/5.3) \[N\].
pub fn wave_series_rows() -> Vec<[f64; 3]> {
    use std::f64::consts::TAU;
    (0..=320)
        .map(|i| {
            let t = i as f64 / 10.0;
            let w = TAU * t / WAVE_PERIOD;
            [
                t,
                0.8 * w.sin(),
                2.0 * (w + 0.5).sin() + 0.5 * (TAU * t / 5.3).sin(),
            ]
        })
        .collect()
}

/// A measured-style load history: [`wave_riser`]'s riser and drag with the load at
/// node 5 read from the time series `wave_series.csv` ([`wave_series_rows`]: an oblique sea of two
/// wave components, so the scene is spatial), ramped in over 8 s, N = 3200 (t ∈ [0, 32] s). No
/// control (2-axis controls: [`oblique_control`]).
///
/// The series' file name is relative to the scene file (examples/scenes/wave_series.csv).
pub fn wave_series() -> Scene {
    let series = LoadSeries {
        file: "wave_series.csv".into(),
        samples: wave_series_rows(),
    };
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .load(PointLoad::series(5, series).ramped(WAVE_PERIOD))
            .steps(3200),
        "wave_series",
    )
}

/// A sheared current on the riser: [`wave_riser`]'s riser with drag D = 10 kg/m in a
/// current along +z that falls linearly from 0.3 m/s at the surface (the top node) to
/// 0.05 m/s at the seabed (the base), h = 0.01 s, N = 1000 (t ∈ [0, 10] s). The drag acts on
/// the motion relative to the water (docs/conventions.md), so the riser drifts downstream toward
/// the static offset of `statics::static_equilibrium`. Piecewise control at node 10 with 10
/// pieces of 1 s (initial guess 0), objective c_sum = Σ M₀(t_k)²: planar, so `chainbeam
/// optimize` computes the platform force that keeps the wellhead moment small.
pub fn sheared_current() -> Scene {
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .current(Current::linear(0.3, 0.05, [0.0, 1.0]))
            .control_piecewise(10, vec![0.0; 10])
            .objective(ObjectiveKind::Sum)
            .steps(1000),
        "sheared_current",
    )
}

/// A current that turns with depth: [`sheared_current`]'s riser and drag in a
/// tabulated current (depth below the surface, speed, direction from +z toward +x):
/// 0.3 m/s along +z at the surface, 0.2 m/s at 45° at 5 m depth, 0.1 m/s along +x at the seabed
/// (10 m), interpolated linearly in depth. Spatial (the current has x components); no control.
/// h = 0.01 s, N = 1000. The riser drifts toward the static offset of
/// `statics::static_equilibrium`, solved in the spatial model (tests/model/statics_spatial.rs).
pub fn turning_current() -> Scene {
    known_good(
        riser_chain_without_load()
            .drag(10.0)
            .current(Current::table(vec![
                [0.0, 0.3, 0.0],
                [5.0, 0.2, 45.0],
                [10.0, 0.1, 90.0],
            ]))
            .steps(1000),
        "turning_current",
    )
}

/// The riser's beam (k₁ = k₁₁ = 2000) without its load.
fn riser_chain_without_load() -> SceneBuilder {
    thesis_chain()
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
}

const RISER_NAMES: [&str; 10] = [
    "riser_1", "riser_2", "riser_3", "riser_4", "riser_5", "riser_6", "riser_7", "riser_8",
    "riser_9", "riser_10",
];

const RISER_DISSIPATIVE_NAMES: [&str; 10] = [
    "riser_dissipative_1",
    "riser_dissipative_2",
    "riser_dissipative_3",
    "riser_dissipative_4",
    "riser_dissipative_5",
    "riser_dissipative_6",
    "riser_dissipative_7",
    "riser_dissipative_8",
    "riser_dissipative_9",
    "riser_dissipative_10",
];

/// Every catalogue scene under a stable name: `thesis_cantilever`, `riser_1`..`riser_10`,
/// `riser_dissipative_1`..`riser_dissipative_10`, `fixed_fixed`, `pinned_pinned`,
/// `dissipative_{cantilever,fixed_fixed,pinned_pinned}_d{10,100}` (the two drags of Fig. 2.14),
/// `scaled_cantilever_n20` (n = 20, L = 10, EI = 1000, M = 10, base factor 2), `long_horizon`,
/// the scenes of the new loads: `oblique_riser`, `oblique_control` (2-axis control),
/// `wave_riser`, `wave_series`, `sheared_current`, `turning_current`, and the closed-loop scene
/// `mpc_riser` with its controller's wrong model `mpc_riser_wrong_model`, and its spatial
/// sibling `spatial_mpc_riser` (current along +z, sea from 60°).
pub fn all() -> Vec<(&'static str, Scene)> {
    let mut scenes = vec![("thesis_cantilever", thesis_cantilever())];
    for (i, name) in RISER_NAMES.iter().enumerate() {
        scenes.push((name, riser(i + 1)));
    }
    for (i, name) in RISER_DISSIPATIVE_NAMES.iter().enumerate() {
        scenes.push((name, riser_dissipative(i + 1)));
    }
    scenes.extend([
        ("fixed_fixed", fixed_fixed()),
        ("pinned_pinned", pinned_pinned()),
        ("dissipative_cantilever_d10", dissipative_cantilever(10.0)),
        ("dissipative_cantilever_d100", dissipative_cantilever(100.0)),
        ("dissipative_fixed_fixed_d10", dissipative_fixed_fixed(10.0)),
        (
            "dissipative_fixed_fixed_d100",
            dissipative_fixed_fixed(100.0),
        ),
        (
            "dissipative_pinned_pinned_d10",
            dissipative_pinned_pinned(10.0),
        ),
        (
            "dissipative_pinned_pinned_d100",
            dissipative_pinned_pinned(100.0),
        ),
        (
            "scaled_cantilever_n20",
            scaled_cantilever(20, 10.0, 1000.0, 10.0, 2.0),
        ),
        ("long_horizon", long_horizon()),
        ("oblique_riser", oblique_riser()),
        ("oblique_control", oblique_control()),
        ("wave_riser", wave_riser()),
        ("wave_series", wave_series()),
        ("sheared_current", sheared_current()),
        ("turning_current", turning_current()),
        ("mpc_riser", mpc_riser()),
        ("mpc_riser_wrong_model", mpc_riser_wrong_model()),
        ("spatial_mpc_riser", spatial_mpc_riser()),
    ]);
    scenes
}

/// The catalogue scene called `name` (see [`all`]), if there is one.
pub fn by_name(name: &str) -> Option<Scene> {
    all().into_iter().find(|(n, _)| *n == name).map(|(_, s)| s)
}

//! Statics in the spatial model: Newton on the product of spheres
//! (`statics::static_equilibrium_spatial`, module docs of `chainbeam::statics`).
//!
//! References: the planar statics (Newton in the absolute angles, an independent
//! parametrisation), which every planar scene solved in the spatial model must reproduce
//! (1e-12); the model's symmetry under rotations about the beam's axis y, under which a point
//! load or a control turned in the x–z plane turns the planar deflection with it (1e-12); the
//! current drag at rest (Morison's, invariant under rotations about y), under which a uniform
//! current at angle α gives the planar deflection turned by α (1e-12); and long
//! dissipative simulations in the spatial model, which settle onto the static offset of the
//! turning current and of an oblique current on a fixed-fixed beam (thesis §2.4.4), to within a
//! bound on their remaining transient that the simulation itself measures.

use chainbeam::model::ModelError;
use chainbeam::statics::{static_equilibrium, static_equilibrium_at, static_equilibrium_spatial};
use chainbeam::*;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000, k₁ = k₁₁ = 2000), h = 0.01 s, N = 1000.
fn riser() -> SceneBuilder {
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .step(0.01)
        .steps(1000)
}

/// max over nodes and components of |a − b|.
fn max_dev(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let pairs = a.iter().zip(b);
    pairs.fold(0.0, |m, (a, b)| {
        (0..3).fold(m, |m: f64, d| m.max((a[d] - b[d]).abs()))
    })
}

/// The planar solution's nodes turned by `alpha` about y: a deflection z along +z becomes
/// (x, z) = z (sin α, cos α), the direction of an angle α from +z toward +x.
fn turned(planar: &statics::StaticSolution, alpha: f64) -> Vec<[f64; 3]> {
    let (s, c) = alpha.sin_cos();
    planar
        .positions_xyz()
        .iter()
        .map(|&[x, y, z]| [c * x + s * z, y, c * z - s * x])
        .collect()
}

/// Every planar catalogue scene with a base or tip spring, solved in the spatial model, equals
/// its planar solution (the other parametrisation) to 1e-12 in the positions, with x exactly 0
/// (the x equations decouple at x = 0) and the same tip multiplier; a pinned-pinned beam, which
/// the spatial model lets turn about z, is refused with the typed error naming its tip.
#[test]
fn planar_scenes_in_the_spatial_model_equal_the_planar_statics() {
    let mut solved = 0;
    for (name, scene) in catalogue::all() {
        if scene.is_spatial() {
            continue;
        }
        let planar = static_equilibrium(&scene).unwrap();
        assert!(!planar.spatial, "{name}");
        let t = scene.time.step * scene.time.steps as f64;
        let u = *scene_controls(&scene).last().unwrap();
        let spatial = static_equilibrium_spatial(&scene, t, [0.0, u]);
        if scene.beam.support == Support::PinnedPinned {
            let err = spatial.unwrap_err();
            assert_eq!(
                err,
                Error::StaticNotIsolated {
                    support: Support::PinnedPinned,
                    tip: TipCondition::Locked
                },
                "{name}"
            );
            assert!(err.to_string().contains("Locked tip"), "{err}");
            continue;
        }
        let spatial = spatial.unwrap();
        let dev = max_dev(&spatial.positions_xyz(), &planar.positions_xyz());
        let dnu = (spatial.tip_multiplier - planar.tip_multiplier).abs();
        println!(
            "{name}: |spatial − planar| = {dev:.1e}, Δν = {dnu:.1e}, iterations {} / {}",
            spatial.iterations, planar.iterations
        );
        assert!(spatial.spatial);
        assert!(dev <= 1e-12, "{name}: {dev:e}");
        assert!(spatial.positions_x.iter().all(|&x| x == 0.0), "{name}");
        assert!(dnu <= 1e-9 * planar.tip_multiplier.abs().max(1.0), "{name}");
        solved += 1;
    }
    assert!(solved >= 20, "{solved}");
}

/// A point load and a control turned by α about the beam's axis y turn the planar deflection by
/// α (the springs, constraints and masses depend only on angles and lengths), to 1e-12, for
/// angles in every quadrant.
#[test]
fn turned_loads_turn_the_planar_deflection() {
    let (f, u) = (3.0, -1.2);
    let planar_scene = riser()
        .point_load(5, f)
        .control_constant(8, u)
        .build()
        .unwrap();
    let planar = static_equilibrium(&planar_scene).unwrap();
    assert!(planar.positions[9][1].abs() > 1e-3);
    for deg in [30.0f64, 45.0, 90.0, 135.0, 200.0, 290.0] {
        let a = deg.to_radians();
        let (s, c) = a.sin_cos();
        let scene = riser()
            .point_load_vector(5, [f * s, f * c])
            .control_constant(8, 0.0)
            .build()
            .unwrap();
        let t = scene.time.step * scene.time.steps as f64;
        let sol = static_equilibrium_spatial(&scene, t, [u * s, u * c]).unwrap();
        let dev = max_dev(&sol.positions_xyz(), &turned(&planar, a));
        println!("α = {deg}°: |spatial − turned planar| = {dev:.1e}");
        assert!(dev <= 1e-12, "{deg}: {dev:e}");
    }
}

/// A uniform current at angle α pushes each pendulum at rest with D |P| P (Morison's drag on
/// the transverse momentum with its Euclidean norm, docs/conventions.md), Pᵢ = Pᵢ (sin α, cos α):
/// the force of the same current along +z, turned by α. The static deflection is therefore the
/// planar one under the current along +z, turned by α, to 1e-12. `static_equilibrium` picks the
/// spatial model for these scenes itself.
#[test]
fn a_turned_uniform_current_turns_the_planar_offset() {
    let speed = 0.3;
    let current = |speed, dir| riser().drag(10.0).current(Current::uniform(speed, dir));
    let planar = static_equilibrium(&current(speed, [0.0, 1.0]).build().unwrap()).unwrap();
    assert!(planar.positions[9][1] > 1e-3);
    for deg in [90.0f64, 30.0, 135.0, 250.0] {
        let a = deg.to_radians();
        let (s, c) = a.sin_cos();
        let scene = current(speed, [s, c]).build().unwrap();
        let sol = static_equilibrium(&scene).unwrap();
        assert!(sol.spatial);
        let dev = max_dev(&sol.positions_xyz(), &turned(&planar, a));
        println!("α = {deg}°: |spatial − turned planar| = {dev:.1e}");
        assert!(dev <= 1e-12, "{deg}: {dev:e}");
    }
}

/// Where a long simulation in the spatial model stands, and a bound on how far it still has to
/// go.
struct Settled {
    /// Node positions (x, y, z) at the end.
    nodes: Vec<[f64; 3]>,
    /// The time reached \[s\].
    time: f64,
    /// A bound on |r(∞) − r(t)| from the remaining transient (see [`settle`]).
    remaining: f64,
}

/// Runs RATTLE in the spatial model from the straight beam in windows of 10 s until the bound
/// on the remaining transient falls below `target` (or `t_max`). If the largest node speed decays
/// like an exponential envelope V e^{−λt}, then |r(∞) − r(t)| ≤ ∫ₜ^∞ |ṙ| ≤ V(t)/λ; V is the
/// largest node speed in the last window and λ = ln(V_prev/V)/10 s the envelope's rate between
/// the last two windows.
fn settle(scene: &Scene, target: f64, t_max: f64) -> Settled {
    let chain = Chain::<f64, 3>::from_scene(scene).unwrap();
    let h = scene.time.step;
    let window = (10.0 / h) as usize;
    let mut r = Rattle::new(chain.clone(), h).unwrap();
    let mut st = r.straight_state();
    let (n, mut k, mut prev, mut remaining) = (chain.n(), 0, f64::INFINITY, f64::INFINITY);
    let (mut qdot, mut nodes) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    while remaining > target && (k as f64) * h < t_max {
        let mut speed: f64 = 0.0;
        for _ in 0..window {
            r.step(&mut st, k, 0.0, 0.0).unwrap();
            k += 1;
            chain.apply_inverse_mass(&st.p, &mut qdot);
            chain.node_positions(&qdot, &mut nodes);
            speed = nodes.iter().flatten().fold(speed, |m, v| m.max(v.abs()));
        }
        let rate = (prev / speed).ln() / (window as f64 * h);
        remaining = if rate > 0.0 && prev.is_finite() {
            speed / rate
        } else {
            f64::INFINITY
        };
        prev = speed;
    }
    chain.node_positions(&st.q, &mut nodes);
    Settled {
        nodes,
        time: k as f64 * h,
        remaining,
    }
}

/// The turning current's static offset (checked as the thesis checks its statics in §2.4.4): the catalogue's riser in the tabulated current that turns from +z at the surface to
/// +x at the seabed (D = 10) settles, in a long simulation in the spatial model, onto the spatial
/// static solution. The tolerance is the simulation's own bound on its remaining transient
/// ([`settle`]), plus round-off.
#[test]
fn turning_current_settles_at_the_spatial_static_offset() {
    let scene = catalogue::turning_current();
    let stat = static_equilibrium(&scene).unwrap();
    assert!(stat.spatial);
    let end = settle(&scene, 1e-9, 20_000.0);
    let dev = max_dev(&end.nodes, &stat.positions_xyz());
    let [x, _, z] = stat.positions_xyz()[9];
    println!(
        "turning current: static tip (x, z) = ({x:.6}, {z:.6}) m in {} Newton iterations; \
         settled after {:.0} s with remaining transient ≤ {:.1e}; |dynamic − static| = {dev:.2e}",
        stat.iterations, end.time, end.remaining
    );
    assert!(x > 1e-3 && z > 1e-3, "the current pushes toward +x and +z");
    assert!(
        dev <= end.remaining + 1e-12,
        "{dev:e} > {:e}",
        end.remaining
    );
}

/// The bordered spatial system: a fixed-fixed beam (D = 100) in a uniform current at 60° from
/// +z toward +x settles onto the spatial static solution, to within the simulation's bound on
/// its remaining transient. As in the model, only the tip's z is locked (z = 0 to round-off)
/// while the tip's x moves with the current, held only by the tip spring.
#[test]
fn fixed_fixed_beam_in_an_oblique_current_settles_at_the_spatial_statics() {
    let (s, c) = 60f64.to_radians().sin_cos();
    let scene = SceneBuilder::new(10)
        .support(Support::FixedFixed)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(100.0)
        .current(Current::uniform(0.1, [s, c]))
        .step(0.01)
        .steps(1000)
        .build()
        .unwrap();
    let stat = static_equilibrium(&scene).unwrap();
    let end = settle(&scene, 1e-9, 20_000.0);
    let dev = max_dev(&end.nodes, &stat.positions_xyz());
    let [x, _, z] = stat.positions_xyz()[9];
    println!(
        "fixed-fixed: static tip (x, z) = ({x:.3e}, {z:.1e}) m, ν = {:.6}, {} iterations; \
         settled after {:.0} s with remaining transient ≤ {:.1e}; |dynamic − static| = {dev:.2e}",
        stat.tip_multiplier, stat.iterations, end.time, end.remaining
    );
    assert!(z.abs() <= 1e-14 && x > 1e-3);
    assert!(stat.tip_multiplier != 0.0);
    assert!(
        dev <= end.remaining + 1e-12,
        "{dev:e} > {:e}",
        end.remaining
    );
}

/// Newton on the spheres converges quadratically from the straight beam: at most 8 iterations
/// for the spatial catalogue scenes and for a large deflection (the loads of
/// [`bad_spatial_statics_give_typed_errors`] at a tenth, F = 10⁵ N: joint 10 at 175°), and in its last steps above round-off each residual is at
/// most the square of the one before, r_{k+1} ≤ r_k² (the residual is scaled by the largest
/// spring, so C ≈ 1 for these beams; a linearly converging iteration would fail this).
#[test]
fn newton_on_the_spheres_converges_quadratically() {
    let f = 1e5;
    let near_fold = riser()
        .point_load_vector(8, [f, 0.0])
        .point_load_vector(9, [-2.0 * f, 0.0])
        .point_load_vector(10, [f, 0.0])
        .build()
        .unwrap();
    let spatial = catalogue::all().into_iter().filter(|(_, s)| s.is_spatial());
    for (name, scene) in spatial.chain([("near fold (joint 10 at 175°)", near_fold)]) {
        let sol = static_equilibrium(&scene).unwrap();
        let history: Vec<String> = sol.residuals.iter().map(|r| format!("{r:.1e}")).collect();
        println!("{name}: residuals {}", history.join(", "));
        assert!(sol.spatial && sol.iterations <= 8, "{name}");
        assert_eq!(sol.residuals.len(), sol.iterations + 1);
        for w in sol.residuals.windows(2) {
            if w[0] < 1e-3 && w[1] > 1e-13 {
                assert!(w[1] <= w[0] * w[0], "{name}: {:e} after {:e}", w[1], w[0]);
            }
        }
    }
}

/// Bad cases give typed errors, never a panic or a wrong answer: loads (F, −2F, F) along x at
/// nodes 8, 9 and 10 (energy F l (q₁₀ₓ − q₉ₓ)) turn pendulum 9 toward +x and pendulum 10 toward
/// −x; with F = 10⁶ N the spring of joint 10 (k = 1000, at most ½kπ² ≈ 5·10³ J against
/// 2F l = 2·10⁶ J) cannot stop the fold: the Newton iterates fold the beam beyond 179°
/// ([`Error::StaticFolded`], naming the Newton iteration rather than a time step; measured:
/// 179.45°; at F = 10⁵ N the equilibrium exists, at 175°). Also a
/// spatial pinned-pinned beam ([`Error::StaticNotIsolated`]) and an x control on a scene without
/// a control node.
#[test]
fn bad_spatial_statics_give_typed_errors() {
    let f = 1e6;
    let folded = riser()
        .point_load_vector(8, [f, 0.0])
        .point_load_vector(9, [-2.0 * f, 0.0])
        .point_load_vector(10, [f, 0.0])
        .build()
        .unwrap();
    let err = static_equilibrium(&folded).unwrap_err();
    println!("folded riser: {err}");
    assert!(
        matches!(err, Error::StaticFolded { joint: 10, .. }),
        "{err:?}"
    );
    assert!(!err.to_string().contains("step"), "{err}");

    let pinned = SceneBuilder::new(10)
        .support(Support::PinnedPinned)
        .point_load_vector(5, [1.0, 1.0])
        .build()
        .unwrap();
    let err = static_equilibrium(&pinned).unwrap_err();
    assert_eq!(
        err,
        Error::StaticNotIsolated {
            support: Support::PinnedPinned,
            tip: TipCondition::Locked
        }
    );
    println!("pinned-pinned: {err}");

    let no_control = riser().point_load_vector(5, [1.0, 1.0]).build().unwrap();
    let err = static_equilibrium_spatial(&no_control, 0.0, [1.0, 0.0]).unwrap_err();
    assert!(
        matches!(err, Error::Model(ModelError::NoControlNode)),
        "{err:?}"
    );
    // A 1-axis `static_equilibrium_at` of a spatial scene is the spatial solve with u_x = 0.
    let a = static_equilibrium_at(&no_control, 10.0, 0.0).unwrap();
    let b = static_equilibrium_spatial(&no_control, 10.0, [0.0, 0.0]).unwrap();
    assert_eq!(a, b);
}

//! The riser system an offshore engineer models: the top held by the vessel (`support =
//! "vessel"`, `[vessel]`; docs/conventions.md "A top held by the vessel").
//!
//! References: the fixed-fixed step (a vessel that holds the top still is exactly that beam), the
//! vessel's prescribed Z(t) (the constraint the step imposes), Richardson ratios of RATTLE's error
//! (order 2), an independent finite-element beam-column model for the natural periods (Hermite
//! cubic elements with the geometric stiffness of the effective tension, tests/common/
//! beam_column.rs, shared with tests/model/riser_scenes.rs), and the closed form of a tensioned
//! beam whose clamped top is displaced.

use crate::beam_column::{chain_frequencies, BeamColumn, Element, TopRotation};
use chainbeam::statics::static_equilibrium;
use chainbeam::{catalogue, simulate, Chain, Rao, Scene, SceneTrajectory, Support, Vessel};
use std::f64::consts::PI;

fn riser_300m() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    ))
    .unwrap()
}

/// riser_300m.toml with its top held by a vessel (and, if given, a `[vessel]` table), its
/// resolution changed.
fn riser_300m_vessel(vessel: &str, n: usize, h: f64, steps: usize) -> Scene {
    let text = riser_300m()
        .replace("support = \"riser\"", "support = \"vessel\"")
        .replace("pendulums = 80", &format!("pendulums = {n}"))
        .replace("step = 0.0125", &format!("step = {h}"))
        .replace("steps = 48000 ", &format!("steps = {steps} "));
    let text = text.split("[mpc]").next().unwrap().to_string() + vessel;
    Scene::from_toml_str(&text).unwrap()
}

fn planar(t: &SceneTrajectory) -> &chainbeam::Trajectory<f64, 2> {
    t.as_planar().expect("planar")
}

/// Reference: the fixed-fixed beam (eq. 2.4.1/2.4.2). A vessel that holds the top still over the
/// wellhead imposes l(q) = 0 and L M⁻¹ p = 0, the fixed-fixed beam's constraints, with the same
/// springs: the two runs must agree bit for bit, here in a current and irregular waves.
#[test]
fn a_vessel_holding_still_is_the_fixed_fixed_beam_bit_for_bit() {
    let vessel = riser_300m_vessel("", 12, 0.05, 400);
    let mut fixed = vessel.clone();
    fixed.beam.support = Support::FixedFixed;
    fixed.vessel = None;
    let (a, b) = (simulate(&vessel).unwrap(), simulate(&fixed).unwrap());
    let (a, b) = (planar(&a), planar(&b));
    for k in 0..=400 {
        assert_eq!(a.q(k), b.q(k), "step {k}");
        assert_eq!(a.moment[k].to_bits(), b.moment[k].to_bits(), "step {k}");
    }
    assert!(
        a.moment.iter().any(|m| m.abs() > 1e3),
        "the sea moves the riser"
    );
}

const RAO: &str = "
[vessel]
offset = 6.0
ramp = 30.0

[vessel.rao]
period = [4.0, 8.0, 12.0, 16.0, 20.0, 30.0]
amplitude = [0.02, 0.25, 0.6, 0.85, 0.95, 1.0]
phase = [-100.0, -95.0, -92.0, -91.0, -90.0, -90.0]
";

/// Reference: the vessel's Z(t) itself. At every step the top node's z is the vessel's, to the
/// Newton tolerance (1e-14 of the riser's length), and the wave-frequency surge is there: the
/// top moves by metres, and about its mean offset once the ramp is over.
#[test]
fn the_top_follows_the_vessel() {
    let scene = riser_300m_vessel(RAO, 20, 0.05, 2400);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let motion = chain.vessel().expect("a vessel");
    let traj = simulate(&scene).unwrap();
    let t = planar(&traj);
    let mut worst: f64 = 0.0;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..=2400 {
        let z = t.positions(k).last().unwrap()[2];
        let [target, _] = motion.at(k as f64 * 0.05);
        worst = worst.max((z - target).abs());
        assert_eq!(t.tip_target[k], if k == 0 { 0.0 } else { target });
        if k as f64 * 0.05 > 30.0 {
            lo = lo.min(z);
            hi = hi.max(z);
        }
    }
    println!("max |z_top - Z| = {worst:.2e} m; top z over 30-120 s in [{lo:.3}, {hi:.3}] m");
    assert!(worst <= 1e-14 * 300.0 * 4.0, "{worst}");
    assert!(hi - lo > 0.1 && lo > 2.0 && hi < 10.0, "[{lo}, {hi}]");
}

/// Reference: RATTLE is of order 2 with the rheonomic tip (docs/conventions.md). On the thesis
/// riser (n = 10, docs/conventions.md) with the vessel moving the top 5 cm over a 0.2 s ramp,
/// the error of z₅ and M₀ at T = 0.1 s (inside the ramp, where Z is smooth) against h = 1/51200 s
/// falls by 4 per halving of h from h = 1/400 s: each ratio of successive errors within
/// [3.8, 4.2]. (From the thesis's h = 0.01 s the first ratios are 6.3 and 5.1: not yet in the
/// asymptotic range.)
#[test]
fn the_step_stays_of_order_two_with_a_moving_top() {
    let run = |h: f64| {
        let mut s = catalogue::riser(5);
        s.beam.support = Support::Vessel;
        s.vessel = Some(Vessel {
            offset: 0.05,
            ramp: 0.2,
            rao: None,
            ..Vessel::default()
        });
        s.loads.drag = 10.0;
        let steps = (0.1 / h).round() as usize;
        s.time.step = h;
        s.time.steps = steps;
        let tr = simulate(&s).unwrap();
        let t = planar(&tr);
        [t.positions(steps)[4][2], t.moment[steps]]
    };
    let reference = run(1.0 / 51200.0);
    let errors: Vec<[f64; 2]> = [400.0, 800.0, 1600.0, 3200.0]
        .iter()
        .map(|&d| {
            let r = run(1.0 / d);
            [(r[0] - reference[0]).abs(), (r[1] - reference[1]).abs()]
        })
        .collect();
    for w in errors.windows(2) {
        for c in 0..2 {
            let ratio = w[0][c] / w[1][c];
            println!("error ratio ({}) {ratio:.4}", ["z5", "M0"][c]);
            assert!((3.8..=4.2).contains(&ratio), "{ratio}: {errors:?}");
        }
    }
}

/// An independent model (`beam_column::BeamColumn`): a tensioned Euler-Bernoulli beam-column
/// EI w⁗ − (T_e w′)′ + μ ẅ = 0 of the uniform pipe, T_e(y) = T − w_s (L − y) at each element's
/// mid-height, in `elements` equal Hermite cubic elements. Base clamped (w = w′ = 0), top
/// rotation clamped (w′ = 0, the chain's tip spring 2EI/l) or free (no tip spring), top
/// deflection free or held (w = 0).
struct UniformPipe {
    length: f64,
    ei: f64,
    mu: f64,
    tension: f64,
    weight: f64,
    top_held: bool,
    /// The top's rotation free (a flex joint without stiffness) instead of clamped.
    top_pinned: bool,
    elements: usize,
}

impl UniformPipe {
    fn frequencies(&self) -> Vec<f64> {
        let ne = self.elements;
        let l = self.length / ne as f64;
        let elements = (0..ne)
            .map(|e| {
                let y = (e as f64 + 0.5) * l;
                Element {
                    length: l,
                    ei: self.ei,
                    mu: self.mu,
                    tension: self.tension - self.weight * (self.length - y),
                    soil: 0.0,
                    end_mass: 0.0,
                }
            })
            .collect();
        BeamColumn {
            elements,
            hinges: Vec::new(),
            top_held: self.top_held,
            top_rotation: if self.top_pinned {
                TopRotation::Free
            } else {
                TopRotation::Clamped
            },
        }
        .frequencies()
    }
}

/// The first three periods of riser_300m (n = 80) as shipped (the top free, held by the tip
/// spring only), with its top held by the vessel (the tip spring 2EI/l, a clamp) and held with
/// no tip spring (a flex joint of no stiffness: pinned), against the finite-element beam-column
/// model of the same pipe (400 elements) with the same tension, weight and mass per length:
/// within 2 %. Measured: free 40.80 / 11.72 / 6.56 s, held and clamped 17.06 / 8.07 / 5.00 s,
/// held and pinned 17.81 / 8.45 / 5.25 s (each within 0.3 % of the beam-column model).
#[test]
fn riser_300m_periods_match_a_beam_column_model_free_and_held() {
    for (held, pinned) in [(false, false), (true, false), (true, true)] {
        let mut scene = Scene::from_toml_str(&riser_300m()).unwrap();
        if held {
            scene.beam.support = Support::Vessel;
        }
        if pinned {
            scene.beam.tip_stiffness = 0.0;
        }
        let pipe = scene.pipe.unwrap();
        let fe = UniformPipe {
            length: pipe.length,
            ei: pipe.bending_stiffness(),
            mu: pipe.mass_per_length(scene.water.density),
            tension: scene.loads.tension,
            weight: scene.loads.axial_weight,
            top_held: held,
            top_pinned: pinned,
            elements: 400,
        }
        .frequencies();
        let chain = chain_frequencies(&scene);
        for j in 0..3 {
            let (tc, tf) = (2.0 * PI / chain[j], 2.0 * PI / fe[j]);
            println!(
                "held {held} pinned {pinned} mode {}: chain {tc:.3} s, beam-column {tf:.3} s ({:+.3} %)",
                j + 1,
                100.0 * (tc / tf - 1.0)
            );
            assert!((tc / tf - 1.0).abs() < 0.02, "mode {}: {tc} vs {tf}", j + 1);
        }
    }
}

/// Reference: a beam under a uniform tension T, clamped at the base, whose clamped top is moved
/// sideways by Z₀: EI w⁗ − T w″ = 0 with w(0) = w′(0) = 0, w(L) = Z₀, w′(L) = 0, so
/// w = A + B y + C cosh αy + D sinh αy (α² = T/EI). The chain's static equilibrium with the
/// vessel's mean offset (n = 200 of the 10 m thesis-like beam) within 0.5 % of Z₀ at every node.
#[test]
fn a_static_offset_bends_the_riser_as_the_closed_form_says() {
    let (n, len, ei, t, z0) = (200, 10.0, 100.0, 50.0, 0.05);
    let l = len / n as f64;
    let mut s = Scene::builder(n)
        .length(l)
        .mass(l)
        .stiffness(ei / l)
        .base_stiffness(2.0 * ei / l)
        .tip_stiffness(2.0 * ei / l)
        .support(Support::Vessel)
        .tension(t)
        .step(1e-3)
        .steps(10)
        .build()
        .unwrap();
    s.vessel = Some(Vessel {
        offset: z0,
        ramp: 1.0,
        rao: None,
        ..Vessel::default()
    });
    let sol = static_equilibrium(&s).unwrap();
    let a = (t / ei).sqrt();
    // w(0) = 0: A + C = 0; w'(0) = 0: B + a D = 0; w(L) = Z0; w'(L) = 0.
    let (ch, sh) = ((a * len).cosh(), (a * len).sinh());
    let mat = nalgebra::Matrix4::new(
        1.0,
        0.0,
        1.0,
        0.0, //
        0.0,
        1.0,
        0.0,
        a, //
        1.0,
        len,
        ch,
        sh, //
        0.0,
        1.0,
        a * sh,
        a * ch,
    );
    let c = mat
        .lu()
        .solve(&nalgebra::Vector4::new(0.0, 0.0, z0, 0.0))
        .unwrap();
    let w = |y: f64| c[0] + c[1] * y + c[2] * (a * y).cosh() + c[3] * (a * y).sinh();
    let mut worst: f64 = 0.0;
    for (i, p) in sol.positions.iter().enumerate() {
        let y = (i + 1) as f64 * l;
        worst = worst.max((p[1] - w(y)).abs());
    }
    println!(
        "max |z - w| = {:.3e} m = {:.3} % of Z0",
        worst,
        100.0 * worst / z0
    );
    assert!(
        (sol.positions[n - 1][1] - z0).abs() < 1e-10,
        "the top sits at Z0"
    );
    assert!(worst < 5e-3 * z0, "{worst}");
}

/// Bad `[vessel]` tables are refused with the key named.
#[test]
fn bad_vessel_tables_name_their_key() {
    let base = riser_300m();
    let cases = [
        (base.replace("\n[mpc]\n", "\n[vessel]\noffset = 1.0\n[mpc]\n"), "vessel"),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"")
                .replace("\n[mpc]\n", "\n[vessel]\noffset = nan\n[mpc]\n"),
            "vessel.offset",
        ),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"")
                .replace("\n[mpc]\n", "\n[vessel]\noffset = 1.0\nramp = 0.0\n[mpc]\n"),
            "vessel.ramp",
        ),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"").replace(
                "\n[mpc]\n",
                "\n[vessel.rao]\nperiod = [5.0, 4.0]\namplitude = [1.0, 1.0]\nphase = [0.0, 0.0]\n[mpc]\n",
            ),
            "vessel.rao.period",
        ),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"").replace(
                "\n[mpc]\n",
                "\n[vessel.rao]\nperiod = [5.0]\namplitude = [-1.0]\nphase = [0.0]\n[mpc]\n",
            ),
            "vessel.rao.amplitude",
        ),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"").replace(
                "\n[mpc]\n",
                "\n[vessel.rao]\nperiod = [5.0]\namplitude = [1.0]\nphase = [0.0, 1.0]\n[mpc]\n",
            ),
            "vessel.rao.phase",
        ),
        (
            base.replace("support = \"riser\"", "support = \"vessel\"")
                .replace("direction = 0.0", "direction = 30.0"),
            "beam.support",
        ),
    ];
    for (text, key) in cases {
        let err = Scene::from_toml_str(&text).unwrap_err();
        assert_eq!(err.key(), Some(key), "{err}");
    }
    let rao = Rao {
        period: vec![5.0, 10.0],
        amplitude: vec![0.2, 1.0],
        phase: vec![-80.0, -90.0],
    };
    // Linear in the period between rows, the end rows' values outside.
    let at = |t: f64| rao.transfer(2.0 * PI / t);
    let [re, im] = at(7.5);
    assert!(((re * re + im * im).sqrt() - 0.6).abs() < 1e-12);
    assert!((im.atan2(re).to_degrees() + 85.0).abs() < 1e-9);
    assert_eq!(at(2.0), at(5.0));
    assert_eq!(at(30.0), at(10.0));
}

/// SHAKE and projected RK4 do not implement the moving tip: they refuse it by name.
#[test]
fn only_rattle_steps_a_tip_held_by_the_vessel() {
    let scene = riser_300m_vessel("", 8, 0.05, 10);
    for method in [
        chainbeam::integrators::IntegratorMethod::Shake,
        chainbeam::integrators::IntegratorMethod::ProjectedRk4,
    ] {
        let err = chainbeam::integrators::Integrator::new(&scene, method, 0.05)
            .map(|_| ())
            .unwrap_err();
        assert!(err.to_string().contains("vessel"), "{err}");
    }
}

// ---------------------------------------------------------------------------------------------
// Morison's drag node by node (`[pipe] drag_model = "morison"`)
// ---------------------------------------------------------------------------------------------

/// riser_300m.toml with Morison's drag node by node (and no momentum-drag constant), at another
/// resolution; `waves` false drops the sea.
fn riser_300m_morison(n: usize, h: f64, steps: usize, waves: bool) -> Scene {
    let mut text = riser_300m()
        .replace(
            "added_mass_coefficient = 1.0\n",
            "added_mass_coefficient = 1.0\ndrag_model = \"morison\"\n",
        )
        .replace("drag = 4.0020e-7 ", "# drag ")
        .replace("pendulums = 80", &format!("pendulums = {n}"))
        .replace("step = 0.0125", &format!("step = {h}"))
        .replace("steps = 48000 ", &format!("steps = {steps} "));
    text = text.split("\n[mpc]\n").next().unwrap().to_string();
    if !waves {
        let a = text.find("\n[loads.waves]\n").unwrap();
        let b = text.find("\n[time]\n").unwrap();
        text.replace_range(a..b, "");
    }
    Scene::from_toml_str(&text).unwrap()
}

/// Reference: Morison's load per unit length ½ ρ_w C_d D_o U² (DNV-RP-C205 eq. 6.1). In a uniform
/// current the straight riser at rest takes on node k exactly ½ ρ_w C_d D_o U² cₖ (cₖ its cell),
/// to 1e-12: the node forces are recovered from the generalised force as F = A Q,
/// Fₖ = Qₖ/lₖ − Qₖ₊₁/lₖ₊₁.
#[test]
fn a_uniform_current_gives_every_node_morisons_load() {
    let scene = riser_300m_morison(30, 0.05, 10, false);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let pipe = scene.pipe.unwrap();
    let per_length = 0.5 * 1025.0 * pipe.drag_coefficient * pipe.outer_diameter * 0.5 * 0.5;
    let n = chain.n();
    let mut q = vec![[0.0; 2]; n];
    let ctx = chainbeam::model::Ctx::new(0.0, 0.0, 0);
    chain.add_node_drag(&vec![[0.0; 2]; n], &ctx, 1.0, &mut q);
    let l = &scene.beam.lengths;
    for k in 0..n {
        let next = if k + 1 < n {
            q[k + 1][1] / l[k + 1]
        } else {
            0.0
        };
        let f = q[k][1] / l[k] - next;
        let cell = 0.5 * (l[k] + l.get(k + 1).copied().unwrap_or(0.0));
        let exact = per_length * cell;
        assert!(
            (f / exact - 1.0).abs() < 1e-12,
            "node {}: {f} vs {exact}",
            k + 1
        );
        assert_eq!(q[k][0], 0.0, "no axial load");
    }
}

/// Reference: the momentum drag with the per-pendulum weights (docs/conventions.md "Equivalent
/// drag constant"), which is Morison's load exactly under a uniform relative flow when
/// D = ½ ρ_w C_d D_o/(μ l₁ S₁). The static offset of riser_300m (n = 40) in its 0.5 m/s current:
/// both drags give the same shape to 1e-9 of the top's offset. (riser_300m.toml's D takes
/// S₁ = μL instead of μ(L − l/2), 1.3 % more at n = 40: its offset is 1.3 % short.)
#[test]
fn in_a_uniform_current_the_two_drags_agree_statically() {
    let morison = riser_300m_morison(40, 0.05, 10, false);
    let mut momentum = morison.clone();
    let mut pipe = momentum.pipe.unwrap();
    pipe.drag_model = chainbeam::scene::DragModel::Momentum;
    momentum.pipe = Some(pipe);
    // D l₁ S₁ μ = ½ ρ_w C_d D_o with S₁ = Σ mₖ (the whole chain's mass, its tip node half a cell):
    // the weights then give every pendulum its Morison load exactly (docs/conventions.md).
    let l = 300.0 / 40.0;
    let mu = pipe.mass_per_length(1025.0);
    let s1: f64 = momentum.beam.masses.iter().sum();
    momentum.loads.drag = pipe.drag_per_length(1025.0) / (l * mu * s1);
    let (a, b) = (
        static_equilibrium(&morison).unwrap(),
        static_equilibrium(&momentum).unwrap(),
    );
    let top = a.positions[39][1];
    println!(
        "static top offset {top:.6} m (momentum {:.6})",
        b.positions[39][1]
    );
    assert!(top > 1.0, "the current pushes the riser");
    for (pa, pb) in a.positions.iter().zip(&b.positions) {
        assert!((pa[1] - pb[1]).abs() < 1e-9 * top, "{pa:?} vs {pb:?}");
    }
}

/// Reference: Dual64 seeded on c through [`NodeDrag::implicit_half_step`] (a dense 2n × 2n
/// Jacobian on n = 6 nodes) against W = A⁻¹ Ω A applied to the unit vectors, and the step's
/// equation p − (h/2) Q(p) = c to round-off, in a current and waves at t = 37 s.
#[test]
fn the_node_half_step_solves_its_equation_and_its_jacobian_is_a_inverse_omega_a() {
    use chainbeam::model::{BlockSym, Ctx};
    use num_dual::Dual64;
    let scene = riser_300m_morison(6, 0.05, 1000, true);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let nd = chain.node_drag().unwrap();
    let n = 6;
    let h = 0.05;
    let c: Vec<[f64; 2]> = (0..n)
        .map(|k| [0.3 * k as f64 - 1.0, 2e4 * ((k as f64) * 1.7).sin()])
        .collect();
    let ls = (chain.lengths(), chain.inverse_lengths());
    let ctx = Ctx::new(37.0, 0.0, 0);
    let (mut p, mut om) = (vec![[0.0; 2]; n], vec![BlockSym::identity(); n]);
    let mut water = vec![[0.0; 2]; n];
    nd.water_momenta(&ctx, &mut water);
    nd.implicit_half_step(&c, ls, (h, &ctx, &water), &mut p, &mut om);
    let mut q = vec![[0.0; 2]; n];
    chain.add_node_drag(&p, &ctx, -0.5 * h, &mut q);
    let scale = c.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    for k in 0..n {
        for d in 0..2 {
            let r = p[k][d] + q[k][d] - c[k][d];
            assert!(
                r.abs() < 1e-13 * scale,
                "residual {r} at {k},{d} (scale {scale})"
            );
        }
    }
    let chain_d = chain.lift::<Dual64>();
    let nd_d = chain_d.node_drag().unwrap();
    let ls_d = (chain_d.lengths(), chain_d.inverse_lengths());
    let ctx_d = Ctx::new(37.0, Dual64::from(0.0), 0);
    let mut water_d = vec![[Dual64::from(0.0); 2]; n];
    nd_d.water_momenta(&ctx_d, &mut water_d);
    for j in 0..n {
        for e in 0..2 {
            let cd: Vec<[Dual64; 2]> = (0..n)
                .map(|k| {
                    std::array::from_fn(|d| {
                        Dual64::new(c[k][d], f64::from(u8::from(k == j && d == e)))
                    })
                })
                .collect();
            let (mut pd, mut omd) = (
                vec![[Dual64::from(0.0); 2]; n],
                vec![BlockSym::identity(); n],
            );
            nd_d.implicit_half_step(&cd, ls_d, (h, &ctx_d, &water_d), &mut pd, &mut omd);
            // W e = A⁻¹ Ω A e, with (A x)ₖ = xₖ/lₖ − xₖ₊₁/lₖ₊₁ and A⁻¹ the suffix sums times l.
            let l = chain.lengths();
            let y: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let ay: [f64; 2] = std::array::from_fn(|d| {
                        let x = |i: usize| f64::from(u8::from(i == j && d == e)) / l[i];
                        x(k) - if k + 1 < n { x(k + 1) } else { 0.0 }
                    });
                    om[k].apply(&ay)
                })
                .collect();
            let mut s = [0.0; 2];
            for k in (0..n).rev() {
                for d in 0..2 {
                    s[d] += y[k][d];
                    let w = s[d] * l[k];
                    let dual = pd[k][d].eps;
                    assert!(
                        (w - dual).abs() < 1e-12 * (1.0 + dual.abs()),
                        "W[{k},{d}; {j},{e}]: {w} vs {dual}"
                    );
                }
            }
        }
    }
}

/// References: central differences of whole simulations (dual-number forward mode through the
/// node half step and Newton's implicit-function update must agree to 1e-6), order 2 in h (error
/// ratios within [3.8, 4.2]), Newton's quadratic convergence with the node-form Newton matrix (at
/// most 3 iterations per step on average).
#[test]
fn node_morison_forward_derivatives_order_and_newton() {
    use chainbeam::adjoint::forward_value;
    use chainbeam::{BendingObjective, Parameter};
    use num_dual::Dual64;
    let scene = riser_300m_morison(12, 0.05, 400, true);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let value = |cd: f64| {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(Parameter::DragCoefficient, Dual64::new(cd, 1.0))
            .unwrap();
        let u = vec![Dual64::from(0.0); 401];
        forward_value(&ch, 0.05, 400, &u, &BendingObjective::summed_moment()).unwrap()
    };
    let fwd = value(1.0);
    let e = 1e-4;
    let fd = (value(1.0 + e).re - value(1.0 - e).re) / (2.0 * e);
    println!(
        "dJ/dC_d: forward {:.9e}, central differences {fd:.9e}",
        fwd.eps
    );
    assert!(
        (fwd.eps - fd).abs() < 1e-6 * fd.abs(),
        "{} vs {fd}",
        fwd.eps
    );

    let traj = simulate(&scene).unwrap();
    let mean = traj.newton_iterations() as f64 / 400.0;
    println!("mean Newton iterations per step {mean:.2}");
    assert!(mean <= 3.0, "{mean}");

    let run = |h: f64| {
        let mut s = riser_300m_morison(12, h, (20.0 / h).round() as usize, true);
        s.time.step = h;
        let tr = simulate(&s).unwrap();
        *tr.moment().last().unwrap()
    };
    let reference = run(0.05 / 64.0);
    let errors: Vec<f64> = [0.05, 0.025, 0.0125]
        .iter()
        .map(|&h| (run(h) - reference).abs())
        .collect();
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        println!("error ratio {ratio:.4}");
        assert!((3.8..=4.2).contains(&ratio), "{errors:?}");
    }
}

/// The discrete adjoint through the node drag: ∂J/∂θ of Σ M₀² for a piecewise-constant force at
/// the top (6 pieces) and the physical parameters C_d, the current's speed and the tension, in a
/// current and waves, against dual-number forward mode (1e-12 of the largest component) and
/// central differences (1e-6 of it).
#[test]
fn node_morison_adjoint_equals_forward_mode_and_finite_differences() {
    use chainbeam::adjoint::forward_value;
    use chainbeam::{
        BendingObjective, ControlMap, ControlProblem, Parameter, Parametrisation, PiecewiseControl,
    };
    use num_dual::Dual64;
    let steps = 240;
    let mut scene = riser_300m_morison(10, 0.05, steps, true);
    scene.control = Some(chainbeam::Control {
        node: 10,
        kind: chainbeam::ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    let map = Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 6 });
    let obj = BendingObjective::summed_moment();
    let prob = ControlProblem::builder(&scene)
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let theta: Vec<f64> = (0..6).map(|j| 2e4 * ((j as f64) * 1.3).sin()).collect();
    let params = [
        Parameter::DragCoefficient,
        Parameter::CurrentSpeed,
        Parameter::Tension,
    ];
    let adj = prob.adjoint(&theta, &params).unwrap();
    let mut g = vec![0.0; 6];
    map.transpose(&adj.control_gradient, &mut g);
    let scale = g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let chain_d = prob.chain_as::<Dual64>();
    for j in 0..6 {
        let th: Vec<Dual64> = theta
            .iter()
            .enumerate()
            .map(|(i, &t)| Dual64::new(t, f64::from(u8::from(i == j))))
            .collect();
        let mut u = vec![Dual64::from(0.0); steps + 1];
        map.controls(&th, &mut u);
        let fwd = forward_value(&chain_d, 0.05, steps, &u, &obj).unwrap().eps;
        assert!(
            (g[j] - fwd).abs() <= 1e-12 * scale,
            "dJ/dθ_{j}: adjoint {} vs forward {fwd}",
            g[j]
        );
        let eps = 1.0;
        let (mut tp, mut tm) = (theta.clone(), theta.clone());
        tp[j] += eps;
        tm[j] -= eps;
        let fd = (prob.value(&tp).unwrap() - prob.value(&tm).unwrap()) / (2.0 * eps);
        assert!(
            (fd - g[j]).abs() <= 1e-6 * scale,
            "dJ/dθ_{j}: FD {fd} vs adjoint {}",
            g[j]
        );
    }
    let u: Vec<Dual64> = prob
        .controls(&theta)
        .unwrap()
        .into_iter()
        .map(Dual64::from)
        .collect();
    for (pi, (&p, nominal)) in params.iter().zip([1.0, 0.5, 1.228e6]).enumerate() {
        let mut ch = prob.chain_as::<Dual64>();
        ch.set_parameter(p, Dual64::new(nominal, 1.0)).unwrap();
        let fwd = forward_value(&ch, 0.05, steps, &u, &obj).unwrap().eps;
        let a = adj.parameter_gradient[pi];
        println!("dJ/d{p:?}: adjoint {a:.12e}, forward {fwd:.12e}");
        assert!(
            (a - fwd).abs() <= 1e-12 * fwd.abs().max(1e-300) * 5.0,
            "{p:?}: {a} vs {fwd}"
        );
    }
}

/// Still water: the node drag only dissipates. A riser set swinging by a ramped 5 m vessel offset
/// (over 10 s) then swings freely against the top held still: the energy averaged over
/// successive 2 s windows (RATTLE's own energy error oscillates at O(h²) within a window)
/// falls from window to window, and ends below the drag-free run's.
#[test]
fn node_morison_only_dissipates() {
    let run = |cd: f64| {
        let mut s = riser_300m_morison(16, 0.05, 1200, false);
        s.loads.current = None;
        let mut pipe = s.pipe.unwrap();
        pipe.drag_coefficient = cd;
        s.pipe = Some(pipe);
        s.beam.support = Support::Vessel;
        s.vessel = Some(Vessel {
            offset: 5.0,
            ramp: 10.0,
            rao: None,
            ..Vessel::default()
        });
        let tr = simulate(&s).unwrap();
        tr.energy()[201..]
            .chunks(40)
            .map(|w| w.iter().sum::<f64>() / w.len() as f64)
            .collect::<Vec<f64>>()
    };
    let (drag, free) = (run(1.0), run(0.0));
    println!("window energies with drag {drag:?}, without {free:?}");
    for w in drag.windows(2) {
        assert!(w[1] < w[0], "{drag:?}");
    }
    assert!(drag.last().unwrap() < free.last().unwrap());
}

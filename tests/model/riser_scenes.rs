//! The real riser-system scenes (examples/scenes/riser_300m_system.toml, riser_1000m_system.toml;
//! docs/riser-system.md): a stack-up from the conductor in the soil to the vessel, Morison's drag
//! node by node, hot spots.
//!
//! References: Morison's drag per unit length ½ ρ_w C_d D U² (DNV-RP-C205 eq. 6.1) computed here
//! from the files' own segment and body tables; the Froude-Krylov surge of a box-shaped hull (the
//! files' RAO tables, recomputed here from the formula their comments give); and an independent
//! finite-element beam-column model of the same stack-up for the natural periods (Hermite cubic
//! elements, tests/common/beam_column.rs, shared with tests/model/riser_system.rs; the stack-up's
//! elements built here: varying EI and mass per element, the bodies as lumped masses on stiff
//! elements, Winkler soil springs, the flex joints as rotational springs across a hinge, the top
//! held by the vessel, the effective tension varying with height).

use crate::beam_column::{chain_frequencies, BeamColumn, Element, TopRotation};
use chainbeam::model::Ctx;
use chainbeam::scene::{Stackup, STANDARD_GRAVITY};
use chainbeam::statics::static_equilibrium;
use chainbeam::{simulate, Chain, Scene, Support};
use std::f64::consts::PI;

fn text(name: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/examples/scenes/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// The file's text with its `[loads.waves]` table (up to the next table) removed.
fn without_waves(mut text: String) -> String {
    let a = text.find("\n[loads.waves]\n").unwrap();
    let b = a + 1 + text[a + 1..].find("\n[").unwrap();
    text.replace_range(a..b, "");
    text
}

/// The file with `pendulums` and `step` replaced.
fn at(text: &str, n: usize, h: f64) -> String {
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with("pendulums = ") {
            out.push_str(&format!("pendulums = {n}\n"));
        } else if line.starts_with("step = ") {
            out.push_str(&format!("step = {h}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The segment or body named `part` in the stack-up as written: (½ ρ_w C_d D_h per length, or a
/// body's ½ ρ_w C_dA per body, is a body).
fn drag_of(st: &Stackup, part: &str, rho_w: f64) -> (f64, bool) {
    if let Some(s) = st.segments.iter().find(|s| s.name == part) {
        let dh = s
            .hydrodynamic_diameter
            .or(s.buoyancy_diameter)
            .unwrap_or(s.outer_diameter);
        return (0.5 * rho_w * s.drag_coefficient * dh, false);
    }
    let b = st.bodies.iter().find(|b| b.name == part).unwrap();
    (0.5 * rho_w * b.drag_area, true)
}

/// Reference: Morison's load per unit length ½ ρ_w C_d D_h U² (DNV-RP-C205 eq. 6.1) on every wet
/// half-pendulum of a segment, with that segment's C_d and hydrodynamic diameter (the buoyancy
/// modules' where it has them), and ½ ρ_w C_dA U²/2 on each end node of a body, from the files'
/// own tables. In the uniform 0.5 m/s current the straight riser at rest takes on every node
/// exactly that sum over its cell, to 1e-12 (the node forces recovered from the generalised force
/// as F = A Q, Fₖ = Qₖ/lₖ − Qₖ₊₁/lₖ₊₁); the conductor's nodes in the soil take none.
#[test]
fn a_uniform_current_gives_every_stackup_node_morisons_load() {
    for name in ["riser_300m_system", "riser_1000m_system"] {
        let scene = Scene::from_toml_str(&at(&without_waves(text(name)), 60, 0.01)).unwrap();
        let st = scene.stackup.as_ref().unwrap();
        assert_eq!(st.drag_model, chainbeam::scene::DragModel::Morison);
        assert_eq!(scene.loads.drag, 0.0, "no momentum-drag constant");
        let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
        assert!(chain.node_drag().is_some());
        let n = chain.n();
        let u = 0.5;
        let rho = scene.water.density;
        let mudline = scene.soil.unwrap().mudline;
        let l = &scene.beam.lengths;
        // Each pendulum's share: half of its Morison load to each end node.
        let mut expect = vec![0.0; n + 1];
        let mut y = 0.0;
        for (j, part) in st.layout.parts.iter().enumerate() {
            let wet = y + 0.5 * l[j] > mudline;
            y += l[j];
            let (c, body) = drag_of(st, part, rho);
            let load = if !wet {
                0.0
            } else if body {
                c * u * u
            } else {
                c * u * u * l[j]
            };
            expect[j] += 0.5 * load;
            expect[j + 1] += 0.5 * load;
        }
        let mut q = vec![[0.0; 2]; n];
        let ctx = Ctx::new(0.0, 0.0, 0);
        chain.add_node_drag(&vec![[0.0; 2]; n], &ctx, 1.0, &mut q);
        let scale = expect.iter().fold(0.0f64, |a, &b| a.max(b));
        for k in 0..n {
            let next = if k + 1 < n {
                q[k + 1][1] / l[k + 1]
            } else {
                0.0
            };
            let f = q[k][1] / l[k] - next;
            let e = expect[k + 1];
            assert!(
                (f - e).abs() <= 1e-12 * scale,
                "{name} node {}: {f} vs {e}",
                k + 1
            );
            if e == 0.0 {
                assert_eq!(f, 0.0, "{name} node {} in the soil", k + 1);
            }
        }
    }
}

/// The Froude-Krylov surge RAO of a box-shaped hull in head seas (the files' comments): length L,
/// draught T, water depth d, X/ζ = [sinh kd − sinh k(d − T)]/(kT cosh kd) · sin(kL/2)/(kL/2) ·
/// coth kd with ω² = g k tanh kd (g = 9.80665 m/s²); returns (amplitude, phase in degrees).
fn froude_krylov_surge(period: f64, depth: f64) -> (f64, f64) {
    let (g, hull, draught) = (STANDARD_GRAVITY, 228.0, 12.0);
    let w = 2.0 * PI / period;
    // Newton on g k tanh(kd) = ω², from the deep-water k.
    let mut k = w * w / g;
    for _ in 0..100 {
        let t = (k * depth).tanh();
        let f = g * k * t - w * w;
        let df = g * t + g * k * depth * (1.0 - t * t);
        k -= f / df;
    }
    let kd = k * depth;
    let vertical = if kd < 30.0 {
        (kd.sinh() - (k * (depth - draught)).sinh()) / (k * draught * kd.cosh())
    } else {
        (1.0 - (-k * draught).exp()) / (k * draught)
    };
    let half = 0.5 * k * hull;
    let x = vertical * half.sin() / half / kd.tanh();
    let zeros = (half / PI).floor() as i64;
    (x.abs(), if zeros % 2 == 0 { -90.0 } else { -270.0 })
}

/// Reference: the formula of the files' comments. Every row of both files' `[vessel.rao]` is the
/// Froude-Krylov surge of the 228 m × 12 m hull in the file's water depth, to the 4 decimals
/// printed (5e-5), and its phase exactly; the long waves approach the surface particles'
/// motion (A → coth kd, ψ = −90°).
#[test]
fn the_vessel_rao_tables_are_the_froude_krylov_surge_of_the_hull() {
    for (name, depth) in [("riser_300m_system", 300.0), ("riser_1000m_system", 1000.0)] {
        let scene = Scene::from_toml_str(&text(name)).unwrap();
        assert_eq!(scene.water.depth, Some(depth));
        let rao = scene.vessel.as_ref().unwrap().rao.as_ref().unwrap();
        assert!(rao.period.len() > 100);
        for i in 0..rao.period.len() {
            let (a, psi) = froude_krylov_surge(rao.period[i], depth);
            assert!(
                (rao.amplitude[i] - a).abs() <= 5.0001e-5,
                "{name} T = {}: {} vs {a}",
                rao.period[i],
                rao.amplitude[i]
            );
            assert_eq!(rao.phase[i], psi, "{name} T = {}", rao.period[i]);
        }
    }
}

/// One stretch of the finite-element model (a segment or body, by name): from `y0` to `y1`, bending stiffness, mass per
/// length (with added mass), submerged weight per length; a body instead carries `point_mass`
/// and `point_weight` (each end half).
struct Stretch {
    name: String,
    y0: f64,
    y1: f64,
    ei: f64,
    mu: f64,
    w: f64,
    body: Option<(f64, f64)>,
}

/// The stack-up as written, part by part from the foot up (each segment then the bodies standing
/// on it), with its own section properties: EI = E π/64 (D_o⁴ − D_i⁴), μ = ρ_s A_s + ρ_c A_i +
/// foam + lines + C_a ρ_w π D_h²/4, w = g (m_air − ρ_w (π D²/4 + line area)), D the modules' or
/// the pipe's outer diameter; a body on stiff elements (10 × the stiffest segment's EI, the
/// stack-up's default) with its mass and added mass and its submerged weight at its ends.
fn stretches(st: &Stackup, rho_w: f64) -> Vec<Stretch> {
    let stiffest = st
        .segments
        .iter()
        .map(|s| {
            let di = s.outer_diameter - 2.0 * s.wall_thickness;
            s.youngs_modulus * PI / 64.0 * (s.outer_diameter.powi(4) - di.powi(4))
        })
        .fold(0.0, f64::max);
    let mut out = Vec::new();
    let mut y = 0.0;
    for s in &st.segments {
        let (o, i) = (s.outer_diameter, s.outer_diameter - 2.0 * s.wall_thickness);
        let foam = match (s.buoyancy_diameter, s.buoyancy_density) {
            (Some(b), Some(rho)) => rho * PI / 4.0 * (b * b - o * o),
            _ => 0.0,
        };
        let air = s.steel_density * PI / 4.0 * (o * o - i * i)
            + s.contents_density * PI / 4.0 * i * i
            + foam
            + s.line_mass;
        let dh = s.hydrodynamic_diameter.or(s.buoyancy_diameter).unwrap_or(o);
        let outer = s.buoyancy_diameter.unwrap_or(0.0).max(o);
        let len = s.length * f64::from(s.joints);
        out.push(Stretch {
            name: s.name.clone(),
            y0: y,
            y1: y + len,
            ei: s.youngs_modulus * PI / 64.0 * (o.powi(4) - i.powi(4)),
            mu: air + s.added_mass_coefficient * rho_w * PI / 4.0 * dh * dh,
            w: STANDARD_GRAVITY * (air - rho_w * (PI / 4.0 * outer * outer + s.line_area)),
            body: None,
        });
        y += len;
        for b in st.bodies.iter().filter(|b| b.above == s.name) {
            out.push(Stretch {
                name: b.name.clone(),
                y0: y,
                y1: y + b.height,
                ei: b.bending_stiffness.unwrap_or(10.0 * stiffest),
                mu: 0.0,
                w: 0.0,
                body: Some((b.mass + b.added_mass, b.submerged_weight)),
            });
            y += b.height;
        }
    }
    out
}

/// The element sizes of the finite-element model: at most `fine` metres below the elevation
/// `above` (the conductor in its soil, the wellhead, the bodies, the lower flex joint), at most
/// `coarse` metres from there up.
#[derive(Clone, Copy, Debug)]
struct Mesh {
    fine: f64,
    coarse: f64,
    above: f64,
}

impl Mesh {
    /// Elements of at most `size` metres everywhere.
    fn uniform(size: f64) -> Self {
        Mesh {
            fine: size,
            coarse: size,
            above: 0.0,
        }
    }

    /// The largest element length on a stretch from `a` up.
    fn size_at(&self, a: f64) -> f64 {
        if a < self.above {
            self.fine
        } else {
            self.coarse
        }
    }
}

/// An independent model of a stack-up held by its vessel (`beam_column::BeamColumn`): the
/// stack-up's stretches cut at every part's end and at the mudline, each piece in Hermite cubic
/// elements of at most `mesh`'s size there (a body one stiff element with its mass at its ends);
/// T_e(y) = T − (the submerged weight above y, the bodies' at their ends) at each element's
/// middle; Winkler soil k_s = E₀ + E₁·depth at the element's middle below the mudline. The foot
/// clamped (w = w′ = 0), the lower flex joint a hinge with its rotational spring between the
/// rotations below and above it, the top held (w = 0) and turned against the vessel by the upper
/// flex joint's spring.
fn beam_column_frequencies(scene: &Scene, mesh: Mesh) -> Vec<f64> {
    let st = scene.stackup.as_ref().unwrap();
    let soil = scene.soil.unwrap();
    let parts = stretches(st, scene.water.density);
    let top = parts.last().unwrap().y1;
    // Flex joints by height: (height, stiffness).
    let flex: Vec<(f64, f64)> = st
        .flex_joints
        .iter()
        .map(|f| {
            let at = f.elevation.unwrap_or_else(|| {
                let name = f.above.as_deref().unwrap();
                parts.iter().find(|p| p.name == name).unwrap().y1
            });
            (at, f.stiffness)
        })
        .collect();
    // Elements: (y0, y1, stretch index).
    let mut cuts: Vec<f64> = parts.iter().map(|p| p.y1).collect();
    cuts.push(0.0);
    cuts.push(soil.mudline);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut spans = Vec::new();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let part = parts
            .iter()
            .position(|p| p.y0 <= a + 1e-9 && b <= p.y1 + 1e-9)
            .unwrap();
        let m = if parts[part].body.is_some() {
            1
        } else {
            ((b - a) / mesh.size_at(a)).ceil() as usize
        };
        for e in 0..m {
            let (e0, e1) = (
                a + (b - a) * e as f64 / m as f64,
                a + (b - a) * (e + 1) as f64 / m as f64,
            );
            spans.push((e0, e1, part));
        }
    }
    // Submerged weight above a height: distributed weight and the bodies' end weights.
    let weight_above = |y: f64| -> f64 {
        let mut sum = 0.0;
        for p in &parts {
            match p.body {
                None => sum += p.w * (p.y1 - p.y1.min(p.y0.max(y))),
                Some((_, wb)) => {
                    for end in [p.y0, p.y1] {
                        if end > y {
                            sum += 0.5 * wb;
                        }
                    }
                }
            }
        }
        sum
    };
    let elements: Vec<Element> = spans
        .iter()
        .map(|&(y0, y1, part)| {
            let p = &parts[part];
            let mid = 0.5 * (y0 + y1);
            Element {
                length: y1 - y0,
                ei: p.ei,
                mu: p.mu,
                tension: scene.loads.tension - weight_above(mid),
                soil: if mid < soil.mudline {
                    soil.modulus + soil.gradient * (soil.mudline - mid)
                } else {
                    0.0
                },
                end_mass: p.body.map_or(0.0, |b| b.0),
            }
        })
        .collect();
    // Node i at spans[i].0 (node spans.len() at the top).
    let node_y: Vec<f64> = spans
        .iter()
        .map(|e| e.0)
        .chain(std::iter::once(top))
        .collect();
    let mut hinges = Vec::new();
    let mut top_rotation = TopRotation::Free;
    for &(at, kf) in &flex {
        let j = node_y.iter().position(|&y| (y - at).abs() < 1e-6).unwrap();
        if j == spans.len() {
            top_rotation = TopRotation::Spring(kf);
        } else {
            hinges.push((j, kf));
        }
    }
    BeamColumn {
        elements,
        hinges,
        top_held: true,
        top_rotation,
    }
    .frequencies()
}

/// The first three periods of `scene` (the chain linearised about the straight riser) against
/// the finite-element beam-column model of the same stack-up on `mesh`, each printed with its
/// difference; returns the periods (chain, beam-column) in seconds.
fn first_three_periods(name: &str, scene: &Scene, mesh: Mesh) -> Vec<(f64, f64)> {
    let chain = chain_frequencies(scene);
    let fe = beam_column_frequencies(scene, mesh);
    (0..3)
        .map(|j| {
            let (tc, tf) = (2.0 * PI / chain[j], 2.0 * PI / fe[j]);
            println!(
                "{name} (n = {}) mode {}: chain {tc:.4} s, beam-column {tf:.4} s ({:+.3} %)",
                scene.n(),
                j + 1,
                100.0 * (tc / tf - 1.0)
            );
            (tc, tf)
        })
        .collect()
}

/// The first three periods of riser_300m_system.toml (its n, the top held by the vessel through
/// the upper flex joint, the conductor in its soil, the BOP and LMRP, the lower flex joint)
/// against the finite-element beam-column model of the same stack-up (elements of at most 0.5 m)
/// within 2 %.
#[test]
fn the_300m_system_periods_match_a_beam_column_model_of_its_stackup() {
    let scene = Scene::from_toml_str(&text("riser_300m_system")).unwrap();
    assert_eq!(scene.beam.support, Support::Vessel);
    for (j, (tc, tf)) in first_three_periods("riser_300m_system", &scene, Mesh::uniform(0.5))
        .into_iter()
        .enumerate()
    {
        assert!((tc / tf - 1.0).abs() < 0.02, "mode {}: {tc} vs {tf}", j + 1);
    }
}

/// The first three periods of riser_1000m_system.toml as shipped (its n and layout; the same
/// parts as the 300 m file, 1000 m of riser) against the finite-element beam-column model of the
/// same stack-up within 2 %. The model's elements are at most 0.5 m up to 80 m above the foot
/// (the conductor in its soil, whose characteristic length (4EI/E_s)^¼ is ≈ 10 m, the wellhead,
/// the BOP and LMRP, the lower flex joint) and at most 4 m above (the riser, whose first three
/// modes are hundreds of metres long): 457 elements where 0.5 m everywhere would be 2 099, a
/// dense eigenproblem too large for a debug test. That mesh is converged: the model on a mesh
/// twice as coarse (1 m and 8 m) gives periods within 0.1 % of it (Hermite elements' periods
/// converge as the fourth power of the element's length, so the finer mesh's own error is
/// ≈ 1/15 of that difference).
#[test]
fn the_1000m_system_periods_match_a_beam_column_model_of_its_stackup() {
    let scene = Scene::from_toml_str(&text("riser_1000m_system")).unwrap();
    assert_eq!(scene.beam.support, Support::Vessel);
    let mesh = Mesh {
        fine: 0.5,
        coarse: 4.0,
        above: 80.0,
    };
    let periods = first_three_periods("riser_1000m_system", &scene, mesh);
    let coarse = beam_column_frequencies(
        &scene,
        Mesh {
            fine: 1.0,
            coarse: 8.0,
            above: 80.0,
        },
    );
    for (j, &(tc, tf)) in periods.iter().enumerate() {
        let tcoarse = 2.0 * PI / coarse[j];
        println!(
            "mode {}: beam-column on the coarser mesh {tcoarse:.4} s ({:+.4} %)",
            j + 1,
            100.0 * (tcoarse / tf - 1.0)
        );
        assert!(
            (tcoarse / tf - 1.0).abs() < 1e-3,
            "mode {}: the beam-column model is not converged: {tcoarse} vs {tf}",
            j + 1
        );
        assert!((tc / tf - 1.0).abs() < 0.02, "mode {}: {tc} vs {tf}", j + 1);
    }
}

/// The scenes run: 2 s of each from its start (rest for 300 m, the static equilibrium for
/// 1000 m), finite, the top following the vessel; and they stand
/// in their current (`static_equilibrium`: the vessel's mean offset and the current push the
/// riser toward +z, the conductor's head held by the soil, moving far less than the top).
#[test]
fn the_system_scenes_run_and_stand() {
    for name in ["riser_300m_system", "riser_1000m_system"] {
        let mut scene = Scene::from_toml_str(&text(name)).unwrap();
        let h = scene.time.step;
        scene.time.steps = (2.0 / h).round() as usize;
        let traj = simulate(&scene).unwrap();
        let t = traj.as_planar().unwrap();
        let last = t.positions(scene.time.steps);
        assert!(last.iter().flatten().all(|x| x.is_finite()));
        assert!(t.moment.iter().all(|m| m.is_finite()));
        let eq = static_equilibrium(&scene).unwrap();
        let n = scene.n();
        let offset = scene.vessel.as_ref().unwrap().offset;
        assert!((eq.positions[n - 1][1] - offset).abs() < 1e-9 * offset);
        let mud = scene
            .beam
            .lengths
            .iter()
            .scan(0.0, |y, l| {
                *y += l;
                Some(*y)
            })
            .position(|y| (y - scene.soil.unwrap().mudline).abs() < 1e-6)
            .unwrap();
        let head = eq.positions[mud][1];
        println!("{name}: mudline deflection {head:.4} m, top {offset} m");
        assert!(head > 0.0 && head < 0.05 * offset);
    }
}

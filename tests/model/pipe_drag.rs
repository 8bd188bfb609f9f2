//! The per-pendulum Morison drag constant of a `[pipe]` scene (docs/conventions.md
//! "Equivalent drag constant"): pendulum i takes Dᵢ = D wᵢ, wᵢ = l₁S₁/(lᵢSᵢ)
//! (Sᵢ = Σ_{k≥i} m_k), so every pendulum gets the same share of its Morison load.
//!
//! References:
//! - **Morison's load, closed form.** Under a uniform relative flow U the node loads
//!   ½ ρ_w C_d D_o c_k U² on their cells c_k (l inside, l/2 at the tip) give pendulum i the
//!   generalised force lᵢ · ½ ρ_w C_d D_o (L − (i − 1) l − l/2) U² (the wetted length beyond joint
//!   i, written from the pipe's geometry, not from the chain's masses). With the scenes' rule
//!   D = ½ ρ_w C_d D_o/(l μ² L) the momentum drag must give that times the one share
//!   (L − l/2)/L on *every* pendulum (1e-12), planar and along a current turned by 35°; a beam
//!   given by its masses (no `[pipe]`) keeps one D, the thesis's eq. 2.4.4, whose share falls
//!   as (L − y)/L up the chain. The still-water drag (no current) takes the same Dᵢ.
//! - **Statics = the settled simulation.** The static solver (angle coordinates, planar; Newton
//!   on the spheres, spatial), which reads the current's steady force from the model, against a
//!   long RATTLE run settling onto it (1e-6 m), with the weights; and the weights move the
//!   equilibrium (it differs from the one-D beam's by more than 100× that).
//! - **MPC's planning chain** (src/mpc/planning.rs) gives its own pendulums the closed-form
//!   share of their Morison load, (L − l_p/2)/L with its own l_p: the weights of its
//!   discretisation, not the plant's.
//!
//! The exact gradients on a `[pipe]` wave scene (now with the weights) are in
//! tests/fatigue/wave_riser.rs; the non-pipe scenes' numbers, unchanged bit for bit, in the existing
//! tests (tests/steppers/verification.rs, tests/scene/tables.rs, tests/model/current.rs, ...).

use chainbeam::model::Ctx;
use chainbeam::mpc::planning::planning_scene;
use chainbeam::scene::{direction_of_angle, drag_weights};
use chainbeam::statics::static_equilibrium;
use chainbeam::*;

const RHO: f64 = 1025.0;
const LENGTH: f64 = 120.0;
const N: usize = 12;

/// A 120 m, 21" riser (D_o = 0.5334 m, t = 22.2 mm, C_d = 1.2) of `n` pendulums under 0.5 MN
/// top tension, drag D = ½ ρ_w C_d D_o/(l μ² L), a uniform `speed` current toward ψ (none for
/// speed 0) and step h.
fn pipe_scene(n: usize, psi: f64, speed: f64, h: f64, steps: usize) -> Scene {
    let pipe = chainbeam::scene::Pipe {
        drag_coefficient: 1.2,
        ..chainbeam::scene::Pipe::new(LENGTH, 0.5334, 0.0222)
    };
    let l = LENGTH / n as f64;
    let mu = pipe.mass_per_length(RHO);
    let d = pipe.drag_per_length(RHO) / (l * mu * mu * LENGTH);
    let [s, c] = direction_of_angle(psi);
    let current = if speed > 0.0 {
        format!(
            "[loads.current]\nprofile = \"uniform\"\nspeed = {speed:e}\n\
             direction = [{s:e}, {c:e}]\n\n"
        )
    } else {
        String::new()
    };
    let text = format!(
        "[beam]\npendulums = {n}\nsupport = \"riser\"\n\n\
         [pipe]\nlength = {LENGTH:e}\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\
         drag_coefficient = 1.2\n\n\
         [water]\ndepth = {LENGTH:e}\n\n\
         [loads]\ndrag = {d:e}\ntension = 5e5\n\n{current}\
         [time]\nstep = {h:e}\nsteps = {steps}\n"
    );
    let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(scene.pipe.unwrap(), pipe);
    scene
}

/// ½ ρ_w C_d D_o of the test pipe \[kg/m²\].
fn drag_per_length() -> f64 {
    0.5 * RHO * 1.2 * 0.5334
}

/// The force of the model's dissipative terms on every pendulum at rest (p = 0), as (x, z).
fn forces_at_rest<const DIM: usize>(scene: &Scene) -> Vec<[f64; 2]> {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let ctx = Ctx::new(0.0, 0.0, 0);
    (0..chain.n())
        .map(|i| {
            let f = chain.dissipative_force(i, &[0.0; DIM], &ctx).unwrap();
            [if DIM == 3 { f[0] } else { 0.0 }, f[DIM - 1]]
        })
        .collect()
}

/// Pendulum i (0-based) of a chain of n: Morison's load lᵢ · ½ ρ_w C_d D_o (L − i l − l/2) U²
/// (module docs).
fn morison_load(n: usize, i: usize, speed: f64) -> f64 {
    let l = LENGTH / n as f64;
    l * drag_per_length() * (LENGTH - i as f64 * l - 0.5 * l) * speed * speed
}

fn check_share<const DIM: usize>(psi: f64) {
    let speed = 0.7;
    let scene = pipe_scene(N, psi, speed, 0.02, 10);
    let share = 1.0 - 0.5 / N as f64;
    let dir = direction_of_angle(psi);
    for (i, f) in forces_at_rest::<DIM>(&scene).iter().enumerate() {
        let want = morison_load(N, i, speed) * share;
        for (c, d) in [(0, dir[0]), (1, dir[1])] {
            let err = (f[c] - want * d).abs();
            assert!(
                err <= 1e-12 * want,
                "ψ = {psi}°, pendulum {}: component {c}: {} vs {}",
                i + 1,
                f[c],
                want * d
            );
        }
    }
    // Without `[pipe]` (the same chain given by its masses) one D: the share (L − y)/L.
    let mut plain = scene.clone();
    plain.pipe = None;
    let forces = forces_at_rest::<DIM>(&plain);
    let l = LENGTH / N as f64;
    for (i, f) in forces.iter().enumerate() {
        let y = i as f64 * l;
        let want = morison_load(N, i, speed) * share * (LENGTH - y - 0.5 * l) / (LENGTH - 0.5 * l);
        let got = f[0].hypot(f[1]);
        assert!(
            (got - want).abs() <= 1e-12 * want,
            "one D, pendulum {}",
            i + 1
        );
    }
    println!(
        "DIM {DIM}, ψ = {psi}°: every pendulum {share:.6} of Morison's load; with one D the top \
         pendulum had {:.4}",
        forces[N - 1][0].hypot(forces[N - 1][1]) / morison_load(N, N - 1, speed)
    );
}

#[test]
fn every_pendulum_gets_the_same_share_of_its_morison_load() {
    check_share::<2>(0.0);
    check_share::<3>(35.0);
    // The scene's weights are the model's, and w₁ = 1 exactly.
    let scene = pipe_scene(N, 0.0, 0.7, 0.02, 10);
    let w = scene.drag_weights().unwrap();
    assert_eq!(w[0], 1.0);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    assert_eq!(chain.drag_weights(), Some(w.as_slice()));
    assert_eq!(
        w,
        drag_weights(&scene.beam.lengths, &scene.beam.masses),
        "one formula"
    );
}

#[test]
fn the_still_water_drag_takes_the_same_constants() {
    // Reference: −Dᵢ p|p| per component (eq. 2.4.4 with Dᵢ = D wᵢ), wᵢ in closed form
    // l₁S₁/(lᵢSᵢ) = (L − l/2)/(L − (i − 1) l − l/2) for the pipe's lumping.
    let scene = pipe_scene(N, 0.0, 0.0, 0.02, 10);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    assert!(chain.current_drag().is_none() && chain.drag().is_some());
    let ctx = Ctx::new(0.0, 0.0, 0);
    let l = LENGTH / N as f64;
    for i in 0..N {
        let w = (LENGTH - 0.5 * l) / (LENGTH - i as f64 * l - 0.5 * l);
        let p = [3.0e4, -2.0e5];
        let f = chain.dissipative_force(i, &p, &ctx).unwrap();
        for d in 0..2 {
            let want = -scene.loads.drag * w * p[d] * p[d].abs();
            assert!(
                (f[d] - want).abs() <= 1e-12 * want.abs(),
                "pendulum {}",
                i + 1
            );
        }
    }
}

/// Runs RATTLE from the straight beam until the largest momentum stays below `p_tol` for 500
/// steps; returns the node positions (x, y, z) and the time.
fn settle<const DIM: usize>(scene: &Scene, p_tol: f64, t_max: f64) -> (Vec<[f64; 3]>, f64) {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let n = chain.n();
    let mut r = Rattle::new(chain.clone(), scene.time.step).unwrap();
    let mut st = r.straight_state();
    let max_steps = (t_max / scene.time.step) as usize;
    let (mut k, mut window_max) = (0, 0.0f64);
    while k < max_steps {
        r.step(&mut st, k, 0.0, 0.0).unwrap();
        k += 1;
        window_max =
            st.p.iter()
                .flatten()
                .fold(window_max, |m, v| m.max(v.abs()));
        if k % 500 == 0 {
            if window_max < p_tol {
                break;
            }
            window_max = 0.0;
        }
    }
    assert!(k < max_steps, "settled within {t_max} s");
    let mut pos = vec![[0.0; DIM]; n];
    chain.node_positions(&st.q, &mut pos);
    let xyz = pos
        .iter()
        .map(|r| [if DIM == 3 { r[0] } else { 0.0 }, r[DIM - 2], r[DIM - 1]])
        .collect();
    (xyz, k as f64 * scene.time.step)
}

fn max_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let pairs = a.iter().zip(b);
    pairs.fold(0.0f64, |m, (a, b)| {
        (0..3).fold(m, |m, d| m.max((a[d] - b[d]).abs()))
    })
}

fn check_statics<const DIM: usize>(psi: f64) {
    let scene = pipe_scene(N, psi, 0.7, 0.02, 10);
    assert_eq!(scene.is_spatial(), DIM == 3);
    let stat = static_equilibrium(&scene).unwrap().positions_xyz();
    let (end, t) = settle::<DIM>(&scene, 1e-4, 2000.0);
    let dev = max_difference(&end, &stat);
    let mut plain = scene.clone();
    plain.pipe = None;
    let one_d = static_equilibrium(&plain).unwrap().positions_xyz();
    let moved = max_difference(&stat, &one_d);
    let tip = stat[N - 1][0].hypot(stat[N - 1][2]);
    println!(
        "DIM {DIM}, ψ = {psi}°: settled after {t:.0} s; tip offset {tip:.5} m; |dynamic − \
         static| = {dev:.2e} m; the weights move it by {moved:.2e} m"
    );
    assert!(tip > 1e-2, "a visible offset");
    assert!(dev <= 1e-6, "{dev:e}");
    assert!(moved > 1e-4, "the weights reach the statics: {moved:e}");
}

#[test]
fn statics_with_the_weights_is_where_the_simulation_settles() {
    check_statics::<2>(0.0);
    check_statics::<3>(35.0);
}

#[test]
fn the_planning_chain_weights_its_own_pendulums() {
    let plant = pipe_scene(N, 0.0, 0.7, 0.02, 10);
    for np in [4, 6, N] {
        let plan = planning_scene(&plant, np, 0.02).unwrap();
        let share = 1.0 - 0.5 / np as f64;
        for (i, f) in forces_at_rest::<2>(&plan).iter().enumerate() {
            let want = morison_load(np, i, 0.7) * share;
            assert!(
                (f[1] - want).abs() <= 1e-12 * want,
                "n_p = {np}, pendulum {}: {} vs {want}",
                i + 1,
                f[1]
            );
        }
    }
}

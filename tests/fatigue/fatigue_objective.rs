//! `[objective] kind = "fatigue"` (docs/fatigue.md, "Fatigue as an objective"): the rainflow Miner damage D(θ)
//! of the wellhead stress as an objective, its value, its exact adjoint gradient, and the
//! refusals.
//!
//! Scene: the thesis riser (examples/scenes/riser_5.toml: F = 2 N at node 5, control at node 10)
//! over 400 steps of 0.01 s, a piecewise control of 4 pieces, `[fatigue]` a 20 mm × 2 mm tube on
//! curve D in air (the section of tests/fatigue/fatigue.rs's simulated gradient check).
//!
//! References: `chainbeam::fatigue::assess` of `simulate`'s moment (the value, bit for bit);
//! central differences of f64 simulations with the pairing checked unchanged at θ ± ε (the
//! gradient, 1e-6 of max|g|); forward-mode dual numbers through the same damage with the
//! pairing held fixed (`forward_value` over `Dual64`, 1e-12).

use chainbeam::adjoint::forward_value;
use chainbeam::fatigue::{assess, rainflow, MomentHistory};
use chainbeam::{simulate, simulate_chain, ControlMap, ControlProblem, Scene};
use num_dual::Dual64;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PIECES: usize = 4;

fn scene_text(values: &[f64]) -> String {
    let values: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!(
        "[beam]\npendulums = 10\nlength = 1.0\nmass = 1.0\nstiffness = 1000.0\nsupport = \"riser\"\n\
         base_stiffness = 2000.0\ntip_stiffness = 2000.0\n\
         [[loads.point]]\nnode = 5\nforce = 2.0\n\
         [time]\nstep = 0.01\nsteps = 400\n\
         [control]\nnode = 10\nkind = \"piecewise\"\nvalues = [{}]\n\
         [objective]\nkind = \"fatigue\"\n\
         [fatigue]\nouter_diameter = 0.02\nwall_thickness = 0.002\ncurve = \"D\"\n\
         environment = \"air\"\n",
        values.join(", ")
    )
}

fn scene(values: &[f64]) -> Scene {
    Scene::from_toml_str(&scene_text(values)).unwrap()
}

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// The stress history's pairing: every cycle's turning points and count.
fn pairing(problem: &ControlProblem, theta: &[f64]) -> Vec<(usize, usize, u64)> {
    let u = problem.controls(theta).unwrap();
    let chain = problem.chain().clone();
    let traj = simulate_chain(chain, problem.time_step(), problem.steps(), &u).unwrap();
    rainflow(&traj.moment)
        .unwrap()
        .iter()
        .map(|c| (c.start, c.end, c.count.to_bits()))
        .collect()
}

/// The objective at the scene's own controls is `assess`'s damage of `simulate`'s moment (what
/// `chainbeam fatigue` reports), bit for bit.
#[test]
fn value_is_the_fatigue_damage_of_the_same_trajectory() {
    let values = [-1.0, 0.5, -2.0, 1.5];
    let scene = scene(&values);
    let problem = ControlProblem::builder(&scene).build_in::<2>().unwrap();
    let j = problem.value(&values).unwrap();
    let traj = simulate(&scene).unwrap();
    let a = assess(
        &scene.fatigue.unwrap(),
        MomentHistory {
            duration_s: 4.0,
            moment: traj.moment(),
            moment_x: None,
            measure: scene.moment_measure(),
        },
    )
    .unwrap();
    println!("J = {j:e}, assess = {:e}", a.damage);
    assert!(a.damage > 0.0);
    assert_eq!(j.to_bits(), a.damage.to_bits());
    let (jv, _) = problem.value_and_gradient(&values).unwrap();
    assert_eq!(jv.to_bits(), j.to_bits());
}

/// The adjoint gradient against central differences (ε = 1e-6 N, the pairing checked the same
/// at θ ± ε) and against forward dual numbers, at three random controls (ChaCha8 seed 31,
/// pieces uniform in [−4, 2] N).
#[test]
fn gradient_matches_central_differences_and_duals() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let problem = ControlProblem::builder(&scene(&[0.0; PIECES]))
        .build_in::<2>()
        .unwrap();
    let eps = 1e-6;
    for _ in 0..3 {
        let theta: Vec<f64> = (0..PIECES)
            .map(|_| -4.0 + 6.0 * uniform(&mut rng))
            .collect();
        let (j, g) = problem.value_and_gradient(&theta).unwrap();
        let gmax = g.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(j > 0.0 && gmax > 0.0);
        let base = pairing(&problem, &theta);
        for i in 0..PIECES {
            let mut plus = theta.clone();
            let mut minus = theta.clone();
            plus[i] += eps;
            minus[i] -= eps;
            assert_eq!(pairing(&problem, &plus), base, "θ = {theta:?}, +ε at {i}");
            assert_eq!(pairing(&problem, &minus), base, "θ = {theta:?}, −ε at {i}");
            let fd = (problem.value(&plus).unwrap() - problem.value(&minus).unwrap()) / (2.0 * eps);
            println!(
                "θ = {theta:.4?}: dD/dθ_{i} = {:.9e}, central {fd:.9e}",
                g[i]
            );
            assert!(
                (fd - g[i]).abs() <= 1e-6 * gmax,
                "θ = {theta:?}, i = {i}: {fd} vs {}",
                g[i]
            );
            // Forward mode: θ_i seeded, the controls u = P θ (piecewise map, linear).
            let mut seed = vec![0.0; PIECES];
            seed[i] = 1.0;
            let (mut u, mut du) = (vec![0.0; 401], vec![0.0; 401]);
            problem.map().controls(&theta, &mut u);
            problem.map().controls(&seed, &mut du);
            let ud: Vec<Dual64> = u
                .iter()
                .zip(&du)
                .map(|(a, b)| Dual64::new(*a, *b))
                .collect();
            let chain = problem.chain_as::<Dual64>();
            let jd = forward_value(&chain, 0.01, 400, &ud, problem.objective()).unwrap();
            assert_eq!(jd.re.to_bits(), j.to_bits());
            assert!(
                (jd.eps - g[i]).abs() <= 1e-12 * gmax,
                "θ = {theta:?}, i = {i}: dual {} vs adjoint {}",
                jd.eps,
                g[i]
            );
        }
    }
}

/// A Hessian-vector product of D (the current pairing's curvature, forward over adjoint) against
/// central differences of the adjoint gradient.
#[test]
fn hessian_vector_product_matches_differences_of_the_gradient() {
    let problem = ControlProblem::builder(&scene(&[0.0; PIECES]))
        .build_in::<2>()
        .unwrap();
    let theta = [-1.0, 0.5, -2.0, 1.5];
    let v = [0.3, -0.2, 0.5, 0.1];
    let hv = problem.hessian_vec(&theta, &v).unwrap();
    let eps = 1e-5;
    let at = |s: f64| -> Vec<f64> {
        let t: Vec<f64> = theta.iter().zip(&v).map(|(a, b)| a + s * b).collect();
        problem.gradient(&t).unwrap()
    };
    let (gp, gm) = (at(eps), at(-eps));
    let scale = hv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..PIECES {
        let fd = (gp[i] - gm[i]) / (2.0 * eps);
        println!("(Hv)_{i} = {:.9e}, difference {fd:.9e}", hv[i]);
        assert!((fd - hv[i]).abs() <= 1e-5 * scale, "{i}: {fd} vs {}", hv[i]);
    }
}

/// kind = "fatigue" without `[fatigue]` is a scene error naming the key `fatigue`.
#[test]
fn fatigue_objective_without_fatigue_table_names_the_key() {
    let text = scene_text(&[0.0; PIECES]);
    let cut = text.find("[fatigue]").unwrap();
    let err = Scene::from_toml_str(&text[..cut]).unwrap_err();
    assert_eq!(err.key(), Some("fatigue"), "{err}");
    // The scene round-trips: kind = "fatigue" is written back and resolved again.
    let s = scene(&[0.0; PIECES]);
    assert_eq!(Scene::from_toml_str(&s.to_toml_string()).unwrap(), s);
}

fn cli(dir: &std::path::Path, args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_chainbeam"))
        .current_dir(dir)
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The command line: `gradient` reports kind "fatigue" and `chainbeam fatigue`'s damage as its
/// objective; `optimize` with L-BFGS lowers it; `--method riccati` and `condensed` refuse it
/// naming kind = "power" with the S-N slope m = 3; `mpc` plans on that proxy and reports the
/// run's rainflow damage, which `chainbeam fatigue --series` of its CSV reproduces.
#[test]
fn command_line_gradient_optimize_refusals_and_mpc() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), scene_text(&[-1.0, 0.5, -2.0, 1.5])).unwrap();
    let json = |s: &str| -> serde_json::Value { serde_json::from_str(s).unwrap() };
    let (ok, g, e) = cli(d, &["gradient", "s.toml"]);
    assert!(ok, "{e}");
    let g = json(&g);
    assert_eq!(g["objective_kind"], "fatigue");
    let (ok, f, e) = cli(d, &["fatigue", "s.toml"]);
    assert!(ok, "{e}");
    assert_eq!(g["objective"], json(&f)["damage"]);

    let (ok, o, e) = cli(
        d,
        &["optimize", "s.toml", "--method", "lbfgs", "--bound", "5"],
    );
    assert!(ok || o.contains("objective"), "{e}");
    let o = json(&o);
    let (j0, j1) = (
        g["objective"].as_f64().unwrap(),
        o["objective"].as_f64().unwrap(),
    );
    println!("L-BFGS: D from {j0:e} to {j1:e}");
    assert!(j1 < j0);

    for m in ["riccati", "condensed"] {
        let (ok, _, e) = cli(d, &["optimize", "s.toml", "--method", m]);
        assert!(!ok);
        assert!(
            e.contains("kind = \"power\", exponent = 3") && e.contains("kind = \"fatigue\""),
            "{m}: {e}"
        );
    }

    let (ok, _, e) = cli(
        d,
        &["mpc", "s.toml", "-o", "mpc.csv", "--summary", "mpc.json"],
    );
    assert!(ok, "{e}");
    let summary = json(&std::fs::read_to_string(d.join("mpc.json")).unwrap());
    let (ok, f, e) = cli(d, &["fatigue", "s.toml", "--series", "mpc.csv"]);
    assert!(ok, "{e}");
    assert!(summary["fatigue_damage"].as_f64().unwrap() > 0.0);
    assert_eq!(summary["fatigue_damage"], json(&f)["damage"]);
}

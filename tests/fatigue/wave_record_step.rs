//! `[loads.waves] record_step` (docs/scene-format.md "[loads.waves]"): the wave record kept every
//! r steps, read at the plant's steps by cubic Hermite interpolation of each series with its
//! exact time derivative.
//!
//! - **Absent or equal to `time.step`**: every number of a run is the one without the key, bit
//!   for bit (`==` on f64).
//! - **Interpolation error**: the model's series Wᵢ (from u) and Gᵢ (from u̇) at every plant step
//!   and half step against their exact values (the direct sum of the components, and the
//!   every-step FFT record at the plant steps), bounded by the closed form of cubic Hermite
//!   interpolation, |y − p| ≤ H⁴/384 · max|y⁗| ≤ H⁴/384 · Σⱼ |Xⱼ| ωⱼ⁴ for y = Re Σⱼ Xⱼ e^{iωⱼ t}
//!   (H = r h), and converging at order 4 (halving H divides the error by about 16; linear
//!   interpolation would give 4).
//! - **Exact gradients** of the model as interpolated: adjoint = forward-mode Dual64 (1e-12) =
//!   five-point central differences (1e-6).
//! - **Typed errors** naming the key; the record's memory check counts the coarser record (the
//!   3-hour `riser_1000m.toml`, over the 4 GiB record and the 8 GiB stored trajectory before, is a
//!   valid scene).
//! - **The shipped deep riser**: the wellhead moment of a shortened `riser_1000m.toml` run with
//!   its `record_step` against a record at every step.

use chainbeam::adjoint::{adjoint_gradient, forward_value};
use chainbeam::*;
use num_dual::Dual64;

use crate::gradient_check;

const H: f64 = 0.05;

/// A 100 m, 21" riser of 10 pendulums in 100 m of water, a uniform 0.5 m/s current and a JONSWAP
/// sea (H_s = 4 m, T_p = 10 s, seed 7, 400 components: ω_c = 6 ω_p = 3.77 rad/s), with the
/// `[loads.waves]` line `extra` (tests/fatigue/wave_riser.rs's scene).
fn scene_text(extra: &str, steps: usize, control: &str) -> String {
    format!(
        "[beam]\npendulums = 10\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 100.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 100.0\n\n\
         [loads]\ndrag = 2e-6\ntension = 2e6\naxial_weight = 1500.0\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.5\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 4.0\ntp = 10.0\nseed = 7\n\
         components = 400\n{extra}\n\n\
         [time]\nstep = {H}\nsteps = {steps}\n\n{control}"
    )
}

fn scene(extra: &str, steps: usize) -> Scene {
    let text = scene_text(extra, steps, "");
    Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn record_step_equal_to_the_time_step_changes_no_bit() {
    let base = scene("", 300);
    let same = scene(&format!("record_step = {H}"), 300);
    assert_eq!(same.loads.waves.unwrap().record_step, Some(H));
    assert_eq!(same.loads.waves.unwrap().record_stride(H).unwrap(), 1);
    let (a, b) = (simulate(&base).unwrap(), simulate(&same).unwrap());
    assert_eq!(a.moment(), b.moment());
    assert_eq!(a.energy(), b.energy());
    for k in [0, 1, 150, 300] {
        assert_eq!(a.positions(k), b.positions(k), "step {k}");
    }
    assert!(a.moment().iter().any(|m| *m != 0.0));
    // The key reads back.
    let again = Scene::from_toml_str(&same.to_toml_string()).unwrap();
    assert_eq!(again, same);
}

/// max over pendulums, plant steps and half steps of |field − exact| for the momentum
/// (`inertia = false`) or inertia series, with the Hermite bound of each series.
fn interpolation_error(r: usize, inertia: bool) -> (f64, f64, f64) {
    let steps = 400;
    let exact = Chain::<f64, 2>::from_scene(&scene("", steps)).unwrap();
    let coarse_scene = scene(&format!("record_step = {}", r as f64 * H), steps);
    let coarse = Chain::<f64, 2>::from_scene(&coarse_scene).unwrap();
    let (fe, fc) = (exact.waves().unwrap(), coarse.waves().unwrap());
    assert_eq!(fc.record_step(), r as f64 * H);
    let sea = fe.sea();
    let omega = sea.frequencies();
    let hr = r as f64 * H;
    let (mut err, mut worst_ratio, mut scale) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..coarse_scene.n() {
        let amp = fe.amplitudes(i, inertia);
        assert_eq!(amp, fc.amplitudes(i, inertia));
        // H⁴/384 · Σⱼ |Xⱼ| ωⱼ⁴ (the fourth derivative's largest possible value).
        let bound = hr.powi(4) / 384.0
            * amp
                .iter()
                .zip(omega)
                .map(|(x, w)| x.norm() * w.powi(4))
                .sum::<f64>();
        let read = |f: &chainbeam::model::WaveField, t: f64| {
            if inertia {
                f.inertia(i, t)
            } else {
                f.momentum(i, t)
            }
        };
        // Round-off of the sums and the transforms: 1e-11 of the series' amplitude sum.
        let slack = 1e-11 * amp.iter().map(|x| x.norm()).sum::<f64>();
        let mut e_i = 0.0f64;
        for k in 0..=2 * steps {
            let t = k as f64 * 0.5 * H;
            let y = sea.sum_at(amp, t);
            scale = scale.max(y.abs());
            e_i = e_i.max((read(fc, t) - y).abs());
            if k % 2 == 0 {
                // The every-step record (one FFT) at the plant steps: the same values.
                e_i = e_i.max((read(fc, t) - read(fe, t)).abs());
                assert!(
                    (read(fe, t) - y).abs() <= slack,
                    "the every-step record at {t}"
                );
            }
        }
        assert!(
            e_i <= bound + slack,
            "r = {r}, pendulum {i}, inertia {inertia}: error {e_i:e} over the bound {bound:e}"
        );
        worst_ratio = worst_ratio.max(e_i / bound);
        err = err.max(e_i);
    }
    (err, worst_ratio, scale)
}

#[test]
fn hermite_record_error_is_within_its_closed_form_bound_and_fourth_order() {
    let sea_len = {
        let c = Chain::<f64, 2>::from_scene(&scene("", 400)).unwrap();
        let sea = c.waves().unwrap().sea();
        (sea.repeat_period() / H).round() as usize
    };
    for inertia in [false, true] {
        let mut last: Option<f64> = None;
        for r in [2, 4, 8] {
            let (err, ratio, scale) = interpolation_error(r, inertia);
            let path = if sea_len.is_multiple_of(r) {
                "M/r"
            } else {
                "M, every r-th"
            };
            println!(
                "{} r = {r} (H = {} s, FFT {path}, M = {sea_len}): max error {err:.3e} of a \
                 series of size {scale:.3e}, {ratio:.3} of the bound",
                if inertia { "G (u̇)" } else { "W (u)" },
                r as f64 * H
            );
            assert!(err > 0.0, "the record is interpolated");
            if let Some(prev) = last {
                // Order 4: doubling H multiplies the error by about 2⁴ = 16 (linear
                // interpolation: 4); more than 8 = 2³ shows the order is above 3.
                let order = (err / prev).log2();
                println!("  observed order {order:.2}");
                assert!(order > 3.0, "order {order}");
            }
            last = Some(err);
        }
    }
    // Both synthesis paths ran (r = 2 divides M = 13334, r = 4 and 8 do not).
    assert!(
        sea_len.is_multiple_of(2) && !sea_len.is_multiple_of(4),
        "M = {sea_len}"
    );
}

#[test]
fn record_step_errors_name_the_key() {
    for bad in ["0.075", "0.025", "0.0", "-0.1", "nan", "inf", "1e300"] {
        let text = scene_text(&format!("record_step = {bad}"), 10, "");
        let e = Scene::from_toml_str(&text).unwrap_err();
        assert_eq!(e.key(), Some("loads.waves.record_step"), "{bad}: {e}");
        let msg = e.to_string();
        assert!(msg.contains("whole multiple"), "{bad}: {msg}");
    }
    // A derived scene with another time step keeps a record step on its grid.
    let mut w = scene("record_step = 0.2", 10).loads.waves.unwrap();
    w.fit_record_step(0.03);
    assert_eq!(w.record_step, Some(6.0 * 0.03));
    w.fit_record_step(0.5);
    assert_eq!(w.record_step, Some(0.5));
}

/// riser_1000m.toml over 3 hours (N = 1 728 000 at n = 320): the record at every step needs
/// (2n + 1)·8 bytes per step, 8.87 GB, over the 4 GiB limit; with the file's record step r h it
/// needs (4n + 2)·8 bytes every r steps. Validation only (the run is the benchmark's).
#[test]
fn the_three_hour_deep_riser_is_a_valid_scene() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_1000m.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let long = text.replace("steps = 96000 ", "steps = 1728000 ");
    assert_ne!(long, text);
    let scene = Scene::from_toml_str(&long).unwrap();
    let w = scene.loads.waves.unwrap();
    let r = w.record_stride(scene.time.step).unwrap();
    assert!(r > 1, "the file sets a record step");
    // A run that stores the trajectory is still refused, by the budget's own check.
    let e = scene.check_stored_trajectory().unwrap_err();
    assert_eq!(e.key(), Some("time.steps"));
    assert!(
        e.to_string().contains("at most 557497 for this beam"),
        "{e}"
    );
    // Without the record step the record is over its limit, naming time.steps and the key.
    let mut every = scene.clone();
    every.loads.waves.as_mut().unwrap().record_step = None;
    let e = every.validate().unwrap_err();
    assert_eq!(e.key(), Some("time.steps"));
    let msg = e.to_string();
    assert!(
        msg.contains("1728001 times × 320 pendulums needs 8861189128 bytes"),
        "{msg}"
    );
    assert!(msg.contains("`loads.waves.record_step`"), "{msg}");
}

/// dJ/dθ of J = Σ_k M₀(t_k)² on a wave scene with a record every 4 steps: the discrete adjoint
/// against forward-mode Dual64 through the whole simulation (1e-12 relative) and five-point
/// central differences (1e-6), for the drag constant, the tension and two controls.
#[test]
fn gradients_are_exact_for_the_interpolated_model() {
    let steps = 60;
    let values: Vec<String> = (0..=steps)
        .map(|k| format!("{:e}", -2e4 * (0.1 * k as f64).sin()))
        .collect();
    let control = format!(
        "[control]\nkind = \"per-step\"\nvalues = [{}]\n",
        values.join(", ")
    );
    let text = scene_text("record_step = 0.2", steps, &control);
    let scene = Scene::from_toml_str(&text).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    assert_eq!(chain.waves().unwrap().record_step(), 0.2);
    let u = scene_controls(&scene);
    let obj = BendingObjective::summed_moment();
    let params = [(Parameter::Drag, 2e-6), (Parameter::Tension, 2e6)];
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adj = adjoint_gradient(&chain, H, steps, &u, &obj, &ps, Checkpointing::default()).unwrap();
    let ud: Vec<Dual64> = u.iter().map(|&x| Dual64::from(x)).collect();
    let five_point = gradient_check::five_point;
    let check = |label: String, adjoint: f64, fwd: f64, fd: f64| {
        gradient_check::assert_derivative(&label, adjoint, fwd, fd);
    };
    for (i, &(p, value)) in params.iter().enumerate() {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(p, Dual64::new(value, 1.0)).unwrap();
        let fwd = forward_value(&ch, H, steps, &ud, &obj).unwrap().eps;
        let at = |v: f64| {
            let mut ch = chain.clone();
            ch.set_parameter(p, v).unwrap();
            forward_value(&ch, H, steps, &u, &obj).unwrap()
        };
        let fd = five_point(&at, value, 1e-4 * value);
        check(format!("{p:?}"), adj.parameter_gradient[i], fwd, fd);
    }
    for k in [0, steps / 3] {
        let mut seeded = ud.clone();
        seeded[k] = Dual64::new(u[k], 1.0);
        let fwd = forward_value(&chain.lift::<Dual64>(), H, steps, &seeded, &obj)
            .unwrap()
            .eps;
        let at = |v: f64| {
            let mut w = u.clone();
            w[k] = v;
            forward_value(&chain, H, steps, &w, &obj).unwrap()
        };
        let fd = five_point(&at, u[k], 10.0);
        check(format!("u[{k}]"), adj.control_gradient[k], fwd, fd);
    }
}

/// The shipped deep riser's wellhead moment with its record step against a record at every step:
/// the first 40 s (6400 steps of 320 pendulums) of `riser_1000m.toml`, the statistics the file's
/// convergence study reports (mean, standard deviation and peak |M₀|). Tolerance: 1e-3 relative,
/// a tenth of the 1 % to which the file's n and h are converged (its comments): the record step
/// must not add an error comparable with the discretisation's. The kinematics' own error is far
/// below (`hermite_record_error_is_within_its_closed_form_bound_and_fourth_order`).
#[test]
fn the_deep_riser_wellhead_moment_with_its_record_step() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_1000m.toml");
    let mut coarse = Scene::from_file(path).unwrap();
    let h = coarse.time.step;
    coarse.time.steps = (40.0 / h).round() as usize;
    let rs = coarse
        .loads
        .waves
        .unwrap()
        .record_step
        .expect("the file's record step");
    let mut every = coarse.clone();
    every.loads.waves.as_mut().unwrap().record_step = None;
    let stats = |s: &Scene| {
        let m = moment_history(s).unwrap().moment;
        let len = m.len() as f64;
        let mean = m.iter().sum::<f64>() / len;
        let std = (m.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / len).sqrt();
        let peak = m.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        [mean, std, peak]
    };
    let (a, b) = (stats(&every), stats(&coarse));
    for (name, (x, y)) in ["mean", "std", "peak"].iter().zip(a.iter().zip(&b)) {
        let rel = (y - x).abs() / x.abs();
        println!("record_step {rs} s vs {h} s: {name} {y:.9e} vs {x:.9e}, relative {rel:.2e}");
        assert!(rel <= 1e-3, "{name}: {rel:e}");
    }
}

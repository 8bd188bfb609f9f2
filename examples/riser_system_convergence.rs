//! The convergence study of the riser-system scenes (examples/scenes/riser_300m_system.toml,
//! riser_1000m_system.toml; docs/riser-system.md): the moment at each hot spot
//! (`[[fatigue.hotspot]]`: the joint torques M_j = k_j θ_j interpolated linearly in elevation
//! between the two joints around it, `hotspots::interpolation_joints`) with other numbers of
//! pendulums n and steps h.
//!
//! For each (n, h), the scene file is read again with `pendulums` and `step` replaced (a
//! stack-up's chain is laid out when the file is read: its pendulum ends fall on the parts' ends,
//! the flex joints and the mudline) and `steps` set to cover T, and it reports per hot spot:
//! - the static moment in the current and at the vessel's mean offset
//!   (`statics::static_equilibrium` without the waves, the joint torques of its attitudes);
//! - the mean and the standard deviation (the rms about the mean) of M_j(t) over t ∈ [T₀, T] of
//!   the irregular sea (`hotspots::joint_moment_history`, streamed);
//! - the CPU time of the run (user + system of this process, from /proc/self/stat; the machine
//!   may be shared, so CPU rather than wall time).
//!
//! It also prints, for the static solution, the elevation of the largest moment below the mudline
//! (where the conductor's hot spot belongs).
//!
//! `cargo run --release --example riser_system_convergence -- SCENE.toml T0 T n1,n2,… h1,h2,…`

use std::time::Instant;

use chainbeam::hotspots::{
    hot_spot_joints, interpolation_joints, joint_elevations, joint_moment, joint_moment_history,
};
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Scene};

fn list<T: std::str::FromStr>(s: &str) -> Vec<T> {
    s.split(',')
        .map(|x| x.parse().ok().expect("a number"))
        .collect()
}

/// User + system CPU seconds of this process so far (Linux: /proc/self/stat, fields 14 and 15 in
/// clock ticks of 1/100 s); `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: split after it.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// The scene file's text with `pendulums`, `step` and `steps` replaced.
fn at(text: &str, n: usize, h: f64, steps: usize) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let key = line.split('=').next().unwrap_or("").trim();
        match key {
            "pendulums" => out.push_str(&format!("pendulums = {n}\n")),
            "step" => out.push_str(&format!("step = {h}\n")),
            "steps" => out.push_str(&format!("steps = {steps}\n")),
            _ => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// The joint torques (N·m) of a planar chain's static attitudes at `joints` (0-based).
fn static_moments(scene: &Scene, joints: &[usize]) -> (Vec<f64>, Vec<f64>) {
    // In the current alone (the waves' loads are time-dependent), at the end of the run (the
    // vessel's ramp over: its mean offset).
    let mut still = scene.clone();
    still.loads.waves = None;
    let chain = Chain::<f64, 2>::from_scene(&still).expect("model");
    let eq = static_equilibrium(&still).expect("statics");
    let n = scene.n();
    // The planar attitudes (y, z) of the (x, y, z) unit vectors.
    let q: Vec<[f64; 2]> = eq.attitudes.iter().map(|a| [a[1], a[2]]).collect();
    let e = [1.0, 0.0];
    let moment = |i: usize| {
        let k = if chain.has_spring(i) {
            chain.springs()[i]
        } else {
            0.0
        };
        let a = if i == 0 { &e } else { &q[i - 1] };
        let b = if i == n { &e } else { &q[i] };
        joint_moment(a, b, k)[1]
    };
    let all: Vec<f64> = (0..=n).map(moment).collect();
    (joints.iter().map(|&i| all[i]).collect(), all)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 6 {
        eprintln!("usage: riser_system_convergence SCENE.toml T0 T n1,n2,... h1,h2,...");
        std::process::exit(2);
    }
    let text = std::fs::read_to_string(&args[1]).expect("scene file");
    let (t0, t_end): (f64, f64) = (args[2].parse().unwrap(), args[3].parse().unwrap());
    let ns: Vec<usize> = list(&args[4]);
    let hs: Vec<f64> = list(&args[5]);
    println!("n,h,hotspot,elevation,joints,static_M,mean_M,std_M,cpu_s,wall_s");
    for &n in &ns {
        for &h in &hs {
            let steps = (t_end / h).round() as usize;
            let scene = match Scene::from_toml_str(&at(&text, n, h, steps)) {
                Ok(s) => s,
                Err(e) => {
                    println!("{n},{h},scene refused: {e}");
                    continue;
                }
            };
            let ys = joint_elevations(&scene.beam.lengths);
            // Two joints per hot spot (the lower and the upper one around its elevation).
            let joints = hot_spot_joints(&scene.beam.lengths, &scene.hotspots);
            let (statics, all) = static_moments(&scene, &joints);
            if let Some(soil) = scene.soil {
                let (mut best, mut at_y) = (0.0f64, 0.0);
                for (i, m) in all.iter().enumerate() {
                    if ys[i] < soil.mudline && m.abs() > best.abs() {
                        (best, at_y) = (*m, ys[i]);
                    }
                }
                println!(
                    "# n = {n}: largest static moment below the mudline {best:.6e} N m at \
                     elevation {at_y:.3} m ({:.3} m below the mudline)",
                    soil.mudline - at_y
                );
            }
            let (cpu0, wall0) = (cpu_seconds(), Instant::now());
            let history = match joint_moment_history(&scene, &joints) {
                Ok(hist) => hist,
                Err(e) => {
                    println!("{n},{h},failed: {e}");
                    continue;
                }
            };
            let wall = wall0.elapsed().as_secs_f64();
            let cpu = match (cpu0, cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            };
            let first = (t0 / h).round() as usize;
            for (s, spot) in scene.hotspots.iter().enumerate() {
                let w = interpolation_joints(&scene.beam.lengths, spot.elevation);
                let (a, b) = (&history.moment[2 * s], &history.moment[2 * s + 1]);
                let window: Vec<f64> = a[first..]
                    .iter()
                    .zip(&b[first..])
                    .map(|(&a, &b)| w.blend(a, b))
                    .collect();
                let len = window.len() as f64;
                let mean = window.iter().sum::<f64>() / len;
                let var = window.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / len;
                println!(
                    "{n},{h},{},{},{:.3}/{:.3},{:.6e},{mean:.6e},{:.6e},{cpu:.2},{wall:.2}",
                    spot.name,
                    spot.elevation,
                    ys[w.lower],
                    ys[w.upper],
                    w.blend(statics[2 * s], statics[2 * s + 1]),
                    var.sqrt()
                );
            }
        }
    }
}

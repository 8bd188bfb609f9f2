//! The convergence study of the real-scale risers (docs/scene-format.md "Real-scale
//! risers"): the wellhead moment M₀(t) of a pipe scene (`examples/scenes/riser_300m.toml`,
//! `riser_1000m.toml`) simulated with other numbers of pendulums n and steps h, over the same sea
//! (the realisation does not depend on h: its repeat period is 3 h, a whole number of steps).
//!
//! For each (n, h): the mean and standard deviation over t ∈ [T₀, T] of the wellhead moment
//! M_w = k₁ z₁/l₁ = M₀ l₁/2 \[N m\] (the base spring's moment; the thesis's M₀ = 2k₁z₁/l₁² of
//! the `moment` column is that times 2/l₁, which is M_w·2 at the thesis's l₁ = 1 m but grows
//! with n at a fixed length), and its largest |M_w|; the drag constant is
//! re-derived for each n as D = ½ ρ_w C_d D_o / (l μ² L) (the scene files' comments), and the
//! model weights it per pendulum for the rebuilt chain (Dᵢ = D l₁S₁/(lᵢSᵢ), `Scene::drag_weights`).
//!
//! The runs keep the moment history only (`chainbeam::moment_history`, no trajectory).
//!
//! The wave record's step (`[loads.waves] record_step`) is the scene's, rounded down to a whole
//! number of each h; an optional last list r1,r2,… of record steps \[s\] runs each (0: a
//! record at every step), for the record step's own convergence study.
//!
//! `cargo run --release --example riser_convergence -- SCENE.toml T0 T n1,n2,… h1,h2,… [r1,r2,…]`

use std::time::Instant;

use chainbeam::{moment_history, Scene};

fn list<T: std::str::FromStr>(s: &str) -> Vec<T> {
    s.split(',')
        .map(|x| x.parse().ok().expect("a number"))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 6 && args.len() != 7 {
        eprintln!("usage: riser_convergence SCENE.toml T0 T n1,n2,... h1,h2,... [r1,r2,...]");
        std::process::exit(2);
    }
    let base = Scene::from_file(&args[1]).expect("scene");
    let (t0, t_end): (f64, f64) = (args[2].parse().unwrap(), args[3].parse().unwrap());
    let ns: Vec<usize> = list(&args[4]);
    let hs: Vec<f64> = list(&args[5]);
    let record_steps: Vec<Option<f64>> = match args.get(6) {
        Some(r) => list::<f64>(r)
            .into_iter()
            .map(|x| (x > 0.0).then_some(x))
            .collect(),
        None => vec![base.loads.waves.and_then(|w| w.record_step)],
    };
    let pipe = base.pipe.expect("a [pipe] scene");
    let rho = base.water.density;
    let mu = pipe.mass_per_length(rho);
    println!("n,h,record_step,D,mean_Mw,std_Mw,max_abs_Mw,seconds");
    for &n in &ns {
        for (&h, &rs) in hs
            .iter()
            .flat_map(|h| record_steps.iter().map(move |r| (h, r)))
        {
            let mut s = base.clone();
            if let Some(w) = s.loads.waves.as_mut() {
                w.record_step = rs;
                w.fit_record_step(h);
            }
            let record = s
                .loads
                .waves
                .and_then(|w| w.record_step)
                .map_or("h".to_string(), |r| format!("{r}"));
            s.beam = pipe
                .beam(n, s.beam.support, rho, (None, None))
                .expect("beam");
            let l = pipe.length / n as f64;
            s.loads.drag = pipe.drag_per_length(rho) / (l * mu * mu * pipe.length);
            s.time.step = h;
            s.time.steps = (t_end / h).round() as usize;
            let start = Instant::now();
            let history = match moment_history(&s) {
                Ok(t) => t,
                Err(e) => {
                    println!("{n},{h},{record},failed: {e}");
                    continue;
                }
            };
            let secs = start.elapsed().as_secs_f64();
            // The base spring's moment k₁ z₁/l₁ = M₀ l₁/2 (M₀ = 2 k₁ z₁/l₁², eq. 3.1.3).
            let m: Vec<f64> = history.moment.iter().map(|m| m * 0.5 * l).collect();
            let first = (t0 / h).round() as usize;
            let window = &m[first..];
            let len = window.len() as f64;
            let mean = window.iter().sum::<f64>() / len;
            let var = window.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / len;
            let max = window.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let d = s.loads.drag;
            println!(
                "{n},{h},{record},{d:.6e},{mean:.6e},{:.6e},{max:.6e},{secs:.2}",
                var.sqrt()
            );
        }
    }
}

//! Quickstart: simulate the thesis cantilever (n = 10, l = 1 m, m = 1 kg, k = 1000 Nm/rad,
//! F = 2 N at the tip, thesis §2.2.4) with RATTLE and print the tip trajectory and the energy.
//!
//! `cargo run --release --example quickstart`

use chainbeam::{catalogue, simulate};

fn run() -> chainbeam::Result<()> {
    let mut scene = catalogue::thesis_cantilever();
    scene.time.steps = 500; // t ∈ [0, 5] s with h = 0.01 s
    let traj = simulate(&scene)?;
    let e0 = traj.energy()[0];
    println!(
        "{:>6} {:>12} {:>12} {:>14} {:>12}",
        "t [s]", "tip y [m]", "tip z [m]", "energy [J]", "H - H0"
    );
    for k in (0..=traj.steps()).step_by(25) {
        let tip = traj.positions(k)[scene.n() - 1];
        println!(
            "{:>6.2} {:>12.6} {:>12.6} {:>14.8} {:>12.3e}",
            traj.time(k),
            tip[1],
            tip[2],
            traj.energy()[k],
            traj.energy()[k] - e0
        );
    }
    let max_err = traj
        .energy()
        .iter()
        .map(|e| (e - e0).abs())
        .fold(0.0, f64::max);
    println!(
        "\n{} steps, {} Newton iterations in all, max |H - H0| = {max_err:.3e}",
        traj.steps(),
        traj.newton_iterations()
    );
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

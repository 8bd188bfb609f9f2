//! The headline of issue 31: the fatigue life of a wellhead in a North Atlantic wave climate
//! without control, with the best constant force, a tuned PD law and MPC at the platform, and
//! the CPU time each took (`chainbeam::fatigue_study::run_study`, the library behind
//! `chainbeam fatigue --scatter FILE --controller none,constant,pd,mpc`).
//!
//! ```sh
//! cargo run --release --example wellhead_fatigue                     # 120 s per cell, all four
//! cargo run --release --example wellhead_fatigue -- 600              # 600 s per cell
//! cargo run --release --example wellhead_fatigue -- 30 none,constant # 30 s per cell, two
//! ```
//!
//! Cost: the plant is n = 80 pendulums at h = 0.00625 s (19 200 steps per cell at 120 s); `none`
//! is a simulation per cell, `constant` a one-piece optimal control per cell (the condensed
//! solver: one sensitivity direction), `pd` one tuning of its gains (20 L-BFGS iterations of a
//! dual-number closed loop over the first 60 s of the scene's own sea, H_s = 4 m, T_p = 10 s: a
//! fixed design, as an engineer would commission one PD law, not one per sea state) and a closed
//! loop per cell, `mpc` a re-plan every second over 20 s on the reduced planning model (the pipe
//! as 20 pendulums at 0.1 s, src/mpc/planning.rs) per cell. The horizon must reach the riser's
//! first natural period (≈ 19 s): 8 s plans are myopic and drive the riser (src/mpc/planning.rs
//! tests, and the commit that added the planning model).
//!
//! - The riser: `examples/scenes/riser_300m.toml` (a 21" drilling riser in 300 m of water, a
//!   JONSWAP sea and a 0.5 m/s current; its sources are in the file), with the record shortened
//!   to the seconds given (default 300 s; a design analysis would run 3 hours per cell: the
//!   damage per year is a rate, and a short record estimates it with sampling error).
//! - The wellhead: the pipe's section, DNV-RP-C203 curve F1 in seawater with cathodic
//!   protection, SCF 1.2, DFF 10 (our choices for a girth weld at a subsea wellhead; OCEAN.md §4
//!   gives 3–10 for the DFF).
//! - The wave climate: the North Atlantic scatter diagram of IACS Rec. No. 34 (as printed in
//!   KR Guidance RA-03-E (2025), Pt 3 Annex 3-2, Table 3; `chainbeam::fatigue::scatter`
//!   cites it) reduced to 20 cells: 2 m × 2 s groups of its classes, T_z → T_p by its
//!   Pierson-Moskowitz spectrum (riser_300m's γ = 1), groups below 0.1 % dropped (0.066 % of
//!   the time) and the rest renormalised (`scatter::reduced_north_atlantic`, the rows of
//!   `examples/scatter/north_atlantic_iacs34.csv`).
//! - The controllers act at the platform (the tip node) with |u| ≤ 200 kN, a decision every
//!   second; MPC plans 20 s ahead with one Gauss-Newton iteration per re-plan. All three minimise
//!   Σ M₀² + ρ h Σ u² (ρ = 10⁻⁴), the thesis's smooth stand-in of the damage. Each cell keeps the
//!   scene's seed (docs/cli.md, "Seeds"); every record starts from the riser at rest with the
//!   current and the sea switched on at t = 0, and the start-up is counted with the rest.

use std::time::Instant;

use chainbeam::fatigue::scatter::reduced_north_atlantic;
use chainbeam::fatigue::{DnvClass, Environment, FatigueSpec};
use chainbeam::fatigue_study::{
    pd_law, run_study, ControlSettings, ControllerKind, Study, StudyInput,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::Scene;

/// MPC's planning model: the riser's pipe as 20 pendulums (15 m each) at h = 0.1 s (the plant:
/// 80 at 0.00625 s), src/mpc/planning.rs.
const PLAN_PENDULUMS: usize = 20;
/// The planning model's step \[s\].
const PLAN_STEP: f64 = 0.1;
/// The PD gains are tuned once, on the first 60 s of the scene's own sea.
const PD_TRAINING_S: f64 = 60.0;

/// Process CPU time (user + system) of every thread so far \[s\].
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct we own.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    let t = |v: libc::timeval| v.tv_sec as f64 + 1e-6 * v.tv_usec as f64;
    t(usage.ru_utime) + t(usage.ru_stime)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: f64 = std::env::args().nth(1).map_or(Ok(120.0), |a| a.parse())?;
    let kinds = match std::env::args().nth(2) {
        Some(list) => ControllerKind::parse_list(&list)?,
        None => ControllerKind::CHOICES.to_vec(),
    };
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let mut scene = Scene::from_file(path)?;
    scene.time.steps = (seconds / scene.time.step).round() as usize;
    let pipe = scene.pipe.ok_or("riser_300m.toml has a [pipe]")?;
    let spec = FatigueSpec {
        scf: 1.2,
        curve: DnvClass::F1,
        environment: Environment::SeawaterCp,
        dff: 10.0,
        ..FatigueSpec::new(pipe.outer_diameter, pipe.wall_thickness)
    };
    let cells = reduced_north_atlantic();
    let kept: f64 = cells.iter().map(|c| c.probability).sum();
    let mut settings = ControlSettings {
        interval: 1.0,
        mpc: MpcOptions {
            horizon: Horizon::Seconds(20.0),
            effort: 1e-4,
            ocp: OcpOptions::default().with_bound(2e5),
            plan_pendulums: Some(PLAN_PENDULUMS),
            plan_step: Some(PLAN_STEP),
            ..MpcOptions::default()
        },
        pd_max_iters: 20,
        pd_training: Some(PD_TRAINING_S),
        pd_gains: None,
    };
    println!(
        "riser_300m: {} pendulums, {seconds} s per cell (h = {} s), {} cells holding {:.2} % of \
         the time",
        scene.n(),
        scene.time.step,
        cells.len(),
        100.0 * kept
    );
    for c in &cells {
        println!(
            "  cell H_s = {:4.2} m, T_p = {:5.2} s, p = {:.4}",
            c.sea.hs, c.sea.tp, c.probability
        );
    }
    let mut studies: Vec<(Study, f64, f64)> = Vec::new();
    for &kind in &kinds {
        let (cpu0, wall0) = (cpu_seconds(), Instant::now());
        if kind == ControllerKind::Pd {
            // One design for every cell, tuned on the scene's own sea (module docs).
            let pd = pd_law(&scene, &settings)?;
            settings.pd_gains = Some([pd.bias, pd.kp, pd.kd]);
            println!(
                "pd gains (tuned on the first {PD_TRAINING_S} s of H_s = 4 m, T_p = 10 s): u_b = \
                 {:.4e} N, K_p = {:.4e} N/(N·m), K_d = {:.4e} N·s/(N·m)",
                pd.bias, pd.kp, pd.kd
            );
        }
        let input = StudyInput {
            scene: &scene,
            spec: &spec,
            cells: Some(&cells),
            controllers: &[kind],
            settings: &settings,
        };
        let study = run_study(&input, &|| {})?;
        let (cpu, wall) = (cpu_seconds() - cpu0, wall0.elapsed().as_secs_f64());
        eprintln!("{}: {cpu:.1} s CPU, {wall:.1} s wall", kind.name());
        studies.push((study, cpu, wall));
    }
    let none_life = studies
        .iter()
        .find(|s| s.0.controllers[0].kind == ControllerKind::None)
        .map_or(f64::NAN, |s| s.0.controllers[0].life_years);
    println!(
        "\n| controller | damage per year | life (years, DFF 10) | life extension | CPU (s) | \
         wall (s) | simulated s per CPU s |\n|---|---|---|---|---|---|---|"
    );
    let simulated = seconds * cells.len() as f64;
    for (study, cpu, wall) in &studies {
        let c = &study.controllers[0];
        println!(
            "| {} | {:.4e} | {:.3e} | {:.2} | {cpu:.1} | {wall:.1} | {:.1} |",
            c.kind.name(),
            c.damage_per_year,
            c.life_years,
            c.life_years / none_life,
            simulated / cpu
        );
    }
    println!("\nper cell, damage per year (probability-weighted), by controller:");
    for (s, cell) in cells.iter().enumerate() {
        let row: Vec<String> = studies
            .iter()
            .map(|(study, _, _)| {
                let c = &study.controllers[0];
                format!("{} {:.3e}", c.kind.name(), c.cells[s].damage_per_year)
            })
            .collect();
        println!(
            "  H_s {:4.2} m, T_p {:5.2} s: {}",
            cell.sea.hs,
            cell.sea.tp,
            row.join(", ")
        );
    }
    Ok(())
}

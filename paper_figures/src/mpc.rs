//! Closed-loop control of the riser (beyond the thesis): the base moment M₀(t) under no control, the best
//! constant force, a tuned PD law on M₀ and receding-horizon control (perfect and wrong model).

use crate::plot::{color, Figure, Legend, Panel, Res, Series};
use crate::{Ctx, Entry, Made};
use chainbeam::catalogue;
use chainbeam::mpc::{
    run_closed_loop, ClosedLoopResult, ConstantForce, Horizon, Mpc, MpcOptions, MpcSolver,
    NoControl, PdLaw, PdTuning,
};
use chainbeam::ocp::OcpOptions;
use chainbeam::optimize::OptimOptions;

pub fn entries() -> Vec<Entry> {
    vec![
    Entry {
        id: "mpc_moment",
        caption: "(beyond the thesis) The base bending moment M₀(t) of the riser under \
                  an irregular sea at node 5 in a sheared current, and a control force at the \
                  platform: no control, the best constant force, a PD law on M₀ with tuned gains, and receding-horizon \
                  control (3 s horizon, a decision every 0.1 s, 1 Gauss-Newton iteration per \
                  re-plan) with a perfect and with a wrong model; lower panel: the forces.",
        make: fig_mpc,
    },
    Entry {
        id: "mpc_horizon",
        caption: "(beyond the thesis) Speed against accuracy of receding-horizon \
                  control on the same scene: closed-loop Σ M₀² (log scale) against the mean \
                  re-plan time, for horizons of 1 to 5 s (a decision every 0.1 s, 1 \
                  Gauss-Newton iteration per re-plan, perfect model), re-planned by the \
                  condensed and by the Riccati solver, with the best constant force and the \
                  tuned PD law as horizontal references.",
        make: fig_horizon,
    }]
}

/// Closed-loop c_sum against the mean re-plan time for horizons of 1..5 s (the default 3 s
/// among them), beside the constant force and the PD law.
fn fig_horizon(ctx: &Ctx) -> Res<Made> {
    let mut scene = catalogue::mpc_riser();
    if ctx.quick {
        scene.time.steps = 1000;
    }
    let (mut constant, _) = ConstantForce::best(&scene, BOUND, EFFORT)?;
    let constant = run_closed_loop(&scene, INTERVAL, &mut constant)?
        .summary
        .c_sum;
    let tuning = PdTuning::new(&scene, INTERVAL, BOUND, EFFORT)?;
    let opts = OptimOptions {
        max_iters: if ctx.quick { 20 } else { 200 },
        first_step: 0.01,
        ..OptimOptions::default()
    };
    let (mut pd, _) = PdLaw::tune(&tuning, &[0.0; 3], &opts)?;
    let pd = run_closed_loop(&scene, INTERVAL, &mut pd)?.summary.c_sum;
    let horizons: &[f64] = if ctx.quick {
        &[1.0, 3.0]
    } else {
        &[1.0, 2.0, 3.0, 4.0, 5.0]
    };
    let mut notes = Vec::new();
    let mut series = Vec::new();
    for (solver, name) in [
        (MpcSolver::Condensed, "condensed"),
        (MpcSolver::Riccati, "Riccati"),
    ] {
        let mut pts = Vec::new();
        for &h in horizons {
            let options = MpcOptions {
                horizon: Horizon::Seconds(h),
                effort: EFFORT,
                solver,
                ocp: OcpOptions::default().with_bound(BOUND),
                ..MpcOptions::default()
            };
            let mut mpc = Mpc::new(&scene, INTERVAL, options)?;
            let r = run_closed_loop(&scene, INTERVAL, &mut mpc)?;
            let ms = 1e3 * r.summary.mean_replan_seconds;
            pts.push((ms, r.summary.c_sum));
            notes.push(format!(
                "{name} {h} s: Σ M₀² = {:.1} at {ms:.1} ms",
                r.summary.c_sum
            ));
        }
        series.push((name, pts));
    }
    let pts: Vec<(f64, f64)> = series.iter().flat_map(|s| s.1.clone()).collect();
    let (x0, x1) = (0.0, pts.iter().fold(0.0f64, |m, p| m.max(p.0)) * 1.1);
    let mut panel = Panel::new(
        "MPC horizon: accuracy against speed",
        "mean re-plan [ms]",
        "Σ M₀²",
    )
    .logy()
    .legend(Legend::UpperRight);
    for (i, (name, pts)) in series.into_iter().enumerate() {
        let label = format!("MPC ({name} solver), horizons 1-5 s");
        panel.push(Series::line(&label, pts, color(3 + i)).markers());
    }
    panel.push(
        Series::line(
            "best constant",
            vec![(x0, constant), (x1, constant)],
            color(1),
        )
        .dashed(),
    );
    panel.push(Series::line("tuned PD on M₀", vec![(x0, pd), (x1, pd)], color(2)).dotted());
    let files = ctx.save(&Figure::single("mpc_horizon", panel))?;
    Ok(Made {
        files,
        note: format!(
            "{}; best constant {constant:.1}, tuned PD {pd:.1} (timings are this machine's).",
            notes.join("; ")
        ),
    })
}

const INTERVAL: f64 = 0.1;
const BOUND: f64 = 5.0;
const EFFORT: f64 = 0.01;

fn fig_mpc(ctx: &Ctx) -> Res<Made> {
    let mut scene = catalogue::mpc_riser();
    if ctx.quick {
        scene.time.steps = 1000;
    }
    let mut model = catalogue::mpc_riser_wrong_model();
    model.time.steps = scene.time.steps;
    let options = MpcOptions {
        horizon: Horizon::Seconds(3.0),
        effort: EFFORT,
        ocp: OcpOptions::default().with_bound(BOUND),
        ..MpcOptions::default()
    };
    let none = run_closed_loop(&scene, INTERVAL, &mut NoControl)?;
    let (mut constant, _) = ConstantForce::best(&scene, BOUND, EFFORT)?;
    let constant = run_closed_loop(&scene, INTERVAL, &mut constant)?;
    let tuning = PdTuning::new(&scene, INTERVAL, BOUND, EFFORT)?;
    let opts = OptimOptions {
        max_iters: if ctx.quick { 20 } else { 200 },
        first_step: 0.01,
        ..OptimOptions::default()
    };
    let (mut pd, _) = PdLaw::tune(&tuning, &[0.0; 3], &opts)?;
    let pd = run_closed_loop(&scene, INTERVAL, &mut pd)?;
    let perfect = run_closed_loop(
        &scene,
        INTERVAL,
        &mut Mpc::new(&scene, INTERVAL, options.clone())?,
    )?;
    let wrong = run_closed_loop(&scene, INTERVAL, &mut Mpc::new(&model, INTERVAL, options)?)?;
    let runs: [(&ClosedLoopResult, &str); 5] = [
        (&none, "no control"),
        (&constant, "best constant"),
        (&pd, "tuned PD on M₀"),
        (&perfect, "MPC, perfect model"),
        (&wrong, "MPC, wrong model"),
    ];
    let mut top = Panel::new("Base bending moment", "t [s]", "M₀ [Nm]").legend(Legend::UpperRight);
    let mut bottom = Panel::new("Control force at the platform", "t [s]", "u [N]");
    let mut notes = Vec::new();
    for (i, (r, name)) in runs.iter().enumerate() {
        let pts = |v: &[f64]| {
            r.t.iter()
                .copied()
                .zip(v.iter().copied())
                .collect::<Vec<_>>()
        };
        top.push(Series::line(*name, pts(&r.moment), color(i)).width(1));
        if i > 0 {
            bottom.push(Series::line(*name, pts(&r.control), color(i)).width(1));
        }
        notes.push(format!(
            "{name}: Σ M₀² = {:.1}, max |M₀| = {:.2} Nm",
            r.summary.c_sum, r.summary.max_abs_moment
        ));
    }
    let files = ctx.save(&Figure::new("mpc_moment", 1, vec![top, bottom]))?;
    Ok(Made {
        files,
        note: format!(
            "{}. MPC re-plans: mean {:.1} ms, worst {:.1} ms per 0.1 s interval. \
             `cargo run --release --example mpc` prints the table.",
            notes.join("; "),
            1e3 * perfect.summary.mean_replan_seconds,
            1e3 * perfect.summary.worst_replan_seconds
        ),
    })
}

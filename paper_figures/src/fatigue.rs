//! Wellhead fatigue (beyond the thesis): where in the wave climate the damage comes
//! from, and what control does to the moment that makes it.
//!
//! * `fatigue_scatter`: left, the damage per year each (H_s, T_p) cell of the reduced
//!   Kvitebjørn diagram (`chainbeam::fatigue::scatter::reduced_kvitebjorn`) contributes at the
//!   wellhead of `examples/scenes/riser_300m.toml` without control (p_s · D_s · Y/T_s, a short
//!   record per cell with the scene's seed); right, the base moment M₀(t) of the
//!   `catalogue::mpc_riser` closed loop without control and under MPC, with the rainflow damage
//!   of each in the note.

use crate::plot::{color, Figure, Heat, Legend, Panel, Res, Series};
use crate::{Ctx, Entry, Made};
use chainbeam::catalogue;
use chainbeam::fatigue::scatter::{reduced_hs_bins, reduced_kvitebjorn, reduced_tp_bins};
use chainbeam::fatigue::{assess, DnvClass, Environment, FatigueSpec, MomentHistory};
use chainbeam::fatigue_study::{run_study, ControlSettings, ControllerKind, StudyInput};
use chainbeam::mpc::{run_closed_loop, Horizon, Mpc, MpcOptions, NoControl};
use chainbeam::ocp::OcpOptions;
use chainbeam::Scene;

pub fn entries() -> Vec<Entry> {
    vec![Entry {
        id: "fatigue_scatter",
        caption: "(beyond the thesis) Left: the wellhead's damage per year from each \
                  (H_s, T_p) cell of a northern North Sea wave climate (the Kvitebjørn joint \
                  model reduced to 11 cells), without control, on the 300 m riser. Right: the \
                  base moment M₀(t) without control and under MPC (the closed-loop riser of \
                  the MPC figure), whose rainflow damage the note gives.",
        make: fig_fatigue,
    }]
}

fn fig_fatigue(ctx: &Ctx) -> Res<Made> {
    let (left, left_note) = damage_map(ctx)?;
    let (right, right_note) = moment_with_control(ctx)?;
    let files = ctx.save(&Figure::new("fatigue_scatter", 2, vec![left, right]))?;
    Ok(Made {
        files,
        note: format!("{left_note} {right_note}"),
    })
}

/// The damage contribution of every cell without control, as a heat map over (H_s, T_p).
fn damage_map(ctx: &Ctx) -> Res<(Panel, String)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/riser_300m.toml"
    );
    let mut scene = Scene::from_file(path)?;
    let seconds = if ctx.quick { 5.0 } else { 60.0 };
    scene.time.steps = (seconds / scene.time.step).round() as usize;
    let pipe = scene.pipe.ok_or("riser_300m.toml has a [pipe]")?;
    let spec = FatigueSpec {
        scf: 1.2,
        curve: DnvClass::F1,
        environment: Environment::SeawaterCp,
        dff: 10.0,
        ..FatigueSpec::new(pipe.outer_diameter, pipe.wall_thickness)
    };
    let cells = reduced_kvitebjorn();
    let input = StudyInput {
        scene: &scene,
        spec: &spec,
        cells: Some(&cells),
        controllers: &[ControllerKind::None],
        settings: &ControlSettings::default(),
    };
    let study = run_study(&input, &|| {})?;
    let none = &study.controllers[0];
    let (hs, tp) = (reduced_hs_bins(), reduced_tp_bins());
    let (nx, ny) = (hs.centres.len(), tp.centres.len());
    let mut values = vec![0.0; nx * ny];
    for c in &none.cells {
        let sea = c.sea.ok_or("a scatter cell has a sea state")?;
        let i = hs.centres.iter().position(|&h| h == sea.hs);
        let j = tp.centres.iter().position(|&t| t == sea.tp);
        if let (Some(i), Some(j)) = (i, j) {
            values[i * ny + j] = c.damage_per_year;
        }
    }
    let top = values.iter().fold(0.0f64, |m, &v| m.max(v));
    let panel = Panel::new(
        "Damage per year by sea state, no control",
        "H_s [m]",
        "T_p [s]",
    )
    .heat(Heat {
        x: (hs.centres[0], hs.centres[nx - 1]),
        y: (tp.centres[0], tp.centres[ny - 1]),
        nx,
        ny,
        values,
        log: true,
        floor: Some(top * 1e-4),
        label: "p_s · D_s · Y/T_s".into(),
    });
    let note = format!(
        "Left: {} cells, {seconds} s per cell (n = {}, h = {} s), total damage per year \
         {:.3e}, life {:.1} years at DFF 10 (curve F1, seawater with CP, SCF 1.2); a short \
         record per cell estimates each rate with sampling error, and every record starts from the \
         straight riser at rest (its first swing, as the current and the sea set in, is counted \
         too).",
        cells.len(),
        scene.n(),
        scene.time.step,
        none.damage_per_year,
        none.life_years
    );
    Ok((panel, note))
}

/// M₀(t) of the issue-14 riser without control and under MPC (3 s horizon, 0.1 s interval,
/// |u| ≤ 5 N), and their rainflow damage for a 20 mm × 2 mm tube (curve F1 in air).
fn moment_with_control(ctx: &Ctx) -> Res<(Panel, String)> {
    let mut scene = catalogue::mpc_riser();
    if ctx.quick {
        scene.time.steps = 1000;
    }
    let options = MpcOptions {
        horizon: Horizon::Seconds(3.0),
        effort: 0.01,
        ocp: OcpOptions::default().with_bound(5.0),
        ..MpcOptions::default()
    };
    let none = run_closed_loop(&scene, 0.1, &mut NoControl)?;
    let mpc = run_closed_loop(&scene, 0.1, &mut Mpc::new(&scene, 0.1, options)?)?;
    let mut spec = FatigueSpec::new(0.02, 0.002);
    spec.curve = DnvClass::F1;
    spec.environment = Environment::Air;
    let duration = scene.time.steps as f64 * scene.time.step;
    let damage = |m: &[f64]| {
        assess(
            &spec,
            MomentHistory {
                duration_s: duration,
                moment: m,
                moment_x: None,
                measure: scene.moment_measure(),
            },
        )
        .map(|a| a.damage)
    };
    let (d_none, d_mpc) = (damage(&none.moment)?, damage(&mpc.moment)?);
    let mut panel =
        Panel::new("Base bending moment", "t [s]", "M₀ [Nm]").legend(Legend::UpperRight);
    for (i, (r, name)) in [(&none, "no control"), (&mpc, "MPC")].iter().enumerate() {
        let pts = r.t.iter().copied().zip(r.moment.iter().copied()).collect();
        panel.push(Series::line(*name, pts, color(if i == 0 { 0 } else { 3 })).width(1));
    }
    let note = format!(
        "Right: catalogue::mpc_riser over {duration} s; rainflow damage of a 20 × 2 mm tube \
         (curve F1, air): {d_none:.3e} without control, {d_mpc:.3e} under MPC (life × {:.1}).",
        d_none / d_mpc
    );
    Ok((panel, note))
}

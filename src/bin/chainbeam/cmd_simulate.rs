//! `chainbeam simulate`: the trajectory as CSV or NumPy `.npy`.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use chainbeam::{
    simulate, simulate_with_controls, simulate_with_controls_xz, ControlMap, Scene, SceneTrajectory,
};

use crate::output::{push_f64, refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{controls_io, lib_error, npy, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `simulate --help`.
pub const LONG_ABOUT: &str = "\
Simulate a scene from the straight beam at rest with RATTLE (step h = time.step, N = time.steps), \
applying the scene's [control] (u_k at node control.node; a constant control is applied at every \
t_k) or the forces of --controls FILE (pairs [u_x, u_z] in the JSON of optimize, or the control_x \
and control columns of a simulate CSV, are a 2-axis control: both components are applied), and \
write the trajectory.

CSV (the default): a header line, then one row per time t_k = k·h, k = 0..N (N + 1 rows):
  t        time t_k [s]
  energy   total energy H(q_k, p_k; t_k, u_k) [J] (kinetic + springs + loads + control + gravity)
  moment   base bending moment M₀(t_k) = 2·k₁·z₁/l₁² [Nm] (thesis eq. 3.1.3)
  xi,yi,zi position of node i = 1..n [m]; the beam lies along +y. x = 0 for a planar scene;
           a scene with a load along x runs the spatial model and fills x in
A spatial scene (a load or a 2-axis control with an x component) has two more columns here:
  moment_x the x component M₀ₓ(t_k) = 2·k₁·x₁/l₁² [Nm] of the base moment vector (M₀ₓ, M₀); the
           objectives use |M₀|² = M₀ₓ² + M₀²
  control_x the x component u_x,k [N] of a 2-axis control (0 for a control along z)
  eta      the surface elevation η(t_k) [m] at x = z = 0 of a scene with [loads.waves] (only
           then; before control)
  control  the control force u_k [N] applied at t_k (0 without a control; its z component for a
           2-axis control); always the last column
--columns t,eta,moment writes those columns only, in that order (any of the above names);
--every K writes the rows k = 0, K, 2K, … only (both for CSV and .npy).
Numbers are written as the shortest decimal that reads back to the same double.

NumPy (--format npy, or an --output name ending in .npy): one C-ordered float64 array of shape \
(N + 1, 3n + 4), or (N + 1, 3n + 6) for a spatial scene (one more with waves), with the same \
columns in the same order (and the same --columns and --every) \
(np.load(FILE); positions are a[:, 3:3 + 3n].reshape(-1, n, 3), the control a[:, -1]).

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z (and F_x > 0 of a vector load \
[F_x, F_z] toward −x); u = −F cancels a tip load F, and a 2-axis control [u_x, u_z] follows the same convention in both \
components. In a spatial scene `moment` is still the moment of z₁ (the bending in the yz-plane) \
and `moment_x` the moment of x₁.";

/// `simulate`'s flags.
#[derive(Args)]
pub struct SimulateArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    pub scene: PathBuf,
    /// Apply these control forces instead of the scene's [control]: the JSON that `optimize` or
    /// `gradient` writes (its `controls`), the `control` column (and `control_x`, if any) of a
    /// `simulate` CSV, or a single column of numbers; 1 value (constant) or N + 1 values
    /// u_0..u_N, finite. Pairs [u_x, u_z] (or a CSV with `control_x`) are a 2-axis control, both
    /// components applied (a scene with a 2-axis control needs them). They act at control.node
    /// (default: the tip).
    #[arg(long, value_name = "FILE")]
    pub controls: Option<PathBuf>,
    /// Output format [default: npy if the --output name ends in .npy, else csv].
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub format: Option<Format>,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    pub output: Option<PathBuf>,
    /// Write only these columns, in this order (comma-separated names of the CSV's header, e.g.
    /// `t,eta,moment`) [default: all].
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub columns: Option<Vec<String>>,
    /// Write every K-th row only: t_k for k = 0, K, 2K, … (K ≥ 1) [default: 1, every row].
    #[arg(long, value_name = "K", default_value_t = std::num::NonZeroUsize::MIN)]
    pub every: std::num::NonZeroUsize,
}

/// The trajectory's file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Comma-separated text with a header line.
    Csv,
    /// NumPy .npy (version 1.0): one float64 array, the CSV's columns.
    Npy,
}

impl Format {
    fn choose(flag: Option<Format>, output: Option<&Path>) -> Format {
        flag.unwrap_or_else(|| match output.and_then(Path::extension) {
            Some(e) if e.eq_ignore_ascii_case("npy") => Format::Npy,
            _ => Format::Csv,
        })
    }
}

/// Runs `simulate`.
pub fn run(a: &SimulateArgs, progress: Progress) -> Result<(), CliError> {
    let format = Format::choose(a.format, a.output.as_deref());
    let out = Output::prepare(a.output.as_deref())?;
    if format == Format::Npy && out.is_stdout() && std::io::stdout().is_terminal() {
        return Err(CliError::msg(
            "--format npy: refusing to write binary data to a terminal; give --output FILE.npy \
             or redirect standard output",
        ));
    }
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    let eta = scene
        .wave_elevation()
        .map_err(|e| lib_error(&a.scene, e.into()))?;
    let names = csv_names(scene.n(), scene.is_spatial(), eta.is_some());
    let select = select_columns(&names, a.columns.as_deref())?;
    let controls = match &a.controls {
        Some(path) => {
            let file = controls_io::read(path)?;
            inputs.file(path);
            Some(controls_u(&scene, &file)?)
        }
        None => None,
    };
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    let steps = scene.time.steps;
    let spinner = progress.spinner(format!(
        "simulating {steps} steps of a {}-pendulum beam",
        scene.n()
    ));
    let traj = match &controls {
        Some((u, None)) => simulate_with_controls(&scene, u),
        Some((u, Some(ux))) => simulate_with_controls_xz(&scene, ux, u),
        None => simulate(&scene),
    };
    spinner.finish_and_clear();
    let traj = traj.map_err(|e| lib_error(&a.scene, e))?;
    check_trajectory(&a.scene, &traj)?;
    if let Some(k) = eta
        .as_ref()
        .and_then(|e| e.iter().position(|v| !v.is_finite()))
    {
        return Err(CliError::msg(format!(
            "{}: the wave elevation is not finite in column `eta` at step {k}; nothing was \
             written",
            a.scene.display()
        )));
    }
    let table = Table {
        traj: &traj,
        eta: eta.as_deref(),
        names: &names,
        select: &select,
        every: a.every.get(),
    };
    let mut sink = out.open()?;
    let bar = progress.bar(traj.steps() as u64 + 1, "writing rows");
    let written = match format {
        Format::Csv => write_csv(sink.writer(), &table, &bar),
        Format::Npy => write_npy(sink.writer(), &table, &bar),
    };
    bar.finish_and_clear();
    if let Err(e) = written {
        return Err(sink.error(&e));
    }
    sink.finish()
}

/// The forces u_0..u_N of a `--controls` file on this scene and, for a 2-axis control, their x
/// components u_{x,0..N}.
fn controls_u(
    scene: &Scene,
    file: &controls_io::ControlsFile,
) -> Result<(Vec<f64>, Option<Vec<f64>>), CliError> {
    file.check_axes(scene)?;
    let map = file.parametrisation(scene.time.steps)?;
    let expand = |values: &[f64]| {
        let mut u = vec![0.0; scene.time.steps + 1];
        map.controls(values, &mut u);
        u
    };
    Ok((expand(&file.values), file.values_x.as_deref().map(expand)))
}

/// Never write NaN: every value is checked before the first byte goes out.
fn check_trajectory(path: &Path, traj: &SceneTrajectory) -> Result<(), CliError> {
    for k in 0..=traj.steps() {
        let bad = |col: &str| {
            CliError::msg(format!(
                "{}: the simulation produced a non-finite value in column `{col}` at step {k} \
                 (t = {}); nothing was written",
                path.display(),
                traj.time(k)
            ))
        };
        for (col, v) in [
            ("t", traj.time(k)),
            ("energy", traj.energy()[k]),
            ("moment", traj.moment()[k]),
            ("control", traj.controls()[k]),
            ("moment_x", traj.moment_x().get(k).copied().unwrap_or(0.0)),
            (
                "control_x",
                traj.controls_x().get(k).copied().unwrap_or(0.0),
            ),
        ] {
            if !v.is_finite() {
                return Err(bad(col));
            }
        }
        for (i, r) in traj.positions(k).iter().enumerate() {
            for (c, v) in ["x", "y", "z"].iter().zip(r) {
                if !v.is_finite() {
                    return Err(bad(&format!("{c}{}", i + 1)));
                }
            }
        }
    }
    Ok(())
}

/// The names of the CSV's columns (see [`LONG_ABOUT`]): `t,energy,moment`, the positions,
/// `moment_x,control_x` for a spatial scene, `eta` for a scene with waves, `control` last.
fn csv_names(n: usize, spatial: bool, waves: bool) -> Vec<String> {
    let mut h: Vec<String> = ["t", "energy", "moment"].map(String::from).to_vec();
    for i in 1..=n {
        h.extend([format!("x{i}"), format!("y{i}"), format!("z{i}")]);
    }
    if spatial {
        h.extend(["moment_x".to_string(), "control_x".to_string()]);
    }
    if waves {
        h.push("eta".to_string());
    }
    h.push("control".to_string());
    h
}

/// The indices of `--columns` in `names` (all columns without the flag); an unknown or
/// repeated name is an error naming the flag.
fn select_columns(names: &[String], wanted: Option<&[String]>) -> Result<Vec<usize>, CliError> {
    let Some(wanted) = wanted else {
        return Ok((0..names.len()).collect());
    };
    let mut out = Vec::with_capacity(wanted.len());
    for w in wanted {
        let w = w.trim();
        let Some(i) = names.iter().position(|n| n == w) else {
            let hint = if w == "eta" {
                " (`eta` needs [loads.waves] in the scene)"
            } else {
                ""
            };
            return Err(CliError::msg(format!(
                "--columns: no column `{w}` in this scene's output{hint}; the columns are {}",
                names.join(",")
            )));
        };
        if out.contains(&i) {
            return Err(CliError::msg(format!("--columns: `{w}` is given twice")));
        }
        out.push(i);
    }
    if out.is_empty() {
        return Err(CliError::msg("--columns: give at least one column name"));
    }
    Ok(out)
}

/// What is written: the trajectory's columns (and η), the selected columns, every K-th row.
struct Table<'a> {
    traj: &'a SceneTrajectory,
    eta: Option<&'a [f64]>,
    names: &'a [String],
    select: &'a [usize],
    every: usize,
}

impl Table<'_> {
    /// The steps written: k = 0, K, 2K, … ≤ N.
    fn steps(&self) -> impl Iterator<Item = usize> {
        (0..=self.traj.steps()).step_by(self.every)
    }

    fn rows(&self) -> usize {
        self.traj.steps() / self.every + 1
    }

    /// The selected values of row k (`all`: scratch for the full row).
    fn row(&self, k: usize, all: &mut Vec<f64>, out: &mut Vec<f64>) {
        let traj = self.traj;
        all.clear();
        all.extend([traj.time(k), traj.energy()[k], traj.moment()[k]]);
        for r in traj.positions(k) {
            all.extend(r);
        }
        if traj.is_spatial() {
            all.push(traj.moment_x()[k]);
            all.push(traj.controls_x().get(k).copied().unwrap_or(0.0));
        }
        if let Some(eta) = self.eta {
            all.push(eta[k]);
        }
        all.push(traj.controls()[k]);
        out.clear();
        out.extend(self.select.iter().map(|&i| all[i]));
    }
}

fn write_csv(
    w: &mut dyn Write,
    table: &Table<'_>,
    bar: &indicatif::ProgressBar,
) -> std::io::Result<()> {
    let header: Vec<&str> = table
        .select
        .iter()
        .map(|&i| table.names[i].as_str())
        .collect();
    w.write_all(header.join(",").as_bytes())?;
    w.write_all(b"\n")?;
    let (mut all, mut values) = (Vec::with_capacity(table.names.len()), Vec::new());
    let mut line = Vec::with_capacity(24 * table.select.len());
    let mut buf = zmij::Buffer::new();
    for k in table.steps() {
        table.row(k, &mut all, &mut values);
        line.clear();
        for (j, v) in values.iter().enumerate() {
            if j > 0 {
                line.push(b',');
            }
            push_f64(&mut line, &mut buf, *v);
        }
        line.push(b'\n');
        w.write_all(&line)?;
        if k % 1024 == 0 {
            bar.set_position(k as u64);
        }
    }
    Ok(())
}

fn write_npy(
    w: &mut dyn Write,
    table: &Table<'_>,
    bar: &indicatif::ProgressBar,
) -> std::io::Result<()> {
    let columns = table.select.len();
    w.write_all(&npy::header(&[table.rows(), columns]))?;
    let (mut all, mut values) = (Vec::with_capacity(table.names.len()), Vec::new());
    let mut bytes = Vec::with_capacity(8 * columns);
    for k in table.steps() {
        table.row(k, &mut all, &mut values);
        npy::write_row(w, &mut bytes, &values)?;
        if k % 1024 == 0 {
            bar.set_position(k as u64);
        }
    }
    Ok(())
}

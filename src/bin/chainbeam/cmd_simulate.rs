//! `chainbeam simulate`: the trajectory as CSV or NumPy `.npy`.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use chainbeam::{
    simulate_streaming, ControlMap, Scene, StepObserver, StepView, StreamControls, StreamError,
};

use crate::output::{push_f64, refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{controls_io, lib_error, npy, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `simulate --help`.
pub const LONG_ABOUT: &str = "\
Simulate a scene from its start ([time] initial: the straight beam at rest by default, or at rest in \
the static equilibrium of its steady loads) with RATTLE (step h = time.step, N = time.steps), \
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
--every K writes the rows k = 0, K, 2K, … only (both for CSV and .npy). Without --columns the \
output is the whole trajectory and a scene whose stored trajectory is over the 8 GiB budget is \
refused (naming time.steps); with --columns the rows stream whatever N.
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

/// Runs `simulate`: the rows are written as RATTLE produces them (the library's
/// [`simulate_streaming`]), so memory stays O(n) however many steps.
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
    if a.columns.is_none() {
        // Every column is the whole trajectory (each node at each step), as large as a stored
        // one: held to its budget. Chosen columns stream a run of any length.
        scene
            .check_stored_trajectory()
            .map_err(|e| lib_error(&a.scene, e.into()))?;
    }
    let controls = match &a.controls {
        Some(path) => {
            let file = controls_io::read(path)?;
            inputs.file(path);
            Some(controls_u(&scene, &file)?)
        }
        None => None,
    };
    let spatial = scene.is_spatial() || matches!(controls, Some((_, Some(_))));
    let names = csv_names(scene.n(), spatial, scene.loads.waves.is_some());
    let select = select_columns(&names, a.columns.as_deref())?;
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    // The elevation's record (one more realisation of the sea, O(N + steps)) only when its
    // column is written.
    let writes_eta = names
        .iter()
        .position(|n| n == "eta")
        .is_some_and(|c| select.contains(&c));
    let eta = if writes_eta {
        scene
            .wave_elevation()
            .map_err(|e| lib_error(&a.scene, e.into()))?
    } else {
        None
    };
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
    let steps = scene.time.steps;
    let mut sink = out.open()?;
    let bar = progress.bar(
        steps as u64 + 1,
        format!("simulating {steps} steps of a {}-pendulum beam", scene.n()),
    );
    let layout = (&names[..], &select[..], scene.n());
    let mut rows = RowWriter::new(layout, format, sink.writer(), &bar);
    rows.eta = eta.as_deref();
    rows.every = a.every.get();
    let stream = match &controls {
        Some((u, None)) => StreamControls::Given(u),
        Some((u, Some(ux))) => StreamControls::GivenXz { x: ux, z: u },
        None => StreamControls::Scene,
    };
    let result = rows
        .start(steps / rows.every + 1)
        .map_err(RowError::Io)
        .map_err(StreamError::Observer)
        .and_then(|()| simulate_streaming(&scene, stream, &mut rows));
    bar.finish_and_clear();
    match result {
        Ok(_) => sink.finish(),
        Err(StreamError::Simulation(e)) => Err(lib_error(&a.scene, e)),
        Err(StreamError::Observer(RowError::Io(e))) => Err(sink.error(&e)),
        Err(StreamError::Observer(RowError::NonFinite { column, k, t })) => {
            Err(CliError::msg(format!(
                "{}: the simulation produced a non-finite value in column `{column}` at step {k} \
                 (t = {t}); stopped, and the output is incomplete (an --output FILE is left as \
                 it was)",
                a.scene.display()
            )))
        }
    }
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

/// One written column: where its value comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Column {
    T,
    Energy,
    Moment,
    /// Node i (0-based), component c (0 = x, 1 = y, 2 = z).
    Position(usize, usize),
    MomentX,
    ControlX,
    Eta,
    Control,
}

impl Column {
    /// The column at index `i` of [`csv_names`]'s layout for `n` pendulums.
    fn at(i: usize, names: &[String], n: usize) -> Column {
        match (i, names[i].as_str()) {
            (0, _) => Column::T,
            (1, _) => Column::Energy,
            (2, _) => Column::Moment,
            (i, _) if i < 3 + 3 * n => Column::Position((i - 3) / 3, (i - 3) % 3),
            (_, "moment_x") => Column::MomentX,
            (_, "control_x") => Column::ControlX,
            (_, "eta") => Column::Eta,
            _ => Column::Control,
        }
    }
}

/// Why writing stopped.
enum RowError {
    Io(std::io::Error),
    /// A value to be written is not finite.
    NonFinite {
        column: String,
        k: usize,
        t: f64,
    },
}

/// The observer of a streamed run that writes the selected columns of every K-th state.
struct RowWriter<'a> {
    /// The selected names, in order.
    header: Vec<&'a str>,
    columns: Vec<Column>,
    format: Format,
    w: &'a mut dyn Write,
    bar: &'a indicatif::ProgressBar,
    eta: Option<&'a [f64]>,
    every: usize,
    energy: bool,
    positions: Vec<[f64; 3]>,
    values: Vec<f64>,
    line: Vec<u8>,
    buf: zmij::Buffer,
}

impl<'a> RowWriter<'a> {
    /// A writer of the columns `select` of [`csv_names`]'s `names` for `n` pendulums.
    fn new(
        (names, select, n): (&'a [String], &[usize], usize),
        format: Format,
        w: &'a mut dyn Write,
        bar: &'a indicatif::ProgressBar,
    ) -> Self {
        let columns: Vec<Column> = select.iter().map(|&i| Column::at(i, names, n)).collect();
        let positions = if columns.iter().any(|c| matches!(c, Column::Position(..))) {
            vec![[0.0; 3]; n]
        } else {
            Vec::new()
        };
        RowWriter {
            header: select.iter().map(|&i| names[i].as_str()).collect(),
            energy: columns.contains(&Column::Energy),
            format,
            w,
            bar,
            eta: None,
            every: 1,
            positions,
            values: Vec::with_capacity(columns.len()),
            line: Vec::with_capacity(24 * columns.len()),
            columns,
            buf: zmij::Buffer::new(),
        }
    }

    /// The CSV header line, or the `.npy` preamble of `rows` rows.
    fn start(&mut self, rows: usize) -> std::io::Result<()> {
        match self.format {
            Format::Csv => {
                self.w.write_all(self.header.join(",").as_bytes())?;
                self.w.write_all(b"\n")
            }
            Format::Npy => self.w.write_all(&npy::header(&[rows, self.columns.len()])),
        }
    }
}

impl StepObserver for RowWriter<'_> {
    type Error = RowError;

    fn observe<const DIM: usize>(&mut self, step: &mut StepView<'_, DIM>) -> Result<(), RowError> {
        let k = step.k();
        if k % 1024 == 0 {
            self.bar.set_position(k as u64);
        }
        if k % self.every != 0 {
            return Ok(());
        }
        let energy = if self.energy { step.energy() } else { 0.0 };
        if !self.positions.is_empty() {
            step.positions(&mut self.positions);
        }
        let [mx, mz] = step.moment_vector();
        self.values.clear();
        for (c, name) in self.columns.iter().zip(&self.header) {
            let v = match *c {
                Column::T => step.time(),
                Column::Energy => energy,
                Column::Moment => mz,
                Column::Position(i, d) => self.positions[i][d],
                Column::MomentX => mx,
                Column::ControlX => step.control_x(),
                Column::Eta => self.eta.map_or(0.0, |e| e[k]),
                Column::Control => step.control(),
            };
            if !v.is_finite() {
                return Err(RowError::NonFinite {
                    column: name.to_string(),
                    k,
                    t: step.time(),
                });
            }
            self.values.push(v);
        }
        let written = match self.format {
            Format::Csv => {
                self.line.clear();
                for (j, v) in self.values.iter().enumerate() {
                    if j > 0 {
                        self.line.push(b',');
                    }
                    push_f64(&mut self.line, &mut self.buf, *v);
                }
                self.line.push(b'\n');
                self.w.write_all(&self.line)
            }
            Format::Npy => npy::write_row(self.w, &mut self.line, &self.values),
        };
        written.map_err(RowError::Io)
    }
}

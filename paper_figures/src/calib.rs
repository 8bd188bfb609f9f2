//! Calibration by gradients (beyond the thesis, issue item 5): the thesis tuned the chain's
//! k = 1.16e3 Nm/rad and m = 2.4 kg by trial and error to match its Euler-Bernoulli beam (Fig.
//! 2.10). Here the chain's parameters are fitted to the (correct free end) finite-difference
//! Euler-Bernoulli trajectory by least squares on the node displacements over time, with the
//! discrete adjoint's parameter gradients (`chainbeam::adjoint::adjoint_gradient`), posed as a
//! `chainbeam::optimize::OptimProblem` in log-parameters and minimised by the library's L-BFGS
//! (`Minimizer`, with a `History` observer for the iterates).

use crate::plot::{color, Dash, Figure, Heat, Legend, Panel, Res, Series, GREY};
use crate::{Ctx, Entry, Made};
use chainbeam::adjoint::{adjoint_gradient, forward_value, Objective, Stage};
use chainbeam::euler_bernoulli::{EbSupport, EulerBernoulli};
use chainbeam::optimize::{
    History, Minimizer, ObserverMode, OptimOptions, OptimProblem, Termination,
};
use chainbeam::{catalogue, Chain, Checkpointing, Parameter, Scalar, Scene};
use plotters::style::RGBColor;
use std::time::Instant;

const BLACK: RGBColor = RGBColor(0, 0, 0);
/// The thesis's hand-tuned values (Fig. 2.10).
const THESIS_K: f64 = 1160.0;
const THESIS_M: f64 = 2.4;

pub fn entries() -> Vec<Entry> {
    vec![Entry {
        id: "calibration",
        caption: "(beyond the thesis) Calibration by gradients: the thesis tuned k = 1.16e3 and \
                  m = 2.4 by trial and error to match Euler-Bernoulli (Fig. 2.10). Fit the \
                  chain's parameters to an Euler-Bernoulli trajectory by least squares with the \
                  adjoint's parameter gradients and L-BFGS; plot before and after, and report the \
                  fitted values and residual.",
        make: calibration,
    }]
}

/// Mean squared node-displacement error against a reference, J = Σ_k Σ_i (z_i(t_k) − z_i^ref(t_k))²
/// / ((N + 1) n) \[m²\].
#[derive(Clone)]
struct EbMisfit {
    /// Reference z of nodes 1..n at every chain step k = 0..=N.
    reference: Vec<Vec<f64>>,
    weight: f64,
}

impl Objective for EbMisfit {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let r = &self.reference[s.k];
        let mut acc = s.moment * 0.0;
        for (z, zr) in s.z.iter().zip(r) {
            let d = *z - *zr;
            acc += d * d;
        }
        acc * self.weight
    }
    fn uses_positions(&self) -> bool {
        true
    }
}

/// Which chain parameters are fitted (all in log space).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Fit {
    /// The thesis's model: one k for every spring (k₁ = k) and m.
    Tied,
    /// Interior k, base k₁ and m separately.
    Free,
}

impl Fit {
    fn name(self) -> &'static str {
        match self {
            Fit::Tied => "fit (k = k₁, m)",
            Fit::Free => "fit (k, k₁, m)",
        }
    }
    /// (k, k₁, m) of log-parameters x.
    fn params(self, x: &[f64]) -> (f64, f64, f64) {
        match self {
            Fit::Tied => (x[0].exp(), x[0].exp(), x[1].exp()),
            Fit::Free => (x[0].exp(), x[1].exp(), x[2].exp()),
        }
    }
    fn start(self) -> Vec<f64> {
        match self {
            Fit::Tied => vec![THESIS_K.ln(), THESIS_M.ln()],
            Fit::Free => vec![THESIS_K.ln(), THESIS_K.ln(), THESIS_M.ln()],
        }
    }
}

/// The calibration problem: the thesis cantilever (n = 10, l = 1 m, F = 2 N at the tip,
/// h = 0.01 s) against the Euler-Bernoulli reference.
struct Calib {
    scene: Scene,
    objective: EbMisfit,
}

impl Calib {
    fn new(ei: f64, t_end: f64) -> Res<Self> {
        let mut scene = catalogue::thesis_cantilever();
        let h = scene.time.step;
        scene.time.steps = (t_end / h).round() as usize;
        let n = scene.n();
        let steps = scene.time.steps;
        // the reference at h_EB = h/10 (Störmer-Verlet, well inside its stability limit)
        let sub = 10;
        let eb = EulerBernoulli::new(n, 10.0, ei, 1.0, EbSupport::Cantilever, &[(n, 2.0)])?;
        let z = eb.simulate(h / sub as f64, steps * sub)?;
        let reference: Vec<Vec<f64>> = (0..=steps).map(|k| z[k * sub][1..=n].to_vec()).collect();
        Ok(Calib {
            scene,
            objective: EbMisfit {
                reference,
                weight: 1.0 / ((steps + 1) * n) as f64,
            },
        })
    }

    fn chain(&self, k: f64, k1: f64, m: f64) -> chainbeam::Result<Chain<f64, 2>> {
        let mut ch = Chain::<f64, 2>::from_scene(&self.scene)?;
        ch.set_parameter(Parameter::InteriorStiffness, k)?;
        ch.set_parameter(Parameter::BaseStiffness, k1)?;
        ch.set_parameter(Parameter::Mass, m)?;
        Ok(ch)
    }

    /// J and (∂J/∂k, ∂J/∂k₁, ∂J/∂m) by one adjoint sweep.
    fn eval(&self, k: f64, k1: f64, m: f64) -> chainbeam::Result<(f64, [f64; 3])> {
        let ch = self.chain(k, k1, m)?;
        let steps = self.scene.time.steps;
        let r = adjoint_gradient(
            &ch,
            self.scene.time.step,
            steps,
            &vec![0.0; steps + 1],
            &self.objective,
            &[
                Parameter::InteriorStiffness,
                Parameter::BaseStiffness,
                Parameter::Mass,
            ],
            Checkpointing::Auto,
        )?;
        let g = &r.parameter_gradient;
        Ok((r.value, [g[0], g[1], g[2]]))
    }

    /// J alone (one forward simulation, no adjoint).
    fn value(&self, k: f64, k1: f64, m: f64) -> chainbeam::Result<f64> {
        let ch = self.chain(k, k1, m)?;
        let steps = self.scene.time.steps;
        forward_value(
            &ch,
            self.scene.time.step,
            steps,
            &vec![0.0; steps + 1],
            &self.objective,
        )
    }

    /// J and its gradient in the log-parameters of `fit`.
    fn eval_log(&self, fit: Fit, x: &[f64]) -> chainbeam::Result<(f64, Vec<f64>)> {
        let (k, k1, m) = fit.params(x);
        let (j, g) = self.eval(k, k1, m)?;
        Ok((
            j,
            match fit {
                Fit::Tied => vec![k * (g[0] + g[1]), m * g[2]],
                Fit::Free => vec![k * g[0], k1 * g[1], m * g[2]],
            },
        ))
    }

    /// Tip z (node n) over time for (k, k₁, m).
    fn tip(&self, k: f64, k1: f64, m: f64) -> Res<Vec<(f64, f64)>> {
        let mut s = self.scene.clone();
        for x in s.beam.stiffness.iter_mut() {
            *x = k;
        }
        s.beam.base_stiffness = k1;
        for x in s.beam.masses.iter_mut() {
            *x = m;
        }
        let tr = crate::planar::simulate(&s)?;
        let n = s.n();
        Ok((0..=tr.steps())
            .map(|j| (tr.time(j), tr.positions(j)[n - 1][2]))
            .collect())
    }

    /// RMS error of each node over time for (k, k₁, m).
    fn node_rms(&self, k: f64, k1: f64, m: f64) -> Res<Vec<f64>> {
        let mut s = self.scene.clone();
        for x in s.beam.stiffness.iter_mut() {
            *x = k;
        }
        s.beam.base_stiffness = k1;
        for x in s.beam.masses.iter_mut() {
            *x = m;
        }
        let tr = crate::planar::simulate(&s)?;
        let n = s.n();
        let mut e = vec![0.0; n];
        for (j, r) in self.objective.reference.iter().enumerate() {
            let p = tr.positions(j);
            for i in 0..n {
                e[i] += (p[i][2] - r[i]).powi(2);
            }
        }
        let len = self.objective.reference.len() as f64;
        Ok(e.iter().map(|x| (x / len).sqrt()).collect())
    }
}

/// The calibration as an optimisation problem: J of the log-parameters x of `fit` (k = eˣ…),
/// with ∇_x J = (∂J/∂k·k, …) from one adjoint sweep. No Hessian-vector products: L-BFGS only.
struct CalibProblem<'a> {
    cal: &'a Calib,
    fit: Fit,
}

impl OptimProblem for CalibProblem<'_> {
    fn n_params(&self) -> usize {
        self.fit.start().len()
    }
    /// One forward simulation.
    fn value(&self, x: &[f64]) -> chainbeam::Result<f64> {
        let (k, k1, m) = self.fit.params(x);
        self.cal.value(k, k1, m)
    }
    fn value_and_gradient(&self, x: &[f64]) -> chainbeam::Result<(f64, Vec<f64>)> {
        self.cal.eval_log(self.fit, x)
    }
}

/// The outcome of [`lbfgs`].
struct LbfgsRun {
    x: Vec<f64>,
    value: f64,
    grad_norm: f64,
    grad_norm0: f64,
    /// J after each iteration (index 0: the start).
    history: Vec<f64>,
    /// x after each iteration (index 0: the start).
    path: Vec<Vec<f64>>,
    /// Adjoint sweeps.
    evals: usize,
    why: String,
}

/// The library's L-BFGS (argmin's, memory 5, More-Thuente line search; a trial point whose
/// simulation fails ends the line search and the run restarts from its best point with a
/// shorter step) on the calibration in log-parameters, from `x0`, with a first step of 0.1 (a
/// factor e^0.1 ≈ 1.1 on k and m: a unit step, a factor e, reaches chains too stiff and light
/// for RATTLE at h = 0.01 s), to ‖∇J‖ ≤ 10⁻⁹‖∇J₀‖ or a relative change of J at round-off
/// (4ε); the iterates come from a `History` observer.
fn lbfgs(cal: &Calib, fit: Fit, x0: &[f64], max_iters: usize) -> Res<LbfgsRun> {
    let problem = CalibProblem { cal, fit };
    let opts = OptimOptions {
        max_iters,
        lbfgs_memory: 5,
        first_step: 0.1,
        rel_grad_tol: 1e-9,
        ..OptimOptions::default()
    };
    let history = History::default();
    let r = Minimizer::new(&problem, opts)
        .add_observer(history.clone(), ObserverMode::Always)
        .run(x0)?;
    let records = history.records();
    let why = match &r.termination {
        Termination::RelativeGradientTolerance { .. } => "‖∇J‖ ≤ 1e-9 ‖∇J₀‖".to_string(),
        Termination::CostChange { .. } => "objective stalled at round-off".to_string(),
        Termination::MaxIterations { .. } => "iteration limit".to_string(),
        t => t.to_string(),
    };
    Ok(LbfgsRun {
        x: r.theta.clone(),
        value: r.objective,
        grad_norm: r.gradient_norm,
        grad_norm0: r.initial_gradient_norm,
        history: records.iter().map(|x| x.objective).collect(),
        path: records.into_iter().map(|x| x.theta).collect(),
        evals: r.gradient_evals,
        why,
    })
}

/// One fit on one beam: the fitted values, the run and what they give.
struct FitResult {
    fit: Fit,
    k: f64,
    k1: f64,
    m: f64,
    run: LbfgsRun,
    seconds: f64,
    /// The fitted chain's tip z over time.
    tip: Vec<(f64, f64)>,
    /// The fitted chain's RMS error per node.
    nodes: Vec<f64>,
}

/// The RMS misfit over the thesis's two-parameter family (k = k₁, m) on a g × g log grid.
struct MisfitGrid {
    g: usize,
    /// The k range \[Nm/rad\].
    k_range: (f64, f64),
    /// The m range \[kg\].
    m_range: (f64, f64),
    /// RMS misfit at (k_i, m_j), index i g + j; NaN where the simulation fails.
    values: Vec<f64>,
    /// (RMS misfit, k, m) of the lowest grid point.
    best: (f64, f64, f64),
}

/// The tied fit (k = k₁, m) from a start other than the thesis's values.
struct OtherStart {
    /// The start (k₀, m₀).
    start: (f64, f64),
    /// Where L-BFGS ended (k, m).
    end: (f64, f64),
    /// J at the end.
    value: f64,
    /// Why it stopped.
    why: String,
    /// The iterates (k, m).
    path: Vec<(f64, f64)>,
}

/// What the calibration computes for one beam EI: the data its panels and note show.
struct BeamCalib {
    ei: f64,
    /// The Euler-Bernoulli tip z over time.
    eb_tip: Vec<(f64, f64)>,
    /// The chain's tip with the thesis's values.
    before_tip: Vec<(f64, f64)>,
    /// The chain's RMS error per node with the thesis's values.
    before_nodes: Vec<f64>,
    /// J with the thesis's values.
    j_before: f64,
    /// J with the discretisation's physical values k = EI/l, k₁ = 2k, m = 1 kg.
    j_physical: f64,
    /// RMS displacement of the reference \[m\].
    rms_ref: f64,
    /// The tied fit (k = k₁, m), then the free fit (k, k₁, m).
    fits: Vec<FitResult>,
    grid: MisfitGrid,
    others: Vec<OtherStart>,
}

/// The tied fit's (k, m) of log-parameters x.
fn tied_km(x: &[f64]) -> (f64, f64) {
    let (k, _, m) = Fit::Tied.params(x);
    (k, m)
}

/// The largest relative error of the adjoint's ∂J/∂(k, k₁, m) against central differences
/// (step 10⁻⁶ relative) at the thesis's values.
fn gradient_check(cal: &Calib) -> Res<f64> {
    let (_, g) = cal.eval(THESIS_K, THESIS_K, THESIS_M)?;
    let mut rel = 0.0f64;
    for (i, p0) in [THESIS_K, THESIS_K, THESIS_M].into_iter().enumerate() {
        let eps = 1e-6 * p0;
        let at = |d: f64| {
            let mut v = [THESIS_K, THESIS_K, THESIS_M];
            v[i] += d;
            cal.eval(v[0], v[1], v[2]).map(|r| r.0)
        };
        let fd = (at(eps)? - at(-eps)?) / (2.0 * eps);
        rel = rel.max(((fd - g[i]) / g[i]).abs());
    }
    Ok(rel)
}

impl MisfitGrid {
    /// The RMS misfit on a g × g grid, geometric in k ∈ [150, 3000] and m ∈ [0.3, 15].
    fn compute(cal: &Calib, g: usize) -> Self {
        let (kr, mr) = ((150.0f64, 3000.0f64), (0.3f64, 15.0f64));
        let geo = |r: (f64, f64), i: usize| r.0 * (r.1 / r.0).powf(i as f64 / (g - 1) as f64);
        let mut vals = Vec::with_capacity(g * g);
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for i in 0..g {
            for j in 0..g {
                let (k, m) = (geo(kr, i), geo(mr, j));
                let v = cal.value(k, k, m).map(f64::sqrt).unwrap_or(f64::NAN);
                if v < best.0 {
                    best = (v, k, m);
                }
                vals.push(v);
            }
        }
        MisfitGrid {
            g,
            k_range: kr,
            m_range: mr,
            values: vals,
            best,
        }
    }

    /// Grid points whose simulation failed.
    fn failed(&self) -> usize {
        self.values.iter().filter(|v| !v.is_finite()).count()
    }
}

impl BeamCalib {
    /// Fits the chain to the Euler-Bernoulli beam of `cal` (tied and free), and computes the
    /// trajectories, errors per node, the misfit grid and the tied fit from four other starts.
    fn compute(cal: &Calib, ei: f64, max_iters: usize, g: usize) -> Res<Self> {
        let mut fits = Vec::new();
        for fit in [Fit::Tied, Fit::Free] {
            let t0 = Instant::now();
            let run = lbfgs(cal, fit, &fit.start(), max_iters)?;
            let (k, k1, m) = fit.params(&run.x);
            let seconds = t0.elapsed().as_secs_f64();
            fits.push(FitResult {
                fit,
                k,
                k1,
                m,
                run,
                seconds,
                tip: cal.tip(k, k1, m)?,
                nodes: cal.node_rms(k, k1, m)?,
            });
        }
        let eb_tip = cal
            .objective
            .reference
            .iter()
            .enumerate()
            .map(|(j, r)| (j as f64 * cal.scene.time.step, r[r.len() - 1]))
            .collect();
        let (j_before, _) = cal.eval(THESIS_K, THESIS_K, THESIS_M)?;
        let (j_physical, _) = cal.eval(ei, 2.0 * ei, 1.0)?;
        let rms_ref = (cal
            .objective
            .reference
            .iter()
            .flatten()
            .map(|z| z * z)
            .sum::<f64>()
            * cal.objective.weight)
            .sqrt();
        let mut others = Vec::new();
        for (k0, m0) in [(200.0, 0.5), (200.0, 2.5), (2500.0, 2.5), (700.0, 1.5)] {
            let run = lbfgs(cal, Fit::Tied, &[f64::ln(k0), f64::ln(m0)], max_iters)?;
            others.push(OtherStart {
                start: (k0, m0),
                end: tied_km(&run.x),
                value: run.value,
                why: run.why,
                path: run.path.iter().map(|x| tied_km(x)).collect(),
            });
        }
        Ok(BeamCalib {
            ei,
            eb_tip,
            before_tip: cal.tip(THESIS_K, THESIS_K, THESIS_M)?,
            before_nodes: cal.node_rms(THESIS_K, THESIS_K, THESIS_M)?,
            j_before,
            j_physical,
            rms_ref,
            fits,
            grid: MisfitGrid::compute(cal, g),
            others,
        })
    }

    /// The largest relative distance of the other starts' ends to the tied fit.
    fn spread(&self) -> f64 {
        let tied = &self.fits[0];
        self.others.iter().fold(0.0f64, |s, o| {
            s.max(((o.end.0 - tied.k) / tied.k).abs())
                .max(((o.end.1 - tied.m) / tied.m).abs())
        })
    }
}

/// Colour and dash of fit `fi` on beam `c`.
fn fit_style(c: usize, fi: usize) -> (RGBColor, Dash) {
    (
        color(2 * c + fi),
        if fi == 0 { Dash::Solid } else { Dash::Dashed },
    )
}

/// Per node (1..=n) values as points.
fn per_node(e: &[f64]) -> Vec<(f64, f64)> {
    e.iter()
        .enumerate()
        .map(|(i, e)| ((i + 1) as f64, *e))
        .collect()
}

/// Top: the tip over time, Euler-Bernoulli, the thesis's values and the fits.
fn tip_panel(c: usize, b: &BeamCalib) -> Panel {
    // room below the deepest excursion for the legend
    let zmin = b.eb_tip.iter().map(|q| q.1).fold(0.0, f64::min);
    let mut p = Panel::new(
        format!("Tip, Euler-Bernoulli EI = {} Nm², m = 1 kg/node", b.ei),
        "t [s]",
        "z₁₀ [m]",
    )
    .legend(Legend::LowerLeft)
    .yr(1.6 * zmin, -0.05 * zmin)
    .with(
        Series::line(
            "Euler-Bernoulli (correct free end)",
            b.eb_tip.clone(),
            BLACK,
        )
        .width(3),
    )
    .with(
        Series::line(
            "before: thesis k = k₁ = 1160, m = 2.4",
            b.before_tip.clone(),
            GREY,
        )
        .dashed(),
    );
    for (fi, f) in b.fits.iter().enumerate() {
        let (col, dash) = fit_style(c, fi);
        p.push(
            Series::line(
                format!(
                    "after {}: k = {:.4e}, k₁ = {:.4e}, m = {:.4}",
                    f.fit.name(),
                    f.k,
                    f.k1,
                    f.m
                ),
                f.tip.clone(),
                col,
            )
            .with_dash(dash),
        );
    }
    p
}

/// Middle: the misfit over (k = k₁, m) with the tied fit's path and those from other starts.
fn misfit_map(b: &BeamCalib) -> Panel {
    let path: Vec<(f64, f64)> = b.fits[0].run.path.iter().map(|x| tied_km(x)).collect();
    let mut map = Panel::new(
        format!("RMS misfit over (k = k₁, m), EI = {} Nm²", b.ei),
        "k = k₁ [Nm/rad]",
        "m [kg]",
    )
    .legend(Legend::UpperLeft)
    .heat(Heat {
        x: b.grid.k_range,
        y: b.grid.m_range,
        nx: b.grid.g,
        ny: b.grid.g,
        values: b.grid.values.clone(),
        log: true,
        floor: None,
        label: "RMS misfit [m]".into(),
    })
    .with(
        Series::line(
            "L-BFGS from the thesis's values (ends at the fit)",
            path,
            RGBColor(214, 39, 40),
        )
        .markers()
        .width(2),
    )
    .with(Series::line("start (thesis)", vec![(THESIS_K, THESIS_M)], GREY).points_only());
    for (i, o) in b.others.iter().enumerate() {
        let name = if i == 0 {
            "paths from 4 other starts"
        } else {
            ""
        };
        map.push(
            Series::line(name, o.path.clone(), RGBColor(255, 150, 40))
                .dashed()
                .width(1),
        );
    }
    map.logx = true;
    map.logy = true;
    map
}

/// Bottom left: the RMS residual per L-BFGS iteration of every fit.
fn convergence_panel(beams: &[BeamCalib]) -> Panel {
    let mut conv = Panel::new("L-BFGS convergence", "iteration", "RMS residual [m]")
        .logy()
        .legend(Legend::UpperRight);
    for (c, b) in beams.iter().enumerate() {
        for (fi, f) in b.fits.iter().enumerate() {
            let (col, dash) = fit_style(c, fi);
            let rms = f.run.history.iter().enumerate();
            conv.push(
                Series::line(
                    format!("EI = {}, {}", b.ei, f.fit.name()),
                    rms.map(|(i, j)| (i as f64, j.sqrt())).collect(),
                    col,
                )
                .with_dash(dash)
                .markers(),
            );
        }
    }
    conv
}

/// Bottom right: the RMS error per node before and after.
fn nodes_panel(beams: &[BeamCalib]) -> Panel {
    let mut nodes = Panel::new("Error per node, before and after", "node", "RMS error [m]")
        .logy()
        .yr(5e-4, 50.0)
        .legend(Legend::UpperLeft);
    for (c, b) in beams.iter().enumerate() {
        let before = if c == 0 { Dash::Dashed } else { Dash::Dotted };
        nodes.push(
            Series::line(
                format!("EI = {}: before", b.ei),
                per_node(&b.before_nodes),
                GREY,
            )
            .with_dash(before)
            .markers(),
        );
        for (fi, f) in b.fits.iter().enumerate() {
            let (col, dash) = fit_style(c, fi);
            nodes.push(
                Series::line(
                    format!("EI = {}: {}", b.ei, f.fit.name()),
                    per_node(&f.nodes),
                    col,
                )
                .with_dash(dash)
                .markers(),
            );
        }
    }
    nodes
}

/// One beam's fits in words.
fn beam_note(b: &BeamCalib) -> String {
    let rows: Vec<String> = b
        .fits
        .iter()
        .map(|f| {
            format!(
                "{}: k = {:.5e} Nm/rad, k₁ = {:.5e} Nm/rad, m = {:.5} kg, RMS residual {:.3e} m \
                 ({:.2}% of the reference's RMS displacement), {} iterations, {} adjoint sweeps, \
                 ‖∇J‖ reduced {:.0e}-fold, stopped: {}, {:.2} s",
                f.fit.name(),
                f.k,
                f.k1,
                f.m,
                f.run.value.sqrt(),
                100.0 * f.run.value.sqrt() / b.rms_ref,
                f.run.history.len() - 1,
                f.run.evals,
                f.run.grad_norm0 / f.run.grad_norm.max(f64::MIN_POSITIVE),
                f.run.why,
                f.seconds
            )
        })
        .collect();
    format!(
        "**EI = {} Nm²** (RMS displacement of the reference {:.3} m): before (thesis k = k₁ = \
         1160, m = 2.4) RMS residual {:.3e} m; {}. For comparison, the discretisation's \
         physical values k = EI/l = {}, k₁ = 2k, m = 1 kg give {:.3e} m.",
        b.ei,
        b.rms_ref,
        b.j_before.sqrt(),
        rows.join("; "),
        b.ei,
        b.j_physical.sqrt()
    )
}

/// One beam's misfit grid and other starts in words.
fn grid_note(b: &BeamCalib) -> String {
    let tied = &b.fits[0];
    let ends: Vec<String> = b
        .others
        .iter()
        .map(|o| {
            format!(
                "({}, {}) → ({:.1}, {:.3}), {:.3e} m (stopped: {})",
                o.start.0,
                o.start.1,
                o.end.0,
                o.end.1,
                o.value.sqrt(),
                o.why
            )
        })
        .collect();
    format!(
        "EI = {}: the lowest grid point, {:.3e} m at k = {:.0}, m = {:.2}, lies next to \
         the L-BFGS fit ({:.3e} m at k = {:.1}, m = {:.3}); L-BFGS from 4 other starts: {} \
         (largest relative distance to the fit {:.1e}); \
         {} of {} grid points (light grey, large k with small m) fail: RATTLE's Newton solve does \
         not converge at h = 0.01 s when the chain is that stiff and light",
        b.ei,
        b.grid.best.0,
        b.grid.best.1,
        b.grid.best.2,
        tied.run.value.sqrt(),
        tied.k,
        tied.m,
        ends.join("; "),
        b.spread(),
        b.grid.failed(),
        b.grid.g * b.grid.g
    )
}

/// The figure's note: the method, the gradient check, each beam's fits and grid.
fn calibration_note(t_end: f64, g: usize, fd_check: &str, beams: &[BeamCalib]) -> String {
    let notes: Vec<String> = beams.iter().map(beam_note).collect();
    let grids: Vec<String> = beams.iter().map(grid_note).collect();
    let ratios: Vec<String> = beams
        .iter()
        .map(|b| format!("{:.2} for EI = {}", b.fits[1].k1 / b.fits[1].k, b.ei))
        .collect();
    format!(
        "The thesis cantilever chain (n = 10, l = 1 m, F = 2 N at the tip, h = 0.01 s, t ∈ \
         [0, {t_end}] s) fitted to the finite-difference Euler-Bernoulli cantilever with the \
         corrected free end (L = 10 m, 10 segments, m = 1 kg per node, h = 0.001 s, sampled \
         at the chain's steps) by least squares on all ten node displacements at every step, \
         J = Σ_k Σ_i (z_i − z_i^EB)² / ((N + 1) n). Gradients: one discrete-adjoint sweep \
         (`adjoint_gradient` with a custom `Objective` on `Stage::z`) gives ∂J/∂k (interior \
         springs), ∂J/∂k₁ (base spring) and ∂J/∂m; the library's L-BFGS (`minimize` on an \
         `OptimProblem`: argmin's L-BFGS, memory 5, More-Thuente line search, iterates \
         recorded by a `History` observer) in log-parameters, started from the thesis's \
         trial-and-error k = 1.16e3, m = 2.4. Two \
         fits: the thesis's model with one k for all springs (k = k₁), and k, k₁ free. {} \
         {} Top: tip trajectories (black: Euler-Bernoulli; grey dashed: the thesis's \
         values; colours: the fits). Middle: the RMS misfit over the thesis's family \
         (k = k₁, m) on a {g}×{g} log grid over k ∈ [150, 3000] Nm/rad, m ∈ [0.3, 15] kg with \
         the (k = k₁) fit's L-BFGS path and those from four other starts ({}). A start \
         that ends elsewhere has found another local minimum: a least-squares fit of \
         oscillating trajectories is not convex in the frequency √(k/m) — a much slower \
         chain can match part of the oscillation — so the start matters; the thesis's \
         hand-tuned values lie in the basin of the good minimum for both beams. Bottom: residual per \
         iteration and per node. The fitted m < 1 kg: the Euler-Bernoulli beam's free tip \
         carries half a cell's mass (0.5 kg, total 9.5 kg), which a uniform-mass chain \
         cannot represent, so the fit trades mass for the right frequencies. Beyond \
         the thesis: it tuned by eye against its own (wrong free end) Euler-Bernoulli beam; \
         against the correct one its values are far off, and the gradient fit recovers \
         k₁/k = {} — the base spring k₁ = 2k that the static formula 2.4.5 asks for, \
         with a departure at EI = 312.5, where the tip swings through 40% of the length and the \
         chain's geometric nonlinearity enters.",
        fd_check,
        notes.join(" "),
        grids.join("; "),
        ratios.join(" and "),
    )
}

/// The calibration figure: data (each beam's fits, grid and other starts) → plot (tips, misfit
/// maps, convergence, errors per node) and note.
fn calibration(ctx: &Ctx) -> Res<Made> {
    let t_end = if ctx.quick { 2.0 } else { 10.0 };
    let max_iters = if ctx.quick { 15 } else { 200 };
    let g = if ctx.quick { 9 } else { 31 };
    let mut fd_check = String::new();
    let mut beams = Vec::new();
    for (c, ei) in [312.5, 1000.0].into_iter().enumerate() {
        let cal = Calib::new(ei, t_end)?;
        if c == 0 {
            fd_check = format!(
                "The adjoint's ∂J/∂(k, k₁, m) agrees with central differences to {:.1e} \
                 (relative) at the start.",
                gradient_check(&cal)?
            );
        }
        beams.push(BeamCalib::compute(&cal, ei, max_iters, g)?);
    }
    let mut panels: Vec<Panel> = beams
        .iter()
        .enumerate()
        .map(|(c, b)| tip_panel(c, b))
        .collect();
    panels.extend(beams.iter().map(misfit_map));
    panels.push(convergence_panel(&beams));
    panels.push(nodes_panel(&beams));
    let files = ctx.save(&Figure::new("calibration", 2, panels))?;
    Ok(Made {
        files,
        note: calibration_note(t_end, g, &fd_check, &beams),
    })
}

//! Chapter 3, the optimiser's figures: the landscapes of the optimal-control problem of thesis
//! §3.3.1 (Fig. 3.7, 3.8, 3.10, 3.13) on the thesis scene (`catalogue::riser(10)`: riser with
//! base and tip springs 2000 Nm/rad, F = 2 N at node 10, control at node 10, h = 0.01 s, N = 10),
//! in single shooting with exact discrete-adjoint gradients (`chainbeam::optimize`,
//! `chainbeam::multistart`).
//!
//! The thesis solved the problem simultaneously (states and controls as SLSQP variables, 800
//! equality constraints) and read its scattered local solutions as a "highly nonconvex" landscape.
//! Here the dynamics are satisfied exactly by simulation, so J is a function of the controls
//! alone and the figures show that function.

use crate::plot::{color, Figure, Heat, Legend, Panel, Res, Series, GREY};
use crate::{Ctx, Entry, Made};
use chainbeam::adjoint::{Objective, Stage};
use chainbeam::multistart::{
    axis, certify, landscape_1d, landscape_2d, multistart, MultistartReport, StartDesign,
};
use chainbeam::optimize::{
    minimize, History, Method, Minimizer, ObserverMode, OptimOptions, OptimResult,
};
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl, Scalar, Scene,
};
use plotters::style::RGBColor;

const BLACK: RGBColor = RGBColor(0, 0, 0);
const RED: RGBColor = RGBColor(214, 39, 40);

/// Thesis Table 3.1 / 3.2, load at node 10: the reported optima (u, J).
const THESIS_OPT_FINAL: (f64, f64) = (-2.00000082, 8.1400e-16);
const THESIS_OPT_SUM: (f64, f64) = (-2.00000132, 6.8049e-16);
/// The local solution the thesis reports first for the final moment (§3.3.1): u, c.
const THESIS_LOCAL: (f64, f64) = (-0.4301, 3.9027e-4);

pub fn entries() -> Vec<Entry> {
    vec![
        Entry {
            id: "fig_3_7",
            caption: "Objective function c_sum(Ỹ) of ten randomized initial conditions of the \
                      Cantilever beam with a spring in the final node, affected by an external \
                      force F = 2 N in the final node. Every point is a local solution of the \
                      optimizer.",
            make: fig_3_7,
        },
        Entry {
            id: "fig_3_8",
            caption: "Optimization results of the Cantilever beam with spring in the final node, \
                      affected by an external force F = 2 N in the final node. Left row shows the \
                      evolution of the control force u and the resulting objective function c(Y). \
                      Top right: figure shows the objective function c(Y) against the control \
                      force u. Bottom right: log plot of the objective function.",
            make: fig_3_8,
        },
        Entry {
            id: "fig_3_10",
            caption: "Objective function c_sum(Ỹ) of ten randomized initial conditions of the \
                      Cantilever beam with a spring in the final node, affected by an external \
                      force F = 2 N in the final node. Every point is a local solution of the \
                      optimizer.",
            make: fig_3_10,
        },
        Entry {
            id: "fig_3_13",
            caption: "Objective function c(Ỹ) of different initial conditions of the Cantilever \
                      beam with a spring in the final node affected by an external force F = 2 N \
                      in the final node. Left: Ten randomized initial conditions. Every horizontal \
                      line of points is a local solution of the optimizer, u = [u_0 … u_N]. \
                      Right: Solutions of 21 initial conditions of the form Ỹ_0, with the control \
                      forces u initialized as a vector of -10 in the first simulation, up to 10 in \
                      the final.",
            make: fig_3_13,
        },
    ]
}

/// The thesis scene of §3.3.1 (load and control at node 10, N = 10).
fn scene() -> Scene {
    catalogue::riser(10)
}

fn constant_problem(obj: BendingObjective) -> Res<ControlProblem> {
    Ok(ControlProblem::new(
        &scene(),
        Parametrisation::Constant,
        obj,
    )?)
}

fn per_step_problem(obj: BendingObjective) -> Res<ControlProblem> {
    let s = scene();
    let map = Parametrisation::PerStep(PerStepControl {
        steps: s.time.steps,
    });
    Ok(ControlProblem::new(&s, map, obj)?)
}

/// Subscript digits.
fn sub(k: usize) -> String {
    k.to_string()
        .chars()
        .map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
        .collect()
}

/// u with a subscript: u₀, u₁₀.
fn us(k: usize) -> String {
    format!("u{}", sub(k))
}

fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// Converged results only; the number that did not converge.
fn converged(rep: &MultistartReport) -> (Vec<&OptimResult>, usize) {
    let ok: Vec<&OptimResult> = rep.results.iter().filter(|r| r.converged).collect();
    let bad = rep.results.len() - ok.len() + rep.failures.len();
    (ok, bad)
}

// ---------------------------------------------------------------------------------------------
// Fig. 3.7 and 3.10: the constant-control landscape
// ---------------------------------------------------------------------------------------------

fn fig_3_7(ctx: &Ctx) -> Res<Made> {
    constant_landscape(ctx, "fig_3_7", BendingObjective::final_moment())
}

fn fig_3_10(ctx: &Ctx) -> Res<Made> {
    constant_landscape(ctx, "fig_3_10", BendingObjective::summed_moment())
}

fn constant_landscape(ctx: &Ctx, name: &str, obj: BendingObjective) -> Res<Made> {
    let final_obj = name == "fig_3_7";
    let (sym, unit) = if final_obj {
        ("c", "c = M₀(T)² [N²m²]")
    } else {
        ("c_sum", "c_sum = Σ M₀(t_k)² [N²m²]")
    };
    let p = constant_problem(obj)?;
    // the default relative gradient tolerance (1e-8 ‖g₀‖) stops starts at |u| ~ 300, where ‖g₀‖ is
    // large, at |u − u*| ~ 1e-6: ask for round-off instead
    let opts = OptimOptions {
        rel_grad_tol: 1e-15,
        ..Default::default()
    };
    let starts = if ctx.quick { 4 } else { 10 };
    // the thesis's Ỹ₀ + U(−0.1, 0.1) (on the control), a box [−10, 10] and a wide box
    let designs = [
        (
            "u₀ ∈ 0 + U(−0.1, 0.1)",
            StartDesign::Perturb {
                center: vec![0.0],
                radius: 0.1,
            },
        ),
        (
            "u₀ ∈ U(−10, 10)",
            StartDesign::RandomBox {
                lo: -10.0,
                hi: 10.0,
            },
        ),
        (
            "u₀ ∈ U(−300, 300)",
            StartDesign::RandomBox {
                lo: -300.0,
                hi: 300.0,
            },
        ),
    ];
    let mut sols = Vec::new();
    let mut start_pts = Vec::new();
    let mut not_conv = 0;
    let mut minima = Vec::new();
    let mut iters = Vec::new();
    for (seed, (_, d)) in designs.iter().enumerate() {
        let rep = multistart(&p, d, starts, 307 + seed as u64, 0, &opts)?;
        let (ok, bad) = converged(&rep);
        not_conv += bad;
        for r in ok {
            sols.push((r.theta[0], r.objective));
            iters.push(r.iterations);
        }
        for s in &rep.start_points {
            start_pts.push(s[0]);
        }
        minima.extend(rep.minima.iter().map(|m| (m.theta[0], m.objective)));
    }
    let n_sol = sols.len();
    let u_min = sols.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let u_max = sols.iter().map(|s| s.0).fold(f64::NEG_INFINITY, f64::max);
    let j_max = sols.iter().map(|s| s.1).fold(0.0, f64::max);

    // left: J(u) on [−10, 6] with the starts (inside the window) and the local solutions
    let pts = if ctx.quick { 81 } else { 321 };
    let curve = landscape_1d(&p, &[0.0], &axis(1, 0), (-10.0, 6.0), pts)?;
    let on_curve: Vec<(f64, f64)> = start_pts
        .iter()
        .filter(|u| (-10.0..=6.0).contains(*u))
        .map(|&u| Ok((u, p.value(&[u])?)))
        .collect::<Res<_>>()?;
    let mut left = Panel::new(
        format!("{sym}(u) for a constant control (exact, single shooting)"),
        "u [N]",
        unit,
    )
    .legend(Legend::UpperLeft)
    .with(Series::line(format!("{sym}(u)"), curve, color(0)))
    .with(
        Series::line(
            format!(
                "start points in view ({} of {})",
                on_curve.len(),
                start_pts.len()
            ),
            on_curve,
            GREY,
        )
        .points_only(),
    )
    .with(
        Series::line(
            format!("{n_sol} local solutions (L-BFGS)"),
            sols.clone(),
            RED,
        )
        .points_only(),
    );
    let mut thesis_note = String::new();
    if final_obj {
        let c_true = p.value(&[THESIS_LOCAL.0])?;
        left.push(
            Series::line(
                "thesis's local solution u = −0.4301 N",
                vec![THESIS_LOCAL],
                color(2),
            )
            .points_only(),
        );
        let p_sum = ControlProblem::new(
            &scene(),
            Parametrisation::Constant,
            BendingObjective::summed_moment(),
        )?;
        let (sum_local, sum0, c0) = (
            p_sum.value(&[THESIS_LOCAL.0])?,
            p_sum.value(&[0.0])?,
            p.value(&[0.0])?,
        );
        thesis_note = format!(
            " The thesis's first 'local solution' (u = −0.4301 N, c = 3.90e-4 N²m², green) is \
             not on the curve: the dynamics give c(−0.4301) = {} N²m² (c_sum {}) and c′ ≠ 0 \
             there, so it is no local minimum of the problem with the dynamics satisfied — most \
             likely a point where the simultaneous SLSQP solve stopped with unsatisfied \
             constraints. The thesis's uncontrolled reference 'c = 1.0843 × 10³ N²m²' is our \
             c_sum(0) = {sum0:.4e} N²m² (c(0) = {c0:.4e}): the value is c_sum and the exponent's \
             sign a typo.",
            sci(c_true),
            sci(sum_local),
        );
    }

    // right: J against |u − u*| on log-log axes, both branches, with the local solutions
    let u_star = -2.0;
    let decades: Vec<f64> = (0..=(if ctx.quick { 40 } else { 120 }))
        .map(|i| 10f64.powf(-8.0 + 10.5 * i as f64 / if ctx.quick { 40.0 } else { 120.0 }))
        .collect();
    let mut below = Vec::new();
    let mut above = Vec::new();
    for &d in &decades {
        below.push((d, p.value(&[u_star - d])?));
        above.push((d, p.value(&[u_star + d])?));
    }
    // parabola through the point d = 1 (J = a d²) and its deviation at the wide end
    let a = above
        .iter()
        .find(|q| (q.0 - 1.0).abs() < 0.05)
        .map_or(p.value(&[u_star + 1.0])?, |q| q.1 / (q.0 * q.0));
    let dev = |q: &(f64, f64)| (q.1 / (a * q.0 * q.0) - 1.0).abs();
    let dev_10 = above
        .iter()
        .chain(below.iter())
        .filter(|q| q.0 <= 10.0)
        .map(dev)
        .fold(0.0, f64::max);
    let dev_300 = above
        .iter()
        .chain(below.iter())
        .map(dev)
        .fold(0.0, f64::max);
    let monotone = |v: &[(f64, f64)]| v.windows(2).all(|w| w[1].1 > w[0].1);
    let one_sign = monotone(&above) && monotone(&below);
    let sym_err = above
        .iter()
        .zip(&below)
        .map(|(x, y)| ((x.1 - y.1) / x.1).abs())
        .fold(0.0, f64::max);
    let floor = 1e-17;
    let sol_pts: Vec<(f64, f64)> = sols
        .iter()
        .map(|&(u, j)| ((u - u_star).abs().max(floor), j.max(1e-40)))
        .collect();
    let thesis_opt = if final_obj {
        THESIS_OPT_FINAL
    } else {
        THESIS_OPT_SUM
    };
    let j_thesis_true = p.value(&[thesis_opt.0])?;
    let right = Panel::new(
        format!("{sym} against the distance from u* = −2 N"),
        "|u − u*| [N]",
        unit,
    )
    .loglog()
    .legend(Legend::UpperLeft)
    .with(Series::line("u > u*", above, color(0)))
    .with(Series::line("u < u*", below, color(1)).dashed())
    .with(
        Series::line(
            format!("slope 2: {} · |u − u*|²", sci(a)),
            vec![(1e-17, a * 1e-34), (1e3, a * 1e6)],
            GREY,
        )
        .dotted()
        .width(1),
    )
    .with(
        Series::line(
            format!("{n_sol} local solutions (exact zeros drawn at the axis edge)"),
            sol_pts,
            RED,
        )
        .points_only(),
    )
    .with(
        Series::line(
            format!(
                "thesis optimum u = {:.8} N (Table {})",
                thesis_opt.0,
                if final_obj { "3.1" } else { "3.2" }
            ),
            vec![((thesis_opt.0 - u_star).abs(), thesis_opt.1)],
            color(2),
        )
        .points_only(),
    )
    .xr(1e-18, 1e3)
    .yr(1e-40, 1e3);
    let files = ctx.save(&Figure::new(name, 2, vec![left, right]))?;
    Ok(Made {
        files,
        note: format!(
            "Riser of §3.3.1 (F = 2 N and the control at node 10, h = 0.01 s, N = 10), objective \
             {sym}{}, constant control. Left: the exact {sym}(u) from the library's simulation \
             (a function of u alone: the dynamics hold exactly in single shooting) and the local \
             solutions of {} L-BFGS runs with exact adjoint gradients from three start designs \
             ({}; {} runs did not converge). Every run ends at the same point: u ∈ [{:.15}, \
             {:.15}] N with {sym} ≤ {} N²m², in {}-{} iterations; `multistart` finds {} \
             minimum per design, at u* = −2 N. Right: {sym} against |u − u*| on log-log axes; the \
             two branches coincide (relative difference ≤ {}: the response depends on F + u only \
             and is mirror symmetric), {} and follow the parabola a·(u − u*)², a = {} N²m²/N², \
             to a relative {} for |u − u*| ≤ 10 N and {:.1}% up to 316 N: one minimum with \
             {sym} = 0 and no other stationary point. Differs from the thesis, whose ten \
             'local solutions' scattered around the parabola came from its simultaneous SLSQP \
             formulation (states as variables, dynamics as 800 equality constraints); the \
             parabola and the minimum at u = −2 N agree. The thesis's optimum u = {:.8} N has \
             the true {sym} = {} (thesis {}); our runs end within {} N of u*, at {sym} ≤ {}.{}",
            if final_obj {
                " = M₀(T)² (eq. 3.3.2; the caption says c_sum, but the figure sits in the \
                 'final bending moment' part of §3.3.1 and its text is about c, which is what \
                 this figure uses — Fig. 3.10 is c_sum)"
            } else {
                " = Σ M₀(t_k)² (eq. 3.3.4)"
            },
            n_sol + not_conv,
            designs
                .iter()
                .map(|d| format!("{} × {starts}", d.0))
                .collect::<Vec<_>>()
                .join(", "),
            not_conv,
            u_min,
            u_max,
            sci(j_max),
            iters.iter().min().copied().unwrap_or(0),
            iters.iter().max().copied().unwrap_or(0),
            if minima.len() == designs.len() {
                "one".to_string()
            } else {
                format!("{} minima in all (see the plot)", minima.len())
            },
            sci(sym_err),
            if one_sign {
                "increase monotonically away from u* over the sampled 10⁻⁸-316 N"
            } else {
                "are NOT monotone (see the plot)"
            },
            sci(a),
            sci(dev_10),
            100.0 * dev_300,
            thesis_opt.0,
            sci(j_thesis_true),
            sci(thesis_opt.1),
            sci(sols
                .iter()
                .map(|s| (s.0 - u_star).abs())
                .fold(0.0, f64::max)),
            sci(j_max),
            thesis_note,
        ),
    })
}

// ---------------------------------------------------------------------------------------------
// Fig. 3.8: optimisation history
// ---------------------------------------------------------------------------------------------

/// The iterates θ_0, θ_1, … of one run, recorded by a `History` observer (the start, every
/// solver iteration and every polish step), ending at the run's result.
fn history(p: &ControlProblem, theta0: &[f64], method: Method) -> Res<Vec<(Vec<f64>, f64)>> {
    let recorder = History::default();
    let opts = OptimOptions {
        method,
        ..Default::default()
    };
    let r = Minimizer::new(p, opts)
        .add_observer(recorder.clone(), ObserverMode::Always)
        .run(theta0)?;
    let mut out: Vec<(Vec<f64>, f64)> = recorder
        .records()
        .into_iter()
        .map(|x| (x.theta, x.objective))
        .collect();
    if out.last().is_none_or(|x| x.0 != r.theta) {
        out.push((r.theta, r.objective));
    }
    Ok(out)
}

/// The thesis's stepping (eq. 3.3.3) on the exact c: u_{m+1} = u_m − α (c_m − c_{m−1})/(u_m −
/// u_{m−1}), from u₀ and the perturbed u₁ = u₀ + δ, until |c_m − c_{m−1}| < tol. In single
/// shooting each of the thesis's local solves is one evaluation of c.
fn thesis_stepping(
    p: &ControlProblem,
    u0: f64,
    delta: f64,
    alpha: f64,
    tol: f64,
) -> Res<Vec<(Vec<f64>, f64)>> {
    let mut h = vec![(vec![u0], p.value(&[u0])?)];
    let u1 = u0 + delta;
    h.push((vec![u1], p.value(&[u1])?));
    while h.len() < 200 {
        let (a, b) = (&h[h.len() - 2], &h[h.len() - 1]);
        if (b.1 - a.1).abs() < tol || b.0[0] == a.0[0] {
            break;
        }
        let u = b.0[0] - alpha * (b.1 - a.1) / (b.0[0] - a.0[0]);
        h.push((vec![u], p.value(&[u])?));
    }
    Ok(h)
}

fn fig_3_8(ctx: &Ctx) -> Res<Made> {
    use crate::plot::Dash;
    let p = constant_problem(BendingObjective::final_moment())?;
    let mut pu = Panel::new("Control force", "iteration", "u [N]").legend(Legend::UpperRight);
    let mut pc = Panel::new("Objective", "iteration", "c [N²m²]").legend(Legend::UpperRight);
    let mut pcu = Panel::new("c against u", "u [N]", "c [N²m²]").legend(Legend::UpperLeft);
    let mut plog = Panel::new(
        "Objective, log scale (c = 0 drawn at 1e-40)",
        "iteration",
        "c [N²m²]",
    )
    .logy()
    .legend(Legend::UpperRight);
    let curve = landscape_1d(&p, &[0.0], &axis(1, 0), (-4.5, 0.5), 101)?;
    pcu.push(Series::line("c(u)", curve, GREY).width(1));
    let alpha = 1000.0;
    let mut runs = vec![(
        format!("thesis stepping (3.3.3), α = {alpha}"),
        thesis_stepping(&p, 0.0, -0.1, alpha, 1e-20)?,
        Dash::Solid,
        color(3),
        1,
    )];
    let tr = history(&p, &[0.0], Method::TrustRegion)?;
    let ncg = history(&p, &[0.0], Method::NewtonCg)?;
    let same = tr.len() == ncg.len()
        && tr
            .iter()
            .zip(&ncg)
            .all(|(a, b)| (a.0[0] - b.0[0]).abs() <= 1e-12 && (a.1 - b.1).abs() <= 1e-20);
    runs.push((
        "L-BFGS".into(),
        history(&p, &[0.0], Method::Lbfgs)?,
        Dash::Solid,
        color(0),
        2,
    ));
    if same {
        runs.push((
            "trust region = Newton-CG (identical)".into(),
            tr,
            Dash::Dashed,
            color(1),
            2,
        ));
    } else {
        runs.push(("trust region".into(), tr, Dash::Dashed, color(1), 2));
        runs.push(("Newton-CG".into(), ncg, Dash::Dotted, color(2), 2));
    }
    let mut rows = Vec::new();
    for (name, h, dash, col, w) in &runs {
        let it = |f: fn(&(Vec<f64>, f64)) -> f64| -> Vec<(f64, f64)> {
            h.iter()
                .enumerate()
                .map(|(j, x)| (j as f64, f(x)))
                .collect()
        };
        let ser = |pts: Vec<(f64, f64)>| {
            Series::line(name.as_str(), pts, *col)
                .with_dash(*dash)
                .width(*w)
                .markers()
        };
        pu.push(ser(it(|x| x.0[0])));
        pc.push(ser(it(|x| x.1)));
        plog.push(ser(it(|x| x.1.max(1e-40))));
        pcu.push(ser(h.iter().map(|x| (x.0[0], x.1)).collect()));
        let last = h.last().map_or((0.0, 0.0), |x| (x.0[0], x.1));
        rows.push(format!(
            "{name}: u = {:.12} N, c = {} N²m² after {} iterations",
            last.0,
            sci(last.1),
            h.len() - 1
        ));
    }
    let files = ctx.save(&Figure::new("fig_3_8", 2, vec![pu, pcu, pc, plog]))?;
    Ok(Made {
        files,
        note: format!(
            "Riser of §3.3.1 with F = 2 N at node 10, constant control, c = M₀(T)², from u = 0 \
             (c = {} N²m²). The library's solvers on exact adjoint gradients (and exact \
             Hessian-vector products for the trust region and Newton-CG; the iterates recorded \
             by a `History` observer on one run), and for \
             comparison the thesis's own stepping rule (eq. 3.3.3: a backward-difference slope \
             and a fixed step α, here α = {alpha} N²/(N²m²) — the thesis does not give its α — \
             from u = 0 and the perturbed u = −0.1 N, stopping when |Δc| < 1e-20) run on the \
             exact c, each of its 'local solves' being one simulation in single shooting. {}. \
             Thesis: u = −2.00000082 N, c = 6.97e-16 N²m². Same picture (u → −2, c → 0 along the \
             parabola; the secant stepping converges linearly), but the \
             library's quasi-Newton and Newton methods need 2-3 iterations and reach round-off, \
             because c is an exact, smooth function of u here with an exact derivative.",
            sci(p.value(&[0.0])?),
            rows.join("; ")
        ),
    })
}

// ---------------------------------------------------------------------------------------------
// Fig. 3.13: the per-step landscape
// ---------------------------------------------------------------------------------------------

/// M₀(t_j): a linear "objective" whose adjoint gradient is row j of the sensitivity matrix
/// ∂M₀(t_j)/∂u_k.
struct MomentAt(usize);

impl Objective for MomentAt {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        if s.k == self.0 {
            s.moment
        } else {
            s.moment * 0.0
        }
    }
}

fn fig_3_13(ctx: &Ctx) -> Res<Made> {
    let quick = ctx.quick;
    let pf = per_step_problem(BendingObjective::final_moment())?;
    let ps = per_step_problem(BendingObjective::summed_moment())?;
    let n = pf.n_params();
    // c_sum's curvature is graded down to ~1e-13 along u₄ (see the note): the default relative
    // gradient tolerance 1e-8 stops L-BFGS at J ~ 1e-12 there; 1e-12 reaches round-off
    let opts = OptimOptions {
        rel_grad_tol: 1e-12,
        ..Default::default()
    };
    let n_random = if quick { 4 } else { 10 };
    let box10 = StartDesign::RandomBox {
        lo: -10.0,
        hi: 10.0,
    };
    // thesis left: random starts; thesis right: 21 constant vectors −10..10
    let rep = multistart(&pf, &box10, n_random, 1313, 0, &OptimOptions::default())?;
    let consts: Vec<f64> = if quick {
        vec![-10.0, 0.0, 10.0]
    } else {
        (0..21).map(|i| -10.0 + i as f64).collect()
    };
    let mut const_sols = Vec::new();
    for &c in &consts {
        const_sols.push(minimize(&pf, &vec![c; n], &OptimOptions::default())?);
    }
    let (rand_sols, rand_bad) = converged(&rep);
    let const_bad = const_sols.iter().filter(|r| !r.converged).count();
    let rows = |sols: &[&OptimResult], title: String| -> Panel {
        let mut p = Panel::new(title, "u_k [N] (k = 0…10)", "c at the solution [N²m²]")
            .logy()
            .legend(Legend::None);
        for (i, r) in sols.iter().enumerate() {
            p.push(
                Series::line(
                    "",
                    r.theta
                        .iter()
                        .map(|&u| (u, r.objective.max(1e-40)))
                        .collect(),
                    color(i),
                )
                .points_only(),
            );
        }
        p
    };
    let jtop = |v: &[&OptimResult]| v.iter().map(|r| r.objective).fold(0.0, f64::max);
    let const_refs: Vec<&OptimResult> = const_sols.iter().collect();
    let left = rows(
        &rand_sols,
        format!(
            "{} random starts in [−10, 10]¹¹: all c ≤ {}",
            n_random,
            sci(jtop(&rand_sols))
        ),
    );
    let right = rows(
        &const_refs,
        format!(
            "{} starts u = (s, …, s), s = −10 … 10: all c ≤ {}",
            consts.len(),
            sci(jtop(&const_refs))
        ),
    );
    let mut files = ctx.save(&Figure::new("fig_3_13", 2, vec![left, right]))?;

    // the landscape itself
    let best = rep
        .minima
        .first()
        .map(|m| m.theta.clone())
        .ok_or("no per-step start converged")?;
    let rep_s = multistart(&ps, &box10, n_random, 1313, 0, &opts)?;
    let best_s = rep_s
        .minima
        .first()
        .map(|m| m.theta.clone())
        .ok_or("no per-step c_sum start converged")?;
    let cert_f = certify(&pf, &best, None)?;
    let cert_s = certify(&ps, &best_s, None)?;
    // convexity in the box: the Hessian's extreme eigenvalues at the random start points
    let mut worst = (0.0f64, 0.0f64);
    for (k, p) in [&pf, &ps].into_iter().enumerate() {
        for th in &rep.start_points {
            let c = certify(p, th, None)?;
            let lo = c.eigenvalues.first().copied().unwrap_or(0.0);
            let hi = c.eigenvalues.last().copied().unwrap_or(0.0);
            let r = if hi > 0.0 { lo / hi } else { 0.0 };
            if k == 0 {
                worst.0 = worst.0.min(r);
            } else {
                worst.1 = worst.1.min(r);
            }
        }
    }
    // c_sum: how far the random-start solutions are from u₀ = … = u₄ = −2
    let (sum_sols, sum_bad) = converged(&rep_s);
    let sum_dev = sum_sols
        .iter()
        .flat_map(|r| r.theta.iter().take(5).map(|u| (u + 2.0).abs()))
        .fold(0.0, f64::max);
    let sum_j = (
        sum_sols
            .iter()
            .map(|r| r.objective)
            .fold(f64::INFINITY, f64::min),
        sum_sols.iter().map(|r| r.objective).fold(0.0, f64::max),
    );
    // the same c_sum starts with the library's defaults, L-BFGS and the trust region
    let summary = |o: &OptimOptions| -> Res<String> {
        let r = multistart(&ps, &box10, n_random, 1313, 0, o)?;
        let (ok, bad) = converged(&r);
        let jm = ok.iter().map(|r| r.objective).fold(0.0, f64::max);
        let du = ok
            .iter()
            .flat_map(|r| r.theta.iter().take(5).map(|u| (u + 2.0).abs()))
            .fold(0.0, f64::max);
        let it = ok.iter().map(|r| r.iterations).max().unwrap_or(0);
        Ok(format!(
            "{}: J ≤ {}, max |u_k + 2| (k ≤ 4) = {}, ≤ {it} iterations, {bad} not converged",
            o.method.name(),
            sci(jm),
            sci(du)
        ))
    };
    let defaults = [
        summary(&OptimOptions::default())?,
        summary(&OptimOptions {
            method: Method::TrustRegion,
            ..Default::default()
        })?,
    ];
    let sum_iters = sum_sols.iter().map(|r| r.iterations).max().unwrap_or(0);
    // (a) control profiles
    let mut prof = Panel::new(
        format!(
            "Local solutions for c ({} random starts); dashed: u ≡ −2 N",
            rand_sols.len()
        ),
        "time step k",
        "u_k [N]",
    )
    .legend(Legend::None);
    for (i, r) in rand_sols.iter().enumerate() {
        prof.push(
            Series::line(
                "",
                r.theta
                    .iter()
                    .enumerate()
                    .map(|(k, &u)| (k as f64, u))
                    .collect(),
                color(i),
            )
            .markers()
            .width(1),
        );
    }
    prof.push(
        Series::line("u ≡ −2 N", vec![(0.0, -2.0), ((n - 1) as f64, -2.0)], BLACK)
            .dashed()
            .width(2),
    );
    // (b) Hessian spectra
    let spec = |c: &chainbeam::multistart::Certificate| -> Vec<(f64, f64)> {
        let mut e: Vec<f64> = c.eigenvalues.iter().map(|x| x.abs()).collect();
        e.sort_by(|a, b| b.total_cmp(a));
        e.iter()
            .enumerate()
            .map(|(i, &x)| ((i + 1) as f64, x.max(1e-30)))
            .collect()
    };
    let rank = |c: &chainbeam::multistart::Certificate| {
        let mx = c.eigenvalues.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        c.eigenvalues
            .iter()
            .filter(|x| x.abs() > 1e-12 * mx)
            .count()
    };
    let (rank_f, rank_s) = (rank(&cert_f), rank(&cert_s));
    let eig = Panel::new(
        "Hessian eigenvalues at a local solution (0 drawn at 1e-30)",
        "index (descending)",
        "|λ| [N²m²/N²]",
    )
    .logy()
    .legend(Legend::UpperRight)
    .with(
        Series::line(
            format!("c (final): {rank_f} above round-off"),
            spec(&cert_f),
            color(0),
        )
        .markers(),
    )
    .with(
        Series::line(
            format!("c_sum: {rank_s} above round-off"),
            spec(&cert_s),
            color(1),
        )
        .markers()
        .dashed(),
    );
    // (c) 1-D slices along each u_k through the solution
    let pts = if quick { 41 } else { 161 };
    let mut slices = Panel::new(
        "1-D slices c(u* + t e_k) through a local solution",
        "t [N]",
        "c [N²m²]",
    )
    .logy()
    .yr(1e-36, 1e-1)
    .legend(Legend::LowerLeft);
    let j_best = pf.value(&best)?;
    let mut flat = Vec::new();
    let mut curved = Vec::new();
    let mut slice_max = Vec::new();
    let mut all = Vec::new();
    for k in 0..n {
        let s = landscape_1d(&pf, &best, &axis(n, k), (-10.0, 10.0), pts)?;
        all.push(
            s.into_iter()
                .map(|(t, j)| (t, j.max(1e-36)))
                .collect::<Vec<_>>(),
        );
    }
    for (k, s) in all.into_iter().enumerate() {
        let mx = s.iter().map(|q| q.1).fold(0.0, f64::max);
        slice_max.push(format!("{}: {}", us(k), sci(mx)));
        // flat: the slice never leaves the round-off of J at the solution
        if mx <= 10.0 * j_best + 1e-24 {
            flat.push(k);
            slices.push(Series::line(format!("{}: flat", us(k)), s, BLACK).dashed());
        } else {
            curved.push(k);
            slices.push(Series::line(us(k), s, color(k)));
        }
    }
    // (d) the segment between two local solutions, for c and c_sum
    let seg = |p: &ControlProblem, a: &[f64], b: &[f64]| -> Res<Vec<(f64, f64)>> {
        let d: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
        Ok(
            landscape_1d(p, a, &d, (-0.5, 1.5), if quick { 41 } else { 161 })?
                .into_iter()
                .map(|(t, j)| (t, j.max(1e-40)))
                .collect(),
        )
    };
    let mut segp = Panel::new(
        "Straight line between two local solutions A (t = 0), B (t = 1)",
        "t",
        "objective [N²m²]",
    )
    .logy()
    .legend(Legend::LowerRight);
    let mut seg_max = (0.0f64, 0.0f64);
    if rand_sols.len() >= 2 {
        let s = seg(&pf, &rand_sols[0].theta, &rand_sols[1].theta)?;
        seg_max.0 = s
            .iter()
            .filter(|q| (0.0..=1.0).contains(&q.0))
            .map(|q| q.1)
            .fold(0.0, f64::max);
        segp.push(Series::line("c, two random-start solutions", s, color(0)));
    }
    if sum_sols.len() >= 2 {
        let s = seg(&ps, &sum_sols[0].theta, &sum_sols[1].theta)?;
        seg_max.1 = s
            .iter()
            .filter(|q| (0.0..=1.0).contains(&q.0))
            .map(|q| q.1)
            .fold(0.0, f64::max);
        segp.push(Series::line("c_sum, two random-start solutions", s, color(1)).dashed());
    }
    files.extend(ctx.save(&Figure::new(
        "fig_3_13_landscape",
        2,
        vec![prof, eig, slices, segp],
    ))?);

    // 2-D slices and the sensitivity matrix
    let g = if quick { 31 } else { 81 };
    let heat2 = |p: &ControlProblem, c: &[f64], i: usize, j: usize, title: String| -> Res<Panel> {
        let v = landscape_2d(p, c, [&axis(n, i), &axis(n, j)], [(-10.0, 10.0); 2], [g, g])?;
        Ok(Panel::new(
            title,
            format!("{} − {}* [N]", us(i), us(i)),
            format!("{} − {}* [N]", us(j), us(j)),
        )
        .legend(Legend::None)
        .heat(Heat {
            x: (-10.0, 10.0),
            y: (-10.0, 10.0),
            nx: g,
            ny: g,
            values: v.iter().map(|r| r[2]).collect(),
            log: true,
            floor: Some(1e-8),
            label: "objective [N²m²]".into(),
        })
        .with(Series::line("", vec![(0.0, 0.0)], RED).points_only()))
    };
    let h01 = heat2(&pf, &best, 0, 1, "c over (u₀, u₁) through u*".into())?;
    let last_free = n - 1;
    let h0f = heat2(
        &pf,
        &best,
        0,
        last_free,
        format!("c over (u₀, {}) through u*", us(last_free)),
    )?;
    let hs = heat2(&ps, &best_s, 0, 1, "c_sum over (u₀, u₁) through u*".into())?;
    // sensitivity ∂M₀(t_j)/∂u_k at u ≡ −2
    let steps = pf.steps();
    let u_eq = vec![-2.0; n];
    let mut sens = vec![0.0; n * (steps + 1)];
    for j in 0..=steps {
        let pj = ControlProblem::new(
            &scene(),
            Parametrisation::PerStep(PerStepControl { steps }),
            MomentAt(j),
        )?;
        let gj = pj.gradient(&u_eq)?;
        for k in 0..n {
            // x = k (control), y = j (time of the moment): values[k * ny + j]
            sens[k * (steps + 1) + j] = gj[k].abs();
        }
    }
    // the same at the best c solution (a bent chain): u₅…u₉ act through the nonlinearity only
    let weak = {
        let pj = ControlProblem::new(
            &scene(),
            Parametrisation::PerStep(PerStepControl { steps }),
            MomentAt(steps),
        )?;
        let g = pj.gradient(&best)?;
        let mx = g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        g[5..n - 1].iter().fold(0.0f64, |a, b| a.max(b.abs())) / mx
    };
    // first step j at which u_k reaches M₀, per k
    let reach: Vec<Option<usize>> = (0..n)
        .map(|k| (0..=steps).find(|&j| sens[k * (steps + 1) + j] > 1e-14))
        .collect();
    let delay = reach
        .iter()
        .enumerate()
        .filter_map(|(k, r)| r.map(|j| j - k))
        .min()
        .unwrap_or(0);
    let hm = Panel::new(
        "Sensitivity |∂M₀(t_j)/∂u_k| at u ≡ −2 N (straight beam)",
        "control step k",
        "moment step j",
    )
    .legend(Legend::None)
    .heat(Heat {
        x: (0.0, (n - 1) as f64),
        y: (0.0, steps as f64),
        nx: n,
        ny: steps + 1,
        values: sens,
        log: true,
        floor: Some(1e-12),
        label: "|∂M₀/∂u| [m] (floor 1e-12)".into(),
    });
    files.extend(ctx.save(&Figure::new("fig_3_13_slices", 2, vec![h01, h0f, hs, hm]))?);

    let jmax = |v: &[&OptimResult]| v.iter().map(|r| r.objective).fold(0.0, f64::max);
    let spread = |v: &[&OptimResult], k: usize| {
        let lo = v.iter().map(|r| r.theta[k]).fold(f64::INFINITY, f64::min);
        let hi = v
            .iter()
            .map(|r| r.theta[k])
            .fold(f64::NEG_INFINITY, f64::max);
        hi - lo
    };
    let reached: Vec<String> = reach
        .iter()
        .enumerate()
        .map(|(k, r)| match r {
            Some(j) => format!("{}→t{}", us(k), sub(*j)),
            None => format!("{}→never", us(k)),
        })
        .collect();
    let fmt_list = |v: &[usize]| v.iter().map(|&k| us(k)).collect::<Vec<_>>().join(", ");
    Ok(Made {
        files,
        note: format!(
            "Per-step control u = (u₀ … u₁₀) at node 10 of the §3.3.1 riser (F = 2 N at node 10, \
             N = 10), single shooting, L-BFGS with exact adjoint gradients. `fig_3_13` is the \
             thesis's layout: every row of points is one local solution, its 11 forces at the \
             height of its objective. Left: {} random starts in [−10, 10]¹¹ ({} not converged); \
             right: {} constant starts −10 … 10 ({} not converged; the start u ≡ −2 is already \
             optimal, c = 0 exactly, drawn at 1e-40). **Every local solution is a \
             global one**: c ≤ {} N²m² (random) and ≤ {} (constant starts), zero up to \
             round-off, reached in {}-{} iterations — the rows differ in height only by \
             round-off and in u because the minimiser is not unique (spread of u₀ over the \
             random solutions {:.2} N, of u₁₀ {:.2} N). `fig_3_13_landscape`: (a) the solutions' \
             control profiles; (b) the Hessian at a solution has {} eigenvalue(s) above \
             round-off for c and {} for c_sum, the other {} and {} are zero to ~1e-18 (the \
             certificate of `multistart::certify`): the minimisers are not isolated points but a \
             valley — the {}-dimensional surface M₀(T) = 0 (c) and the {}-dimensional affine \
             subspace u₀ = … = u₄ = −2 (c_sum), all with J = 0; (c) \
             1-D slices along each u_k through a solution (log scale) are parabola-like for {} \
             and flat for {}; their maxima over t ∈ [−10, 10] N: {} — the curvature falls by \
             orders of magnitude from u₀ to u₄, and u₅ … u₉ act on M₀(T) only through the \
             chain's geometric nonlinearity (a tip force on the bent chain has an axial part \
             that the rigid links pass on at once), orders of magnitude more weakly; at the {} random start points the \
             Hessian's smallest eigenvalue is ≥ {} (c) and ≥ {} (c_sum) times its largest: \
             slight negative curvature from the chain's geometric nonlinearity (c = r² has \
             Hessian 2∇r∇rᵀ + 2r∇²r), six orders below the curvature across the valley, so both \
             objectives are convex on the box to within that; (d) along the straight line between two solutions J stays ≤ {} (c) and \
             ≤ {} (c_sum) between them: the minima are connected along a valley floor at J ≈ 0 \
             (for c the surface M₀(T) = 0 is slightly curved, hence the small bump). \
             `fig_3_13_slices`: 2-D slices (log colour) — c over (u₀, u₁) is a straight valley \
             (c = r(u)² with one residual r = M₀(T), rank-1 curvature), c over (u₀, \
             {}) does not depend on {} at all (u_N acts on p_N only), c_sum over (u₀, u₁) is a \
             strongly elongated bowl; and the sensitivity |∂M₀(t_j)/∂u_k| (adjoint of the \
             linear objective M₀(t_j)) at u ≡ −2 N, where the beam stays straight: to first \
             order a force applied at the tip at step k first reaches the base moment {} steps \
             later ({}), so with N = 10 the last controls cannot influence any M₀(t_j) — finite \
             propagation of the discrete wave, plus u_N acting on p_N only (thesis §3.3.1); on a \
             bent chain (the random-start solutions) |∂M₀(T)/∂u_k| for k = 5 … 9 is at most {} \
             of the largest. For c_sum the same {} random starts ({} not converged, ≤ {} \
             iterations, rel_grad_tol = 1e-12) end at J ∈ [{}, {}] with u₀…u₄ within {} N of −2 \
             and u₅…u₁₀ where they started: the minimisers are exactly the set u₀ = … = u₄ = −2 \
             (M₀(t₆…t₁₀) depend on u₀…u₄ through a square lower-triangular sensitivity), a \
             6-dimensional affine subspace. That block is graded (Hessian eigenvalues from \
             2.5e-4 down to ~1e-13), so a loose tolerance stops early: with the library's \
             defaults (rel_grad_tol = 1e-8) {}; {} — ill-conditioning, which the thesis \
             (Table 3.4, 'not necessarily global solutions') may have read as nonconvexity. \
             **Verdict:** the thesis's 'highly nonconvex' landscape (Fig. 3.13, \
             abstract, Conclusion) is not what the dynamics give: within [−10, 10]¹¹ every local solution \
             found is global (J = 0 to round-off) and the objective is a nearly convex, \
             degenerate quadratic — \
             many solutions because of flat directions (non-uniqueness), not because of \
             nonconvexity. The scatter of the thesis's rows in c cannot come from the dynamics \
             (here it is round-off): most likely its simultaneous SLSQP solves stopped at points \
             where the dynamics constraints were not yet satisfied. An effort penalty ρ h Σ u_k² \
             (`BendingObjective::with_effort`) makes the minimum unique.",
            n_random,
            rand_bad,
            consts.len(),
            const_bad,
            sci(jmax(&rand_sols)),
            sci(jmax(&const_refs)),
            rand_sols
                .iter()
                .chain(const_refs.iter())
                .map(|r| r.iterations)
                .min()
                .unwrap_or(0),
            rand_sols
                .iter()
                .chain(const_refs.iter())
                .map(|r| r.iterations)
                .max()
                .unwrap_or(0),
            spread(&rand_sols, 0),
            spread(&rand_sols, n - 1),
            rank_f,
            rank_s,
            n - rank_f,
            n - rank_s,
            n - rank_f,
            n - rank_s,
            fmt_list(&curved),
            fmt_list(&flat),
            slice_max.join(", "),
            rep.start_points.len(),
            sci(worst.0),
            sci(worst.1),
            sci(seg_max.0),
            sci(seg_max.1),
            us(last_free),
            us(last_free),
            delay,
            reached.join(", "),
            sci(weak),
            n_random,
            sum_bad,
            sum_iters,
            sci(sum_j.0),
            sci(sum_j.1),
            sci(sum_dev),
            defaults[0],
            defaults[1],
        ),
    })
}

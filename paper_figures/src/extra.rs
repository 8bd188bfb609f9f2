//! Figures beyond the thesis: speed against accuracy (work-precision), energy over long runs,
//! stability limits, convergence of the chain to Euler-Bernoulli, calibration by gradients.

use crate::ch2::{fit_slope, retime};
use crate::planar::simulate;
use crate::plot::{color, Figure, Legend, Panel, Res, Series, GREY};
use crate::{Ctx, Entry, Made};
use chainbeam::catalogue;
use chainbeam::euler_bernoulli::{static_cantilever, EbSupport, EulerBernoulli};
use chainbeam::integrators::{integrate, Integrator, IntegratorMethod};
use chainbeam::statics::static_equilibrium;
use chainbeam::Scene;
use std::time::Instant;

pub fn entries() -> Vec<Entry> {
    vec![
        Entry {
            id: "work_precision_conservative",
            caption: "(beyond the thesis) Work-precision: error at a fixed final time against a \
                      high-accuracy reference versus CPU time, RATTLE over a sweep of h and two \
                      other integrators; conservative cantilever.",
            make: wp_conservative,
        },
        Entry {
            id: "work_precision_drag",
            caption: "(beyond the thesis) Work-precision as above for the cantilever with drag.",
            make: wp_drag,
        },
        Entry {
            id: "work_precision_energy",
            caption: "(beyond the thesis) Energy error against time over a long run (10⁵ steps) \
                      for each integrator.",
            make: wp_energy,
        },
        Entry {
            id: "stability_stiffness",
            caption: "(beyond the thesis) For each integrator, the largest step that stays stable \
                      (or whose Newton solve converges) as a function of the stiffness k.",
            make: stability_k,
        },
        Entry {
            id: "stability_pendulums",
            caption: "(beyond the thesis) The largest stable step as a function of n.",
            make: stability_n,
        },
        Entry {
            id: "convergence",
            caption: "(beyond the thesis; its open question at the end of §2.4.4) The chain \
                      converging to Euler-Bernoulli as n grows at fixed length when k and m are \
                      scaled with the discretisation: error against n with the fitted rate.",
            make: convergence,
        },
    ]
}

fn max_node_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b.iter())
        .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
        .fold(0.0, f64::max)
}

/// Runs `method` to `t_end` with step h: (final node positions, CPU seconds per run).
fn timed_run(
    scene: &Scene,
    method: IntegratorMethod,
    h: f64,
    t_end: f64,
) -> Option<(Vec<[f64; 2]>, f64)> {
    // h is adjusted so that the run ends exactly at t_end
    let steps = ((t_end / h).round() as usize).max(1);
    let h = t_end / steps as f64;
    let mut reps = 0;
    let t0 = Instant::now();
    let mut last = None;
    while reps == 0 || (t0.elapsed().as_secs_f64() < 0.05 && reps < 50) {
        let it = integrate(scene, method, h, steps, steps, |_| {}).ok()?;
        last = Some(it.positions());
        reps += 1;
    }
    Some((last?, t0.elapsed().as_secs_f64() / reps as f64))
}

fn work_precision(ctx: &Ctx, scene: Scene, name: &str, title: &str) -> Res<Made> {
    let t_end = if ctx.quick { 0.5 } else { 2.0 };
    let h_ref = if ctx.quick { 1e-4 } else { 2e-5 };
    let reference = integrate(
        &scene,
        IntegratorMethod::ProjectedRk4,
        h_ref,
        (t_end / h_ref).round() as usize,
        usize::MAX,
        |_| {},
    )?
    .positions();
    let hs: Vec<f64> = if ctx.quick {
        vec![0.01, 0.005, 0.0025]
    } else {
        (0..14)
            .map(|j| 2.0 / (100.0 * 1.4f64.powi(j)).round())
            .collect()
    };
    let mut p = Panel::new(
        title,
        "CPU time per run [s]",
        "max node position error at T [m]",
    )
    .loglog()
    .legend(Legend::UpperRight);
    let mut summary = Vec::new();
    for (c, m) in IntegratorMethod::ALL.into_iter().enumerate() {
        let mut pts = Vec::new();
        let mut failed = Vec::new();
        for &h in &hs {
            match timed_run(&scene, m, h, t_end) {
                Some((pos, secs)) => pts.push((secs, max_node_distance(&pos, &reference), h)),
                None => failed.push(h),
            }
        }
        let order = fit_slope(
            &pts.iter()
                .map(|p| (p.2, p.1))
                .filter(|p| p.1 > 1e-11)
                .collect::<Vec<_>>(),
        );
        summary.push(format!(
            "{}: order {:.1} in h{}",
            m.name(),
            order,
            if failed.is_empty() {
                String::new()
            } else {
                format!(
                    ", fails (typed error) for h ≥ {:.4} s",
                    failed.iter().cloned().fold(f64::INFINITY, f64::min)
                )
            }
        ));
        let s = Series::line(
            format!("{} (h {:.0e}-{:.0e} s)", m.name(), hs[hs.len() - 1], hs[0]),
            pts.iter().map(|p| (p.0, p.1)).collect(),
            color(c),
        )
        .markers();
        p.push(if m == IntegratorMethod::Shake {
            s.dashed()
        } else {
            s
        });
    }
    let files = ctx.save(&Figure::single(name, p))?;
    Ok(Made {
        files,
        note: format!(
            "Error of all node positions at T = {t_end} s against projected RK4 at h = {h_ref:e} \
             s, against the CPU time of one run (mean of repeats), h from {:.0e} to {:.2} s. {}. \
             SHAKE's positions coincide with RATTLE's (the methods are equivalent in q), so it \
             differs only in cost and in its momenta (see `work_precision_energy`); with drag its \
             extrapolated drag momentum makes it less accurate than RATTLE. On this small, smooth \
             problem the explicit fourth-order method reaches a given position error at the \
             lowest CPU time wherever it is stable; RATTLE's advantages are structural (bounded \
             energy error over long runs, an exact discrete adjoint), not speed at fixed accuracy.",
            hs[hs.len() - 1],
            hs[0],
            summary.join("; ")
        ),
    })
}

fn wp_conservative(ctx: &Ctx) -> Res<Made> {
    work_precision(
        ctx,
        catalogue::thesis_cantilever(),
        "work_precision_conservative",
        "Work-precision, conservative cantilever",
    )
}

fn wp_drag(ctx: &Ctx) -> Res<Made> {
    work_precision(
        ctx,
        catalogue::dissipative_cantilever(10.0),
        "work_precision_drag",
        "Work-precision, cantilever with drag D = 10 kg/m",
    )
}

fn wp_energy(ctx: &Ctx) -> Res<Made> {
    let steps = if ctx.quick { 10_000 } else { 100_000 };
    let h = 0.01;
    let scene = catalogue::thesis_cantilever();
    let mut p = Panel::new(
        format!("Energy error over {steps} steps, h = {h} s, conservative cantilever"),
        "t [s]",
        "max |H(t) − H(0)| per 1 s window [J]",
    )
    .logy()
    .legend(Legend::LowerRight);
    let mut notes = Vec::new();
    for (c, m) in IntegratorMethod::ALL.into_iter().enumerate() {
        let mut it = Integrator::new(&scene, m, h)?;
        let e0 = it.energy();
        let mut pts = Vec::new();
        let mut wmax: f64 = 0.0;
        let t0 = Instant::now();
        let mut err = None;
        for k in 1..=steps {
            if let Err(e) = it.step() {
                err = Some(e);
                break;
            }
            wmax = wmax.max((it.energy() - e0).abs());
            if k % 100 == 0 {
                pts.push((it.time(), wmax));
                wmax = 0.0;
            }
        }
        let secs = t0.elapsed().as_secs_f64();
        let last = pts.last().map_or(f64::NAN, |p| p.1);
        notes.push(match err {
            Some(e) => format!("{} stopped: {e}", m.name()),
            None => format!("{}: final window {last:.1e} J ({secs:.2} s)", m.name()),
        });
        let s = Series::line(m.name(), pts, color(c)).width(1);
        p.push(if m == IntegratorMethod::Shake {
            s.dashed()
        } else {
            s
        });
    }
    let files = ctx.save(&Figure::single("work_precision_energy", p))?;
    Ok(Made {
        files,
        note: format!(
            "{}. RATTLE's and SHAKE's energy errors oscillate within a fixed bound (symplectic; \
             SHAKE's unprojected central-difference momenta make its bound larger), while the \
             explicit projected RK4 loses energy steadily (it damps the fast modes) until it \
             settles far below. Asserted in `tests/steppers/integrators.rs`.",
            notes.join("; ")
        ),
    })
}

/// Whether `method` integrates `scene` stably with step h to t_end: no typed error and an energy
/// error below 10% of the largest kinetic energy seen (drag-free scenes).
fn stable(scene: &Scene, method: IntegratorMethod, h: f64, t_end: f64) -> bool {
    let steps = ((t_end / h).round() as usize).max(50);
    let Ok(mut it) = Integrator::new(scene, method, h) else {
        return false;
    };
    let e0 = it.energy();
    let mut scratch = vec![[0.0; 2]; it.chain().n()];
    let mut tmax: f64 = 0.0;
    let mut emax: f64 = 0.0;
    for _ in 0..steps {
        if it.step().is_err() {
            return false;
        }
        let t = it.chain().kinetic_energy(it.p(), &mut scratch);
        tmax = tmax.max(t);
        emax = emax.max((it.energy() - e0).abs());
    }
    emax <= 0.1 * tmax.max(1e-12)
}

/// Largest stable h by bisection in log h between 1e-6 and 0.5.
fn h_max(scene: &Scene, method: IntegratorMethod, t_end: f64, iters: usize) -> f64 {
    let (mut lo, mut hi) = (1e-6f64, 0.5f64);
    if stable(scene, method, hi, t_end) {
        return hi;
    }
    for _ in 0..iters {
        let mid = (lo * hi).sqrt();
        if stable(scene, method, mid, t_end) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

fn stability_k(ctx: &Ctx) -> Res<Made> {
    let ks: Vec<f64> = if ctx.quick {
        vec![100.0, 1000.0]
    } else {
        (0..9).map(|j| 10f64.powf(1.0 + 0.5 * j as f64)).collect()
    };
    let (t_end, iters) = if ctx.quick { (0.5, 6) } else { (3.0, 14) };
    let mut p = Panel::new(
        "Largest stable step, cantilever n = 10, l = 1 m, m = 1 kg, F = 2 N",
        "spring constant k = k₁ [Nm/rad]",
        "largest stable h [s]",
    )
    .loglog()
    .legend(Legend::UpperRight);
    let mut rows = Vec::new();
    for (c, m) in IntegratorMethod::ALL.into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = ks
            .iter()
            .map(|&k| {
                let mut s = catalogue::thesis_cantilever();
                s.beam.stiffness.iter_mut().for_each(|x| *x = k);
                s.beam.base_stiffness = k;
                (k, h_max(&s, m, t_end, iters))
            })
            .collect();
        rows.push(format!("{}: slope {:.2}", m.name(), fit_slope(&pts)));
        let s = Series::line(m.name(), pts, color(c)).markers();
        p.push(if m == IntegratorMethod::Shake {
            s.dashed()
        } else {
            s
        });
    }
    // Störmer–Verlet's linear limit 2/ω_max on the equivalent finite-difference beam
    let sv: Vec<(f64, f64)> = ks
        .iter()
        .filter_map(|&k| {
            EulerBernoulli::new(10, 10.0, k, 1.0, EbSupport::Cantilever, &[(10, 2.0)])
                .ok()
                .map(|b| (k, b.stability_limit()))
        })
        .collect();
    p.push(Series::line("Störmer–Verlet on FD Euler-Bernoulli (2/ω_max)", sv, GREY).dashed());
    let files = ctx.save(&Figure::single("stability_stiffness", p))?;
    Ok(Made {
        files,
        note: format!(
            "Bisection on h (stable = every step succeeds over {t_end} s and the energy error stays \
             below 10% of the largest kinetic energy). {}: all scale like k^(−1/2) (h ω bounded). \
             RATTLE's and SHAKE's limit coincides with Störmer–Verlet's linear limit 2/ω_max \
             of the equivalent finite-difference beam (grey; RATTLE is Störmer–Verlet on the \
             constrained system), where they fail by their Newton solve not converging (a typed \
             NewtonNotConverged error naming the step), the explicit RK4 by blowing up or folding \
             (typed NonFinite/Folded). At the thesis's k = 1000: RATTLE/SHAKE fail between \
             h = 0.015 and 0.019, RK4 near 0.022.",
            rows.join(", ")
        ),
    })
}

fn stability_n(ctx: &Ctx) -> Res<Made> {
    let ns: Vec<usize> = if ctx.quick {
        vec![5, 10]
    } else {
        vec![5, 10, 20, 40, 80]
    };
    let (t_end, iters) = if ctx.quick { (0.5, 6) } else { (1.0, 12) };
    let mut p = Panel::new(
        "Largest stable step, cantilever L = 10 m, EI = 1000 Nm², M = 10 kg",
        "pendulums n",
        "largest stable h [s]",
    )
    .loglog()
    .legend(Legend::UpperRight);
    let mut rows = Vec::new();
    for (c, m) in IntegratorMethod::ALL.into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = ns
            .iter()
            .map(|&n| {
                let s = catalogue::scaled_cantilever(n, 10.0, 1000.0, 10.0, 2.0);
                (n as f64, h_max(&s, m, t_end, iters))
            })
            .collect();
        rows.push(format!("{}: slope {:.2}", m.name(), fit_slope(&pts)));
        let s = Series::line(m.name(), pts, color(c)).markers();
        p.push(if m == IntegratorMethod::Shake {
            s.dashed()
        } else {
            s
        });
    }
    let files = ctx.save(&Figure::single("stability_pendulums", p))?;
    Ok(Made {
        files,
        note: format!(
            "Same criterion with k = EI/l and m = M/n (the fastest mode grows like n²). {}: the \
             stable step shrinks like n⁻² for every method, so none escapes the stiffness of fine \
             discretisations; RATTLE's implicitness does not buy a larger step because its Newton \
             solve is the first thing to fail.",
            rows.join(", ")
        ),
    })
}

/// [`catalogue::scaled_cantilever`]'s beam (k = EI/l, k₁ = 2k, m = M/n, F = 2 N at the tip) on a
/// one-step time grid: statics needs no trajectory, and the catalogue's 10 s grid would exceed the
/// library's stored-state limit for n = 320.
fn scaled_cantilever_static(n: usize, length: f64, ei: f64, mass: f64) -> Res<Scene> {
    let l = length / n as f64;
    let k = ei / l;
    Ok(Scene::builder(n)
        .length(l)
        .mass(mass / n as f64)
        .stiffness(k)
        .base_stiffness(2.0 * k)
        .support(chainbeam::Support::Cantilever)
        .point_load(n, 2.0)
        .step(0.01)
        .steps(1)
        .build()?)
}

/// Static tip deflections z_n of the scaled cantilever chain for each n (Newton statics).
fn static_tips(ns: &[usize], l_total: f64) -> Res<Vec<(usize, f64)>> {
    let mut tips = Vec::new();
    for &n in ns {
        let eq = static_equilibrium(&scaled_cantilever_static(n, l_total, 1000.0, 10.0)?)?;
        tips.push((n, eq.positions[n - 1][1]));
    }
    Ok(tips)
}

/// The tip's z at 101 equally spaced times of [0, `t_end`] for each n, with h shrinking as n².
fn dynamic_tips(dyn_ns: &[usize], l_total: f64, t_end: f64) -> Res<Vec<(usize, Vec<f64>)>> {
    let mut trajs = Vec::new();
    for &n in dyn_ns {
        let s = catalogue::scaled_cantilever(n, l_total, 1000.0, 10.0, 2.0);
        let h = 0.01 * (10.0 / n as f64).powi(2).min(1.0) * 0.25;
        let tr = simulate(&retime(s, h, t_end))?;
        let samples: Vec<f64> = (0..=100)
            .map(|j| {
                let k = ((j as f64 / 100.0) * tr.steps() as f64).round() as usize;
                tr.positions(k)[n - 1][2]
            })
            .collect();
        trajs.push((n, samples));
    }
    Ok(trajs)
}

/// The finite-difference Euler-Bernoulli beam's static tip error against eq. 2.4.5, per n.
fn fd_errors(ns: &[usize], l_total: f64, eb_tip: f64) -> Vec<(f64, f64)> {
    ns.iter()
        .filter_map(|&n| {
            EulerBernoulli::new(
                n,
                l_total,
                1000.0,
                10.0 / n as f64,
                EbSupport::Cantilever,
                &[(n, 2.0)],
            )
            .ok()
            .map(|b| (n as f64, (b.static_solution()[n] - eb_tip).abs()))
        })
        .collect()
}

fn convergence(ctx: &Ctx) -> Res<Made> {
    let ns: Vec<usize> = if ctx.quick {
        vec![5, 10, 20]
    } else {
        vec![5, 10, 20, 40, 80, 160, 320]
    };
    let l_total = 10.0;
    let eb_tip = static_cantilever(l_total, 2.0, 1000.0, l_total);
    // static tip deflection of the chain vs eq. 2.4.5, and vs the finest chain (self-convergence)
    let tips = static_tips(&ns, l_total)?;
    let finest = tips.last().map_or(0.0, |t| t.1);
    let vs_eb: Vec<(f64, f64)> = tips
        .iter()
        .map(|&(n, z)| (n as f64, (z - eb_tip).abs()))
        .collect();
    let vs_fine: Vec<(f64, f64)> = tips[..tips.len() - 1]
        .iter()
        .map(|&(n, z)| (n as f64, (z - finest).abs()))
        .collect();
    let rate = fit_slope(&vs_fine);
    // dynamics: tip trajectory over [0, T] vs the finest dynamic chain
    let t_end = if ctx.quick { 0.5 } else { 2.0 };
    let dyn_ns: Vec<usize> = if ctx.quick {
        vec![5, 10, 20]
    } else {
        vec![5, 10, 20, 40, 80]
    };
    let trajs = dynamic_tips(&dyn_ns, l_total, t_end)?;
    let fine_dyn = trajs.last().map(|t| t.1.clone()).unwrap_or_default();
    let dyn_err: Vec<(f64, f64)> = trajs[..trajs.len() - 1]
        .iter()
        .map(|(n, s)| {
            (
                *n as f64,
                s.iter()
                    .zip(fine_dyn.iter())
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max),
            )
        })
        .collect();
    let dyn_rate = fit_slope(&dyn_err);
    // the FD Euler-Bernoulli beam for comparison
    let fd = fd_errors(&ns, l_total, eb_tip);
    let fd_rate = fit_slope(&fd);
    let p = Panel::new(
        "Cantilever L = 10 m, EI = 1000 Nm², M = 10 kg, k = EI/l, k₁ = 2k, m = M/n",
        "pendulums n",
        "tip error [m]",
    )
    .loglog()
    .legend(Legend::LowerLeft)
    .with(
        Series::line(
            format!("static chain vs finest chain (rate n^{rate:.2})"),
            vs_fine,
            color(0),
        )
        .markers(),
    )
    .with(
        Series::line("static chain vs eq. 2.4.5 (linear EB)", vs_eb, color(3))
            .markers()
            .dashed(),
    )
    .with(
        Series::line(
            format!("dynamic tip, max over t ≤ {t_end} s, vs finest (rate n^{dyn_rate:.2})"),
            dyn_err,
            color(2),
        )
        .markers(),
    )
    .with(
        Series::line(
            format!("FD Euler-Bernoulli static vs eq. 2.4.5 (rate n^{fd_rate:.2})"),
            fd,
            GREY,
        )
        .markers()
        .dotted(),
    );
    let files = ctx.save(&Figure::single("convergence", p))?;
    Ok(Made {
        files,
        note: format!(
            "Answers the thesis's open question (end of §2.4.4): with k = EI/l, k₁ = 2k and \
             m = M/n at fixed L the chain converges as n grows, the static tip at rate \
             n^{rate:.2} and the dynamic tip trajectory at n^{dyn_rate:.2} (against the finest \
             chain, n = {} and {}). Its limit is not the linear Euler-Bernoulli beam but the \
             geometrically nonlinear one (an inextensible elastica): the distance to eq. 2.4.5 \
             levels off at {:.1e} m, the nonlinearity of a {:.2} m tip deflection. The \
             finite-difference Euler-Bernoulli beam converges to eq. 2.4.5 at n^{fd_rate:.2}.",
            ns[ns.len() - 1],
            dyn_ns[dyn_ns.len() - 1],
            (finest - eb_tip).abs(),
            eb_tip.abs()
        ),
    })
}

//! Chapter 3: manual control (Fig. 3.1-3.2), the reaction-force tip and move-and-lock
//! (Fig. 3.3-3.6) and the optimal-control figures that need no optimiser (Fig. 3.9, 3.11, 3.12).

use crate::ch2::{node_z, retime};
use crate::planar::{simulate, simulate_with_controls};
use crate::plot::{color, Figure, Legend, Panel, Res, Series, GREY};
use crate::{Ctx, Entry, Made};
use chainbeam::{
    catalogue, piecewise_constant_controls, ControlProblem, ObjectiveKind, Scene, Support,
    Trajectory,
};

const THESIS_U: [f64; 10] = [
    -0.37, -0.72, -1.01, -1.28, -1.50, -1.68, -1.83, -1.93, -1.99, -2.0,
];

pub fn entries() -> Vec<Entry> {
    vec![
        Entry {
            id: "fig_3_1",
            caption: "Evolution of the bending moment in the origin (3.1.3) of 10 different \
                      systems, with and without control force. External force F = 2 N is applied \
                      to node i in system i as shown in the legend. Top: No control. Bottom: Left: \
                      Controlled system 1-5. Right: Controlled system 6-10.",
            make: fig_3_1,
        },
        Entry {
            id: "fig_3_2",
            caption: "Trajectories of the nodes of the system where the external force F = 2 N is \
                      applied to the fifth node, and counteracted by the control force u = -1.50 N \
                      applied to the final node",
            make: fig_3_2,
        },
        Entry {
            id: "fig_3_3",
            caption: "Trajectories of the nodes of the constrained beams modeled by the Chain of \
                      Pendulums model affected by a point load in the central node. The solid \
                      lines represent the system with a constraint (2.4.4), and the dashed lines \
                      represent the system where the constraint is replaced by a reaction force \
                      λ_l (3.2.2). Left: Fixed-Fixed beam. Right: Pinned-Pinned beam.",
            make: fig_3_3,
        },
        Entry {
            id: "fig_3_4",
            caption: "Trajectories of the nodes of the system modeled by the dissipative Chain of \
                      Pendulums model with the constraint as a reaction force (3.2.2). Left: \
                      Control force u = 1 N is applied over t ∈ [0, 1]. Right: Control force \
                      u = 1 N is applied over t ∈ [0, 1] and then u = -1 N is applied over \
                      t ∈ [1, 2].",
            make: fig_3_4,
        },
        Entry {
            id: "fig_3_5",
            caption: "System affected by control force u = 1 N applied over t ∈ [0, 1] and then \
                      u = -1 N is applied over t ∈ [1, 2]. Left: Input force necessary to achieve \
                      the trajectory shown in Figure 3.4(right). Right: Trajectories of the nodes \
                      of the constrained beams modeled by the dissipative Chain of Pendulums model \
                      with constraint in the z-axis as a reaction force (3.2.2), solid lines, \
                      compared to the dissipative model (2.4.4) with affected by a force that \
                      consist of λ_L + u, dashed lines.",
            make: fig_3_5,
        },
        Entry {
            id: "fig_3_6",
            caption: "The system where an external force F = 2 N is applied to the central node \
                      at t ∈ [2, 10]. The system's final node is prior moved from z = 0 to \
                      z = 0.042 by a control force u. Left: Control force u. Right: Resulting \
                      bending moment of uncontrolled, control from last section, and the move and \
                      lock systems.",
            make: fig_3_6,
        },
        Entry {
            id: "fig_3_9",
            caption: "Left: Trajectory of the Cantilever beam with spring in the final node, \
                      affected by an external force F = 2 N in the fourth node, and a control \
                      force at the final node as usual. Left: Trajectory. Right: Absolute bending \
                      moment of the same Cantilever beam affected by the obtained optimal control \
                      force u = 131.92079771 N over time t ∈ [0, 2T], to show increased bending \
                      moment. A reference system with no control u = 0 is also plotted.",
            make: fig_3_9,
        },
        Entry {
            id: "fig_3_11",
            caption: "Squared bending moment of the Cantilever beam with a spring in the final \
                      node, affected by an external force F = 2 N in the fifth node. Final: System \
                      affected by the control force obtained by optimizing the final squared \
                      bending moment. Sum: System affected by the control force obtained by \
                      optimizing the sum of squared bending moments.",
            make: fig_3_11,
        },
        Entry {
            id: "fig_3_12",
            caption: "Absolute bending moment of the Cantilever beam with a spring in the final \
                      node, affected by an external force F = 2 N in the fifth node. The system is \
                      simulated three times, with u = 0, 1, -1 N.",
            make: fig_3_12,
        },
    ]
}

fn t_end(ctx: &Ctx, full: f64) -> f64 {
    if ctx.quick {
        full.min(2.5)
    } else {
        full
    }
}

fn moment(traj: &Trajectory<f64, 2>, f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    (0..=traj.steps())
        .map(|k| (traj.time(k), f(traj.moment[k])))
        .collect()
}

fn constant(scene: &Scene, u: f64) -> Vec<f64> {
    vec![u; scene.time.steps + 1]
}

fn fig_3_1(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let mut top = Panel::new("No control", "t [s]", "M₀ [Nm]").legend(Legend::LowerLeft);
    let mut bl =
        Panel::new("Controlled, systems 1-5", "t [s]", "M₀ [Nm]").legend(Legend::LowerLeft);
    let mut br =
        Panel::new("Controlled, systems 6-10", "t [s]", "M₀ [Nm]").legend(Legend::LowerLeft);
    let mut mean_abs = Vec::new();
    for i in 1..=10 {
        let scene = retime(catalogue::riser_dissipative(i), 0.01, t);
        let free = simulate_with_controls(&scene, &constant(&scene, 0.0))?;
        let ctl = simulate_with_controls(&scene, &constant(&scene, THESIS_U[i - 1]))?;
        top.push(
            Series::line(format!("F at node {i}"), moment(&free, |m| m), color(i - 1)).width(1),
        );
        let s = Series::line(
            format!("node {i}, u = {:.2} N", THESIS_U[i - 1]),
            moment(&ctl, |m| m),
            color(i - 1),
        )
        .width(1);
        if i <= 5 {
            bl.push(s);
        } else {
            br.push(s);
        }
        let avg = |tr: &Trajectory<f64, 2>| {
            tr.moment.iter().map(|m| m.abs()).sum::<f64>() / tr.moment.len() as f64
        };
        mean_abs.push(format!("{i}: {:.2}→{:.2}", avg(&free), avg(&ctl)));
    }
    let files = ctx.save(&Figure::new("fig_3_1", 1, vec![top, bl, br]))?;
    Ok(Made {
        files,
        note: format!(
            "Riser (k₁ = k₁₁ = 2000 Nm/rad, D = 10 kg/m), F = 2 N at node i, with the thesis's \
             manual controls u = −[0.37 … 2] N at the tip (panels stacked top to bottom instead \
             of the thesis's 1 + 2 layout). Mean |M₀| [Nm] uncontrolled → controlled: {}. As in \
             the thesis: the further out the load the larger M₀, and the control removes most of \
             it (all of it for node 10), except an unavoidable transient at the start.",
            mean_abs.join(", ")
        ),
    })
}

fn fig_3_2(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let scene = retime(catalogue::riser_dissipative(5), 0.01, t);
    let traj = simulate_with_controls(&scene, &constant(&scene, -1.5))?;
    let mut p = Panel::new(
        "F = 2 N at node 5, u = −1.50 N at node 10",
        "t [s]",
        "z [m]",
    )
    .legend(Legend::Right);
    for i in 1..=10 {
        p.push(Series::line(format!("node {i}"), node_z(&traj, i, 1), color(i - 1)).width(1));
    }
    let n = traj.steps();
    let k0 = n / 2;
    let tip_mean = (k0..=n).map(|k| traj.positions(k)[9][2]).sum::<f64>() / (n - k0 + 1) as f64;
    let files = ctx.save(&Figure::single("fig_3_2", p))?;
    Ok(Made {
        files,
        note: format!(
            "All nodes of the riser with the load at node 5 and u = −1.5 N: the tip oscillates \
             about z ≈ {tip_mean:.3} m over the second half of the run (thesis: ≈ 0.042 m)."
        ),
    })
}

fn fig_3_3(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let mut panels = Vec::new();
    let mut diffs = Vec::new();
    for (name, base) in [
        ("Fixed-fixed", catalogue::fixed_fixed()),
        ("Pinned-pinned", catalogue::pinned_pinned()),
    ] {
        let s = retime(base, 0.01, t);
        let mut r = s.clone();
        r.beam.reaction_force = true;
        let a = simulate(&s)?;
        let b = simulate(&r)?;
        let mut p = Panel::new(name, "t [s]", "z [m]").legend(Legend::None);
        for i in 1..=9 {
            p.push(Series::line("", node_z(&a, i, 1), color(i - 1)).width(2));
            p.push(Series::line("", node_z(&b, i, 1), GREY).dashed().width(1));
        }
        let d = (0..=a.steps())
            .flat_map(|k| (0..10).map(move |i| (k, i)))
            .map(|(k, i)| (a.positions(k)[i][2] - b.positions(k)[i][2]).abs())
            .fold(0.0, f64::max);
        diffs.push(d);
        panels.push(p);
    }
    let files = ctx.save(&Figure::new("fig_3_3", 2, panels))?;
    Ok(Made {
        files,
        note: format!(
            "Locked tip (solid, colours per node) and reaction-force tip with u = 0 (grey dashed), \
             D = 0: identical, as in the thesis (largest difference {:.1e} m and {:.1e} m; with \
             u = 0 the reaction-force variant is exactly the locked beam, see `chainbeam::rattle`).",
            diffs[0], diffs[1]
        ),
    })
}

/// The reaction-force beam of §3.2: dissipative fixed-fixed (D = 10), no load, tip driven by u.
fn reaction_scene(t: f64) -> Scene {
    let mut s = retime(catalogue::dissipative_fixed_fixed(10.0), 0.01, t);
    s.loads.points.clear();
    s.beam.reaction_force = true;
    s
}

fn fig_3_4(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let mut panels = Vec::new();
    let mut notes = Vec::new();
    for (title, pieces) in [
        ("u = 1 N on [0, 1] s", vec![(0.0, 1.0, 1.0)]),
        (
            "u = 1 N on [0, 1] s, −1 N on [1, 2] s",
            vec![(0.0, 1.0, 1.0), (1.0, 2.0, -1.0)],
        ),
    ] {
        // the one-sided push drives the tip away until the chain folds: shorten until it runs
        let mut tt = t;
        let traj = loop {
            let s = reaction_scene(tt);
            let u = piecewise_constant_controls(0.01, s.time.steps, &pieces);
            match simulate_with_controls(&s, &u) {
                Ok(tr) => break tr,
                Err(e) if tt > 0.5 => {
                    notes.push(format!("{title}: to {tt} s fails ({e})"));
                    tt *= 0.8;
                }
                Err(e) => return Err(e.into()),
            }
        };
        let mut p = Panel::new(title, "t [s]", "z [m]").legend(Legend::LowerLeft);
        for i in 1..=10 {
            p.push(Series::line(format!("node {i}"), node_z(&traj, i, 1), color(i - 1)).width(1));
        }
        let tip = traj.positions(traj.steps())[9][2];
        notes.push(format!(
            "{title}: tip at z = {tip:.3} m at t = {:.1} s",
            traj.time(traj.steps())
        ));
        panels.push(p);
    }
    let files = ctx.save(&Figure::new("fig_3_4", 2, panels))?;
    Ok(Made {
        files,
        note: format!(
            "Dissipative fixed-fixed beam (D = 10 kg/m) with the reaction-force tip, no load; the \
             tip follows m_n ζ̈ = −u (so u > 0 drives it toward −z). {}. As in the thesis, a single \
             push keeps the tip moving (until the chain cannot follow: shown up to the last time \
             that still runs), and an equal and opposite push stops it.",
            notes.join("; ")
        ),
    })
}

fn fig_3_5(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let s = reaction_scene(t);
    let n = s.n();
    let steps = s.time.steps;
    let u = piecewise_constant_controls(0.01, steps, &[(0.0, 1.0, 1.0), (1.0, 2.0, -1.0)]);
    let traj = simulate_with_controls(&s, &u)?;
    // total force on the tip: u_k + λ_L; u_k pairs with λ of step k (stored at k + 1) and μ of
    // step k − 1 (stored at k)
    let total: Vec<f64> = (0..=steps)
        .map(|k| {
            let lam = if k < steps {
                traj.lambda(k + 1)[n]
            } else {
                traj.mu(k)[n]
            };
            u[k] + 0.5 * (lam + traj.mu(k)[n])
        })
        .collect();
    let left = Panel::new("Input force", "t [s]", "force [N]")
        .legend(Legend::UpperRight)
        .with(Series::line(
            "u + λ_L",
            total
                .iter()
                .enumerate()
                .map(|(k, &f)| (k as f64 * 0.01, f))
                .collect(),
            color(0),
        ))
        .with(
            Series::line(
                "u",
                u.iter()
                    .enumerate()
                    .map(|(k, &f)| (k as f64 * 0.01, f))
                    .collect(),
                color(1),
            )
            .dashed(),
        );
    // the same beam with a free tip (riser support) driven by u + λ_L
    let mut free = s.clone();
    free.beam.reaction_force = false;
    free.beam.support = Support::Riser;
    let replay = simulate_with_controls(&free, &total)?;
    let mut right = Panel::new(
        "Reaction-force model vs free tip driven by u + λ_L",
        "t [s]",
        "z [m]",
    )
    .legend(Legend::None);
    for i in 1..=10 {
        right.push(Series::line("", node_z(&traj, i, 1), color(i - 1)).width(2));
        right.push(
            Series::line("", node_z(&replay, i, 1), GREY)
                .dashed()
                .width(1),
        );
    }
    let d = (0..=steps)
        .map(|k| (traj.positions(k)[n - 1][2] - replay.positions(k)[n - 1][2]).abs())
        .fold(0.0, f64::max);
    let files = ctx.save(&Figure::new("fig_3_5", 2, vec![left, right]))?;
    Ok(Made {
        files,
        note: format!(
            "Left: the force the tip actually needs, u + λ_L (λ_L the tip multiplier, averaged over \
             the two half steps that use u_k), which settles to a constant holding force after \
             t = 2 s. Right: the reaction-force model (solid) and the same beam with a free tip \
             (riser support, D = 10) driven by u + λ_L (grey dashed) coincide, as in the thesis \
             (largest tip difference {d:.1e} m, from pairing λ and μ of neighbouring steps)."
        ),
    })
}

fn fig_3_6(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let h = 0.01;
    let load_at_2 = |mut s: Scene| {
        for p in s.loads.points.iter_mut() {
            p.start = 2.0;
        }
        s
    };
    let riser = load_at_2(retime(catalogue::riser_dissipative(5), h, t));
    let steps = riser.time.steps;
    let free = simulate_with_controls(&riser, &vec![0.0; steps + 1])?;
    let active = simulate_with_controls(&riser, &vec![-1.5; steps + 1])?;
    // move and lock: the reaction-force fixed-fixed beam (same springs and drag), the tip moved to
    // ζ = 0.042 m by u = −0.042 N on [0, 1] s and +0.042 N on [1, 2] s, then held (u = 0)
    let mut ml = load_at_2(retime(catalogue::dissipative_fixed_fixed(10.0), h, t));
    ml.beam.reaction_force = true;
    let a = 0.042 * ml.beam.masses[ml.n() - 1];
    let u = piecewise_constant_controls(h, steps, &[(0.0, 1.0, -a), (1.0, 2.0, a)]);
    let lock = simulate_with_controls(&ml, &u)?;
    let n = ml.n();
    let total: Vec<(f64, f64)> = (0..=steps)
        .map(|k| {
            let lam = if k < steps {
                lock.lambda(k + 1)[n]
            } else {
                lock.mu(k)[n]
            };
            (k as f64 * h, u[k] + 0.5 * (lam + lock.mu(k)[n]))
        })
        .collect();
    let left = Panel::new("Tip force", "t [s]", "force [N]")
        .legend(Legend::UpperRight)
        .with(Series::line("move and lock: u + λ_L", total, color(2)))
        .with(
            Series::line(
                "active control u = −1.5 N",
                vec![(0.0, -1.5), (t, -1.5)],
                color(1),
            )
            .dashed(),
        );
    let right = Panel::new("Base bending moment", "t [s]", "M₀ [Nm]")
        .legend(Legend::LowerLeft)
        .with(Series::line("uncontrolled", moment(&free, |m| m), color(0)).width(1))
        .with(Series::line("u = −1.5 N", moment(&active, |m| m), color(1)).width(1))
        .with(Series::line("move and lock", moment(&lock, |m| m), color(2)).width(1));
    let zeta = lock.tip_target[(2.0 / h) as usize];
    let files = ctx.save(&Figure::new("fig_3_6", 2, vec![left, right]))?;
    Ok(Made {
        files,
        note: format!(
            "Load F = 2 N at node 5 from t = 2 s on the riser (D = 10). Move and lock: the \
             reaction-force beam's tip is driven to ζ = {zeta:.4} m by ±0.042 N pushes on [0, 2] s \
             and then held by the lock; the lock's force (u + λ_L, left) after t = 2 s oscillates \
             about the −1.5 N of the active control, and both controlled systems keep M₀ near zero \
             while the uncontrolled one does not, as in the thesis. Our move is a bang-bang push \
             (the thesis's u on [0, 2] is not given)."
        ),
    })
}

fn fig_3_9(ctx: &Ctx) -> Res<Made> {
    let _ = ctx;
    let u_star = 131.92079771;
    let mut s = catalogue::riser(4);
    s.time.steps = 20;
    let ctl = simulate_with_controls(&s, &constant(&s, u_star))?;
    let free = simulate_with_controls(&s, &constant(&s, 0.0))?;
    let mut left = Panel::new("Trajectory, F at node 4, u = 131.92 N", "t [s]", "z [m]")
        .legend(Legend::LowerLeft);
    for i in 1..=10 {
        left.push(Series::line(format!("node {i}"), node_z(&ctl, i, 1), color(i - 1)).markers());
    }
    let right = Panel::new("|M₀| over [0, 2T]", "t [s]", "|M₀| [Nm]")
        .legend(Legend::UpperLeft)
        .with(Series::line("u = 131.92 N", moment(&ctl, f64::abs), color(0)).markers())
        .with(
            Series::line("u = 0", moment(&free, f64::abs), color(1))
                .markers()
                .dashed(),
        );
    let files = ctx.save(&Figure::new("fig_3_9", 2, vec![left, right]))?;
    Ok(Made {
        files,
        note: format!(
            "The riser (D = 0, h = 0.01 s) with the thesis's optimal constant control for node 4, \
             run over 2T = 0.2 s: M₀ passes through zero at T = 0.1 s (|M₀(T)| = {:.1e} Nm) and \
             then grows far beyond the uncontrolled |M₀(2T)| = {:.2e} Nm (controlled {:.2e}), as \
             in the thesis.",
            ctl.moment[10].abs(),
            free.moment[20].abs(),
            ctl.moment[20].abs()
        ),
    })
}

/// Minimises a convex function of one variable by golden-section search on [a, b].
fn golden(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, iters: usize) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..iters {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

fn fig_3_11(ctx: &Ctx) -> Res<Made> {
    let _ = ctx;
    let mut fin = catalogue::riser(5);
    fin.objective = Some(ObjectiveKind::Final);
    let mut sum = catalogue::riser(5);
    sum.objective = Some(ObjectiveKind::Sum);
    let pf = ControlProblem::builder(&fin).build_in::<2>()?;
    let ps = ControlProblem::builder(&sum).build_in::<2>()?;
    let cf = |u: f64| pf.value(&[u]).unwrap_or(f64::INFINITY);
    let cs = |u: f64| ps.value(&[u]).unwrap_or(f64::INFINITY);
    let u_f = golden(cf, -600.0, 600.0, 120);
    let u_s = golden(cs, -600.0, 600.0, 120);
    let a = simulate_with_controls(&fin, &constant(&fin, u_f))?;
    let b = simulate_with_controls(&fin, &constant(&fin, u_s))?;
    let p = Panel::new("Squared base moment, F at node 5", "t [s]", "M₀² [N²m²]")
        .legend(Legend::UpperLeft)
        .with(
            Series::line(
                format!("Final: u = {u_f:.4} N"),
                moment(&a, |m| m * m),
                color(0),
            )
            .markers(),
        )
        .with(
            Series::line(
                format!("Sum: u = {u_s:.4} N"),
                moment(&b, |m| m * m),
                color(1),
            )
            .markers()
            .dashed(),
        );
    let files = ctx.save(&Figure::single("fig_3_11", p))?;
    Ok(Made {
        files,
        note: format!(
            "Riser (D = 0), F at node 5, constant controls minimising c = M₀(T)² (u = {u_f:.6} N; \
             thesis −33.40695642) and c_sum (u = {u_s:.6} N; thesis −47.56869973), found here by \
             golden-section search on the library's objective. c_sum = {:.4} N²m² for the \
             final-optimal control and {:.4} for the sum-optimal one (thesis 2.1335 and 2.0774).",
            cs(u_f),
            cs(u_s)
        ),
    })
}

fn fig_3_12(ctx: &Ctx) -> Res<Made> {
    let t = t_end(ctx, 10.0);
    let s = retime(catalogue::riser(5), 0.01, t);
    let mut p = Panel::new(
        "|M₀|, F = 2 N at node 5, riser (D = 0)",
        "t [s]",
        "|M₀| [Nm]",
    )
    .legend(Legend::UpperLeft);
    let mut means = Vec::new();
    for (c, u) in [0.0, 1.0, -1.0].into_iter().enumerate() {
        let tr = simulate_with_controls(&s, &constant(&s, u))?;
        let m = tr.moment.iter().map(|x| x.abs()).sum::<f64>() / tr.moment.len() as f64;
        means.push(format!("u = {u}: {m:.2} Nm"));
        let ser = Series::line(format!("u = {u} N"), moment(&tr, f64::abs), color(c)).width(1);
        p.push(match c {
            1 => ser.dashed(),
            2 => ser.dotted(),
            _ => ser,
        });
    }
    let files = ctx.save(&Figure::single("fig_3_12", p))?;
    Ok(Made {
        files,
        note: format!(
            "Over t ∈ [0, {t}] s (the riser of §3.3.1, no drag), mean |M₀|: {}. As in the thesis, \
             u = +1 N (the load's direction) lowers |M₀| at first but raises it in the long run, \
             u = −1 N the opposite.",
            means.join(", ")
        ),
    })
}

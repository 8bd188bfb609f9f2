use chainbeam::ocp::{self, OcpOptions, Solver};
use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
fn main() {
    let steps: usize = std::env::args().nth(1).map_or(1000, |s| s.parse().unwrap());
    let at: usize = std::env::args().nth(2).map_or(7, |s| s.parse().unwrap());
    let mut scene = catalogue::long_horizon();
    scene.time.steps = steps;
    if let Some(c) = scene.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let p = ControlProblem::new(
        &scene,
        Parametrisation::PerStep(PerStepControl { steps }),
        obj,
    )
    .unwrap();
    let th0 = vec![0.0; p.n_params()];
    let opts = OcpOptions::default().with_bound(5.0);
    let rs = ocp::solve(&p, &th0, &opts).unwrap();
    let ts = rs.theta.clone();
    let o7 = OcpOptions {
        max_iters: at,
        ..opts.clone()
    };
    let r7 = ocp::solve(&p, &th0, &o7).unwrap();
    let t7 = r7.theta.clone();
    let d: Vec<f64> = ts.iter().zip(&t7).map(|(a, b)| a - b).collect();
    let (j7, g) = p.value_and_gradient(&t7).unwrap();
    let js = p.value(&ts).unwrap();
    let hd = p.hessian_vec(&t7, &d).unwrap();
    let mut s = Solver::new(&p, &opts).unwrap();
    s.set_point(&t7).unwrap();
    let (hgn, _g2) = s.dense_gauss_newton().unwrap();
    let m = d.len();
    let mut dgd = 0.0;
    for i in 0..m {
        for j in 0..m {
            dgd += d[i] * hgn[(i, j)] * d[j];
        }
    }
    let gd: f64 = g.iter().zip(&d).map(|(a, b)| a * b).sum();
    let dhd: f64 = hd.iter().zip(&d).map(|(a, b)| a * b).sum();
    let dn: f64 = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    println!("J7 {j7:.12} J* {js:.12} dJ {:.3e} |d| {dn:.3e}", js - j7);
    println!("g.d {gd:.4e}  dHd exact {dhd:.4e}  dHd GN {dgd:.4e}");
    println!(
        "model exact {:.4e}  model GN {:.4e}",
        gd + 0.5 * dhd,
        gd + 0.5 * dgd
    );
    // per-free-set: how much of d is on active bounds
    let act = ts.iter().filter(|x| x.abs() >= 5.0 - 1e-12).count();
    println!(
        "active at *: {act}, |d| on active {:.3e}",
        d.iter()
            .zip(&ts)
            .filter(|(_, t)| t.abs() >= 5.0 - 1e-12)
            .map(|(x, _)| x * x)
            .sum::<f64>()
            .sqrt()
    );
    // spectrum hint: random-ish high-frequency direction
    let e: Vec<f64> = (0..m)
        .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let he = p.hessian_vec(&t7, &e).unwrap();
    let ehe: f64 = he.iter().zip(&e).map(|(a, b)| a * b).sum();
    let mut ege = 0.0;
    for i in 0..m {
        for j in 0..m {
            ege += e[i] * hgn[(i, j)] * e[j];
        }
    }
    println!("alternating: exact {ehe:.4e} GN {ege:.4e}");
}

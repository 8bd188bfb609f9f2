use chainbeam::ocp::{self, OcpOptions};
use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let steps: usize = a[0].parse().unwrap();
    let drag: f64 = a[1].parse().unwrap();
    let rho: f64 = a[2].parse().unwrap();
    let umax: f64 = a[3].parse().unwrap();
    let mut scene = catalogue::long_horizon();
    scene.time.steps = steps;
    scene.loads.drag = drag;
    if let Some(c) = scene.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    let p = ControlProblem::new(
        &scene,
        Parametrisation::PerStep(PerStepControl { steps }),
        BendingObjective::summed_moment().with_effort(rho),
    )
    .unwrap();
    let r = ocp::solve(
        &p,
        &vec![0.0; steps + 1],
        &OcpOptions {
            max_iters: 60,
            ..OcpOptions::default().with_bound(umax)
        },
    )
    .unwrap();
    for (i, h) in r.history.iter().enumerate() {
        println!(
            "{:>3} J={:.12} pg={:.3e} a={} mu={:.0e}",
            i + 1,
            h.objective,
            h.projected_gradient_norm,
            h.alpha,
            h.regularisation
        );
    }
    println!(
        "{} {} {:.3e} {:.3}s rollouts {} jac {} riccati {}",
        r.converged,
        r.iterations,
        r.projected_gradient_norm / r.initial_gradient_norm,
        r.seconds,
        r.rollouts,
        r.jacobian_passes,
        r.backward_passes
    );
}

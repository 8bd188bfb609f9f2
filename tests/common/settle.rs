//! A planar beam run until it settles, shared by `tests/model/core.rs` and `tests/model/current.rs` (their
//! references for the static solver: thesis §2.4.4 checks eq. 2.4.4's damped beams the same way).

use chainbeam::*;

/// Runs a dissipative scene with RATTLE from the straight beam under the constant control `u`
/// (without storing the trajectory) until the largest attitude rate |q̇ᵢ| = |(M⁻¹p)ᵢ| over a
/// window of 1000 steps falls below `v_tol`, or `t_max` is reached; returns the node positions
/// (y, z) and the time.
pub fn settle(scene: &Scene, u: f64, v_tol: f64, t_max: f64) -> (Vec<[f64; 2]>, f64) {
    let chain = Chain::<f64, 2>::from_scene(scene).unwrap();
    let n = chain.n();
    let mut r = Rattle::new(chain.clone(), scene.time.step).unwrap();
    let mut st = r.straight_state();
    let max_steps = (t_max / scene.time.step) as usize;
    let (mut k, mut v, mut window_max) = (0, vec![[0.0; 2]; n], 0.0f64);
    while k < max_steps {
        r.step(&mut st, k, u, u).unwrap();
        k += 1;
        chain.apply_inverse_mass(&st.p, &mut v);
        window_max = v
            .iter()
            .fold(window_max, |m, v| m.max(v[0].abs()).max(v[1].abs()));
        if k % 1000 == 0 {
            if window_max < v_tol {
                break;
            }
            window_max = 0.0;
        }
    }
    let mut pos = vec![[0.0; 2]; n];
    chain.node_positions(&st.q, &mut pos);
    (pos, k as f64 * scene.time.step)
}

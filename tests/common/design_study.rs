//! The reduced scatter studies of the design tests (tests/design): the diagram's cells, the
//! study of a reduced scene, its evaluation, and the two checks of the design gradient every
//! reduced scene goes through: against central differences of D_y (the one gradient check,
//! `gradient_check::{central, assert_close}`), and cell by cell against forward-mode dual
//! numbers through the library's fatigue objective.
#![allow(dead_code)]

use crate::gradient_check::{assert_close, central, Tolerance};
use chainbeam::adjoint::{Objective, Stage};
use chainbeam::design::{
    DesignParameter, DesignPoint, DesignStudy, Execution, ScatterGradient, Want,
};
use chainbeam::fatigue::{DamageGradient, MomentMeasure, ScatterCell, SeaState, WellheadDamage};
use chainbeam::hotspots::{
    interpolation_joints, joint_moment_history, HotSpotSpec, JointInterpolation,
};
use chainbeam::{Chain, FatigueObjective, Scalar, Scene};
use num_dual::Dual64;

/// The 21-inch riser's section (outer diameter, wall thickness) \[m\]: the `[fatigue]` section
/// of the reduced riser (tests/design/design.rs) and of the reduced riser system
/// (tests/design/design_vessel.rs), that of examples/scenes/riser_300m.toml.
pub const RISER_SECTION: (f64, f64) = (0.5334, 0.022225);

/// The text of a reduced scene of the design tests: `specific` (its beam, loads, sea, time and
/// stack-up), then the keys every one of them shares, the 300 m of sea water
/// (1025 kg/m³) of examples/scenes/riser_300m.toml, its uniform 0.5 m/s current and a
/// `[fatigue]` section of outer diameter and wall thickness `section` \[m\] (SCF 1.2, DNV's F1
/// curve in sea water with cathodic protection, DFF 10), then `design` (the `[design]` table,
/// hot spots).
pub fn scene_text(specific: &str, section: (f64, f64), design: &str) -> String {
    let (outer_diameter, wall_thickness) = section;
    format!(
        r#"{specific}
[water]
depth = 300.0
density = 1025.0

[loads.current]
profile = "uniform"
speed = 0.5

[fatigue]
outer_diameter = {outer_diameter:?}
wall_thickness = {wall_thickness:?}
scf = 1.2
curve = "F1"
environment = "seawater-cp"
dff = 10.0
{design}
"#
    )
}

/// Cells of a reduced diagram from (H_s \[m\], T_p \[s\], probability), no direction.
pub fn cells(list: &[(f64, f64, f64)]) -> Vec<ScatterCell> {
    list.iter()
        .map(|&(hs, tp, probability)| ScatterCell {
            sea: SeaState {
                hs,
                tp,
                direction: None,
            },
            probability,
        })
        .collect()
}

/// The study of `scene` over `cells`, `record` seconds counted after `spin_up`.
pub fn study<'a>(
    scene: &'a Scene,
    cells: &'a [ScatterCell],
    record: f64,
    spin_up: f64,
) -> DesignStudy<'a> {
    DesignStudy {
        scene,
        cells: Some(cells),
        record: Some(record),
        spin_up,
    }
}

/// The scene's own values of `params`.
pub fn values(scene: &Scene, params: &[DesignParameter]) -> Vec<f64> {
    params.iter().map(|p| p.value(scene).unwrap()).collect()
}

/// D_y (and its gradient with [`Want::Gradient`]) at the values `v` of `params`.
pub fn eval(
    st: &DesignStudy<'_>,
    params: &[DesignParameter],
    v: &[f64],
    want: Want,
    execution: Execution,
) -> ScatterGradient {
    let point = DesignPoint { params, values: v };
    st.evaluate(&point, want, execution, &|| {}).unwrap()
}

/// [`check_central_differences`] for every parameter at each of `designs`, with the checks the
/// buoyancy tests add: the buoyancy diameter (parameter 0) moves the damage, and the serial
/// evaluation equals the parallel one bit for bit.
pub fn check_buoyancy_designs(
    st: &DesignStudy<'_>,
    params: &[DesignParameter],
    designs: [Vec<f64>; 2],
) {
    let which: Vec<usize> = (0..params.len()).collect();
    for v in designs {
        let g = check_central_differences(st, params, &v, &which);
        eprintln!(
            "at {v:?}: D_y = {:e}, dD_y/dθ = {:?}",
            g.damage_per_year, g.gradient
        );
        assert!(g.gradient[0] != 0.0, "the modules move the damage: {g:?}");
        let serial = eval(st, params, &v, Want::Gradient, Execution::Serial);
        assert_eq!(serial, g);
    }
}

/// ∂D_y/∂θ_i by the adjoint against central differences of D_y (each D_y by forward runs of
/// every cell) with the step 10⁻⁵ θ_i, to 10⁻⁵ relative, for the parameters `which` (indices
/// into `params`) at the design `v`; also D_y of the forward runs = the adjoint sweeps' bit for
/// bit (the same forward arithmetic). The reference is the central difference: truncation
/// O(10⁻¹⁰) relative for the step. The comparison is of the relative sensitivities θ_i ∂D_y/∂θ_i
/// (one unit, that of D_y, whatever the parameter's), each to 10⁻⁵ of the largest of them: the
/// difference's round-off, about ε D_y / (2 · 10⁻⁵) in θ_i ∂D_y/∂θ_i, is the same for every
/// parameter, so a parameter that barely moves D_y cannot be checked to 10⁻⁵ of itself (the tip
/// spring for the hot spot near the base of tests/design/design_hotspot.rs: ∂D_y/∂k_tip =
/// 1.38905·10⁻¹⁴ by the adjoint, 1.38903·10⁻¹⁴ by the difference, 1.2·10⁻⁵ apart).
/// Returns the evaluation at `v`.
pub fn check_central_differences(
    st: &DesignStudy<'_>,
    params: &[DesignParameter],
    v: &[f64],
    which: &[usize],
) -> ScatterGradient {
    let g = eval(st, params, v, Want::Gradient, Execution::Parallel);
    assert!(g.damage_per_year > 0.0);
    let plain = eval(st, params, v, Want::Value, Execution::Parallel);
    assert_eq!(plain.damage_per_year.to_bits(), g.damage_per_year.to_bits());
    let fd: Vec<f64> = which
        .iter()
        .map(|&i| {
            let at = |x: f64| {
                let mut w = v.to_vec();
                w[i] = x;
                eval(st, params, &w, Want::Value, Execution::Parallel).damage_per_year
            };
            central(&at, v[i], 1e-5 * v[i])
        })
        .collect();
    let got: Vec<f64> = which.iter().map(|&i| v[i] * g.gradient[i]).collect();
    let fd: Vec<f64> = which.iter().zip(&fd).map(|(&i, d)| v[i] * d).collect();
    let largest = fd.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let names: Vec<String> = which.iter().map(|&i| params[i].name()).collect();
    let label = format!("θ dD_y/dθ for ({}) at {v:?}", names.join(", "));
    let worst = assert_close(
        &label,
        &got,
        &fd,
        "central differences, step 1e-5 of each parameter",
        Tolerance::of_scale(1e-5, largest),
    );
    let each: Vec<f64> = got
        .iter()
        .zip(&fd)
        .map(|(a, d)| (a - d).abs() / d.abs())
        .collect();
    eprintln!(
        "{label}: adjoint {got:?}, central differences {fd:?}; relative to the largest \
         {worst:e}, each to itself {each:?}"
    );
    g
}

/// Cell `s`'s scene at `point` and the library's fatigue objective on it (its section and moment
/// measure, no effort term), which counts the whole record: the reference a forward-mode run
/// differentiates.
pub fn cell_objective(
    st: &DesignStudy<'_>,
    s: usize,
    point: &DesignPoint<'_>,
) -> (Scene, FatigueObjective) {
    let cs = st.cell_scene(s, point).unwrap();
    let spec = cs.fatigue_spec().unwrap();
    let objective = FatigueObjective {
        damage: WellheadDamage::new(&spec, cs.moment_measure()).unwrap(),
        effort: 0.0,
    };
    (cs.into_inner(), objective)
}

/// ∂D_s/∂θ_i of every cell by the adjoint = the dual part of D_s computed in `Dual64` with θ_i
/// seeded through `Chain::set_parameter` (forward-mode differentiation of the whole run through
/// the library's fatigue objective, [`FatigueObjective`], which counts the whole record: the
/// study's spin-up must be 0), to 10⁻⁹ relative (both exact; they differ by round-off in
/// different orders of operations), and D_s itself to 10⁻¹² (dual arithmetic rounds some real
/// parts differently, by an ulp).
pub fn check_dual_numbers(st: &DesignStudy<'_>, params: &[DesignParameter], v: &[f64]) {
    assert_eq!(st.spin_up, 0.0, "the dual check counts the whole record");
    let g = eval(st, params, v, Want::Gradient, Execution::Serial);
    let point = DesignPoint { params, values: v };
    for (s, cell) in g.cells.iter().enumerate() {
        let (cs, objective) = cell_objective(st, s, &point);
        let steps = cs.time.steps;
        for (i, p) in params.iter().enumerate() {
            let mut chain = Chain::<Dual64, 2>::from_scene(&cs).unwrap();
            chain
                .set_parameter(p.parameter(&cs).unwrap(), Dual64::new(v[i], 1.0))
                .unwrap();
            let u = vec![Dual64::from(0.0); steps + 1];
            let d = chainbeam::adjoint::forward_value(&chain, cs.time.step, steps, &u, &objective)
                .unwrap();
            let rel_d = (d.re - cell.damage).abs() / cell.damage;
            assert!(
                rel_d < 1e-12,
                "cell {s}: D_s {} against {}",
                d.re,
                cell.damage
            );
            let rel = (cell.gradient[i] - d.eps).abs() / d.eps.abs();
            assert!(
                rel < 1e-9,
                "cell {s}, {}: adjoint {:e}, Dual64 {:e} (relative {rel:e})",
                p.name(),
                cell.gradient[i],
                d.eps
            );
        }
    }
}

/// Cell scene `cs`'s chain in `Dual64` with the buoyancy diameter `p` of a stack-up segment
/// seeded: every node quantity it moves set to x + ε ∂x/∂D_b, the derivatives the layout's own
/// (`Stackup::buoyancy_tangents`: masses with added mass, submerged weights, Morison drag and
/// the waves' inertia), through the library's public pieces alone (`Chain::set_node_quantities`).
/// A forward run of it (`adjoint::forward_value`) is the forward-mode reference of ∂J/∂D_b.
pub fn seeded_buoyancy_chain(cs: &Scene, p: &DesignParameter) -> Chain<Dual64, 2> {
    use chainbeam::model::{NodeQuantities, WaveTangent};
    let stack = cs.stackup.as_ref().unwrap();
    let t = stack.buoyancy_tangents(
        p.segment(cs).unwrap(),
        &cs.beam.lengths,
        cs.water.density,
        cs.mudline(),
    );
    let dual = |re: &[f64], eps: &[f64]| -> Vec<Dual64> {
        re.iter()
            .zip(eps)
            .map(|(&r, &e)| Dual64::new(r, e))
            .collect()
    };
    let mut chain = Chain::<Dual64, 2>::from_scene(cs).unwrap();
    chain
        .set_node_quantities(NodeQuantities {
            masses: dual(&cs.beam.masses, &t.masses),
            weights: dual(&stack.layout.node_weights, &t.weights),
            drag: dual(&stack.layout.node_drag, &t.drag),
            waves: Some(WaveTangent {
                masses: t.masses.clone(),
                inertia: t.inertia.clone(),
                seed: Dual64::new(0.0, 1.0),
            }),
        })
        .unwrap();
    chain
}

/// The linearised damage J = Σ_k g_k M(t_k) at a hot spot between joints a and b, written here
/// independently of the library's stage cost: each pendulum's attitude (q_y, q_z) from the nodes'
/// z (q_z = (z_p − z_{p−1})/l_p, q_y = √(1 − q_z²)), the joint angle atan2(a_y b_z − a_z b_y,
/// a·b) as `chainbeam::hotspots::joint_moment` takes it, the springs constant. At the run's
/// rainflow pairing dD/dθ = Σ_k g_k dM(t_k)/dθ, the derivative part of J in a forward-mode run
/// (plus, for a parameter that is one of the two springs, its direct term Σ_k g_k ∂M/∂k).
#[derive(Clone)]
pub struct LinearisedHotSpot {
    /// g_k = ∂D/∂M(t_k), k = 0..=N.
    pub g: std::sync::Arc<[f64]>,
    /// The pendulums' lengths.
    pub lengths: std::sync::Arc<[f64]>,
    /// (joint, coefficient: weight × spring).
    pub terms: [(usize, f64); 2],
}

impl LinearisedHotSpot {
    fn attitude<D: Scalar>(&self, p: usize, z: &[D]) -> (D, D) {
        if p >= self.lengths.len() {
            return (D::one(), D::zero());
        }
        let below = if p == 0 { D::zero() } else { z[p - 1] };
        let qz = (z[p] - below) / self.lengths[p];
        ((D::one() - qz * qz).sqrt(), qz)
    }
}

impl Objective for LinearisedHotSpot {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let mut m = D::zero();
        for &(j, c) in &self.terms {
            let (ay, az) = if j == 0 {
                (D::one(), D::zero())
            } else {
                self.attitude(j - 1, s.z)
            };
            let (by, bz) = self.attitude(j, s.z);
            m += (ay * bz - az * by).atan2(ay * by + az * bz) * c;
        }
        m * self.g[s.k]
    }
    fn uses_positions(&self) -> bool {
        true
    }
}

/// A cell's hot-spot damage by this test's own f64 run of the joint torques
/// (`hotspots::joint_moment_history`, the whole record counted): the damage D, the two joints
/// and the upper one's weight, the blended moment's g_k = ∂D/∂M(t_k), and the joints' torques.
pub struct HotSpotRun {
    /// D of the whole record.
    pub damage: f64,
    /// The two joints around the hot spot and the upper one's weight.
    pub joints: JointInterpolation,
    /// g_k = ∂D/∂M(t_k).
    pub g: Vec<f64>,
    /// The two joints' torques k θ(t_k) \[N·m\].
    pub torques: [Vec<f64>; 2],
}

/// [`HotSpotRun`] of cell scene `cs` at the hot spot `hot`.
pub fn hot_spot_run(cs: &Scene, hot: &HotSpotSpec) -> HotSpotRun {
    let w = interpolation_joints(&cs.beam.lengths, hot.elevation);
    let history = joint_moment_history(cs, &[w.lower, w.upper]).unwrap();
    let m: Vec<f64> = history.moment[0]
        .iter()
        .zip(&history.moment[1])
        .map(|(&a, &b)| w.blend(a, b))
        .collect();
    let damage = WellheadDamage::new(&hot.spec, MomentMeasure::Wellhead).unwrap();
    let mut g = vec![0.0; m.len()];
    let d = damage
        .value_and_gradient(
            &m,
            None,
            DamageGradient {
                grad: &mut g,
                grad_x: &mut [],
            },
        )
        .unwrap();
    let [a, b]: [Vec<f64>; 2] = history.moment.try_into().unwrap();
    HotSpotRun {
        damage: d,
        joints: w,
        g,
        torques: [a, b],
    }
}

impl HotSpotRun {
    /// The linearised damage of this run on `cs` ([`LinearisedHotSpot`]), the springs those of
    /// `cs`'s chain.
    pub fn linearised(&self, cs: &Scene) -> LinearisedHotSpot {
        let k = Chain::<f64, 2>::from_scene(cs).unwrap().springs().to_vec();
        let w = self.joints;
        LinearisedHotSpot {
            g: self.g.clone().into(),
            lengths: cs.beam.lengths.clone().into(),
            terms: [
                (w.lower, (1.0 - w.weight) * k[w.lower]),
                (w.upper, w.weight * k[w.upper]),
            ],
        }
    }
}

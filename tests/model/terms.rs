//! The one-model contract (issue "One model, every derivative from it"): for every force term of
//! the chain × {planar, spatial} × {f64, Dual64}, each derivative the solvers use agrees with the
//! dual-number derivative of the term's own definition:
//! * the generalised force = the dual gradient of the energy (1e-12 relative);
//! * K v (the hand-written spring override and the dual-derived default) = the dual derivative of
//!   the force along v (1e-12);
//! * ⟨K v, w⟩ = ⟨v, Kᵀ w⟩ (the transposed product is consistent, 1e-12);
//! * w·∂F/∂θ and w·∂F/∂u (dual-derived defaults and overrides) = central finite differences of
//!   w·F in θ (set on the model) and in u (1e-7: the FD error; step 1e-4·max(|θ|, 1) in θ, where
//!   w·F is linear except in the phases of the harmonic loads, so the rounding of the whole
//!   model's w·F (~1e-16·|w·F|/step) dominates, and 1e-5 in u).
//!
//! The configurations are away from the straight beam and cover both branches of the spring
//! function (the series for θ ≲ 11.5° and the closed form beyond) and joint angles above 90°.

use chainbeam::model::{
    BlockSym, CoupledAt, CoupledDissipativeTerm, Ctx, DissipationVisitor, DissipativeTerm,
    DualScratch, Embed, ForceTerm, HalfKick, HalfSteps, TermVisitor,
};
use chainbeam::scene::Soil;
use chainbeam::{
    catalogue, Chain, Current, Harmonic, LoadSeries, Parameter, PointLoad, Scalar, Scene,
    SceneBuilder, Support,
};
use num_dual::{Dual, Dual64};

use crate::gradient_check;
use gradient_check::Tolerance;

/// A scene with every conservative term: springs (base, interior, tip), point loads of every
/// kind (constant, time-windowed, a ramped sum of two harmonics, a time series), gravity, a
/// control at node 4, drag, and soil springs on the nodes below a mudline. `spatial`: the loads get x components (a vector force, a
/// direction out of the yz-plane, an F_x column), so the spatial model's x terms are checked too;
/// otherwise the same loads lie in the yz-plane and the planar model can run the scene.
fn all_terms_scene(spatial: bool) -> Scene {
    let x = if spatial { 1.0 } else { 0.0 };
    let harmonics = vec![
        Harmonic {
            amplitude: 0.8,
            period: 2.0,
            phase: 0.3,
        },
        Harmonic {
            amplitude: 0.3,
            period: 0.7,
            phase: -1.1,
        },
    ];
    // t = 1 (where the terms are evaluated) lies between rows, inside the ramp of the harmonics
    let rows = vec![
        [0.0, 0.0, 0.2],
        [0.5, 0.4 * x, -0.3],
        [1.3, -0.7 * x, 0.9],
        [10.0, 0.1 * x, 0.0],
    ];
    SceneBuilder::new(6)
        .support(Support::Riser)
        .lengths(vec![1.0, 0.8, 1.2, 0.9, 1.1, 1.0])
        .masses(vec![1.0, 1.5, 0.7, 1.2, 0.9, 1.1])
        .stiffness(900.0)
        .base_stiffness(2100.0)
        .tip_stiffness(1700.0)
        .gravity(9.81)
        .tension(350.0)
        .axial_weight(40.0)
        .drag(10.0)
        .point_load_vector(3, [0.5 * x, 2.0])
        .point_load_window(6, -1.5, 0.0, 5.0)
        .load(
            PointLoad::harmonic(5, [0.6 * x, 0.8], harmonics)
                .window(0.2, None)
                .ramped(1.5),
        )
        .load(PointLoad::series(
            2,
            LoadSeries::new("in code", rows).expect("valid rows"),
        ))
        .control_constant(4, -0.7)
        // The mudline 2.5 m above the foot: nodes 1 and 2 in the soil, node 3's cell partly.
        .soil(Soil {
            mudline: 2.5,
            modulus: 300.0,
            gradient: 150.0,
        })
        .build()
        .expect("valid scene")
}

/// Unit attitudes with joint angles spanning ~3° to ~120° (both s(x) branches, a·b < 0 once).
fn attitudes<const DIM: usize>(n: usize) -> Vec<[f64; DIM]> {
    let angles = [0.05, 0.35, 2.1, 1.0, 0.3, -0.4, 0.6, 0.1];
    let mut phi: f64 = 0.0;
    (0..n)
        .map(|i| {
            phi += angles[i % angles.len()];
            let (s, c) = phi.sin_cos();
            let mut q = [0.0; DIM];
            if DIM == 3 {
                // tilt out of the plane so the spatial model is exercised off the yz-plane
                let tilt: f64 = 0.2 * (i as f64 + 1.0).sin();
                q[0] = tilt.sin() * c;
                q[1] = tilt.cos() * c;
                q[2] = s;
            } else {
                q[0] = c;
                q[1] = s;
            }
            q
        })
        .collect()
}

fn vectors<const DIM: usize>(n: usize, seed: f64) -> Vec<[f64; DIM]> {
    (0..n)
        .map(|i| std::array::from_fn(|d| ((i * DIM + d) as f64 * 0.7 + seed).sin()))
        .collect()
}

fn lift<D: Scalar, const DIM: usize>(v: &[[f64; DIM]]) -> Vec<[D; DIM]> {
    v.iter().map(|x| x.map(D::from)).collect()
}

fn inner<D: Scalar, const DIM: usize>(a: &[[D; DIM]], b: &[[D; DIM]]) -> D {
    let mut s = D::zero();
    for (x, y) in a.iter().zip(b) {
        for d in 0..DIM {
            s += x[d] * y[d];
        }
    }
    s
}

fn close(label: &str, a: f64, b: f64, scale: f64, tol: f64) {
    let err = (a - b).abs() / scale.max(1e-300);
    assert!(
        err <= tol,
        "{label}: {a:e} vs {b:e} (rel. error {err:e} > {tol:e})"
    );
}

fn max_abs<D: Scalar, const DIM: usize>(v: &[[D; DIM]]) -> f64 {
    v.iter().flatten().fold(0.0f64, |m, x| m.max(x.re().abs()))
}

/// Checks one term at (q, t, u); records which terms were checked.
struct Check<D: Scalar, const DIM: usize> {
    q: Vec<[D; DIM]>,
    v: Vec<[D; DIM]>,
    w: Vec<[D; DIM]>,
    t: f64,
    u: D,
    chain: Chain<D, DIM>,
    checked: Vec<&'static str>,
}

impl<D: Scalar, const DIM: usize> Check<D, DIM> {
    /// The force equals the dual gradient of the energy (one seeded direction per component).
    fn force_is_energy_gradient<T: ForceTerm<D, DIM>>(&self, term: &T) {
        let n = self.q.len();
        let ctx = Ctx::new(self.t, self.u, 0);
        let mut f = vec![[D::zero(); DIM]; n];
        term.force(&self.q, &ctx, &mut f).unwrap();
        let scale = max_abs(&f).max(1.0);
        let dctx = Ctx::new(self.t, Dual::from_re(self.u), 0);
        for i in 0..n {
            for d in 0..DIM {
                let mut qd: Vec<[Dual<D>; DIM]> =
                    self.q.iter().map(|x| x.map(Dual::from_re)).collect();
                qd[i][d].eps = D::one();
                let g = term.energy(&qd, &dctx).eps;
                let label = format!("{} dU/dq[{i}][{d}]", term.name());
                close(&label, f[i][d].re(), g.re(), scale, 1e-12);
            }
        }
    }

    /// K v (the term's product) equals the dual derivative of the force along v; ⟨Kv, w⟩ =
    /// ⟨v, Kᵀw⟩.
    fn jvp_is_force_derivative<T: ForceTerm<D, DIM>>(&self, term: &T) {
        let n = self.q.len();
        let ctx = Ctx::new(self.t, self.u, 0);
        let mut scratch = DualScratch::new(n);
        let mut kv = vec![[D::zero(); DIM]; n];
        term.force_jvp(&self.q, &self.v, &ctx, D::one(), &mut kv, &mut scratch)
            .unwrap();
        let qd: Vec<[Dual<D>; DIM]> = self
            .q
            .iter()
            .zip(&self.v)
            .map(|(q, v)| std::array::from_fn(|d| Dual::new(q[d], v[d])))
            .collect();
        let mut fd = vec![[Dual::from_re(D::zero()); DIM]; n];
        let dctx = Ctx::new(self.t, Dual::from_re(self.u), 0);
        term.force(&qd, &dctx, &mut fd).unwrap();
        let scale = fd
            .iter()
            .flatten()
            .fold(1.0f64, |m, x| m.max(x.eps.re().abs()));
        for i in 0..n {
            for d in 0..DIM {
                let label = format!("{} (Kv)[{i}][{d}]", term.name());
                close(&label, kv[i][d].re(), fd[i][d].eps.re(), scale, 1e-12);
            }
        }
        let mut ktw = vec![[D::zero(); DIM]; n];
        term.force_vjp(&self.q, &self.w, &ctx, D::one(), &mut ktw, &mut scratch)
            .unwrap();
        let (a, b) = (inner(&kv, &self.w), inner(&self.v, &ktw));
        let label = format!("{} <Kv,w> = <v,K'w>", term.name());
        close(&label, a.re(), b.re(), scale * n as f64, 1e-12);
    }

    /// w·∂F/∂θ and w·∂F/∂u equal central differences of w·F.
    fn contractions_match_fd<T: ForceTerm<D, DIM>>(&self, term: &T) {
        let n = self.q.len();
        let ctx = Ctx::new(self.t, self.u, 0);
        let mut scratch = DualScratch::new(n);
        let wf = |chain: &Chain<D, DIM>, u: D| -> f64 {
            let mut f = vec![[D::zero(); DIM]; n];
            chain
                .potential_gradient(&self.q, self.t, u, 0, &mut f)
                .unwrap();
            inner(&f, &self.w).re()
        };
        let params = [
            (Parameter::InteriorStiffness, 900.0),
            (Parameter::BaseStiffness, 2100.0),
            (Parameter::TipStiffness, 1700.0),
            (Parameter::Mass, 1.0),
            (Parameter::Tension, 350.0),
            (Parameter::AxialWeight, 40.0),
            (Parameter::SoilModulus, 300.0),
            (Parameter::LoadForce(0), 2.0),
            (Parameter::LoadForceX(0), 0.5),
            (Parameter::LoadForce(1), -1.5),
            (
                Parameter::LoadAmplitude {
                    load: 2,
                    harmonic: 0,
                },
                0.8,
            ),
            (
                Parameter::LoadAmplitude {
                    load: 2,
                    harmonic: 1,
                },
                0.3,
            ),
            (
                Parameter::LoadPhase {
                    load: 2,
                    harmonic: 0,
                },
                0.3,
            ),
            (
                Parameter::LoadPhase {
                    load: 2,
                    harmonic: 1,
                },
                -1.1,
            ),
        ];
        let mut tested = 0;
        for (p, value) in params {
            if !term.has_parameter(p) {
                continue;
            }
            let got = term
                .parameter_contraction(&self.q, &self.w, &ctx, p, &mut scratch)
                .unwrap();
            // FD on the whole model: only this term reads p (mass: only gravity among the terms).
            let hstep = 1e-4 * f64::abs(value).max(1.0);
            let (mut cp, mut cm) = (self.chain.clone(), self.chain.clone());
            cp.set_parameter(p, D::from(value + hstep)).unwrap();
            cm.set_parameter(p, D::from(value - hstep)).unwrap();
            let fd = (wf(&cp, self.u) - wf(&cm, self.u)) / (2.0 * hstep);
            let label = format!("{} w.dF/d{p:?}", term.name());
            close(&label, got.re(), fd, fd.abs().max(1.0), 1e-7);
            assert!(got.re().abs() > 1e-6, "{label} = {got:?} is not exercised");
            tested += 1;
        }
        if term.name() == "point loads" {
            // F_z, F_x (spatial only), F_z of the windowed load, two amplitudes, two phases
            assert_eq!(
                tested,
                if DIM == 3 { 7 } else { 6 },
                "load parameters checked"
            );
        }
        let got = term
            .control_contraction(&self.q, &self.w, &ctx, &mut scratch)
            .unwrap();
        let expect = if term.depends_on_control() {
            let hu = 1e-5;
            (wf(&self.chain, self.u + hu) - wf(&self.chain, self.u - hu)) / (2.0 * hu)
        } else {
            0.0
        };
        let label = format!("{} w.dF/du", term.name());
        close(&label, got.re(), expect, expect.abs().max(1.0), 1e-7);
    }
}

impl<D: Scalar, const DIM: usize> TermVisitor<D, DIM> for Check<D, DIM> {
    fn visit<T: ForceTerm<D, DIM>>(&mut self, term: &T) -> chainbeam::Result<()> {
        self.force_is_energy_gradient(term);
        self.jvp_is_force_derivative(term);
        self.contractions_match_fd(term);
        self.checked.push(term.name());
        Ok(())
    }
}

/// [`all_terms_scene`] described as a pipe (for the inertia coefficient) in irregular waves
/// (`[loads.waves]`) at 40° (spatial) or 180° (planar), with a current in the spatial
/// case: the wave inertia load joins the conservative terms and the drag is relative to the
/// water (current + waves).
fn waves_scene(spatial: bool) -> Scene {
    let mut s = all_terms_scene(spatial);
    s.pipe = Some(chainbeam::scene::Pipe::new(6.0, 0.05, 0.005));
    s.water.depth = Some(5.5);
    let mut w = chainbeam::scene::Waves::jonswap(1.5, 4.0);
    w.direction = if spatial { 40.0 } else { 180.0 };
    w.components = Some(120);
    s.loads.waves = Some(w);
    if spatial {
        s.loads.current = Some(Current::linear(0.8, 0.3, [0.6, 0.8]));
    }
    s.validate().unwrap();
    assert_eq!(s.is_spatial(), spatial);
    s
}

fn check_all_terms<D: Scalar, const DIM: usize>() {
    check_terms_of::<D, DIM>(&all_terms_scene(DIM == 3), &[]);
    check_terms_of::<D, DIM>(&waves_scene(DIM == 3), &["wave inertia"]);
}

fn check_terms_of<D: Scalar, const DIM: usize>(scene: &Scene, more: &[&str]) {
    let scene = scene.clone();
    assert_eq!(scene.is_spatial(), DIM == 3);
    let chain = Chain::<D, DIM>::from_scene(&scene).unwrap();
    let n = chain.n();
    let mut check = Check {
        q: lift(&attitudes::<DIM>(n)),
        v: lift(&vectors::<DIM>(n, 0.3)),
        w: lift(&vectors::<DIM>(n, 1.9)),
        t: 1.0,
        u: D::from(-0.7),
        chain: chain.clone(),
        checked: Vec::new(),
    };
    // A joint above 90° (the a·b ≤ 0 branch of the joint angle) is among the configurations.
    assert!(chain.max_joint_angle(&check.q) > std::f64::consts::FRAC_PI_2);
    chain.visit_terms(&mut check).unwrap();
    let mut expect = vec![
        "springs",
        "point loads",
        "gravity",
        "tension",
        "axial_weight",
        "control",
    ];
    expect.extend_from_slice(more);
    expect.push("soil");
    assert_eq!(
        check.checked, expect,
        "every conservative term of the scene was checked"
    );
}

#[test]
fn every_force_term_planar_f64() {
    check_all_terms::<f64, 2>();
}

#[test]
fn every_force_term_spatial_f64() {
    check_all_terms::<f64, 3>();
}

#[test]
fn every_force_term_planar_dual64() {
    check_all_terms::<Dual64, 2>();
}

#[test]
fn every_force_term_spatial_dual64() {
    check_all_terms::<Dual64, 3>();
}

/// The drag term: F(p) = −D p|p| (eq. 2.4.4) per component in the planar model; its slope and
/// parameter derivative from duals equal the closed forms −2D|p| and −p|p| (the general checks
/// of every dissipative term follow).
#[test]
fn drag_term_closed_forms() {
    let chain = Chain::<f64, 2>::from_scene(&all_terms_scene(false)).unwrap();
    let drag = chain.drag().expect("scene has drag").clone();
    let ctx = Ctx::new(0.0, 0.0, 0);
    let d = 10.0;
    for p in [-3.0, -0.2, 0.0, 0.05, 1.7] {
        let x = [0.4 - p, p];
        let (f, slope) = DissipativeTerm::<f64, 2>::force_and_slope(&drag, 0, &x, &ctx);
        let dd =
            DissipativeTerm::<f64, 2>::parameter_derivative(&drag, 0, &x, &ctx, Parameter::Drag);
        for c in 0..2 {
            close("F_D", f[c], -d * x[c] * f64::abs(x[c]), 1.0, 1e-15);
            close("F_D'", slope.diag[c], -2.0 * d * f64::abs(x[c]), 1.0, 1e-15);
            close("dF_D/dD", dd[c], -x[c] * f64::abs(x[c]), 1.0, 1e-15);
        }
    }
}

/// Σ_T F_T of a chain's dissipative terms evaluated in any scalar `E` (through the visitor).
struct ForceIn<'a, E, const DIM: usize> {
    i: usize,
    p: &'a [E; DIM],
    ctx: &'a Ctx<E>,
    sum: [E; DIM],
}

impl<D: Scalar, E: Embed<D>, const DIM: usize> DissipationVisitor<D, DIM> for ForceIn<'_, E, DIM> {
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        let f = term.force(self.i, self.p, self.ctx);
        self.sum = std::array::from_fn(|d| self.sum[d] + f[d]);
    }
}

/// Whether some term of the chain reads a parameter.
struct Reads(Parameter, bool);

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for Reads {
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.1 |= term.has_parameter(self.0);
    }
}

/// The trait's defaults (the `Dual<D>` slope and parameter derivative, the Newton implicit
/// solve) applied to the sum of the chain's dissipative terms, for comparison with the closed
/// forms the chain's methods use.
#[derive(Clone, Debug)]
struct DefaultSolve<D: Scalar, const DIM: usize>(Chain<D, DIM>);

impl<D: Scalar, const DIM: usize> DissipativeTerm<D, DIM> for DefaultSolve<D, DIM> {
    fn name(&self) -> &'static str {
        "default solve"
    }
    fn force<E: Embed<D>>(&self, i: usize, p: &[E; DIM], ctx: &Ctx<E>) -> [E; DIM] {
        let mut v = ForceIn {
            i,
            p,
            ctx,
            sum: [E::zero(); DIM],
        };
        self.0.visit_dissipation(&mut v);
        v.sum
    }
    fn has_parameter(&self, p: Parameter) -> bool {
        let mut v = Reads(p, false);
        self.0.visit_dissipation(&mut v);
        v.1
    }
}

/// Entry (r, c) of a block.
fn entry<D: Scalar, const DIM: usize>(b: &BlockSym<D, DIM>, r: usize, c: usize) -> D {
    if r == c {
        b.diag[r]
    } else if DIM == 3 && r + c == 2 && r != 1 {
        b.xz
    } else {
        D::zero()
    }
}

/// The scene of [`all_terms_scene`] with a current (replacing the still-water drag): a linear
/// shear, or a table whose direction turns with depth (`table`); out of the yz-plane when
/// `spatial`.
fn current_scene(spatial: bool, table: bool) -> Scene {
    let mut s = all_terms_scene(spatial);
    let dir = if spatial { [0.6, 0.8] } else { [0.0, -1.0] };
    let psi = if spatial { 40.0 } else { 180.0 };
    s.loads.current = Some(if table {
        Current::table(vec![[0.0, 0.9, 0.0], [2.5, 0.6, psi], [5.0, 0.2, psi]]).with_surface(5.5)
    } else {
        Current::linear(0.8, 0.3, dir)
    });
    s.validate().unwrap();
    assert_eq!(s.is_spatial(), spatial);
    s
}

/// Momenta (block samples) on both sides of the current's, with transverse components of both
/// signs and of different sizes.
const MOMENTA: [[f64; 3]; 4] = [
    [-3.0, 0.3, 2.2],
    [0.4, -0.4, -3.0],
    [2.2, 1.0, 0.3],
    [-0.7, 2.2, -0.4],
];

fn block<const DIM: usize>(v: &[f64; 3]) -> [f64; DIM] {
    std::array::from_fn(|d| if DIM == 3 { v[d] } else { v[d + 1] })
}

/// Every dissipative term a scene can have (still-water drag; a current, linear and tabulated),
/// summed as the solvers sum them ([`Chain::dissipative_slope`] and friends), for every pendulum
/// at momenta on both sides of the current's:
/// * ∂F/∂p (closed form) = central differences of F in each component (step 1e-5; F is
///   piecewise quadratic, so the FD error is round-off, 1e-8 relative), the block symmetric;
/// * ∂F/∂θ for each parameter the terms read (D, the current's speed, the mass) = central
///   differences of F with θ set on the model (step 1e-5·θ; 1e-7 relative), and θ they do not
///   read give 0;
/// * the closed-form implicit half step = the trait's default Newton solve ([`DefaultSolve`],
///   1e-14), and solves p − (h/2)F(p) = c;
/// * the closed-form (F, ∂F/∂p) = the trait's default `Dual<D>` evaluation (1e-15).
fn check_dissipation<D: Scalar, const DIM: usize>(scene: &Scene, expect: &[&str]) {
    let chain = Chain::<D, DIM>::from_scene(scene).unwrap();
    assert_eq!(chain.dissipation_names(), expect);
    let ctx = Ctx::new(1.0, D::from(-0.7), 0);
    let generic = DefaultSolve(chain.clone());
    let force = |ch: &Chain<D, DIM>, i, p: &[f64; DIM]| {
        ch.dissipative_force(i, &p.map(D::from), &ctx)
            .unwrap()
            .map(|x| x.re())
    };
    let params = [
        (Parameter::Drag, 10.0),
        (Parameter::CurrentSpeed, 0.8),
        (Parameter::Mass, 1.0),
    ];
    let mut exercised = 0;
    for i in 0..chain.n() {
        for p in MOMENTA.iter().map(block::<DIM>) {
            let pd = p.map(D::from);
            let (f, slope) = chain.dissipative_slope(i, &pd, &ctx).unwrap();
            // The closed-form override = the trait's `Dual<D>` default (same rounding).
            let (f2, slope2) = generic.force_and_slope(i, &pd, &ctx);
            for r in 0..DIM {
                close(
                    "F override",
                    f[r].re(),
                    f2[r].re(),
                    f2[r].re().abs().max(1.0),
                    1e-15,
                );
                for c in 0..DIM {
                    let (a, b) = (entry(&slope, r, c).re(), entry(&slope2, r, c).re());
                    close("F' override", a, b, b.abs().max(1.0), 1e-15);
                    let hp = 1e-5;
                    let (mut pp, mut pm) = (p, p);
                    pp[c] += hp;
                    pm[c] -= hp;
                    let fd = (force(&chain, i, &pp)[r] - force(&chain, i, &pm)[r]) / (2.0 * hp);
                    close(&format!("dF[{r}]/dp[{c}]"), a, fd, fd.abs().max(1.0), 1e-8);
                }
            }
            for (param, value) in params {
                let got = chain.dissipative_parameter_derivative(i, &pd, &ctx, param);
                if !chain.dissipation_has_parameter(param) {
                    assert!(got.iter().all(|g| g.re() == 0.0), "{param:?} not read");
                    continue;
                }
                if param == Parameter::Mass && !chain.has_parameter(param) {
                    continue;
                }
                let hstep = 1e-5 * value;
                let (mut cp, mut cm) = (chain.clone(), chain.clone());
                cp.set_parameter(param, D::from(value + hstep)).unwrap();
                cm.set_parameter(param, D::from(value - hstep)).unwrap();
                let (fp, fm) = (force(&cp, i, &p), force(&cm, i, &p));
                for (r, g) in got.iter().enumerate() {
                    let fd = (fp[r] - fm[r]) / (2.0 * hstep);
                    let label = format!("{expect:?} dF[{i}][{r}]/d{param:?} at p = {p:?}");
                    close(&label, g.re(), fd, fd.abs().max(1.0), 1e-7);
                    exercised += usize::from(g.re().abs() > 1e-3);
                }
            }
        }
        for scale in [-40.0, -1.0, -1e-3, 0.0, 2e-2, 3.0, 55.0] {
            for v in &MOMENTA {
                let c = block::<DIM>(v).map(|x| D::from(x * scale));
                let h = 0.01;
                let terms = chain.dissipation_count();
                let (p1, w1) = chain.dissipative_half_step(terms, i, &c, h, &ctx);
                let (p2, w2) = generic.implicit_half_step(i, &c, h, &ctx);
                let f = chain.dissipative_force(i, &p1, &ctx).unwrap();
                for r in 0..DIM {
                    let cr = c[r].re();
                    close(
                        "implicit p",
                        p1[r].re(),
                        p2[r].re(),
                        cr.abs().max(1.0),
                        1e-14,
                    );
                    for col in 0..DIM {
                        let (a, b) = (entry(&w1, r, col).re(), entry(&w2, r, col).re());
                        close("implicit W", a, b, 1.0, 1e-14);
                    }
                    let res = (p1[r] - f[r] * (0.5 * h)).re();
                    close("residual", res, cr, cr.abs().max(1.0), 1e-14);
                }
            }
        }
    }
    assert!(exercised > 0, "no parameter derivative was exercised");
}

fn check_every_dissipation<D: Scalar, const DIM: usize>() {
    let spatial = DIM == 3;
    check_dissipation::<D, DIM>(&all_terms_scene(spatial), &["drag"]);
    check_dissipation::<D, DIM>(&current_scene(spatial, false), &["current drag"]);
    check_dissipation::<D, DIM>(&current_scene(spatial, true), &["current drag"]);
    check_dissipation::<D, DIM>(&waves_scene(spatial), &["water drag"]);
}

/// The scene `s` described as a pipe: the drag constant then takes per-pendulum weights
/// (wᵢ ≠ 1 on this beam of unequal lengths and masses).
fn with_pipe(mut s: Scene) -> Scene {
    s.pipe = Some(chainbeam::scene::Pipe::new(6.0, 0.05, 0.005));
    s.validate().unwrap();
    assert!(s
        .drag_weights()
        .unwrap()
        .iter()
        .any(|w| (w - 1.0).abs() > 0.1));
    s
}

/// The bits of a value (real and derivative parts: `Debug` prints the shortest decimal that reads
/// back to the same f64, the sign of a zero included).
fn bits<D: Scalar>(x: &D) -> String {
    format!("{x:?}")
}

/// The batched forms RATTLE calls once per step ([`Chain::dissipative_half_steps`],
/// [`Chain::dissipative_half_kick`]: the terms' overrides that hoist what every block shares)
/// give **bit for bit** what the block-by-block forms give ([`Chain::dissipative_half_step`],
/// pᵢ − s gᵢ + s [`Chain::dissipative_force`]), for every term, with and without the pipe's
/// drag weights, at momenta of both signs and several sizes: the reference is the same model's
/// per-block arithmetic, so equality, not a tolerance.
fn check_batched<D: Scalar, const DIM: usize>(scene: &Scene) {
    let chain = Chain::<D, DIM>::from_scene(scene).unwrap();
    let n = chain.n();
    let terms = chain.dissipation_count();
    let ctx = Ctx::new(1.3, D::zero(), 0);
    let (h, s) = (0.01, 0.005);
    for scale in [-40.0, -1.0, 0.0, 2e-2, 3.0, 55.0] {
        let c: Vec<[D; DIM]> = (0..n)
            .map(|i| {
                block::<DIM>(&MOMENTA[i % 4]).map(|x| D::from(x * scale * (1.0 + 0.1 * i as f64)))
            })
            .collect();
        let (mut p, mut w) = (c.clone(), vec![BlockSym::zero(); n]);
        chain.dissipative_half_steps(HalfSteps::new(&c, &mut p, &mut w), h, &ctx);
        let g: Vec<[D; DIM]> = c.iter().map(|v| v.map(|x| x * 0.5 + 0.25)).collect();
        let mut a = vec![[D::zero(); DIM]; n];
        let kick = HalfKick { p: &c, g: &g, s };
        chain.dissipative_half_kick(kick, &ctx, &mut a);
        for i in 0..n {
            let (p1, w1) = chain.dissipative_half_step(terms, i, &c[i], h, &ctx);
            let f = chain.dissipative_force(i, &c[i], &ctx).unwrap();
            let b: [D; DIM] = std::array::from_fn(|d| c[i][d] - g[i][d] * s + f[d] * s);
            let at = format!("{:?} block {i} at scale {scale}", chain.dissipation_names());
            assert_eq!(p[i].map(|x| bits(&x)), p1.map(|x| bits(&x)), "p, {at}");
            assert_eq!(
                w[i].diag.map(|x| bits(&x)),
                w1.diag.map(|x| bits(&x)),
                "W, {at}"
            );
            assert_eq!(bits(&w[i].xz), bits(&w1.xz), "W_xz, {at}");
            assert_eq!(a[i].map(|x| bits(&x)), b.map(|x| bits(&x)), "kick, {at}");
        }
    }
}

fn check_every_batched<D: Scalar, const DIM: usize>() {
    let spatial = DIM == 3;
    for scene in [
        all_terms_scene(spatial),
        with_pipe(all_terms_scene(spatial)),
        current_scene(spatial, false),
        with_pipe(current_scene(spatial, false)),
        current_scene(spatial, true),
        waves_scene(spatial),
    ] {
        check_batched::<D, DIM>(&scene);
    }
}

#[test]
fn batched_dissipation_is_block_by_block_bit_for_bit() {
    check_every_batched::<f64, 2>();
    check_every_batched::<f64, 3>();
    check_every_batched::<Dual64, 2>();
    check_every_batched::<Dual64, 3>();
}

#[test]
fn every_dissipative_term_planar_f64() {
    check_every_dissipation::<f64, 2>();
}

#[test]
fn every_dissipative_term_spatial_f64() {
    check_every_dissipation::<f64, 3>();
}

#[test]
fn every_dissipative_term_planar_dual64() {
    check_every_dissipation::<Dual64, 2>();
}

#[test]
fn every_dissipative_term_spatial_dual64() {
    check_every_dissipation::<Dual64, 3>();
}

/// The thesis scenes still build their terms from the catalogue (a smoke check that `visit_terms`
/// lists exactly the terms a scene has: no gravity and no drag on the thesis riser).
#[test]
fn terms_present_are_the_scene_s() {
    struct Names(Vec<&'static str>);
    impl TermVisitor<f64, 2> for Names {
        fn visit<T: ForceTerm<f64, 2>>(&mut self, t: &T) -> chainbeam::Result<()> {
            self.0.push(t.name());
            Ok(())
        }
    }
    let chain = Chain::<f64, 2>::from_scene(&catalogue::riser(5)).unwrap();
    let mut names = Names(Vec::new());
    chain.visit_terms(&mut names).unwrap();
    assert_eq!(names.0, ["springs", "point loads", "control"]);
    assert!(chain.drag().is_none());
}

/// The reaction-force tip drive (eq. 3.2.1/3.2.2) is linear in (ζ_k, v_k, u_k, u_{k+1}); its
/// hand-written transpose `ReactionTip::reverse` must equal the Dual64 derivatives of the forward
/// map `first_half` ∘ `second_half` contracted with the cotangent (ζ̄, v̄), including the
/// derivative in 1/m_n, to 1e-12.
#[test]
fn reaction_tip_reverse_is_the_transposed_dual_jacobian() {
    use chainbeam::model::ReactionTip;
    let (h, inv_m, bar) = (0.01, 1.0 / 1.7, [0.37, -1.9]);
    let x = [0.12, -0.4, 2.5, -3.1]; // ζ_k, v_k, u_k, u_{k+1}
    let tip = ReactionTip {
        inv_tip_mass: inv_m,
    };
    let rev = tip.reverse(bar, (x[2], x[3]), h);
    let got = [
        rev.target[0],
        rev.target[1],
        rev.controls.0,
        rev.controls.1,
        rev.inv_tip_mass,
    ];
    for (j, got) in got.iter().enumerate() {
        let seed = |i: usize, v: f64| Dual64::new(v, if i == j { 1.0 } else { 0.0 });
        let tip = ReactionTip {
            inv_tip_mass: seed(4, inv_m),
        };
        let xd: Vec<Dual64> = x.iter().enumerate().map(|(i, &v)| seed(i, v)).collect();
        let (zeta, v_half) = tip.first_half([xd[0], xd[1]], xd[2], h);
        let v = tip.second_half(v_half, xd[3], h);
        let want = bar[0] * zeta.eps + bar[1] * v.eps;
        assert!(
            (got - want).abs() <= 1e-12 * want.abs().max(1.0),
            "direction {j}: reverse {got} vs dual {want}"
        );
    }
}

/// The closed-form (F, ∂F/∂p) of the still-water drag and of the current's drag also carry the
/// derivative parts of a dual p (the forward-over-reverse Hessians of `ocp` differentiate the
/// slope): with p = p₀ + ε e_s (each component s in turn), the override's ε-parts equal the
/// trait default's (its `Dual<D>` evaluation, [`DefaultSolve`]) to 1e-15, and F's ε-part is
/// column s of the slope itself.
#[test]
fn drag_slope_overrides_carry_derivatives() {
    let scenes = [
        (all_terms_scene(false), "drag"),
        (current_scene(false, false), "current drag"),
        (current_scene(false, true), "current drag"),
    ];
    for (scene, name) in scenes {
        let chain = Chain::<Dual64, 2>::from_scene(&scene).unwrap();
        assert_eq!(chain.dissipation_names(), [name]);
        let generic = DefaultSolve(chain.clone());
        let ctx = Ctx::new(1.0, Dual64::from(-0.7), 0);
        for i in 0..chain.n() {
            for p in MOMENTA.iter().map(block::<2>) {
                for s in 0..2 {
                    let x: [Dual64; 2] =
                        std::array::from_fn(|d| Dual64::new(p[d], if d == s { 1.0 } else { 0.0 }));
                    let (f, j) = chain.dissipative_slope(i, &x, &ctx).unwrap();
                    let (f2, j2) = generic.force_and_slope(i, &x, &ctx);
                    for r in 0..2 {
                        close(
                            "F eps",
                            f[r].eps,
                            f2[r].eps,
                            f2[r].eps.abs().max(1.0),
                            1e-15,
                        );
                        let (a, b) = (entry(&j, r, r).eps, entry(&j2, r, r).eps);
                        close("F' eps", a, b, b.abs().max(1.0), 1e-15);
                        let col = entry(&j, r, s).re;
                        close("F eps = F'", f[r].eps, col, col.abs().max(1.0), 1e-15);
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Joint damping: the coupled dissipative term F = −Gᵀ C G q̇ (docs/conventions.md
// "Joint damping"), checked like every term against its own definition.

/// [`current_scene`] (a current and the drag relative to it, 6 pendulums, riser support) with
/// joint dampers at every spring (joints 1..=7, a different c at each: the array form).
fn damped_scene(spatial: bool) -> Scene {
    let mut s = current_scene(spatial, false);
    s.beam.joint_damping = vec![3.0, 1.5, 2.5, 0.7, 1.1, 2.0, 4.0];
    s.validate().unwrap();
    s
}

/// The same with one damper value at every joint and equal masses (so that
/// [`Parameter::JointDamping`], the dampers' common value, and [`Parameter::Mass`] are defined).
fn uniform_damped_scene(spatial: bool) -> Scene {
    let mut s = current_scene(spatial, false);
    s.beam.joint_damping = vec![2.0; 7];
    s.beam.masses = vec![1.2; 6];
    s.validate().unwrap();
    s
}

/// For the joint damping in both dimensions and scalars (references in brackets):
/// * F is linear in q̇ with a symmetric, negative semidefinite ∂F/∂q̇: ⟨w, F(q, v)⟩ =
///   ⟨v, F(q, w)⟩ and v·F(q, v) = −Σ c|θ̇|² ≤ 0 [Rayleigh's dissipation function; 1e-12];
/// * Fᵢ ⊥ qᵢ (a torque turns a pendulum, it does not stretch it) [1e-13];
/// * the closed-form ∇_q(w·F) = the trait's dual-number default [1e-12] = central differences
///   of w·F in q [1e-6];
/// * w·∂F/∂c (dual seed) and w·∂F/∂m (−w·F/m at fixed p) = central differences with c, m set
///   on the model [1e-7].
fn check_joint_damping<D: Scalar, const DIM: usize>() {
    let spatial = DIM == 3;
    let chain = Chain::<D, DIM>::from_scene(&uniform_damped_scene(spatial)).unwrap();
    assert_eq!(chain.coupled_dissipation_names(), ["joint damping"]);
    assert_eq!(chain.dissipation_names(), ["current drag"]);
    let n = chain.n();
    let q: Vec<[D; DIM]> = lift(&attitudes::<DIM>(n));
    let v: Vec<[D; DIM]> = lift(&vectors::<DIM>(n, 0.3));
    let w: Vec<[D; DIM]> = lift(&vectors::<DIM>(n, 1.9));
    let ctx = Ctx::new(1.0, D::zero(), 0);
    let force = |ch: &Chain<D, DIM>, q: &[[D; DIM]], v: &[[D; DIM]]| {
        let mut f = vec![[D::zero(); DIM]; n];
        ch.coupled_force(q, v, &ctx, &mut f);
        f
    };
    let fv = force(&chain, &q, &v);
    let fw = force(&chain, &q, &w);
    let (a, b) = (inner(&w, &fv).re(), inner(&v, &fw).re());
    close("⟨w, F(v)⟩ = ⟨v, F(w)⟩", a, b, a.abs().max(1.0), 1e-12);
    let power = inner(&v, &fv).re();
    let jd = chain.joint_damping().unwrap();
    let dissipated = jd.dissipated_power(&q, &v).re();
    assert!(power < 0.0, "dissipative: {power}");
    close("v·F = −Σ c θ̇²", -power, dissipated, dissipated, 1e-12);
    for (fi, qi) in fv.iter().zip(&q) {
        let along: f64 = (0..DIM).map(|d| (fi[d] * qi[d]).re()).sum();
        assert!(along.abs() <= 1e-13 * max_abs(&fv), "F ⊥ q: {along}");
    }
    // ∇_q(w·F): closed form, dual default, central differences.
    let mut closed = vec![[D::zero(); DIM]; n];
    let mut scratch = DualScratch::new(n);
    let at = CoupledAt {
        q: &q,
        v: &v,
        w: &w,
    };
    chain.coupled_force_q_vjp(at, &ctx, D::one(), &mut closed, &mut scratch);
    let mut dual = vec![[D::zero(); DIM]; n];
    DefaultVjp(jd.clone()).force_q_vjp(at, &ctx, D::one(), &mut dual, &mut scratch);
    let scale = max_abs(&dual);
    assert!(scale > 1e-3, "exercised");
    for i in 0..n {
        for d in 0..DIM {
            let (c, g) = (closed[i][d].re(), dual[i][d].re());
            close("∇_q(w·F) closed = dual", c, g, scale, 1e-12);
            let hq = 1e-6;
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i][d] += D::from(hq);
            qm[i][d] -= D::from(hq);
            let fd = (inner(&w, &force(&chain, &qp, &v)) - inner(&w, &force(&chain, &qm, &v))).re()
                / (2.0 * hq);
            close("∇_q(w·F) = FD", c, fd, scale, 1e-6);
        }
    }
    // Parameters: the dampers' common value and the (uniform) mass, at fixed p = M v.
    let mut p = vec![[D::zero(); DIM]; n];
    chain.apply_mass(&v, &mut p);
    let wf_at = |ch: &Chain<D, DIM>| {
        let mut vv = vec![[D::zero(); DIM]; n];
        ch.apply_inverse_mass(&p, &mut vv);
        inner(&w, &force(ch, &q, &vv)).re()
    };
    for (param, value) in [(Parameter::JointDamping, 2.0), (Parameter::Mass, 1.2)] {
        assert!(chain.coupled_has_parameter(param) && chain.has_parameter(param));
        let got = chain
            .coupled_parameter_contraction(at, &ctx, param, &mut scratch)
            .re();
        let hstep = 1e-5 * value;
        let (mut cp, mut cm) = (chain.clone(), chain.clone());
        cp.set_parameter(param, D::from(value + hstep)).unwrap();
        cm.set_parameter(param, D::from(value - hstep)).unwrap();
        let fd = (wf_at(&cp) - wf_at(&cm)) / (2.0 * hstep);
        assert!(fd.abs() > 1e-3, "{param:?} exercised");
        close(&format!("w·∂F/∂{param:?}"), got, fd, fd.abs(), 1e-7);
    }
    assert!(!chain.coupled_has_parameter(Parameter::Drag));
    // The array form: dampers differ, so their common value is no parameter.
    let varied = Chain::<D, DIM>::from_scene(&damped_scene(spatial)).unwrap();
    assert!(!varied.has_parameter(Parameter::JointDamping));
}

/// The trait's dual-number default of ∇_q(w·F), for comparison with the closed form.
#[derive(Clone, Debug)]
struct DefaultVjp<D>(chainbeam::model::JointDamping<D>);

impl<D: Scalar, const DIM: usize> CoupledDissipativeTerm<D, DIM> for DefaultVjp<D> {
    fn name(&self) -> &'static str {
        "default"
    }
    fn force<E: Embed<D>>(
        &self,
        q: &[[E; DIM]],
        v: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) {
        CoupledDissipativeTerm::<D, DIM>::force(&self.0, q, v, ctx, out);
    }
    fn has_parameter(&self, p: Parameter) -> bool {
        CoupledDissipativeTerm::<D, DIM>::has_parameter(&self.0, p)
    }
}

#[test]
fn joint_damping_term_planar_f64() {
    check_joint_damping::<f64, 2>();
}

#[test]
fn joint_damping_term_spatial_f64() {
    check_joint_damping::<f64, 3>();
}

#[test]
fn joint_damping_term_planar_dual64() {
    check_joint_damping::<Dual64, 2>();
}

#[test]
fn joint_damping_term_spatial_dual64() {
    check_joint_damping::<Dual64, 3>();
}

/// Joint damping beside the drag in a current, planar and spatial (current at (0.6, 0.8)), with
/// every conservative term of [`all_terms_scene`] and a per-step control at node 4: the adjoint's gradient of J = Σ M₀² (a) along a direction
/// d of the controls and (b) with respect to the dampers' common value c, the drag D, the
/// current's speed and the mass = forward-mode Dual64 of the same discrete map (1e-12 relative)
/// = central differences (five-point, 1e-6).
#[test]
fn joint_damping_gradients_beside_drag_in_a_current() {
    for spatial in [false, true] {
        let mut s = uniform_damped_scene(spatial);
        s.objective = Some(chainbeam::ObjectiveKind::Sum);
        s.time.step = 0.01;
        s.time.steps = 30;
        s.validate().unwrap();
        if spatial {
            damped_gradients::<3>(&s);
        } else {
            damped_gradients::<2>(&s);
        }
    }
}

fn damped_gradients<const DIM: usize>(scene: &Scene) {
    use chainbeam::adjoint::{adjoint_gradient, forward_value};
    use chainbeam::{BendingObjective, Checkpointing};
    let (h, steps) = (scene.time.step, scene.time.steps);
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let u: Vec<f64> = (0..=steps)
        .map(|k| -0.4 + 0.3 * (0.37 * k as f64).sin())
        .collect();
    let obj = BendingObjective::summed_moment();
    let params = [
        (Parameter::JointDamping, 2.0),
        (Parameter::Drag, 10.0),
        (Parameter::CurrentSpeed, 0.8),
        (Parameter::Mass, chain.masses()[0]),
    ];
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adj = adjoint_gradient(&chain, h, steps, &u, &obj, &ps, Checkpointing::default()).unwrap();
    let value = |ch: &Chain<f64, DIM>, u: &[f64]| forward_value(ch, h, steps, u, &obj).unwrap();
    let five_point = |f: &dyn Fn(f64) -> f64, d: f64| gradient_check::five_point(f, 0.0, d);
    // (a) the controls, along d.
    let dir: Vec<f64> = (0..=steps).map(|k| (1.3 * k as f64).cos()).collect();
    let g_adj: f64 = adj
        .control_gradient
        .iter()
        .zip(&dir)
        .map(|(g, d)| g * d)
        .sum();
    let ud: Vec<Dual64> = u
        .iter()
        .zip(&dir)
        .map(|(&x, &d)| Dual64::new(x, d))
        .collect();
    let g_fwd = forward_value(&chain.lift::<Dual64>(), h, steps, &ud, &obj)
        .unwrap()
        .eps;
    let shifted = |e: f64| {
        let v: Vec<f64> = u.iter().zip(&dir).map(|(x, d)| x + e * d).collect();
        value(&chain, &v)
    };
    let g_fd = five_point(&shifted, 1e-3);
    println!("DIM {DIM}:");
    gradient_check::assert_derivative("u·d", g_adj, g_fwd, g_fd);
    // (b) the parameters.
    let ud: Vec<Dual64> = u.iter().map(|&x| Dual64::from(x)).collect();
    for (i, &(p, at)) in params.iter().enumerate() {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(p, Dual64::new(at, 1.0)).unwrap();
        let fwd = forward_value(&ch, h, steps, &ud, &obj).unwrap().eps;
        let moved = |e: f64| {
            let mut ch = chain.clone();
            ch.set_parameter(p, at + e).unwrap();
            value(&ch, &u)
        };
        let fd = five_point(&moved, 1e-3 * at);
        let a = adj.parameter_gradient[i];
        println!(
            "DIM {DIM}: dJ/d{p:?} = {fwd:.12e}: adjoint {:.1e}, FD {:.1e} (relative)",
            ((a - fwd) / fwd).abs(),
            ((fd - fwd) / fwd).abs()
        );
        assert!(fwd.abs() > 1e-10, "{p:?} is exercised");
        let label = format!("DIM {DIM}: dJ/d{p:?}");
        let dual = "forward-mode Dual64";
        gradient_check::assert_close(&label, &[a], &[fwd], dual, Tolerance::relative(1e-12));
        let fd_label = format!("{label}, five-point central difference");
        gradient_check::assert_close(&fd_label, &[fd], &[fwd], dual, Tolerance::relative(1e-6));
    }
}

/// `joint_damping = 0` (every damper zero) builds no term, and the trajectory (RATTLE, drag in a
/// current, every conservative term) is the one without the key, bit for bit; the statics of a
/// damped scene are those of the undamped one bit for bit (F_J = 0 at rest).
#[test]
fn zero_joint_damping_changes_nothing() {
    for spatial in [false, true] {
        let mut without = current_scene(spatial, false);
        without.time.step = 0.01;
        without.time.steps = 60;
        let mut zero = without.clone();
        zero.beam.joint_damping = vec![0.0; 7];
        zero.validate().unwrap();
        assert!(Chain::<f64, 3>::from_scene(&zero)
            .unwrap()
            .joint_damping()
            .is_none());
        let (a, b) = (
            chainbeam::simulate(&without).unwrap(),
            chainbeam::simulate(&zero).unwrap(),
        );
        for k in [1, 30, 60] {
            assert_eq!(a.positions(k), b.positions(k), "step {k}");
        }
        let mut damped = without.clone();
        damped.beam.joint_damping = vec![2.0; 7];
        let (sa, sd) = (
            chainbeam::statics::static_equilibrium(&without).unwrap(),
            chainbeam::statics::static_equilibrium(&damped).unwrap(),
        );
        assert_eq!(format!("{sa:?}"), format!("{sd:?}"), "statics at rest");
    }
}

/// Bad `[beam] joint_damping` values are refused with a typed error naming the key: negative,
/// NaN (as `nan` in TOML), an array of the wrong length, a damper at the free tip of a
/// cantilever (no spring there).
#[test]
fn bad_joint_damping_is_refused() {
    let text = |c: &str| {
        format!(
            "[beam]\npendulums = 4\nlength = 1.0\nmass = 1.0\nstiffness = 1000.0\n\
             support = \"cantilever\"\njoint_damping = {c}\n\
             [time]\nstep = 0.01\nsteps = 10\n"
        )
    };
    let good = Scene::from_toml_str(&text("1.5")).unwrap();
    assert_eq!(good.beam.joint_damping, [1.5, 1.5, 1.5, 1.5, 0.0]);
    let good = Scene::from_toml_str(&text("[1.0, 2.0, 3.0, 4.0, 0.0]")).unwrap();
    assert_eq!(good.beam.joint_damping, [1.0, 2.0, 3.0, 4.0, 0.0]);
    let back = Scene::from_toml_str(&good.to_toml_string()).unwrap();
    assert_eq!(
        back.beam.joint_damping, good.beam.joint_damping,
        "round trip"
    );
    for (bad, what) in [
        ("-1.0", "negative"),
        ("nan", "NaN"),
        ("[1.0, 2.0, 3.0]", "wrong length"),
        ("[1.0, 2.0, 3.0, 4.0, 5.0]", "damper at the free tip"),
        ("[1.0, -2.0, 3.0, 4.0, 0.0]", "one negative"),
    ] {
        let e = Scene::from_toml_str(&text(bad)).expect_err(what);
        let key = e.key().unwrap_or_default();
        println!("{what}: {e}");
        assert!(key.starts_with("beam.joint_damping"), "{what}: key {key:?}");
        assert!(
            matches!(
                e.kind,
                chainbeam::scene::SceneErrorKind::InvalidValue { .. }
                    | chainbeam::scene::SceneErrorKind::WrongCount { .. }
            ),
            "{what}: {e:?}"
        );
    }
}

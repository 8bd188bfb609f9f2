//! The loads a riser really sees: vector loads in the transverse plane,
//! harmonic loads and time series, the choice of the planar or spatial model, the gradients with
//! respect to the load parameters, and bad input.
//!
//! References: the rotational symmetry of the model about the beam's axis y (springs, length
//! constraints and masses depend only on angles and lengths, so a load turned by α in the xz-plane
//! turns the exact discrete trajectory by α: to round-off, 1e-12); the planar model, which the
//! spatial one must reproduce for loads in the yz-plane (1e-12); the closed form of the harmonic
//! sampled on the grid (the series interpolates it exactly there, 1e-12) and the second order of
//! linear interpolation between coarser samples; forward-mode dual numbers through the same
//! simulation for the adjoint's load-parameter gradients (1e-12 relative) and central finite
//! differences (1e-6 relative).
//!
//! The still-water drag of thesis eq. 2.4.4 acts per momentum component, so it is not rotation
//! invariant; gravity acts along z. The symmetry tests therefore run without either.

use std::f64::consts::{FRAC_PI_4, TAU};
use std::path::Path;

use chainbeam::adjoint::forward_value;
use chainbeam::*;
use num_dual::Dual64;

use crate::gradient_check;

const H: f64 = 0.01;

/// A conservative riser (thesis §3.3.1: n = 10, l = 1 m, m = 1 kg, k = 1000, k₁ = k₁₁ = 2000),
/// h = 0.01 s, N = `steps`, without loads.
fn riser(steps: usize) -> SceneBuilder {
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .step(H)
        .steps(steps)
}

/// Two harmonics of periods short enough to act within a few hundred steps.
fn harmonics() -> Vec<Harmonic> {
    vec![
        Harmonic {
            amplitude: 1.5,
            period: 0.9,
            phase: 0.3,
        },
        Harmonic {
            amplitude: 0.6,
            period: 0.37,
            phase: -2.0,
        },
    ]
}

/// Rows (t, 0, f(t)) of a load history along z, every 0.05 s over [0, 5] s.
fn rows_z() -> Vec<[f64; 3]> {
    (0..=100)
        .map(|i| {
            let t = i as f64 / 20.0;
            [t, 0.0, 1.2 * (3.1 * t).sin() - 0.4 * (7.3 * t + 1.0).cos()]
        })
        .collect()
}

/// Every kind of load, each turned by α from z toward x in the transverse plane: a constant
/// 2 N at node 5, a windowed −1 N at the tip, two ramped harmonics at node 8, a series at node 3.
fn loads_turned_by(b: SceneBuilder, alpha: f64) -> SceneBuilder {
    let (s, c) = alpha.sin_cos();
    let turn = |f: f64| [f * s, f * c];
    let rows = rows_z()
        .into_iter()
        .map(|[t, _, f]| [t, f * s, f * c])
        .collect();
    b.point_load_vector(5, turn(2.0))
        .load(PointLoad::vector(10, turn(-1.0)).window(0.4, Some(1.7)))
        .load(PointLoad::harmonic(8, [s, c], harmonics()).ramped(0.5))
        .load(PointLoad::series(3, LoadSeries::new("rows", rows).unwrap()))
}

/// The trajectory of `scene` in the model of dimension DIM, with the scene's controls.
fn run<const DIM: usize>(scene: &Scene) -> Trajectory<f64, DIM> {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    simulate_chain(
        chain,
        scene.time.step,
        scene.time.steps,
        &scene_controls(scene),
    )
    .unwrap()
}

/// max over k and nodes of |r_a − r_b| (componentwise).
fn max_position_difference(
    a: &impl Fn(usize) -> Vec<[f64; 3]>,
    b: &impl Fn(usize) -> Vec<[f64; 3]>,
    steps: usize,
) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..=steps {
        for (ra, rb) in a(k).iter().zip(b(k)) {
            for d in 0..3 {
                worst = worst.max((ra[d] - rb[d]).abs());
            }
        }
    }
    worst
}

#[test]
fn scalar_force_is_the_z_component_and_planar() {
    let text = |force: &str| {
        format!(
            "[beam]\npendulums = 3\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
             support = \"cantilever\"\n[[loads.point]]\nnode = 3\nforce = {force}\n\
             [time]\nstep = 0.01\nsteps = 5\n"
        )
    };
    let a = Scene::from_toml_str(&text("2.0")).unwrap();
    let b = Scene::from_toml_str(&text("[0.0, 2.0]")).unwrap();
    assert_eq!(a, b);
    assert!(!a.is_spatial());
    assert!(!simulate(&a).unwrap().is_spatial());
    let c = Scene::from_toml_str(&text("[0.5, 2.0]")).unwrap();
    assert!(c.is_spatial());
    assert_eq!(c.spatial_key().as_deref(), Some("loads.point[0].force"));
    assert_eq!(
        (c.loads.points[0].force_x, c.loads.points[0].force),
        (0.5, 2.0)
    );
    let traj = simulate(&c).unwrap();
    assert!(traj.is_spatial() && traj.dim() == 3);
    // F_x > 0 pushes toward −x, as F_z > 0 pushes toward −z (docs/scene-format.md)
    let tip = traj.positions(5)[2];
    assert!(tip[0] < 0.0 && tip[2] < 0.0, "tip {tip:?}");
}

/// A load turned by α about y turns the whole trajectory by α: r = (z_ref sin α, y_ref,
/// z_ref cos α) with (0, y_ref, z_ref) the planar trajectory of the untouched loads.
#[test]
fn rotated_loads_rotate_the_trajectory() {
    let steps = 300;
    let reference = loads_turned_by(riser(steps), 0.0).build().unwrap();
    assert!(!reference.is_spatial());
    let planar = run::<2>(&reference);
    let tip_z = planar.positions(steps)[9][2];
    assert!(tip_z.abs() > 1e-3, "the loads move the tip: {tip_z}");
    for deg in [30.0f64, 45.0, 135.0, 250.0] {
        let alpha = deg.to_radians();
        let scene = loads_turned_by(riser(steps), alpha).build().unwrap();
        assert!(scene.is_spatial());
        let traj = simulate(&scene).unwrap();
        let Some(spatial) = traj.as_spatial() else {
            panic!("{deg}°: the spatial model must run")
        };
        let (s, c) = alpha.sin_cos();
        let turned = |k: usize| {
            planar
                .positions(k)
                .into_iter()
                .map(|[_, y, z]| [z * s, y, z * c])
                .collect::<Vec<_>>()
        };
        let err = max_position_difference(&|k| spatial.positions(k), &turned, steps);
        println!("α = {deg}°: max |r − R(α) r_ref| = {err:.2e}");
        assert!(err <= 1e-12, "{deg}°: {err:e}");
    }
}

/// The catalogue's oblique riser (F = 2 N at 45° between x and z) deflects as far as the in-plane
/// riser with F = 2 N along z, in the 45° direction.
#[test]
fn load_at_45_degrees_deflects_as_far_as_in_plane() {
    let oblique = catalogue::oblique_riser();
    let steps = oblique.time.steps;
    let in_plane = riser(steps).point_load(5, 2.0).build().unwrap();
    let (a, b) = (simulate(&oblique).unwrap(), simulate(&in_plane).unwrap());
    assert!(a.is_spatial() && !b.is_spatial());
    let mut worst: f64 = 0.0;
    let mut largest: f64 = 0.0;
    for k in 0..=steps {
        for (r, r0) in a.positions(k).iter().zip(b.positions(k)) {
            let magnitude = r[0].hypot(r[2]);
            worst = worst
                .max((magnitude - r0[2].abs()).abs())
                .max((r[0] - r[2]).abs()) // along the 45° direction
                .max((r[1] - r0[1]).abs());
            largest = largest.max(r0[2].abs());
        }
    }
    println!("45°: max deviation {worst:.2e} (largest deflection {largest:.3} m)");
    assert!(largest > 0.01);
    assert!(worst <= 1e-12, "{worst:e}");
    // the deflection is along −(1, 1)/√2: the load's direction, thesis sign
    let tip = a.positions(steps / 4)[9];
    assert!(tip[0] < 0.0 && tip[2] < 0.0, "tip {tip:?}");
    assert!((tip[0].atan2(tip[2]) + 3.0 * FRAC_PI_4).abs() < 1e-12);
}

/// Loads in the yz-plane of every kind, with gravity, drag and a control, give the same motion in
/// the spatial model as in the planar one (x stays 0).
#[test]
fn planar_scene_in_the_spatial_model_equals_the_planar_model() {
    let steps = 300;
    let scene = loads_turned_by(riser(steps), 0.0)
        .gravity(9.81)
        .drag(10.0)
        .control_per_step(
            7,
            (0..=steps).map(|k| 0.5 * (k as f64 * 0.03).cos()).collect(),
        )
        .build()
        .unwrap();
    let (p, s) = (run::<2>(&scene), run::<3>(&scene));
    let err = max_position_difference(&|k| p.positions(k), &|k| s.positions(k), steps);
    let moment: f64 = p
        .moment
        .iter()
        .zip(&s.moment)
        .fold(0.0, |m, (a, b)| m.max((a - b).abs()));
    println!("planar vs spatial: positions {err:.2e}, M₀ {moment:.2e}");
    assert!(
        err <= 1e-12 && moment <= 1e-12 * 2000.0,
        "{err:e} {moment:e}"
    );
    assert!(p.positions(steps)[9][2].abs() > 1e-3);
}

/// f(t) = ρ(t) Σ Aⱼ sin(2π t/Tⱼ + φⱼ) of [`harmonics`] with a ramp of 0.5 s: the closed form the
/// model's harmonic load implements.
fn harmonic_value(t: f64) -> f64 {
    let ramp = if t < 0.5 {
        0.5 * (1.0 - (std::f64::consts::PI * t / 0.5).cos())
    } else {
        1.0
    };
    ramp * harmonics()
        .iter()
        .map(|h| h.amplitude * (h.phase + TAU * t / h.period).sin())
        .sum::<f64>()
}

/// The harmonic load and a series sampled from it at every grid time give the same trajectory;
/// sampled coarser, the difference falls like Δt² (linear interpolation).
#[test]
fn series_sampled_from_the_harmonic_reproduces_it() {
    let steps = 200;
    for (dir, label) in [([0.0, 1.0], "planar"), ([0.6, 0.8], "spatial")] {
        let wave = riser(steps)
            .load(PointLoad::harmonic(6, dir, harmonics()).ramped(0.5))
            .build()
            .unwrap();
        let sampled = |every: usize| {
            let rows = (0..=steps.div_ceil(every))
                .map(|i| {
                    let t = (i * every) as f64 * H;
                    let f = harmonic_value(t);
                    [t, dir[0] * f, dir[1] * f]
                })
                .collect();
            riser(steps)
                .load(PointLoad::series(
                    6,
                    LoadSeries::new("sampled", rows).unwrap(),
                ))
                .build()
                .unwrap()
        };
        let reference = simulate(&wave).unwrap();
        assert_eq!(reference.is_spatial(), label == "spatial");
        let error = |every: usize| {
            let t = simulate(&sampled(every)).unwrap();
            max_position_difference(&|k| reference.positions(k), &|k| t.positions(k), steps)
        };
        let exact = error(1);
        let (e4, e8) = (error(4), error(8));
        println!("{label}: grid samples {exact:.2e}; every 4 steps {e4:.2e}, every 8 {e8:.2e}");
        assert!(exact <= 1e-12, "{label}: {exact:e}");
        // second order: halving Δt divides the error by 4 (observed 4.0 ± 0.2)
        assert!(
            (3.5..=4.5).contains(&(e8 / e4)),
            "{label}: ratio {}",
            e8 / e4
        );
    }
}

/// A short planar wave scene for the gradients: two ramped harmonics at node 6 and a constant
/// load at node 3, control constant at the tip, c_sum = Σ M₀².
fn gradient_scene(direction: [f64; 2], force: [f64; 2]) -> Scene {
    riser(40)
        .load(PointLoad::harmonic(6, direction, harmonics()).ramped(0.1))
        .point_load_vector(3, force)
        .control_constant(10, -0.4)
        .objective(ObjectiveKind::Sum)
        .build()
        .unwrap()
}

/// The five-point central difference (8(J(v+δ) − J(v−δ)) − (J(v+2δ) − J(v−2δ)))/(12δ) with
/// δ = 1e-3·max(|v|, 1): truncation error O(δ⁴), rounding error ~1e-16·|J|/δ, so it resolves
/// derivatives far smaller than J (∂J/∂F_x is 1e-5 of J here, since M₀ measures z only).
fn central_difference(j: &dyn Fn(f64) -> f64, v: f64) -> f64 {
    gradient_check::five_point(j, v, central_difference_step(v))
}

/// The step of [`central_difference`] at v: 10⁻³ of |v|, at least 10⁻³.
fn central_difference_step(v: f64) -> f64 {
    1e-3 * v.abs().max(1.0)
}

fn load_parameters() -> Vec<(Parameter, f64)> {
    let mut v = Vec::new();
    for (j, h) in harmonics().iter().enumerate() {
        v.push((
            Parameter::LoadAmplitude {
                load: 0,
                harmonic: j,
            },
            h.amplitude,
        ));
        v.push((
            Parameter::LoadPhase {
                load: 0,
                harmonic: j,
            },
            h.phase,
        ));
    }
    v
}

/// ∂J/∂A and ∂J/∂φ of the harmonics (and ∂J/∂F of the constant load): the adjoint
/// (`ControlProblem::parameter_gradient`) = forward-mode Dual64 (1e-12) = central differences
/// ([`central_difference`], 1e-6).
#[test]
fn load_parameter_gradients_planar() {
    let scene = gradient_scene([0.0, 1.0], [0.0, 1.1]);
    let problem = ControlProblem::builder(&scene).build_in::<2>().unwrap();
    let mut params = load_parameters();
    params.push((Parameter::LoadForce(1), 1.1));
    let theta = [-0.4];
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adjoint = problem.parameter_gradient(&theta, &ps).unwrap();
    let u: Vec<Dual64> = problem
        .controls(&theta)
        .unwrap()
        .into_iter()
        .map(Dual64::from)
        .collect();
    let obj = BendingObjective::summed_moment();
    for (i, &(p, value)) in params.iter().enumerate() {
        let mut ch = problem.chain_as::<Dual64>();
        ch.set_parameter(p, Dual64::new(value, 1.0)).unwrap();
        let fwd = forward_value(&ch, H, 40, &u, &obj).unwrap().eps;
        let at = |v: f64| {
            let mut ch = problem.chain().clone();
            ch.set_parameter(p, v).unwrap();
            let u: Vec<f64> = u.iter().map(|x| x.re).collect();
            forward_value(&ch, H, 40, &u, &obj).unwrap()
        };
        let fd = central_difference(&at, value);
        gradient_check::assert_derivative(&format!("{p:?}"), adjoint[i], fwd, fd);
    }
}

/// The same in the spatial model (harmonics along (0.6, 0.8), a constant load with an x
/// component, and ∂J/∂F_x), by `adjoint_gradient` on `Chain<_, 3>`
/// ([`gradient_check::check_parameters`]).
#[test]
fn load_parameter_gradients_spatial() {
    let scene = gradient_scene([0.6, 0.8], [0.7, 1.1]);
    assert!(scene.is_spatial());
    assert!(matches!(
        ControlProblem::builder(&scene).build_in::<2>(),
        Err(Error::NeedsSpatialModel { .. })
    ));
    let mut params = load_parameters();
    params.push((Parameter::LoadForce(1), 1.1));
    params.push((Parameter::LoadForceX(1), 0.7));
    let chain = Chain::<f64, 3>::from_scene(&scene).unwrap();
    let u = scene_controls(&scene);
    gradient_check::check_parameters(&chain, &u, &params, (H, 40), central_difference_step);
    // F_x is not a parameter of the planar model of a planar scene
    let planar = Chain::<f64, 2>::from_scene(&gradient_scene([0.0, 1.0], [0.0, 1.1])).unwrap();
    assert!(!planar.has_parameter(Parameter::LoadForceX(1)));
    assert!(planar.has_parameter(Parameter::LoadPhase {
        load: 0,
        harmonic: 1
    }));
    assert!(!planar.has_parameter(Parameter::LoadPhase {
        load: 0,
        harmonic: 2
    }));
}

/// The planar model refuses a spatial scene, naming the key with the x component; `simulate`
/// and the statics run it in the spatial model (tests/model/statics_spatial.rs).
#[test]
fn planar_model_refuses_a_spatial_scene() {
    let scene = catalogue::wave_series();
    assert!(scene.is_spatial());
    let err = Chain::<f64, 2>::from_scene(&scene).unwrap_err();
    assert_eq!(
        err,
        Error::NeedsSpatialModel {
            key: "loads.point[0].series".into()
        }
    );
    let msg = err.to_string();
    assert!(
        msg.contains("`loads.point[0].series` has an x component"),
        "{msg}"
    );
    assert!(msg.contains("spatial model"), "{msg}");
    let oblique = catalogue::oblique_riser();
    let stat = statics::static_equilibrium(&oblique).unwrap();
    assert!(stat.spatial && stat.positions_x[9] != 0.0);
    assert!(simulate(&oblique).unwrap().into_planar().is_err());
}

// ---------------------------------------------------------------------------------------------
// Scene files: the new keys, round trips and bad input
// ---------------------------------------------------------------------------------------------

const BEAM: &str = "[beam]\npendulums = 4\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
                    support = \"cantilever\"\n[time]\nstep = 0.01\nsteps = 10\n";

/// A scene file with `loads` in a temporary directory, with the files `extra` beside it.
fn scene_file(loads: &str, extra: &[(&str, &str)]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in extra {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, format!("{BEAM}{loads}")).unwrap();
    (dir, path)
}

#[test]
fn every_new_key_parses_and_round_trips() {
    let loads = "[[loads.point]]\nnode = 2\nforce = [0.5, -1.0]\nstart = 0.01\nend = 0.08\n\
                 ramp = 0.03\ndirection = [1.0, 1.0]\nseries = \"f.csv\"\n\
                 [[loads.point.harmonic]]\namplitude = 2.0\nperiod = 0.05\nphase = 0.4\n\
                 [[loads.point.harmonic]]\namplitude = -0.5\nperiod = 0.02\n";
    let csv = "# a comment\nt, fx, fz\n0, 0, 1\n\n0.05, 1.5, -2\n0.1,0,0\n";
    let (dir, path) = scene_file(loads, &[("f.csv", csv)]);
    let scene = Scene::from_file(&path).unwrap();
    let p = &scene.loads.points[0];
    assert_eq!((p.force_x, p.force, p.ramp), (0.5, -1.0, 0.03));
    assert_eq!(p.direction, [1.0, 1.0]);
    assert_eq!(p.harmonics.len(), 2);
    assert_eq!(p.harmonics[1].phase, 0.0);
    let series = p.series.as_ref().unwrap();
    assert_eq!(series.file, Path::new("f.csv"));
    assert_eq!(
        series.samples,
        vec![[0.0, 0.0, 1.0], [0.05, 1.5, -2.0], [0.1, 0.0, 0.0]]
    );
    // linear interpolation between the rows, exact at a row
    assert_eq!(series.at(0.025), [0.75, -0.5]);
    assert_eq!(series.at(0.05), [1.5, -2.0]);
    let text = scene.to_toml_string();
    assert_eq!(
        Scene::from_toml_str_in_dir(&text, dir.path()).unwrap(),
        scene
    );
    assert!(simulate(&scene).unwrap().is_spatial());
}

/// (loads table, files beside the scene, the key named, texts the message must contain)
type BadCase<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str, &'a [&'a str]);

#[test]
fn bad_loads_name_the_key_and_the_file() {
    let p = "[[loads.point]]\nnode = 2\n";
    let cases: Vec<BadCase> = vec![
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "t,fx,fz\n0,0,1\n0.2,0,2\n0.1,0,3\n")],
            "loads.point[0].series",
            &[
                "series file `f.csv`, line 4",
                "times must increase strictly: t = 0.1 after t = 0.2",
            ],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "0,0,1\n0.05,NaN,2\n0.1,0,3\n")],
            "loads.point[0].series",
            &[
                "series file `f.csv`, line 2",
                "fx is NaN; every value must be finite",
            ],
        ),
        (
            "series = \"missing.csv\"\n",
            &[],
            "loads.point[0].series",
            &["series file `missing.csv`", "cannot read it"],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "0,0,1\n0.05;1;2\n")],
            "loads.point[0].series",
            &["line 2", "expected 3 numbers `t, fx, fz`", "got 1 field"],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "0,0,1\n0.1,zero,2\n")],
            "loads.point[0].series",
            &["line 2", "`zero` in column fx is not a number"],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "t,fx,fz\n0,0,1\n")],
            "loads.point[0].series",
            &["at least 2 rows"],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "0,0,1\n0.05,0,2\n")],
            "loads.point[0].series",
            &["cover t ∈ [0, 0.05] s", "acts for t ∈ [0, 0.1] s"],
        ),
        (
            "series = \"f.csv\"\n",
            &[("f.csv", "0,0,1\n0.1,0,2e13\n")],
            "loads.point[0].series",
            &[
                "line 2",
                "fz = 20000000000000 N is outside the supported range",
            ],
        ),
        (
            "series = \"/dev/zero\"\n",
            &[],
            "loads.point[0].series",
            // read as a stream (the bounded reader), refused at its first byte
            &["series file `/dev/zero`", "line 1", "a NUL byte (byte 0)"],
        ),
        (
            "series = \".\"\n",
            &[],
            "loads.point[0].series",
            &["cannot read it: it is a directory"],
        ),
        (
            "direction = [0.0, 0.0]\n[[loads.point.harmonic]]\namplitude = 1.0\nperiod = 1.0\n",
            &[],
            "loads.point[0].direction",
            &["non-zero length", "zero length"],
        ),
        (
            "force = 1.0\ndirection = [1.0, 0.0]\n",
            &[],
            "loads.point[0].direction",
            &["applies to the load's harmonics"],
        ),
        (
            "force = [1.0, 2.0, 3.0]\n",
            &[],
            "loads.point[0].force",
            &["2 components [fx, fz]", "got 3 values"],
        ),
        (
            "force = [1.0, nan]\n",
            &[],
            "loads.point[0].force",
            &["must be finite"],
        ),
        (
            "ramp = -1.0\nforce = 1.0\n",
            &[],
            "loads.point[0].ramp",
            &["non-negative"],
        ),
        (
            "[[loads.point.harmonic]]\namplitude = 1.0\nperiod = 0.0\n",
            &[],
            "loads.point[0].harmonic[0].period",
            &["must be positive"],
        ),
        (
            "[[loads.point.harmonic]]\namplitude = 1.0\nperiod = 1e-310\n",
            &[],
            "loads.point[0].harmonic[0].period",
            &["must be at least 1e-12 s", "must stay finite"],
        ),
        (
            "[[loads.point.harmonic]]\namplitude = 1e13\nperiod = 1.0\n",
            &[],
            "loads.point[0].harmonic[0].amplitude",
            &["at most 1e12 N"],
        ),
        (
            "[[loads.point.harmonic]]\namplitude = 1.0\nperiod = 1.0\nphase = inf\n",
            &[],
            "loads.point[0].harmonic[0].phase",
            &["must be finite"],
        ),
        (
            "[[loads.point.harmonic]]\namplitude = 1.0\nperiod = 1.0\nwavelength = 3\n",
            &[],
            "loads.point[0].harmonic[0].wavelength",
            &["unknown key", "`amplitude`, `period`, `phase`"],
        ),
        (
            "ramp = 1.0\n",
            &[],
            "loads.point[0].force",
            &[
                "missing required key",
                "unless the load has a `harmonic` or a `series`",
            ],
        ),
    ];
    for (loads, files, key, want) in cases {
        if !cfg!(unix) && loads.contains("/dev/") {
            continue;
        }
        let (_dir, path) = scene_file(&format!("{p}{loads}"), files);
        let err = Scene::from_file(&path).unwrap_err();
        let msg = err.to_string();
        println!("{msg}");
        assert_eq!(err.key(), Some(key), "{msg}");
        assert!(
            msg.starts_with(&format!("{}: key `{key}`", path.display())),
            "{msg}"
        );
        for w in want {
            assert!(msg.contains(w), "{msg}\n  wants {w}");
        }
        assert!(!msg.contains('\n'));
    }
    // rows given in code are checked too, named by row
    let err = LoadSeries::new("code", vec![[0.0, 0.0, 0.0], [0.0, 1.0, 1.0]]).unwrap_err();
    assert!(
        err.to_string()
            .contains("row 2: times must increase strictly"),
        "{err}"
    );
}

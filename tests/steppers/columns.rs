//! `SceneTrajectory::into_columns` (the columns the Python package hands to numpy, built in the
//! trajectory's own memory) against the trajectory's accessors: the reference is the same
//! trajectory read through `time`, `energy`, `moment`, `positions`, `controls`, `moment_x` and
//! `controls_x`, compared bit for bit (the same floating-point operations in the same order).

use std::path::Path;

use chainbeam::{simulate, Error, Scene, SceneTrajectory, SimulateInput};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/scenes")
        .join(name);
    Scene::from_file(&path).unwrap()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Every column equals the accessors' numbers bit for bit.
fn assert_columns_match(traj: SceneTrajectory) {
    let (steps, n, spatial) = (traj.steps(), traj.n(), traj.is_spatial());
    let t: Vec<f64> = (0..=steps).map(|k| traj.time(k)).collect();
    let positions: Vec<f64> = (0..=steps)
        .flat_map(|k| traj.positions(k))
        .flatten()
        .collect();
    let (energy, moment) = (traj.energy().to_vec(), traj.moment().to_vec());
    let (controls, moment_x) = (traj.controls().to_vec(), traj.moment_x().to_vec());
    let controls_x = traj.controls_x().to_vec();
    let c = traj.into_columns().unwrap();
    assert_eq!(c.n, n);
    assert_eq!(c.positions.len(), (steps + 1) * n * 3);
    assert_eq!(bits(&c.t), bits(&t));
    assert_eq!(bits(&c.positions), bits(&positions));
    assert_eq!(bits(&c.energy), bits(&energy));
    assert_eq!(bits(&c.moment), bits(&moment));
    assert_eq!(bits(&c.controls), bits(&controls));
    if spatial {
        assert_eq!(bits(c.moment_x.as_ref().unwrap()), bits(&moment_x));
        let ux = c.controls_x.unwrap();
        if controls_x.is_empty() {
            assert!(ux.iter().all(|&u| u == 0.0) && ux.len() == steps + 1);
        } else {
            assert_eq!(bits(&ux), bits(&controls_x));
        }
    } else {
        assert!(c.moment_x.is_none() && c.controls_x.is_none());
    }
}

#[test]
fn planar_columns_equal_the_accessors() {
    let traj = simulate(&scene("riser_5.toml")).unwrap();
    assert!(!traj.is_spatial());
    assert_columns_match(traj);
}

#[test]
fn planar_columns_with_controls_equal_the_accessors() {
    let s = scene("riser_5.toml");
    let u: Vec<f64> = (0..=s.time.steps).map(|k| -0.2 * k as f64).collect();
    assert_columns_match(simulate(SimulateInput::new(&s).controls(&u)).unwrap());
}

#[test]
fn spatial_columns_equal_the_accessors() {
    for name in ["oblique_riser.toml", "oblique_control.toml"] {
        let mut s = scene(name);
        s.time.steps = s.time.steps.min(200);
        if let Some(c) = s.control.as_mut() {
            // A constant control (2-axis where the scene has one), not zero.
            c.kind = chainbeam::ControlKind::Constant;
            c.values = vec![0.5];
            c.values_x = c.values_x.as_ref().map(|_| vec![-0.25]);
        }
        let traj = simulate(&s).unwrap();
        assert!(traj.is_spatial(), "{name}");
        assert_columns_match(traj);
    }
}

/// A non-finite value (planted: the simulation of a valid scene does not produce one) is refused
/// with the first step that holds one, as the command line's check does.
#[test]
fn a_non_finite_value_names_the_first_step() {
    let Ok(mut t) = simulate(&scene("riser_5.toml")).unwrap().into_planar() else {
        panic!("riser_5 is planar");
    };
    t.energy[7] = f64::INFINITY;
    t.moment[3] = f64::NAN;
    match SceneTrajectory::from(t).into_columns() {
        Err(Error::NonFinite { step, .. }) => assert_eq!(step, 3),
        other => panic!("expected NonFinite at step 3, got {other:?}"),
    }
}

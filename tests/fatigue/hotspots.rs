//! Hot spots along the riser (`[[fatigue.hotspot]]`, `chainbeam::hotspots`, docs/conventions.md
//! "Hot spots: the joint torque M_j"): the moment at a hot spot is the joint torque k_j θ_j, here
//! at hot spots that lie on joints (tests/fatigue/hotspot_interpolation.rs: between joints).
//!
//! References, each independent of the code under test:
//! - statics: at equilibrium the spring of joint j balances the moment about node j−1 of every
//!   load beyond it (the pendulums' constraint forces at node j−1 have no moment about it), so a
//!   cantilever with a tip force P has k_j θ_j = P·(y_n − y_{j−1}) exactly, at any deflection
//!   (y the deflected nodes' heights from `static_equilibrium`);
//! - the wellhead: at the base (a = e₂) the torque is k₁θ₁ and today's wellhead moment is
//!   M_w = k₁ sin θ₁ = M₀·l₁/2, so sample by sample M_hot = k₁·asin(M_w/k₁) (planar);
//! - the assessment: each hot spot's damage is `fatigue::assess` of its joint's torque history,
//!   D_y = D·Y/T and L = 1/(DFF·D_y) with its own DFF.

use std::fs;

use chainbeam::fatigue::{assess, MomentHistory, MomentMeasure, SECONDS_PER_YEAR};
use chainbeam::hotspots::{joint_moment, joint_moment_history, nearest_joint};
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Scene};

use crate::fatigue_cli;
use fatigue_cli::{json, run};

/// A 60 m steel riser (6 pendulums of 10 m, 533.4 × 22.2 mm) under 1 MN top tension in a JONSWAP
/// sea (seed `seed`, from `direction` degrees) and a 0.3 m/s current, `steps` steps of 0.05 s,
/// curve D in seawater with CP; `hotspots` appended after the `[fatigue]` table.
fn riser(seed: u64, direction: f64, steps: usize, hotspots: &str) -> String {
    format!(
        "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 60.0\n\n\
         [loads]\ntension = 1e6\ndrag = 1e-4\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.3\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 3.0\ntp = 9.0\nseed = {seed}\n\
         direction = {direction:?}\n\n\
         [time]\nstep = 0.05\nsteps = {steps}\n\n\
         [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n{hotspots}"
    )
}

/// Three hot spots: the wellhead datum, a riser weld at 20 m (F1, SCF 1.3, DFF 3: on joint 3)
/// and the top joint at 60 m (the upper flex joint's spring): each on a joint, so each reads that
/// joint's torque alone (tests/fatigue/hotspot_interpolation.rs covers hot spots between joints).
const THREE: &str = "\n[[fatigue.hotspot]]\nname = \"wellhead\"\nelevation = 0.0\n\
                     \n[[fatigue.hotspot]]\nname = \"weld\"\nelevation = 20.0\nscf = 1.3\n\
                     curve = \"F1\"\ndff = 3.0\n\
                     \n[[fatigue.hotspot]]\nname = \"top\"\nelevation = 60.0\n";

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// A cantilever at a large deflection: every joint's torque k_j θ_j equals the moment of the tip
/// force about node j−1, P·(y_n − y_{j−1}), to the statics' tolerance; the linearised wellhead
/// moment k₁ sin θ₁ does not (it is θ₁²/6 low), which is why the hot spots use the angle.
#[test]
fn joint_torque_is_the_moment_of_the_loads_beyond_the_joint() {
    let (n, p) = (10, 4.0);
    let text = format!(
        "[beam]\npendulums = {n}\nsupport = \"cantilever\"\nlength = 1.0\nmass = 1.0\n\
         stiffness = 100.0\nbase_stiffness = 200.0\n\
         [[loads.point]]\nnode = {n}\nforce = {p}\n\
         [time]\nstep = 0.01\nsteps = 10\n"
    );
    let scene = Scene::from_toml_str(&text).unwrap();
    let sol = static_equilibrium(&scene).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let q: Vec<[f64; 2]> = sol.attitudes.iter().map(|a| [a[1], a[2]]).collect();
    let theta1 = q[0][1].atan2(q[0][0]).abs();
    assert!(
        theta1 > 0.1,
        "θ₁ = {theta1} rad: the test needs a large angle"
    );
    let e2 = [1.0, 0.0];
    for j in 0..n {
        let a = if j == 0 { e2 } else { q[j - 1] };
        let [mx, mz] = joint_moment(&a, &q[j], chain.springs()[j]);
        let below = if j == 0 { 0.0 } else { sol.positions[j - 1][0] };
        let lever = sol.positions[n - 1][0] - below;
        assert_eq!(mx, 0.0);
        // Thesis sign: F > 0 pushes toward −z and bends the joints negative.
        assert!(
            (mz + p * lever).abs() <= 1e-8 * (p * lever).abs(),
            "joint {}: k θ = {mz}, P (y_n − y_j-1) = {}",
            j + 1,
            p * lever
        );
    }
    let wellhead = chain.base_moment(&q) * scene.beam.lengths[0] / 2.0;
    let exact = p * sol.positions[n - 1][0];
    let linearised = (wellhead.abs() - exact) / exact;
    assert!(
        (linearised + theta1 * theta1 / 6.0).abs() < 0.05 * theta1 * theta1,
        "M_w is {linearised:e} off the moment balance, −θ₁²/6 = {:e}",
        -theta1 * theta1 / 6.0
    );
}

/// At elevation 0 the hot spot reads joint 1: sample by sample its torque is
/// k₁·asin(M_w/k₁) with M_w = M₀·l₁/2 the wellhead moment of the same run (planar), and in a
/// spatial sea the vector (M_x, M_z) is M_w's times θ₁/sin θ₁ with θ₁ = asin(|M_w|/k₁). The
/// damage differs from the wellhead's by at most the factor the ranges can take,
/// (1/cos θ_max)^m with m ≤ 5 the curve's slopes, and is never below it.
#[test]
fn elevation_zero_is_the_wellhead_moment_up_to_theta_over_sine() {
    for direction in [0.0, 30.0] {
        let scene = Scene::from_toml_str(&riser(7, direction, 400, "")).unwrap();
        assert_eq!(scene.is_spatial(), direction != 0.0);
        let k1 = scene.beam.base_stiffness;
        let half_l1 = scene.beam.lengths[0] / 2.0;
        assert_eq!(nearest_joint(&scene.beam.lengths, 0.0), 0);
        let h = joint_moment_history(&scene, &[0]).unwrap();
        // The base moment of the same run is `moment_history`'s, bit for bit.
        let m0 = chainbeam::moment_history(&scene).unwrap();
        assert_eq!(h.base_moment, m0.moment);
        assert_eq!(h.base_moment_x, m0.moment_x);
        let mut theta_max = 0.0_f64;
        for k in 0..h.base_moment.len() {
            let mwz = h.base_moment[k] * half_l1;
            let mwx = h.base_moment_x.as_ref().map_or(0.0, |m| m[k] * half_l1);
            let sin = mwz.hypot(mwx) / k1;
            let theta = sin.asin();
            theta_max = theta_max.max(theta);
            let factor = if sin > 0.0 { theta / sin } else { 1.0 };
            let hz = h.moment[0][k];
            assert!(
                (hz - mwz * factor).abs() <= 1e-12 * k1 * theta.max(1e-300),
                "step {k}: {hz} vs {}",
                mwz * factor
            );
            if let Some(mx) = &h.moment_x {
                assert!((mx[0][k] - mwx * factor).abs() <= 1e-12 * k1 * theta.max(1e-300));
            }
            assert!(hz.is_finite());
        }
        assert!(theta_max > 0.0);
        let spec = scene.fatigue.unwrap();
        let wellhead = assess(
            &spec,
            MomentHistory {
                duration_s: m0.duration(),
                moment: &m0.moment,
                moment_x: m0.moment_x.as_deref(),
                measure: scene.moment_measure(),
            },
        )
        .unwrap();
        let hot = assess(
            &spec,
            MomentHistory {
                duration_s: h.duration(),
                moment: &h.moment[0],
                moment_x: h.moment_x.as_ref().map(|m| &m[0][..]),
                measure: MomentMeasure::Wellhead,
            },
        )
        .unwrap();
        let ratio = hot.damage / wellhead.damage;
        let bound = theta_max.cos().recip().powi(5);
        println!(
            "direction {direction}: θ_max = {theta_max:.3e} rad, D_hot/D_w − 1 = {:.3e}, bound {:.3e}",
            ratio - 1.0,
            bound - 1.0
        );
        assert!(
            ratio >= 1.0 - 1e-12 && ratio <= bound + 1e-12,
            "{ratio} not in [1, {bound}]"
        );
    }
}

/// `chainbeam fatigue` with three hot spots: each has `name`, `elevation`, `damage_per_year`,
/// `life_years` (and the joint it read); its damage is `assess` of that joint's torque from
/// `joint_moment_history`, D_y = D·Y/T, L = 1/(DFF·D_y) with its own DFF; `critical` names the
/// least life; the top-level numbers stay the wellhead's of the `[fatigue]` table (the same as
/// the scene without hot spots, bit for bit); at elevation 0 the hot spot's damage is within
/// the θ/sin θ bound of it.
#[test]
fn cli_reports_every_hot_spot_and_the_critical_one() {
    let dir = tempfile::tempdir().unwrap();
    let text = riser(7, 0.0, 400, THREE);
    fs::write(dir.path().join("h.toml"), &text).unwrap();
    fs::write(dir.path().join("plain.toml"), riser(7, 0.0, 400, "")).unwrap();
    let (code, out, stderr) = run(dir.path(), &["fatigue", "h.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let (code, plain, stderr) = run(dir.path(), &["fatigue", "plain.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let plain = json(&plain);
    for key in [
        "cycles",
        "damage",
        "duration_s",
        "damage_per_year",
        "life_years",
    ] {
        assert_eq!(v[key], plain[key], "{key}");
    }
    assert!(plain.get("hotspots").is_none() && plain.get("critical").is_none());

    let scene = Scene::from_toml_str(&text).unwrap();
    let joints: Vec<usize> = scene
        .hotspots
        .iter()
        .map(|h| nearest_joint(&scene.beam.lengths, h.elevation))
        .collect();
    assert_eq!(joints, [0, 2, 6]);
    let h = joint_moment_history(&scene, &joints).unwrap();
    let spots = v["hotspots"].as_array().unwrap();
    assert_eq!(spots.len(), 3);
    let mut lives = Vec::new();
    for (s, spot) in spots.iter().enumerate() {
        let spec = &scene.hotspots[s];
        assert_eq!(spot["name"].as_str(), Some(spec.name.as_str()));
        assert_eq!(num(&spot["elevation"]), spec.elevation);
        assert_eq!(spot["joint"].as_u64(), Some(joints[s] as u64 + 1));
        let a = assess(
            &spec.spec,
            MomentHistory {
                duration_s: h.duration(),
                moment: &h.moment[s],
                moment_x: None,
                measure: MomentMeasure::Wellhead,
            },
        )
        .unwrap();
        assert!(a.damage > 0.0, "{}", spec.name);
        assert_eq!(num(&spot["damage"]), a.damage);
        let per_year = a.damage * SECONDS_PER_YEAR / 20.0;
        assert!((num(&spot["damage_per_year"]) - per_year).abs() <= 1e-12 * per_year);
        let life = 1.0 / (spec.spec.dff * per_year);
        assert!((num(&spot["life_years"]) - life).abs() <= 1e-12 * life);
        lives.push(life);
    }
    let least = (0..3)
        .min_by(|&a, &b| lives[a].total_cmp(&lives[b]))
        .unwrap();
    assert_eq!(
        v["critical"].as_str(),
        Some(spots[least]["name"].as_str().unwrap())
    );
    // The weld's own DFF 3 and F1 curve were used (not the table's D and 1).
    assert_eq!(scene.hotspots[1].spec.dff, 3.0);
    let ratio = num(&spots[0]["damage"]) / num(&v["damage"]);
    assert!(
        (1.0..1.01).contains(&ratio),
        "wellhead hot spot / wellhead {ratio}"
    );
}

/// Bad `[[fatigue.hotspot]]` entries are refused by `chainbeam fatigue` with one line naming the
/// key (exit 1, nothing written).
#[test]
fn bad_hot_spot_keys_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let one = |body: &str| format!("\n[[fatigue.hotspot]]\nname = \"a\"\n{body}");
    for (entries, key) in [
        (one("elevation = -1.0\n"), "fatigue.hotspot[0].elevation"),
        (one("elevation = 60.5\n"), "fatigue.hotspot[0].elevation"),
        (one("elevation = nan\n"), "fatigue.hotspot[0].elevation"),
        (
            one("elevation = 1.0\n") + &one("elevation = 2.0\n"),
            "fatigue.hotspot[1].name",
        ),
        (
            "\n[[fatigue.hotspot]]\nname = \" \"\nelevation = 1.0\n".to_string(),
            "fatigue.hotspot[0].name",
        ),
        (
            one("elevation = 1.0\nscf = 0.0\n"),
            "fatigue.hotspot[0].scf",
        ),
        (
            one("elevation = 1.0\ncurve = \"Z\"\n"),
            "fatigue.hotspot[0].curve",
        ),
        (
            one("elevation = 1.0\nenvironment = \"mud\"\n"),
            "fatigue.hotspot[0].environment",
        ),
        (
            one("elevation = 1.0\nwall_thickness = 0.3\n"),
            "fatigue.hotspot[0].wall_thickness",
        ),
        (
            one("elevation = 1.0\ndff = -2.0\n"),
            "fatigue.hotspot[0].dff",
        ),
        (one("elevation = 1.0\nsfc = 1.2\n"), "sfc"),
        (one(""), "elevation"),
    ] {
        fs::write(dir.path().join("b.toml"), riser(7, 0.0, 10, &entries)).unwrap();
        let (code, out, stderr) = run(dir.path(), &["fatigue", "b.toml"]);
        assert_eq!(code, 1, "{entries}: {stderr}");
        assert!(out.is_empty());
        assert!(
            stderr.contains("b.toml") && stderr.contains(key),
            "{key}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

/// `--seeds 3`: the cell's `seed_damages` are, in order, the plain runs of the scene written with
/// seeds 7, 8, 9 (with the same `--record` and `--spin-up`); `damage` is their mean, `damage_std`
/// their sample standard deviation (K − 1), `damage_min`/`damage_max` their range;
/// `life_years_seeds` each seed's life 1/(DFF·D_i·Y/T) and `seeds` the seeds run; the hot spots'
/// damage per year is the mean over the seeds of their plain runs' and `critical` is named.
#[test]
fn seeds_spread_in_the_json() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), riser(7, 0.0, 10, THREE)).unwrap();
    let flags = ["--record", "12", "--spin-up", "3"];
    let (code, out, stderr) = run(
        dir.path(),
        &[&["fatigue", "s.toml", "--seeds", "3"][..], &flags].concat(),
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let seeds: Vec<u64> = v["seeds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_u64().unwrap())
        .collect();
    assert_eq!(seeds, [7, 8, 9]);
    let cell = &v["cells"][0];
    assert_eq!(num(&cell["duration_s"]), 12.0);
    let got: Vec<f64> = cell["seed_damages"]
        .as_array()
        .unwrap()
        .iter()
        .map(num)
        .collect();
    let mut expected = Vec::new();
    let mut hot = [0.0; 3];
    for seed in [7, 8, 9] {
        fs::write(dir.path().join("one.toml"), riser(seed, 0.0, 10, THREE)).unwrap();
        let (code, out, stderr) = run(dir.path(), &[&["fatigue", "one.toml"][..], &flags].concat());
        assert_eq!(code, 0, "{stderr}");
        let p = json(&out);
        assert_eq!(num(&p["duration_s"]), 12.0);
        expected.push(num(&p["damage"]));
        for (s, spot) in p["hotspots"].as_array().unwrap().iter().enumerate() {
            hot[s] += num(&spot["damage_per_year"]) / 3.0;
        }
    }
    assert_eq!(got, expected);
    assert!(expected[0] != expected[1], "the seeds draw different seas");
    let mean = expected.iter().sum::<f64>() / 3.0;
    assert!((num(&cell["damage"]) - mean).abs() <= 1e-15 * mean);
    let var = expected.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / 2.0;
    assert!((num(&cell["damage_std"]) - var.sqrt()).abs() <= 1e-12 * var.sqrt());
    let min = expected.iter().copied().fold(f64::INFINITY, f64::min);
    let max = expected.iter().copied().fold(0.0, f64::max);
    assert_eq!(
        (num(&cell["damage_min"]), num(&cell["damage_max"])),
        (min, max)
    );
    let lives: Vec<f64> = v["life_years_seeds"]
        .as_array()
        .unwrap()
        .iter()
        .map(num)
        .collect();
    for (life, d) in lives.iter().zip(&expected) {
        let l = 1.0 / (d * SECONDS_PER_YEAR / 12.0);
        assert!((life - l).abs() <= 1e-12 * l, "{life} vs {l}");
    }
    let lmin = lives.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = lives.iter().copied().fold(0.0, f64::max);
    assert_eq!(
        (num(&v["life_years_min"]), num(&v["life_years_max"])),
        (lmin, lmax)
    );
    let spots = v["hotspots"].as_array().unwrap();
    for (s, spot) in spots.iter().enumerate() {
        let d = num(&spot["damage_per_year"]);
        assert!(
            (d - hot[s]).abs() <= 1e-12 * hot[s],
            "{}: {d} vs {}",
            s,
            hot[s]
        );
    }
    assert!(v["critical"].is_string());
    // One seed keeps the JSON's shape (no spread fields).
    fs::write(
        dir.path().join("one.csv"),
        "hs,tp,probability\n3.0,9.0,1.0\n",
    )
    .unwrap();
    let (code, out1, stderr) = run(
        dir.path(),
        &[&["fatigue", "s.toml", "--scatter", "one.csv"][..], &flags].concat(),
    );
    assert_eq!(code, 0, "{stderr}");
    let w = json(&out1);
    assert!(w.get("seeds").is_none() && w.get("life_years_seeds").is_none());
    assert!(w["cells"][0].get("seed_damages").is_none());
    assert_eq!(num(&w["cells"][0]["damage"]), expected[0]);
}

/// Refusals of `--seeds` and `--record`, naming the flag: 0 seeds, more than one seed without a
/// sea to draw, a record that is not positive, or longer than the scene can run.
#[test]
fn seeds_and_record_refusals() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), riser(7, 0.0, 10, "")).unwrap();
    let calm = "[beam]\npendulums = 3\nsupport = \"riser\"\nlength = 1.0\nmass = 1.0\n\
                stiffness = 100.0\nbase_stiffness = 200.0\ntip_stiffness = 200.0\n\
                [[loads.point]]\nnode = 2\nforce = 1.0\n\
                [time]\nstep = 0.01\nsteps = 10\n\
                [fatigue]\nouter_diameter = 0.02\nwall_thickness = 0.002\n";
    fs::write(dir.path().join("calm.toml"), calm).unwrap();
    for (args, flag, what) in [
        (&["s.toml", "--seeds", "0"][..], "--seeds", "must be 1 to"),
        (
            &["calm.toml", "--seeds", "2", "--record", "1"][..],
            "--seeds",
            "[loads.waves]",
        ),
        (&["s.toml", "--record", "0"][..], "--record", "positive"),
        (
            &["s.toml", "--record", "-5", "--seeds", "2"][..],
            "--record",
            "positive",
        ),
        (&["s.toml", "--record", "1e9"][..], "--record", "time.steps"),
    ] {
        let (code, out, stderr) = run(dir.path(), &[&["fatigue"][..], args].concat());
        assert_eq!(code, 1, "{args:?}: {stderr}");
        assert!(out.is_empty());
        assert!(
            stderr.contains(flag) && stderr.contains(what),
            "{args:?}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

/// A study cell counts 3 hours after the spin-up by default: a 2-pendulum chain (100 kg
/// masses, first period ≈ 2π s) at h = 0.5 s
/// runs --controller none for 60 + 10 800 s and reports `duration_s` = 10 800 and the
/// `settings.record` it used.
#[test]
fn study_cells_default_to_three_hour_records() {
    let dir = tempfile::tempdir().unwrap();
    let text = "[beam]\npendulums = 2\nsupport = \"riser\"\nlength = 1.0\nmass = 100.0\n\
                stiffness = 100.0\nbase_stiffness = 200.0\ntip_stiffness = 200.0\n\
                [loads]\ndrag = 0.1\n\
                [[loads.point]]\nnode = 2\nforce = 1.0\n\
                [[loads.point.harmonic]]\namplitude = 1.0\nperiod = 9.0\n\
                [time]\nstep = 0.5\nsteps = 10\n\
                [fatigue]\nouter_diameter = 0.02\nwall_thickness = 0.002\n";
    fs::write(dir.path().join("c.toml"), text).unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "c.toml",
            "--controller",
            "none",
            "--spin-up",
            "60",
            "--interval",
            "0.5",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    assert_eq!(num(&v["settings"]["record"]), 10_800.0);
    assert_eq!(v["settings"]["seeds"].as_u64(), Some(1));
    assert_eq!(
        num(&v["controllers"]["none"]["cells"][0]["duration_s"]),
        10_800.0
    );
    // The plain assessment keeps the scene's own record (10 steps of 0.5 s).
    let (code, out, stderr) = run(dir.path(), &["fatigue", "c.toml"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(num(&json(&out)["duration_s"]), 5.0);
}

/// `--controller none,constant,pd` on a scene with hot spots: every controller reports its hot
/// spots and a critical one. The closed loops' joint torques come from their decisions replayed
/// on the plant (`replay_joint_moments`); the replay's base moment is the closed loop's record
/// bit for bit (the same states), and for `none` the study's hot-spot damage per year is the
/// plain run's (the same streamed run).
#[test]
fn closed_loops_report_hot_spots_from_their_replayed_decisions() {
    use chainbeam::fatigue_study::{
        replay_joint_moments, run_controller, ControlSettings, ControllerKind,
    };
    let dir = tempfile::tempdir().unwrap();
    let mut text = riser(7, 0.0, 200, THREE);
    text.push_str("\n[control]\nnode = 6\nkind = \"constant\"\nvalues = [0.0]\n");
    fs::write(dir.path().join("c.toml"), &text).unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "c.toml",
            "--controller",
            "constant,pd",
            "--record",
            "10",
            "--bound",
            "5e4",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let (code, plain, stderr) = run(dir.path(), &["fatigue", "c.toml", "--record", "10"]);
    assert_eq!(code, 0, "{stderr}");
    let plain = json(&plain);
    for name in ["none", "constant", "pd"] {
        let c = &v["controllers"][name];
        let spots = c["hotspots"]
            .as_array()
            .unwrap_or_else(|| panic!("{name}: {c}"));
        assert_eq!(spots.len(), 3, "{name}");
        assert!(c["critical"].is_string(), "{name}");
        for (s, spot) in spots.iter().enumerate() {
            assert!(num(&spot["damage_per_year"]) > 0.0, "{name} {s}");
            if name == "none" {
                let p = num(&plain["hotspots"][s]["damage_per_year"]);
                assert!((num(&spot["damage_per_year"]) - p).abs() <= 1e-12 * p);
            }
        }
    }
    // The replay reproduces the closed loop's states.
    let scene = Scene::from_toml_str(&text).unwrap();
    let settings = ControlSettings {
        mpc: chainbeam::mpc::MpcOptions {
            ocp: chainbeam::ocp::OcpOptions::default().with_bound(5e4),
            ..Default::default()
        },
        ..ControlSettings::default()
    };
    let record = run_controller(&scene, ControllerKind::Pd, &settings).unwrap();
    let decisions = record.decisions.as_deref().unwrap();
    assert_eq!(decisions.len(), 100);
    let replay = replay_joint_moments(&scene, settings.interval, decisions, &[0, 2, 6]).unwrap();
    assert_eq!(replay.base_moment, record.moment);
    assert_eq!(replay.moment[0].len(), record.moment.len());
}

/// A study spread cell by cell (`run_study_cell` for each cell, then `combine_study`: the
/// Python package's executor path) is `run_study` bit for bit, seeds and hot spots included:
/// two cells × two seeds × `none,constant` on the three hot spots. Runs that are not one per
/// (cell, seed, controller) are refused, not combined.
#[test]
fn a_study_cell_by_cell_combines_to_the_whole_study() {
    use chainbeam::fatigue::{ScatterCell, SeaState};
    use chainbeam::fatigue_study::{
        combine_study, run_study, run_study_cell, ControlSettings, ControllerKind, StudyError,
        StudyInput,
    };
    let scene = Scene::from_toml_str(&riser(7, 0.0, 120, THREE)).unwrap();
    let spec = scene.fatigue_spec().unwrap();
    let cells: Vec<ScatterCell> = [(2.0, 8.0, 0.6), (3.0, 9.0, 0.4)]
        .iter()
        .map(|&(hs, tp, probability)| ScatterCell {
            sea: SeaState {
                hs,
                tp,
                direction: None,
            },
            probability,
        })
        .collect();
    let settings = ControlSettings {
        spin_up: 1.0,
        record: Some(4.0),
        seeds: 2,
        ..ControlSettings::default()
    };
    let controllers = [ControllerKind::None, ControllerKind::Constant];
    let input = StudyInput {
        scene: &scene,
        spec: &spec,
        cells: Some(&cells),
        controllers: &controllers,
        settings: &settings,
    };
    let whole = run_study(&input, &|| {}).unwrap();
    let mut runs = Vec::new();
    for cell in 0..cells.len() {
        runs.extend(run_study_cell(&input, cell).unwrap());
    }
    assert_eq!(runs.len(), 2 * 2 * 2);
    let combined = combine_study(&input, &runs).unwrap();
    assert_eq!(combined, whole);
    let none = &whole.controllers[0];
    assert_eq!(none.hotspots.len(), 3);
    assert!(none.cells.iter().all(|c| c.seed_damages.len() == 2
        && c.seed_damages[0] != c.seed_damages[1]
        && c.seed_spread().is_some_and(|s| s.min < s.max)));
    assert!(matches!(
        combine_study(&input, &runs[1..]),
        Err(StudyError::RunCount {
            expected: 8,
            got: 7
        })
    ));
    assert!(matches!(
        run_study_cell(&input, 2),
        Err(StudyError::CellIndex { cell: 2, cells: 2 })
    ));
}

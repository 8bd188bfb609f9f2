//! The thesis riser in waves held by a vessel whose thrust is the control, for the tests of MPC
//! through the vessel's thrust (tests/mpc: mpc_vessel.rs, thrust_plan_step.rs,
//! forecast_noisy.rs).

use chainbeam::Scene;

/// riser_300m.toml's pipe and sea at n = 15, h = 0.05 s, `steps` steps, held by a
/// drillship-sized vessel (5·10⁷ kg, 10 % added mass, c = 10⁵ N·s/m, |F| ≤ 2·10⁶ N,
/// |Ḟ| ≤ 2·10⁵ N/s) whose thrust is the control; `waves` is added to `[loads.waves]` and
/// `vessel` to `[vessel]` (both empty: the scene as written).
pub fn riser_in_waves_with(steps: usize, waves: &str, vessel: &str) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.split("\n[mpc]\n").next().unwrap().to_string()
        + "\n[fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.022225\ncurve = \"F1\"\n";
    let mut text = text
        .replace("pendulums = 80", "pendulums = 15")
        .replace("support = \"riser\"", "support = \"vessel\"")
        .replace("step = 0.0125", "step = 0.05")
        .replace("steps = 48000 ", &format!("steps = {steps} "))
        .replace("drag = 4.0020e-7 ", "drag = 7.504e-8 ");
    if !waves.is_empty() {
        text = text.replace(
            "lumping = \"cell\" ",
            &format!("lumping = \"cell\"\n{waves}\n#"),
        );
    }
    let text = text
        + "\n[vessel]\noffset = 3.0\nramp = 5.0\nmass = 5e7\nadded_mass = 5e6\ndamping = 1e5\n\
           thrust_bound = 2e6\nthrust_rate_bound = 2e5\n"
        + vessel;
    Scene::from_toml_str(&text).unwrap()
}

/// [`riser_in_waves_with`] as written.
pub fn riser_in_waves(steps: usize) -> Scene {
    riser_in_waves_with(steps, "", "")
}

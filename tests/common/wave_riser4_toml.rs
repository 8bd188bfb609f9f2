//! A small wave-driven riser as a scene file for the command-line tests: planar
//! (tests/cli/cli_mpc.rs) and in space (tests/cli/cli_spatial.rs).
#![allow(dead_code)]

/// A small riser (n = 4, D = 10 kg/m) with a wave of period 2 s at node 2 (amplitude 2 N,
/// ramped in over 0.5 s), controlled at the tip, h = 0.01 s, 100 steps: 1 s of closed loop.
pub const PLANAR: &str = r#"[beam]
pendulums = 4
length = 1.0
mass = 1.0
stiffness = 1000.0
support = "riser"
base_stiffness = 2000.0
tip_stiffness = 2000.0

[loads]
drag = 10.0

[[loads.point]]
node = 2
ramp = 0.5

[[loads.point.harmonic]]
amplitude = 2.0
period = 2.0

[time]
step = 0.01
steps = 100

[control]
node = 4
kind = "constant"
values = [0.0]
"#;

/// The riser of [`PLANAR`] in space: the wave from 60° (its direction (x, z) = (sin 60°,
/// cos 60°)) and a linear current along +z, 0.1 m/s at the surface to 0.02 m/s at the seabed.
pub fn spatial() -> String {
    let (wave, time) = ("ramp = 0.5\n", "\n[time]\n");
    assert!(PLANAR.matches(wave).count() == 1 && PLANAR.matches(time).count() == 1);
    let direction = "direction = [0.8660254037844386, 0.5000000000000001]\n";
    let current = "\n[loads.current]\nprofile = \"linear\"\nspeed = 0.1\nbottom_speed = 0.02\n\
                   direction = [0.0, 1.0]\n";
    PLANAR
        .replacen(wave, &format!("{wave}{direction}"), 1)
        .replacen(time, &format!("{current}{time}"), 1)
}

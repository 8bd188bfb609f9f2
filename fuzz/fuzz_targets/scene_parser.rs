//! Fuzz target for the scene parser (`Scene::from_toml_str`, docs/scene-format.md).
//!
//! Properties checked on every input:
//! - parsing never panics; an error has a non-empty one-line message;
//! - an accepted scene validates, and round-trips exactly through `Scene::to_toml_string`;
//! - a small accepted scene simulates without panic (a typed error is fine).
#![no_main]

use chainbeam::Scene;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Scene::from_toml_str(text) {
        Ok(scene) => {
            assert!(scene.validate().is_ok(), "an accepted scene must validate");
            let written = scene.to_toml_string();
            let again = Scene::from_toml_str(&written)
                .unwrap_or_else(|e| panic!("written scene does not parse: {e}\n{written}"));
            assert_eq!(again, scene, "round trip changed the scene");
            // Keep each run short: only small scenes are simulated.
            if scene.n() <= 8 && scene.time.steps <= 50 {
                let _ = chainbeam::simulate(&scene);
            }
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.is_empty(), "empty error message");
            assert!(!msg.contains('\n'), "multi-line error message: {msg:?}");
        }
    }
});

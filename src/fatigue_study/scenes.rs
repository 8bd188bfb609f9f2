//! The scenes a study derives from the user's: one per sea state of the scatter diagram, per
//! seed of the sea and per record length, and the spin-up and the fatigue proxy objective.

use super::*;
use crate::scene::SceneError;

/// The scene with a cell's sea state: `[loads.waves]` `hs`, `tp` (and `direction` when
/// given) replaced, every other key (the seed among them) kept (module docs, "Sea states and
/// seeds").
///
/// # Errors
/// [`StudyError::SeaState`] when the scene has no `[loads.waves]` to set, or the values are
/// invalid for it (naming the key).
pub fn with_sea_state(
    scene: &Scene,
    sea: &SeaState,
    cell: usize,
) -> Result<ValidScene, StudyError> {
    let mut out = scene.clone();
    set_sea_state(&mut out, sea, cell)?;
    out.into_valid().map_err(|e| sea_state_error(sea, cell, &e))
}

/// [`with_sea_state`]'s edit, in place and not validated.
fn set_sea_state(out: &mut Scene, sea: &SeaState, cell: usize) -> Result<(), StudyError> {
    let Some(waves) = out.loads.waves.as_mut() else {
        return Err(StudyError::SeaState {
            cell,
            reason: "the scene has no [loads.waves] table whose hs and tp a scatter cell could \
                     set (docs/scene-format.md)"
                .to_string(),
        });
    };
    waves.hs = sea.hs;
    waves.tp = sea.tp;
    if let Some(direction) = sea.direction {
        waves.direction = direction;
    }
    Ok(())
}

/// A cell's sea state that the scene refuses, naming the values and the key.
fn sea_state_error(sea: &SeaState, cell: usize, e: &SceneError) -> StudyError {
    StudyError::SeaState {
        cell,
        reason: format!(
            "H_s = {} m, T_p = {} s{}: {e}",
            sea.hs,
            sea.tp,
            sea.direction
                .map_or_else(String::new, |d| format!(", direction {d}°"))
        ),
    }
}

/// A cell's scene: the sea state `sea` = (state, cell) ([`with_sea_state`]) run for `record`
/// = (settings, controller, seconds) ([`with_record`]), validated once for both edits; the
/// scene as it is without them. A refusal is reported as when each edit was validated in
/// turn: the sea state's error when the sea state alone is refused (a second validation, on
/// the error path only), the record's otherwise.
///
/// # Errors
/// [`with_sea_state`]'s and [`with_record`]'s; without either edit, the scene's own
/// validation error as [`StudyError::Record`] over the scene's own duration.
pub fn cell_scene(
    scene: &Scene,
    sea: Option<(&SeaState, usize)>,
    record: Option<(&ControlSettings, ControllerKind, f64)>,
) -> Result<ValidScene, StudyError> {
    let mut out = scene.clone();
    if let Some((sea, cell)) = sea {
        set_sea_state(&mut out, sea, cell)?;
    }
    // The sea state's own refusal first, as when it was validated before the record.
    let first = |otherwise: StudyError| {
        sea.and_then(|(sea, cell)| with_sea_state(scene, sea, cell).err())
            .unwrap_or(otherwise)
    };
    if let Some((settings, kind, seconds)) = record {
        out.time.steps = record_steps(scene, settings, kind, seconds).map_err(first)?;
    }
    out.into_valid().map_err(|e| match (sea, record) {
        (_, Some((.., seconds))) => first(record_error(seconds, &e)),
        (Some((sea, cell)), None) => sea_state_error(sea, cell, &e),
        (None, None) => StudyError::Record {
            record: scene.time.steps as f64 * scene.time.step,
            reason: e.to_string(),
        },
    })
}

/// The scene's own sea state (`[loads.waves]` hs, tp, direction), if it has one.
pub fn scene_sea_state(scene: &Scene) -> Option<SeaState> {
    scene.loads.waves.map(|w| SeaState {
        hs: w.hs,
        tp: w.tp,
        direction: Some(w.direction),
    })
}

/// The seeds a study of `seeds` seeds per cell draws, s, s + 1, …, s + K − 1 (s the scene's
/// `[loads.waves]` seed), as reports list them: `None` with one seed or without a sea.
pub fn seeds_run(scene: &Scene, seeds: usize) -> Option<Vec<u64>> {
    let w = scene.loads.waves.as_ref().filter(|_| seeds > 1)?;
    Some(
        (0..seeds as u64)
            .map(|i| w.seed.saturating_add(i))
            .collect(),
    )
}

/// The scene with seed number `index` of a cell (module docs, "Records"): `[loads.waves]`
/// `seed` + `index`; the scene itself for index 0.
///
/// # Errors
/// [`StudyError::Seeds`] for index > 0 on a scene without `[loads.waves]`, or a seed past
/// the largest the scene file can hold (2⁶³ − 1).
pub fn with_seed(scene: &Scene, index: usize) -> Result<Scene, StudyError> {
    if index == 0 {
        return Ok(scene.clone());
    }
    let mut out = scene.clone();
    let err = |reason: &str| StudyError::Seeds {
        seeds: index + 1,
        reason: reason.to_string(),
    };
    let waves = out.loads.waves.as_mut().ok_or_else(|| {
        err("more than one seed needs a sea to draw ([loads.waves]); this scene has none")
    })?;
    waves.seed = waves
        .seed
        .checked_add(index as u64)
        .filter(|&s| s <= i64::MAX as u64)
        .ok_or_else(|| err("the seeds would pass 2^63 − 1"))?;
    Ok(out)
}

/// The scene run for `spin_up` + `record` seconds (module docs, "Records"): N = ⌈spin_up/h⌉ +
/// ⌈record/h⌉ steps, rounded up to whole control intervals for a closed-loop controller (so the
/// counted record is at least `record`; its exact duration is the cell's `duration_s`).
///
/// # Errors
/// [`StudyError::Record`] for a record that is not positive and finite, or a run the scene
/// refuses (too many steps, a load series that does not cover it: the message names the key);
/// [`StudyError::SpinUp`] for an invalid spin-up.
pub fn with_record(
    scene: &Scene,
    settings: &ControlSettings,
    kind: ControllerKind,
    record: f64,
) -> Result<ValidScene, StudyError> {
    let mut out = scene.clone();
    out.time.steps = record_steps(scene, settings, kind, record)?;
    out.into_valid().map_err(|e| record_error(record, &e))
}

/// A record that the scene refuses, naming the key.
fn record_error(record: f64, e: &SceneError) -> StudyError {
    StudyError::Record {
        record,
        reason: e.to_string(),
    }
}

/// [`with_record`]'s number of steps, checked (not validated with the scene).
fn record_steps(
    scene: &Scene,
    settings: &ControlSettings,
    kind: ControllerKind,
    record: f64,
) -> Result<usize, StudyError> {
    let err = |reason: String| StudyError::Record { record, reason };
    if !(record.is_finite() && record > 0.0) {
        return Err(err("must be positive and finite".into()));
    }
    let h = scene.time.step;
    let spin_up = settings.spin_up;
    if !(spin_up.is_finite() && spin_up >= 0.0) {
        return Err(StudyError::SpinUp {
            spin_up,
            duration_s: spin_up + record,
        });
    }
    let steps_of = |t: f64| (t / h * (1.0 - 1e-12)).ceil();
    let mut steps = steps_of(spin_up) + steps_of(record).max(1.0);
    // An interval that is not a multiple of h is the run's own error (naming the interval).
    if let (true, Ok(m)) = (kind.is_feedback(), interval_steps(settings.interval, h)) {
        let m = m as f64;
        steps = (steps / m).ceil() * m;
    }
    if steps > crate::scene::MAX_STEPS as f64 {
        return Err(err(format!(
            "{steps} steps of h = {h} s, more than {} (time.steps' limit)",
            crate::scene::MAX_STEPS
        )));
    }
    Ok(steps as usize)
}

/// The objective MPC plans on as the fatigue proxy: Σ|M₀(t_k)|^m with m the first slope of
/// `spec`'s S-N curve ([`WellheadDamage::exponent`]; m = 3 for the DNV curves C–W3, 4 for B1
/// and B2).
///
/// # Errors
/// The spec's [`FatigueError`].
pub fn fatigue_proxy(spec: &FatigueSpec, scene: &Scene) -> Result<ObjectiveKind, StudyError> {
    let exponent = WellheadDamage::new(spec, scene.moment_measure())?.exponent();
    Ok(ObjectiveKind::Power { exponent })
}

/// The steps of the spin-up window: ⌈spin_up/h⌉ (module docs, "The start of a record").
///
/// # Errors
/// [`StudyError::SpinUp`] for a window that is not finite and ≥ 0, or that leaves fewer than
/// two samples of the record.
pub fn spin_up_steps(scene: &Scene, spin_up: f64) -> Result<usize, StudyError> {
    let h = scene.time.step;
    let duration_s = h * scene.time.steps as f64;
    let steps = (spin_up / h * (1.0 - 1e-12)).ceil();
    if !(spin_up.is_finite() && spin_up >= 0.0) || steps >= scene.time.steps as f64 {
        return Err(StudyError::SpinUp {
            spin_up,
            duration_s,
        });
    }
    Ok(steps as usize)
}

//! A scene validated once: [`ValidScene`] holds a scene that passed [`Scene::validate`] and
//! cannot change since (it derefs to `&Scene` and gives no `&mut`), and [`SceneInput`] is what
//! the library builds a model or a run from: a [`Scene`] or a [`ValidScene`].
//!
//! A [`Scene`]'s fields are public, so a scene read from a file may have been edited before it
//! reaches the model: [`Chain::from_scene`](crate::Chain::from_scene) and the runs built on it
//! validate a [`Scene`] when they are given one. A scene derived inside a study (a scatter
//! cell's sea state, a seed, a record length, a design's parameters) is validated once where it
//! is made, as a [`ValidScene`], and every model built from it takes that proof instead of
//! validating again.
//!
//! ```
//! use chainbeam::{catalogue, Chain};
//!
//! let valid = catalogue::riser(5).into_valid()?; // validated here, once
//! let chain = Chain::<f64, 2>::from_scene(&valid)?; // no second validation
//! assert_eq!(chain.n(), valid.n());
//! let mut scene = valid.into_inner(); // to edit it again
//! scene.time.steps = 20;
//! let chain = Chain::<f64, 2>::from_scene(&scene)?; // validated, since it may have changed
//! # assert_eq!(chain.n(), scene.n());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::{Scene, SceneError};

/// A scene that passed [`Scene::validate`] and has not changed since: read through `Deref`,
/// edited only after [`ValidScene::into_inner`]. Built by [`Scene::into_valid`].
#[derive(Clone, Debug)]
pub struct ValidScene(Scene);

impl Scene {
    /// Validates the scene ([`Scene::validate`]) and keeps the proof: a model built from the
    /// [`ValidScene`] does not validate it again.
    ///
    /// # Errors
    /// [`Scene::validate`]'s.
    pub fn into_valid(self) -> Result<ValidScene, SceneError> {
        self.validate()?;
        Ok(ValidScene(self))
    }
}

impl ValidScene {
    /// Reads, parses and validates a scene file ([`Scene::from_file`], which validates it),
    /// keeping the proof.
    ///
    /// # Errors
    /// [`Scene::from_file`]'s.
    pub fn from_file(path: impl AsRef<std::path::Path>) -> Result<ValidScene, SceneError> {
        Scene::from_file(path).map(ValidScene)
    }

    /// Parses and validates a scene file's text ([`Scene::from_toml_str`], which validates
    /// it), keeping the proof.
    ///
    /// # Errors
    /// [`Scene::from_toml_str`]'s.
    pub fn from_toml_str(text: &str) -> Result<ValidScene, SceneError> {
        Scene::from_toml_str(text).map(ValidScene)
    }

    /// The proof, borrowed.
    pub(crate) fn proof(&self) -> Checked<'_> {
        Checked(&self.0)
    }

    /// [`Checked::without_control`] of this scene.
    pub(crate) fn without_control(&self) -> ValidScene {
        Checked(&self.0).without_control()
    }

    /// The scene, to edit (it is validated again where a model is built from it).
    pub fn into_inner(self) -> Scene {
        self.0
    }
}

impl std::ops::Deref for ValidScene {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.0
    }
}

impl AsRef<Scene> for ValidScene {
    fn as_ref(&self) -> &Scene {
        &self.0
    }
}

/// A validated scene inside the library: a shared borrow of a scene that passed
/// [`Scene::validate`] (the borrow keeps it from changing while the proof lives). Made only by
/// [`SceneInput`]'s validation, so a function that takes one never validates.
/// (Public only as the sealed trait's return type: no path outside the crate names it.)
#[derive(Clone, Copy, Debug)]
#[allow(unreachable_pub)]
pub struct Checked<'a>(&'a Scene);

impl<'a> Checked<'a> {
    /// The scene, for the lifetime of the borrow.
    #[allow(unreachable_pub)]
    pub fn scene(self) -> &'a Scene {
        self.0
    }

    /// The scene without its `[control]`, still valid: the rules a control takes part in
    /// (its own keys, and the step-number bound, in which its largest force adds to the
    /// load) only get easier without it, so no validation is needed.
    pub(crate) fn without_control(self) -> ValidScene {
        let mut scene = self.0.clone();
        scene.control = None;
        ValidScene(scene)
    }
}

impl std::ops::Deref for Checked<'_> {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        self.0
    }
}

/// What the library builds a model or a run from: a [`Scene`] (validated there, since its
/// public fields may have been edited since it was read) or a [`ValidScene`] (validated once,
/// when it was made). Implemented for these two only.
pub trait SceneInput: sealed::Validate {}

impl SceneInput for Scene {}
impl SceneInput for ValidScene {}
/// The library's own proof passes where a scene does (it cannot be made outside the crate).
#[doc(hidden)]
impl SceneInput for Checked<'_> {}

pub(crate) mod sealed {
    use super::{Checked, Scene, SceneError, ValidScene};

    /// The validation behind [`super::SceneInput`], callable inside the crate only.
    #[allow(unreachable_pub)] // sealed: nameable only inside the crate.
    pub trait Validate {
        /// The scene, validated unless it already is.
        fn checked(&self) -> Result<Checked<'_>, SceneError>;
        /// The scene, whether validated or not (to read what a builder's defaults need).
        fn scene(&self) -> &Scene;
        /// The proof, when the scene carries one.
        fn known_valid(&self) -> Option<Checked<'_>>;
        /// An owned validated copy (validated unless it already is).
        fn to_valid(&self) -> Result<ValidScene, SceneError> {
            Ok(ValidScene(self.checked()?.scene().clone()))
        }
    }

    impl Validate for Scene {
        fn checked(&self) -> Result<Checked<'_>, SceneError> {
            self.validate()?;
            Ok(Checked(self))
        }
        fn scene(&self) -> &Scene {
            self
        }
        fn known_valid(&self) -> Option<Checked<'_>> {
            None
        }
    }

    impl Validate for Checked<'_> {
        fn checked(&self) -> Result<Checked<'_>, SceneError> {
            Ok(*self)
        }
        fn scene(&self) -> &Scene {
            self.0
        }
        fn known_valid(&self) -> Option<Checked<'_>> {
            Some(*self)
        }
    }

    impl Validate for ValidScene {
        fn checked(&self) -> Result<Checked<'_>, SceneError> {
            Ok(Checked(&self.0))
        }
        fn scene(&self) -> &Scene {
            &self.0
        }
        fn known_valid(&self) -> Option<Checked<'_>> {
            Some(Checked(&self.0))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `without_control` claims validity without validating: every shipped example scene with
    /// a `[control]` (read from examples/scenes/) stays valid without it, checked by
    /// validating what it returns.
    #[test]
    fn a_scene_without_its_control_stays_valid() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
        let mut with_control = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let valid = ValidScene::from_file(&path).unwrap();
            if valid.control.is_none() {
                continue;
            }
            with_control += 1;
            let free = valid.without_control();
            assert!(free.control.is_none());
            free.validate()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
        assert!(
            with_control >= 3,
            "{with_control} example scenes have a control"
        );
    }

    /// A `ValidScene` read from text runs as the plain scene read from the same text: the
    /// moment history of a 50-step run bit for bit (the proof changes what is validated, not
    /// what is built).
    #[test]
    fn a_valid_scene_runs_as_the_plain_scene() {
        let mut scene = crate::catalogue::riser(4);
        scene.time.steps = 50;
        let text = scene.to_toml_string();
        let valid = ValidScene::from_toml_str(&text).unwrap();
        let plain = Scene::from_toml_str(&text).unwrap();
        let a = crate::moment_history(&valid).unwrap();
        let b = crate::moment_history(&plain).unwrap();
        assert_eq!(a.moment.len(), 51);
        assert!(a
            .moment
            .iter()
            .zip(&b.moment)
            .all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(a.moment.iter().any(|&m| m != 0.0));
    }
}

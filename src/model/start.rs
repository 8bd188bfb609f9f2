//! The state a chain's runs start from at t₀ = 0 (`[time] initial`, docs/conventions.md "The
//! start of a run"): the straight beam at rest (qⱼ = e₂, p = 0) or, for
//! `initial = "static"`, at rest in the static equilibrium of the steady loads, whose attitudes
//! the statics solve ([`crate::statics::set_static_start`]) and the chain keeps.

use std::sync::Arc;

use super::geometry::{e2, yi, zi};
use super::Chain;
use crate::base::Scalar;
use crate::error::{Error, ModelError, Result};
use crate::scene::Initial;

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// The state the scene asked its runs to start from (`[time] initial`).
    pub fn initial(&self) -> Initial {
        self.initial
    }

    /// Sets the static start's attitudes qⱼ(0), given as (x, y, z) per pendulum (a planar chain
    /// keeps (y, z)), and marks the chain as starting there.
    ///
    /// # Errors
    /// [`ModelError::StartSize`] for a count other than n, or an attitude that is not a finite
    /// unit vector (to 10⁻⁹); [`Error::NeedsSpatialModel`] for a planar chain given an x ≠ 0.
    pub fn set_static_start(&mut self, attitudes: &[[f64; 3]]) -> Result<()> {
        let bad = attitudes.iter().position(|q| {
            let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            !norm.is_finite() || (norm - 1.0).abs() > 1e-9
        });
        if attitudes.len() != self.n || bad.is_some() {
            return Err(ModelError::StartSize {
                n: self.n,
                got: attitudes.len(),
                pendulum: bad.map(|j| j + 1),
            }
            .into());
        }
        if DIM == 2 && attitudes.iter().any(|q| q[0] != 0.0) {
            return Err(Error::NeedsSpatialModel {
                key: "time.initial".to_string(),
            });
        }
        self.initial = Initial::Static;
        self.start = Some(Arc::from(attitudes));
        Ok(())
    }

    /// Whether the chain's runs start from a static equilibrium it holds.
    pub fn has_static_start(&self) -> bool {
        self.start.is_some()
    }

    /// The attitudes qⱼ(0) the runs start from: the static start's, or the straight beam's e₂.
    ///
    /// # Errors
    /// [`Error::StaticStartRefused`] for a chain of a scene with `initial = "static"` whose
    /// start was not set ([`crate::statics::set_static_start`]): it never starts straight
    /// silently.
    pub fn start_attitudes(&self) -> Result<Vec<[D; DIM]>> {
        let Some(start) = &self.start else {
            if self.initial == Initial::Static {
                return Err(Error::StaticStartRefused {
                    reason: "this chain was built without its static start \
                             (chainbeam::statics::set_static_start sets it)",
                });
            }
            return Ok(vec![e2::<D, DIM>(); self.n]);
        };
        let lift = |a: &[f64; 3]| {
            let mut q = [D::zero(); DIM];
            if DIM == 3 {
                q[0] = D::from(a[0]);
            }
            q[yi::<DIM>()] = D::from(a[1]);
            q[zi::<DIM>()] = D::from(a[2]);
            q
        };
        Ok(start.iter().map(lift).collect())
    }

    /// The tip target (Z, Ż)(0) the runs start from: for a static start of a vessel under
    /// thrust (x_v = 0, ẋ_v = 0), the prescribed (Z₀, 0); (0, 0) otherwise.
    pub fn start_tip_target(&self) -> [D; 2] {
        match (&self.start, self.thrust_drive()) {
            (Some(_), Some(_)) => self.prescribed_tip(0.0).unwrap_or([D::zero(); 2]),
            _ => [D::zero(); 2],
        }
    }
}

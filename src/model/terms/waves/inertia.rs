//! The waves' inertia load on the chain, the Froude-Krylov and added-mass force ρ_w (1 + C_a) A_o
//! c_k u̇_k at every node k ([`WaveInertia`]), and its tangent for a design parameter that moves
//! the nodes' coefficients ([`WaveInertiaTangent`]).

use super::*;

/// The Froude-Krylov + added-mass inertia load of the waves (docs/ocean.md, "The loads of the
/// water on the pipe"): the force
/// F_k = ρ_w (1 + C_a) A_o c_k u̇_k(t) e on node k along the mean direction e, a known function
/// of time and depth. Conservative in q: U = −Σ_k F_k · r_k with r_k = Σ_{j≤k} l_j q_j, so
/// U = −Σⱼ Gⱼ(t) e · qⱼ and ∂U/∂qⱼ = −Gⱼ(t) e (transverse components) with Gⱼ of
/// [`WaveField::inertia`]. It reads no parameter (its coefficient comes from `[pipe]`).
#[derive(Clone, Debug)]
pub struct WaveInertia {
    pub(crate) field: Arc<WaveField>,
}

impl WaveInertia {
    /// The load of `field`.
    pub fn new(field: Arc<WaveField>) -> Self {
        WaveInertia { field }
    }

    /// Its field.
    pub fn field(&self) -> &WaveField {
        &self.field
    }

    /// The direction e in the model's components (x only in the spatial model).
    #[inline]
    fn unit<const DIM: usize>(&self) -> [f64; DIM] {
        direction_in::<DIM>(&self.field)
    }
}

/// A wave field's horizontal direction (d_x, d_z) as a unit vector e in the model's
/// components: e_z = d_z, and e_x = d_x in the spatial model only (the planar model has no x).
#[inline]
fn direction_in<const DIM: usize>(field: &WaveField) -> [f64; DIM] {
    let [dx, dz] = field.direction();
    let mut e = [0.0; DIM];
    e[zi::<DIM>()] = dz;
    if DIM == 3 {
        e[0] = dx;
    }
    e
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for WaveInertia {
    fn name(&self) -> &'static str {
        "wave inertia"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let e = self.unit::<DIM>();
        let mut u = E::zero();
        let at = self.field.at(ctx.t);
        for (j, qj) in q.iter().enumerate() {
            let g = self.field.inertia_at(j, at);
            for d in 0..DIM {
                if e[d] != 0.0 {
                    u -= qj[d] * (g * e[d]);
                }
            }
        }
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        let e = self.unit::<DIM>();
        let at = self.field.at(ctx.t);
        // Every Gⱼ at the located time (WaveField::read_all: inertia_at's values).
        self.field.read_all(true, at, |j, g| {
            for d in 0..DIM {
                if e[d] != 0.0 {
                    out[j][d] -= E::from(g * e[d]);
                }
            }
        });
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, _p: Parameter) -> bool {
        false
    }
}

/// The derivative part of the waves' inertia load under a seeded parameter that moves the nodes'
/// inertia coefficients c_k (a segment's buoyancy diameter,
/// [`crate::Chain::set_node_quantities`]): the force of [`WaveInertia`] with Gⱼ replaced by
/// `seed` · ∂Gⱼ/∂θ, ∂Gⱼ/∂θ the inertia series of `field`
/// ([`WaveField::with_node_coefficients`] with the coefficients' derivatives), so that
/// [`WaveInertia`] and this term together load pendulum j with (Gⱼ + seed ∂Gⱼ/∂θ) e: the
/// dual number's derivative part with `seed` = ε. Zero in real arithmetic (the seed's real
/// part is 0).
#[derive(Clone, Debug)]
pub struct WaveInertiaTangent<D> {
    pub(crate) field: Arc<WaveField>,
    pub(crate) seed: D,
}

impl<D> WaveInertiaTangent<D> {
    /// The direction e in the model's components, as [`WaveInertia`]'s.
    #[inline]
    fn unit<const DIM: usize>(&self) -> [f64; DIM] {
        direction_in::<DIM>(&self.field)
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for WaveInertiaTangent<D> {
    fn name(&self) -> &'static str {
        "wave inertia (tangent)"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let e = self.unit::<DIM>();
        let mut u = E::zero();
        let at = self.field.at(ctx.t);
        let seed = E::embed(self.seed);
        for (j, qj) in q.iter().enumerate() {
            let g = self.field.inertia_at(j, at);
            for d in 0..DIM {
                if e[d] != 0.0 {
                    u -= qj[d] * (seed * (g * e[d]));
                }
            }
        }
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        let e = self.unit::<DIM>();
        let at = self.field.at(ctx.t);
        let seed = E::embed(self.seed);
        for (j, o) in out.iter_mut().enumerate() {
            let g = self.field.inertia_at(j, at);
            for d in 0..DIM {
                if e[d] != 0.0 {
                    o[d] -= seed * (g * e[d]);
                }
            }
        }
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, _p: Parameter) -> bool {
        false
    }
}

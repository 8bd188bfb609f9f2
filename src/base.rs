//! The words every layer of the crate shares, defined below all of them: the scalar type the
//! physics is written over, the tip condition, the physical parameters of a gradient, a step's
//! statistics. This module imports nothing of the crate, so the scene, the errors, the model and
//! the steppers can all name these types without importing one another.

use num_dual::DualNum;

/// The scalar type every model term is written over: `f64`, `Dual64`, `DualSVec64<N>`, … .
///
/// This is `num_dual::DualNum<Primitive = f64> + Copy` with the thread-safety bounds the
/// multistart code needs; it is implemented for every such type.
pub trait Scalar: DualNum<Primitive = f64> + Copy + Send + Sync + 'static {}
impl<T: DualNum<Primitive = f64> + Copy + Send + Sync + 'static> Scalar for T {}

/// What holds the tip's z coordinate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TipCondition {
    /// The tip is free (cantilever, riser).
    Free,
    /// The tip's z is locked by l(q) = Σ lᵢ e₃ᵀqᵢ = 0 (fixed-fixed, pinned-pinned; eq. 2.4.1).
    Locked,
    /// The tip's z is held where the vessel puts it: l(q) = Z(t), a known function of time
    /// (`support = "vessel"`, [`crate::model::VesselMotion`]).
    Prescribed,
    /// Reaction-force variant (eq. 3.2.1/3.2.2): the reaction λ_l cancels every force on the tip's
    /// z except the control, so m_n z̈_n = −u. Discretised as a rheonomic tip constraint
    /// l(q_k) = ζ_k whose target ζ follows the control by Störmer–Verlet (see [`crate::steppers::rattle`]).
    Reaction,
}

/// A physical parameter of the chain, for parameter derivatives (seeded with dual numbers or
/// differentiated by the adjoint).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Parameter {
    /// All interior spring constants k₂..kₙ, set to one common value.
    InteriorStiffness,
    /// The base spring k₁ (also the k₁ of the bending moment, eq. 3.1.3).
    BaseStiffness,
    /// The tip spring k_{n+1}.
    TipStiffness,
    /// All masses m₁..mₙ, set to one common value.
    Mass,
    /// The drag constant D (eq. 2.4.4).
    Drag,
    /// The z component F_z of the constant force of the `i`-th point load of the scene (0-based,
    /// in scene order): the thesis's F.
    LoadForce(usize),
    /// The x component F_x of the constant force of the `i`-th point load (spatial model only).
    LoadForceX(usize),
    /// The amplitude Aⱼ of harmonic `harmonic` of point load `load` (0-based, in scene order).
    LoadAmplitude {
        /// The load's index in the scene.
        load: usize,
        /// The harmonic's index in the load.
        harmonic: usize,
    },
    /// The phase φⱼ \[rad\] of harmonic `harmonic` of point load `load`.
    LoadPhase {
        /// The load's index in the scene.
        load: usize,
        /// The harmonic's index in the load.
        harmonic: usize,
    },
    /// The `speed` of the current's profile (`[loads.current]`: uniform, linear or power law;
    /// a table has none).
    CurrentSpeed,
    /// The top tension T \[N\] at the tip (`[loads] tension`).
    Tension,
    /// The axial (submerged) weight w \[N/m\] (`[loads] axial_weight`).
    AxialWeight,
    /// The drag coefficient C_d of the node-by-node Morison drag (`[pipe] drag_coefficient` with
    /// `drag_model = "morison"`).
    DragCoefficient,
    /// All joint dampers c_j \[N·m·s/rad\] at the joints with a spring, set to one common value
    /// (`[beam] joint_damping`; the torque −c_j θ̇_j, docs/conventions.md "Joint damping").
    JointDamping,
    /// The soil's p-y modulus at the mudline E₀ \[N/m²\] (`[soil] modulus`): every node's lateral
    /// spring k_i = E₀ aᵢ + E₁ bᵢ is affine in it (docs/conventions.md "Soil springs").
    SoilModulus,
    /// The spring k_{j+1} of interior joint `j` alone (1 ≤ j ≤ n − 1, the joint between
    /// pendulums j and j + 1, 1-based pendulums): a stack-up's flex joint away from the ends
    /// (`[[stackup.flex_joint]]`), whose torque −k_{j+1} s(q_{j}·q_{j+1}) it scales. The end
    /// springs are [`Parameter::BaseStiffness`] and [`Parameter::TipStiffness`].
    JointStiffness(usize),
    /// The vessel's mean offset Z₀ \[m\] (`[vessel] offset`, `support = "vessel"`): the top's
    /// prescribed z is Z(t) = ρ(t)(Z₀ + d_z X_w(t)) (and the prescribed part P(t) of a vessel
    /// under thrust, Z = P + x_v), so that ∂Z/∂Z₀ = ρ(t) and ∂Ż/∂Z₀ = ρ̇(t)
    /// ([`crate::model::VesselMotion`]).
    VesselOffset,
}

/// Statistics of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Newton iterations (linear solves) for λ.
    pub iterations: usize,
    /// Final max-norm constraint residual.
    pub residual: f64,
}

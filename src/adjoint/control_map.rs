//! Control parametrisations θ ↦ (u_0, …, u_N) with their transposes (docs/conventions.md).

use crate::base::Scalar;

/// A control parametrisation θ ↦ (u_0, …, u_N) with its transpose product.
pub trait ControlMap: Send + Sync {
    /// Number of parameters θ.
    fn n_params(&self) -> usize;
    /// Writes u_0..u_N (`u.len()` = N + 1) from θ.
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]);
    /// Accumulates θ̄ = (∂u/∂θ)ᵀ ū.
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]);
}

/// One constant force u for all k (1 parameter).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConstantControl;

impl ControlMap for ConstantControl {
    fn n_params(&self) -> usize {
        1
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        u.iter_mut().for_each(|x| *x = theta[0]);
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        theta_bar[0] += u_bar.iter().fold(D::zero(), |a, b| a + *b);
    }
}

/// One force per time t_k (N + 1 parameters; u_N only reaches p_N, thesis §3.3.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerStepControl {
    /// N.
    pub steps: usize,
}

impl ControlMap for PerStepControl {
    fn n_params(&self) -> usize {
        self.steps + 1
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        u.copy_from_slice(theta);
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        for (t, b) in theta_bar.iter_mut().zip(u_bar) {
            *t += *b;
        }
    }
}

/// Piecewise-constant control on a coarser grid (so long horizons are optimised with few
/// parameters): P = `pieces` values splitting the N effective steps evenly, piece j covering the
/// steps k = 0..N−1 with ⌊k·P/N⌋ = j, and u_N (which has no effect) taking the last piece
/// ([`crate::simulate::piece_index`]; the scene file's `kind = "piecewise"`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PiecewiseControl {
    /// N.
    pub steps: usize,
    /// Number of pieces P (1..=N; P = N is one piece per step).
    pub pieces: usize,
}

impl PiecewiseControl {
    fn piece(&self, k: usize) -> usize {
        crate::simulate::piece_index(k, self.steps, self.pieces)
    }
}

impl ControlMap for PiecewiseControl {
    fn n_params(&self) -> usize {
        self.pieces
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        for (k, x) in u.iter_mut().enumerate() {
            *x = theta[self.piece(k)];
        }
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        for (k, b) in u_bar.iter().enumerate() {
            theta_bar[self.piece(k)] += *b;
        }
    }
}

/// Any of the three built-in parametrisations (what a scene file can ask for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Parametrisation {
    /// [`ConstantControl`].
    Constant,
    /// [`PerStepControl`].
    PerStep(PerStepControl),
    /// [`PiecewiseControl`].
    Piecewise(PiecewiseControl),
}

impl ControlMap for Parametrisation {
    fn n_params(&self) -> usize {
        match self {
            Parametrisation::Constant => 1,
            Parametrisation::PerStep(p) => p.n_params(),
            Parametrisation::Piecewise(p) => p.n_params(),
        }
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        match self {
            Parametrisation::Constant => ConstantControl.controls(theta, u),
            Parametrisation::PerStep(p) => p.controls(theta, u),
            Parametrisation::Piecewise(p) => p.controls(theta, u),
        }
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        match self {
            Parametrisation::Constant => ConstantControl.transpose(u_bar, theta_bar),
            Parametrisation::PerStep(p) => p.transpose(u_bar, theta_bar),
            Parametrisation::Piecewise(p) => p.transpose(u_bar, theta_bar),
        }
    }
}

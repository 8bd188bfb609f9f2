//! The tape of the discrete adjoint: the forward states the reverse sweep reads, stored flat, with
//! the checkpointing strategies (docs/conventions.md), and what each forward step records for its adjoint.
//!
//! A step k → k+1 records, besides the state (q, p, λ, μ, tip target) at k+1, the half-step
//! momentum p_{k+½} and W = ∂p_{k+½}/∂c when the model has drag (without drag p_{k+½} does not
//! enter the adjoint and W = I): the reverse step then reads them instead of recomputing the
//! forward step's force and drag root.

use crate::base::Scalar;
use crate::model::BlockSym;
use crate::steppers::rattle::State;

/// How the reverse sweep gets the forward states.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Checkpointing {
    /// Every state is kept (memory O(nN), no recomputation).
    StoreAll,
    /// Every K-th state is kept, segments are recomputed (memory O(n(N/K + K))).
    Every(usize),
    /// K = ⌈√N⌉: memory O(n√N), one extra forward sweep.
    Sqrt,
    /// Store every state while the trajectory fits in [`AUTO_MEMORY_BUDGET`] bytes (no
    /// recomputation: the gradient then costs one forward and one reverse sweep), otherwise
    /// K = ⌈√N⌉ (memory O(n√N), one extra forward sweep).
    #[default]
    Auto,
}

/// Memory for stored states below which [`Checkpointing::Auto`] keeps every state: 256 MiB.
pub const AUTO_MEMORY_BUDGET: usize = 256 << 20;

impl Checkpointing {
    pub(crate) fn interval(self, steps: usize, state_bytes: usize) -> usize {
        match self {
            Checkpointing::StoreAll => 1,
            Checkpointing::Every(k) => k.clamp(1, steps.max(1)),
            Checkpointing::Auto
                if (steps + 1).saturating_mul(state_bytes) <= AUTO_MEMORY_BUDGET =>
            {
                1
            }
            Checkpointing::Auto | Checkpointing::Sqrt => {
                ((steps as f64).sqrt().ceil() as usize).max(1)
            }
        }
    }
}

/// Value and gradients from one forward and one reverse sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct AdjointResult<D> {
    /// The objective.
    pub value: D,
    /// ∂J/∂u_k, k = 0..=N (the z components of a 2-axis control).
    pub control_gradient: Vec<D>,
    /// ∂J/∂u_{x,k}, k = 0..=N, for a 2-axis control (empty for a 1-axis control).
    pub control_gradient_x: Vec<D>,
    /// ∂J/∂θ for the requested physical parameters, in request order.
    pub parameter_gradient: Vec<D>,
    /// Bytes of forward states held at the peak (checkpoints plus the segment buffer).
    pub state_bytes: usize,
}

/// Forward states stored flat (one allocation per array, sized once), for the reverse sweep.
pub(crate) struct StateStore<D, const DIM: usize> {
    n: usize,
    nc: usize,
    records_half_step: bool,
    q: Vec<[D; DIM]>,
    p: Vec<[D; DIM]>,
    lambda: Vec<D>,
    mu: Vec<D>,
    /// The predictor's gaps of each state ([`crate::steppers::rattle::Multipliers::gaps`],
    /// 2 nc per state) when the chain keeps them, so that a segment recomputed from a
    /// checkpoint repeats the forward sweep's arithmetic bit for bit; empty otherwise.
    gaps: Vec<D>,
    keeps_gaps: bool,
    /// Whether the state had gaps (only when `keeps_gaps`).
    has_gaps: Vec<bool>,
    /// Whether the state has multipliers (false for an initial state; λ, μ are stored as zeros).
    has_multipliers: Vec<bool>,
    tip: Vec<[D; 2]>,
    phalf: Vec<[D; DIM]>,
    w: Vec<BlockSym<D, DIM>>,
}

/// A stored state, borrowed, with the half-step record of the step that produced it (empty
/// slices when not recorded).
pub(crate) struct StateView<'a, D, const DIM: usize> {
    pub q: &'a [[D; DIM]],
    pub p: &'a [[D; DIM]],
    /// λ of the step into this state (zeros for an initial state).
    pub lambda: &'a [D],
    /// μ of the step into this state (zeros for an initial state).
    pub mu: &'a [D],
    pub tip: [D; 2],
    /// p_{k−½} of the step into this state.
    pub phalf: &'a [[D; DIM]],
    /// W of the step into this state.
    pub w: &'a [BlockSym<D, DIM>],
}

impl<D: Scalar, const DIM: usize> StateStore<D, DIM> {
    /// Room for `capacity` states of n pendulums with nc multipliers; `records_half_step` when
    /// the model has drag, `keeps_gaps` when its states carry the predictor's gaps.
    pub(super) fn new(
        n: usize,
        nc: usize,
        capacity: usize,
        (records_half_step, keeps_gaps): (bool, bool),
    ) -> Self {
        let half = if records_half_step { capacity * n } else { 0 };
        let gaps = if keeps_gaps { capacity * 2 * nc } else { 0 };
        StateStore {
            n,
            nc,
            records_half_step,
            q: Vec::with_capacity(capacity * n),
            p: Vec::with_capacity(capacity * n),
            lambda: Vec::with_capacity(capacity * nc),
            mu: Vec::with_capacity(capacity * nc),
            gaps: Vec::with_capacity(gaps),
            keeps_gaps,
            has_gaps: Vec::with_capacity(if keeps_gaps { capacity } else { 0 }),
            has_multipliers: Vec::with_capacity(capacity),
            tip: Vec::with_capacity(capacity),
            phalf: Vec::with_capacity(half),
            w: Vec::with_capacity(half),
        }
    }

    /// Bytes of one stored state.
    pub(super) fn state_bytes(
        n: usize,
        nc: usize,
        (records_half_step, keeps_gaps): (bool, bool),
    ) -> usize {
        let blocks = if records_half_step { 3 } else { 2 };
        let w = if records_half_step {
            n * std::mem::size_of::<BlockSym<D, DIM>>()
        } else {
            0
        };
        let gaps = if keeps_gaps { 2 * nc } else { 0 };
        (blocks * n * DIM + 2 * nc + gaps + 2) * std::mem::size_of::<D>() + w
    }

    /// Appends a state and the half-step record (p_{k−½}, W) of the step that produced it (any
    /// slices at k = 0, where there is none; ignored unless the store records half steps).
    pub(super) fn push(&mut self, s: &State<D, DIM>, half: (&[[D; DIM]], &[BlockSym<D, DIM>])) {
        self.q.extend_from_slice(&s.q);
        self.p.extend_from_slice(&s.p);
        match &s.multipliers {
            Some(m) => {
                self.lambda.extend_from_slice(&m.lambda);
                self.mu.extend_from_slice(&m.mu);
            }
            None => {
                self.lambda.extend(std::iter::repeat_n(D::zero(), self.nc));
                self.mu.extend(std::iter::repeat_n(D::zero(), self.nc));
            }
        }
        if self.keeps_gaps {
            // A state without gaps (the initial state, or the first step's) keeps zeros and
            // is loaded without them.
            match &s.multipliers {
                Some(m) if m.gaps.len() == 2 * self.nc => self.gaps.extend_from_slice(&m.gaps),
                _ => self
                    .gaps
                    .extend(std::iter::repeat_n(D::zero(), 2 * self.nc)),
            }
            self.has_gaps
                .push(s.multipliers.as_ref().is_some_and(|m| !m.gaps.is_empty()));
        }
        self.has_multipliers.push(s.multipliers.is_some());
        self.tip.push(s.tip_target);
        if self.records_half_step {
            if half.0.is_empty() {
                // The initial state: no step produced it.
                let z = [D::zero(); DIM];
                self.phalf.extend(std::iter::repeat_n(z, self.n));
                self.w.extend(std::iter::repeat_n(BlockSym::zero(), self.n));
            } else {
                self.phalf.extend_from_slice(half.0);
                self.w.extend_from_slice(half.1);
            }
        }
    }

    /// Forgets every state (keeps the memory).
    pub(super) fn clear(&mut self) {
        self.q.clear();
        self.p.clear();
        self.lambda.clear();
        self.mu.clear();
        self.gaps.clear();
        self.has_gaps.clear();
        self.has_multipliers.clear();
        self.tip.clear();
        self.phalf.clear();
        self.w.clear();
    }

    /// Number of stored states.
    pub(super) fn len(&self) -> usize {
        self.tip.len()
    }

    /// Number of states the memory holds.
    pub(super) fn capacity(&self) -> usize {
        self.tip.capacity()
    }

    /// The i-th stored state.
    pub(super) fn view(&self, i: usize) -> StateView<'_, D, DIM> {
        let (n, nc) = (self.n, self.nc);
        let r = if self.records_half_step {
            i * n..(i + 1) * n
        } else {
            0..0
        };
        StateView {
            q: &self.q[i * n..(i + 1) * n],
            p: &self.p[i * n..(i + 1) * n],
            lambda: &self.lambda[i * nc..(i + 1) * nc],
            mu: &self.mu[i * nc..(i + 1) * nc],
            tip: self.tip[i],
            phalf: &self.phalf[r.clone()],
            w: &self.w[r],
        }
    }

    /// Loads the i-th stored state into `s` (to recompute a segment from it).
    pub(super) fn load(&self, i: usize, s: &mut State<D, DIM>) {
        let v = self.view(i);
        s.q.copy_from_slice(v.q);
        s.p.copy_from_slice(v.p);
        if self.has_multipliers[i] {
            let m = s.multipliers_mut(self.nc);
            m.lambda.copy_from_slice(v.lambda);
            m.mu.copy_from_slice(v.mu);
            m.gaps.clear();
            if self.keeps_gaps && self.has_gaps[i] {
                let g = 2 * self.nc;
                m.gaps.extend_from_slice(&self.gaps[i * g..(i + 1) * g]);
            }
        } else {
            s.multipliers = None;
        }
        s.tip_target = v.tip;
    }
}

//! The interior point of the box QP (module docs, "The step"; Rao, Wright, Rawlings 1998, the
//! scheme of HPIPM): the multipliers z, z′ ≥ 0 of the lower and upper bounds, their steps, and
//! the barrier terms a Riccati pass adds (Q_uu += z/s + z′/s′, l_u += −τ/s + τ/s′).

/// The controls at the QP's current point: v_i = ū_i + δv_i for each decision i = k m + a
/// (m controls per stage: a = 0 the z component ū_k, a = 1 the x component ū_{x,k} of a
/// 2-axis control), which stages have a decision, and the box (on every component).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Controls<'a> {
    /// ū_k, the nominal's controls (z components).
    pub nominal: &'a [f64],
    /// ū_{x,k} of a 2-axis control (empty otherwise).
    pub nominal_x: &'a [f64],
    /// δv_i.
    pub dv: &'a [f64],
    /// Per stage.
    pub free: &'a [bool],
    pub lower: f64,
    pub upper: f64,
}

impl Controls<'_> {
    /// Controls per stage m.
    #[inline]
    fn per_stage(&self) -> usize {
        if self.nominal_x.is_empty() {
            1
        } else {
            2
        }
    }

    /// v_i.
    #[inline]
    fn v(&self, i: usize) -> f64 {
        let m = self.per_stage();
        let (k, a) = (i / m, i % m);
        let u = if a == 0 {
            self.nominal[k]
        } else {
            self.nominal_x[k]
        };
        u + self.dv[i]
    }

    /// Whether decision i's stage has a decision.
    #[inline]
    fn free(&self, i: usize) -> bool {
        self.free[i / self.per_stage()]
    }
}

/// The primal and dual step lengths that keep 0.5 % of the distance to the boundary.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StepLengths {
    pub primal: f64,
    pub dual: f64,
}

/// The multipliers and the barrier terms (sized once per problem).
#[derive(Clone, Debug)]
pub(crate) struct InteriorPoint {
    zl: Vec<f64>,
    zh: Vec<f64>,
    dzl: Vec<f64>,
    dzh: Vec<f64>,
    /// The barrier curvature z/s + z′/s′ and gradient −τ/s + τ/s′ per decision.
    pub quu: Vec<f64>,
    pub lu: Vec<f64>,
    /// Whether the next Riccati pass adds them (and drops the box of its stage QPs).
    pub on: bool,
}

impl InteriorPoint {
    /// For `decisions` controls (m per stage of the horizon).
    pub(super) fn new(decisions: usize) -> Self {
        InteriorPoint {
            zl: vec![0.0; decisions],
            zh: vec![0.0; decisions],
            dzl: vec![0.0; decisions],
            dzh: vec![0.0; decisions],
            quu: vec![0.0; decisions],
            lu: vec![0.0; decisions],
            on: false,
        }
    }

    /// Centred multipliers: every finite bound's complementarity s·z = τ₀, i.e.
    /// z = τ₀/max(s, κ) (0 for an infinite bound).
    pub(super) fn centre(&mut self, c: &Controls<'_>, tau0: f64, kappa: f64) {
        let (lo, hi) = (c.lower, c.upper);
        for k in 0..self.zl.len() {
            let u = c.v(k);
            self.zl[k] = if lo.is_finite() {
                tau0 / (u - lo).max(kappa)
            } else {
                0.0
            };
            self.zh[k] = if hi.is_finite() {
                tau0 / (hi - u).max(kappa)
            } else {
                0.0
            };
        }
    }

    /// The complementarity gap Σ (v − lo) z + (hi − v) z′ over the free stages.
    pub(super) fn complementarity(&self, c: &Controls<'_>) -> f64 {
        let (lo, hi) = (c.lower, c.upper);
        let mut gap = 0.0;
        for k in 0..self.zl.len() {
            if c.free(k) {
                let u = c.v(k);
                if lo.is_finite() {
                    gap += (u - lo) * self.zl[k];
                }
                if hi.is_finite() {
                    gap += (hi - u) * self.zh[k];
                }
            }
        }
        gap
    }

    /// The barrier terms of the next Riccati pass: Q_uu += z/s + z′/s′, l_u += −τ/s + τ/s′.
    pub(super) fn barrier_terms(&mut self, c: &Controls<'_>, tau: f64) {
        let (lo, hi) = (c.lower, c.upper);
        for k in 0..self.zl.len() {
            let (mut qs, mut ls) = (0.0, 0.0);
            if c.free(k) {
                let u = c.v(k);
                if lo.is_finite() {
                    let s = u - lo;
                    qs += self.zl[k] / s;
                    ls -= tau / s;
                }
                if hi.is_finite() {
                    let s = hi - u;
                    qs += self.zh[k] / s;
                    ls += tau / s;
                }
            }
            self.quu[k] = qs;
            self.lu[k] = ls;
        }
    }

    /// The multipliers' steps along the direction `dir` (in `dzl`, `dzh`) and the primal and
    /// dual step lengths that keep 0.5 % of the distance to the boundary.
    pub(super) fn fraction_to_boundary(
        &mut self,
        c: &Controls<'_>,
        dir: &[f64],
        tau: f64,
    ) -> StepLengths {
        let (lo, hi) = (c.lower, c.upper);
        let (mut ap, mut ad) = (1.0f64, 1.0f64);
        for k in 0..self.zl.len() {
            if !c.free(k) {
                continue;
            }
            let u = c.v(k);
            let dx = dir[k];
            if lo.is_finite() {
                let s = u - lo;
                if dx < 0.0 {
                    ap = ap.min(-0.995 * s / dx);
                }
                let dzl = tau / s - self.zl[k] - self.zl[k] / s * dx;
                if dzl < 0.0 {
                    ad = ad.min(-0.995 * self.zl[k] / dzl);
                }
                self.dzl[k] = dzl;
            }
            if hi.is_finite() {
                let s = hi - u;
                if dx > 0.0 {
                    ap = ap.min(0.995 * s / dx);
                }
                let dzh = tau / s - self.zh[k] + self.zh[k] / s * dx;
                if dzh < 0.0 {
                    ad = ad.min(-0.995 * self.zh[k] / dzh);
                }
                self.dzh[k] = dzh;
            }
        }
        StepLengths {
            primal: ap,
            dual: ad,
        }
    }

    /// z += α_d Δz, z′ += α_d Δz′ (the free stages of `c`).
    pub(super) fn step_multipliers(&mut self, c: &Controls<'_>, ad: f64) {
        let (lo, hi) = (c.lower, c.upper);
        for k in 0..self.zl.len() {
            if c.free(k) {
                if lo.is_finite() {
                    self.zl[k] += ad * self.dzl[k];
                }
                if hi.is_finite() {
                    self.zh[k] += ad * self.dzh[k];
                }
            }
        }
    }

    /// The bound a control the interior point left within 10⁻⁶ of the box width (`width`) of
    /// it goes onto, when its multiplier exceeds the slack (then bounds are met with equality,
    /// not approached): stage k at the point `c`.
    pub(super) fn snap(&self, c: &Controls<'_>, k: usize, width: f64) -> Option<f64> {
        let (lo, hi) = (c.lower, c.upper);
        let v = c.v(k);
        if lo.is_finite() && v - lo <= 1e-6 * width && self.zl[k] > v - lo {
            Some(lo)
        } else if hi.is_finite() && hi - v <= 1e-6 * width && self.zh[k] > hi - v {
            Some(hi)
        } else {
            None
        }
    }
}

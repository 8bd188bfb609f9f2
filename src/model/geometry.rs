//! Geometry of the chain written once over [`Scalar`]: the undeformed direction, dot and cross
//! products, the spring function s(x) = arccos(x)/√(1 − x²) (thesis eq. 2.2.1) and the joint angle.

use crate::base::Scalar;

/// How many derivative-only Newton updates a solve over `D` needs after its real part has
/// converged: `D::NDERIV` (0 for `f64`, 1 for first-order duals, 2 for second-order or nested
/// duals). Newton on dual numbers converges only linearly in the derivative parts; each such
/// update makes one more order of derivatives exact (the implicit function theorem).
#[inline]
pub(crate) fn derivative_updates<D: Scalar>() -> usize {
    D::NDERIV
}

/// Index of the z component in a `DIM`-vector (planar: 1, spatial: 2).
#[inline]
pub const fn zi<const DIM: usize>() -> usize {
    DIM - 1
}

/// Index of the y component in a `DIM`-vector.
#[inline]
pub const fn yi<const DIM: usize>() -> usize {
    DIM - 2
}

/// The undeformed direction e₂ = (0, 1, 0) (planar: (1, 0)).
#[inline]
pub(crate) fn e2<D: Scalar, const DIM: usize>() -> [D; DIM] {
    let mut v = [D::zero(); DIM];
    v[yi::<DIM>()] = D::one();
    v
}

/// Dot product.
#[inline(always)]
pub(crate) fn dot<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    let mut s = a[0] * b[0];
    for i in 1..DIM {
        s += a[i] * b[i];
    }
    s
}

/// ‖a × b‖², computed from the cross product's components (exact to relative precision even
/// when a ∥ b, unlike ‖a‖²‖b‖² − (a·b)²).
#[inline]
pub(crate) fn cross_norm2<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    if DIM == 2 {
        let c = a[0] * b[1] - a[1] * b[0];
        c * c
    } else {
        let cx = a[1] * b[2] - a[2] * b[1];
        let cy = a[2] * b[0] - a[0] * b[2];
        let cz = a[0] * b[1] - a[1] * b[0];
        cx * cx + cy * cy + cz * cz
    }
}

/// Below this w = (1 − x)/2 the series of [`spring_s`] is used (θ ≲ 11.5°); 10 terms give
/// round-off accuracy there (c₁₀ w¹⁰ < 3·10⁻²¹).
const S_SERIES_MAX_W: f64 = 0.01;

/// Taylor coefficients of s around x = 1 in w = (1 − x)/2: c_k = 4ᵏ(k!)²/(2k+1)!, i.e.
/// c_k = c_{k−1}·2k/(2k+1).
const C: [f64; 10] = [
    1.0,
    2.0 / 3.0,
    8.0 / 15.0,
    16.0 / 35.0,
    128.0 / 315.0,
    256.0 / 693.0,
    1024.0 / 3003.0,
    2048.0 / 6435.0,
    32768.0 / 109395.0,
    65536.0 / 230945.0,
];

/// s(x) = arccos(x)/√(1 − x²) = θ/sin θ with x = cos θ (thesis eq. 2.2.1 and the line before it).
///
/// s is analytic at x = 1 (θ/sin θ is even in θ, hence analytic in cos θ): near x = 1 it is
/// evaluated by its Taylor series s = Σₖ cₖ wᵏ, w = (1 − x)/2, cₖ = 4ᵏ(k!)²/(2k+1)!, so that the
/// value and all its derivatives, in dual arithmetic too, are finite and exact at the straight
/// configuration (s(1) = 1, s'(1) = −1/3). The series also covers x slightly above 1 (round-off).
///
/// For first-order dual numbers (`D::NDERIV == 1`) s is evaluated on the real part with its
/// derivative ([`spring_s_ds`]) and lifted, s(x) = s(re x) + s′(re x)(x − re x): exact for
/// them, with the real part bit for bit that of the `f64` evaluation, and one dual operation
/// instead of the series' ten (the stage Jacobians of [`crate::ocp`] evaluate it 22 times per
/// dual step).
#[inline]
pub fn spring_s<D: Scalar>(x: D) -> D {
    if D::NDERIV == 1 {
        let (s, ds) = spring_s_ds(x.re());
        return lift_first_order(x, s, ds);
    }
    let w = (-x + 1.0) * 0.5;
    if w.re() <= S_SERIES_MAX_W {
        // Horner on c_k, c_k = c_{k-1} * 2k/(2k+1).
        let mut s = D::from(C[9]);
        for &c in C[..9].iter().rev() {
            s = s * w + c;
        }
        s
    } else {
        x.acos() * (-(x * x) + 1.0).sqrt().recip()
    }
}

/// f(x) for a first-order dual x from f and f′ at its real part: f(re x) + f′(re x)(x − re x).
/// The real part is f(re x) exactly (x − re x has real part 0).
#[inline]
fn lift_first_order<D: Scalar>(x: D, f: f64, df: f64) -> D {
    debug_assert_eq!(D::NDERIV, 1);
    (x - x.re()) * df + f
}

/// s(x) and s′(x) together (for Jacobian products of the spring force, eq. 2.2.3 differentiated).
/// Near x = 1 both come from the series of [`spring_s`] (s′(1) = −1/3); elsewhere
/// s′ = (x s − 1)/(1 − x²).
#[inline]
pub fn spring_s_ds<D: Scalar>(x: D) -> (D, D) {
    let w = (-x + 1.0) * 0.5;
    if w.re() <= S_SERIES_MAX_W {
        let mut s = D::from(C[9]);
        for &c in C[..9].iter().rev() {
            s = s * w + c;
        }
        // ds/dw = Σ k c_k w^{k−1} (the exact derivative of the same polynomial); dw/dx = −1/2
        let mut ds = D::from(9.0 * C[9]);
        for k in (1..9).rev() {
            ds = ds * w + (k as f64) * C[k];
        }
        (s, ds * (-0.5))
    } else {
        let s = x.acos() * (-(x * x) + 1.0).sqrt().recip();
        let ds = (x * s - 1.0) * (-(x * x) + 1.0).recip();
        (s, ds)
    }
}

/// θ² = arccos(x)² for x = cos θ, the spring energy's angle as a function of x = a·b (so that its
/// gradient is exactly the spring force −s(x)·b of eq. 2.2.3, also off the unit sphere, where
/// the constraint forces absorb the normal components).
///
/// Near x = 1, arccos(x)² = (1 − x)(1 + x) s(x)² with the series of [`spring_s`], so that the value
/// and its derivatives are finite and exact at θ = 0; elsewhere arccos(x)².
#[inline]
pub fn arccos_squared<D: Scalar>(x: D) -> D {
    let w = (-x + 1.0) * 0.5;
    if w.re() <= S_SERIES_MAX_W {
        let s = spring_s(x);
        (-x + 1.0) * (x + 1.0) * s * s
    } else {
        let t = x.acos();
        t * t
    }
}

/// The squared joint angle θ² = ∠(a, b)² of two unit vectors, accurate at small and large angles
/// and differentiable at θ = 0 (used for the spring energy ½ k θ², eq. 2.2.2).
///
/// For a·b > 0, θ = arcsin(‖a×b‖) and θ² = y A(y)², y = ‖a×b‖², A(y) = arcsin(√y)/√y, which is
/// analytic in y (series near 0). For a·b ≤ 0, θ = atan2(‖a×b‖, a·b).
pub fn joint_angle_squared<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    let x = dot(a, b);
    let y = cross_norm2(a, b);
    if x.re() > 0.0 {
        let amp = if y.re() <= 0.01 {
            // a_k = a_{k-1} (2k-1)^2 / (2k (2k+1)).
            const A: [f64; 10] = [
                1.0,
                1.0 / 6.0,
                3.0 / 40.0,
                5.0 / 112.0,
                35.0 / 1152.0,
                63.0 / 2816.0,
                231.0 / 13312.0,
                143.0 / 10240.0,
                6435.0 / 557056.0,
                12155.0 / 1245184.0,
            ];
            let mut s = D::from(A[9]);
            for &c in A[..9].iter().rev() {
                s = s * y + c;
            }
            s
        } else {
            let r = y.sqrt();
            r.asin() * r.recip()
        };
        y * amp * amp
    } else {
        let th = y.sqrt().atan2(x);
        th * th
    }
}

//! The linear dispersion relation of surface gravity waves in water of depth d:
//! ω² = g k tanh(k d) (DNV-RP-C205 eq. 3.2.7).

/// The wavenumber k \[rad/m\] of angular frequency ω \[rad/s\] in water of depth d \[m\] under
/// gravity g \[m/s²\]: the root of ω² = g k tanh(k d), solved by Newton in x = k d on
/// F(x) = x tanh x − ω² d/g from Eckart's approximation x₀ = ν/√(tanh ν), ν = ω² d/g (within
/// 5 % everywhere), to a relative step of 4 ε. `depth = ∞` gives the deep-water k = ω²/g;
/// ω ≤ 0 gives 0. Uses `libm`'s tanh: the same bits on every machine.
///
/// Limits: k d → ∞ gives k → ω²/g, k d → 0 gives k → ω/√(g d) (tested in `tests/fatigue/waves.rs`).
pub fn wavenumber(omega: f64, depth: f64, g: f64) -> f64 {
    if omega <= 0.0 {
        return 0.0;
    }
    let k_deep = omega * omega / g;
    if depth.is_infinite() {
        return k_deep;
    }
    let nu = k_deep * depth;
    // Beyond ν = 40 tanh ν = 1 to within 2e-35: the deep-water root is exact in f64.
    if nu > 40.0 {
        return k_deep;
    }
    // A depth so small that ν is subnormal or 0 (where ν/√(tanh ν) would be 0/0): the
    // shallow-water root k = ω/√(g d), exact to round-off there (tanh x = x to ε below 10⁻⁸).
    if nu < f64::MIN_POSITIVE {
        return omega / (g * depth).sqrt();
    }
    let mut x = nu / libm::tanh(nu).sqrt();
    for _ in 0..60 {
        let t = libm::tanh(x);
        let f = x * t - nu;
        let df = t + x * (1.0 - t * t);
        let dx = f / df;
        x -= dx;
        if dx.abs() <= 4.0 * f64::EPSILON * x {
            break;
        }
    }
    x / depth
}

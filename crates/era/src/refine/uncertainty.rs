//! Standard deviations of natural frequency and damping ratio from the Gauss–Newton
//! covariance of the pole parameters.
//!
//! At the optimum the covariance of the nonlinear parameters, with the linear ones
//! eliminated, is `σ² (JᵀJ)⁻¹` with Kaufman's projected Jacobian `J = −P⊥ (∂Φ) c`
//! (its normal matrix is exactly the Schur complement of the full problem's, see Golub &
//! Pereyra 2003, §3), and `σ² = ‖r‖²/(m − n)` from the residual (`m` real observations,
//! `n` real unknowns, linear ones included). It is propagated to
//! `f = |s|/2π` and `ζ = σ/|s|` (`s = −σ + jω_d`) to first order:
//!
//! ```text
//! ∂f/∂σ = σ/(2π|s|),  ∂f/∂ω_d = ω_d/(2π|s|),  ∂ζ/∂σ = ω_d²/|s|³,  ∂ζ/∂ω_d = −σω_d/|s|³
//! ```
//!
//! times `dσ/dx = σ` when the damping parameter is `x = ln σ`.

use super::model::PoleParameters;
use num_complex::Complex64;
use std::f64::consts::PI;

/// `(std f [Hz], std ζ)` of pole `s` from the 2 × 2 covariance of its parameters.
pub(crate) fn mode_std(s: Complex64, parameters: PoleParameters, cov: [[f64; 2]; 2]) -> (f64, f64) {
    let sigma = -s.re;
    let wd = s.im;
    let wn = s.norm();
    let dsigma_dx = if parameters.log_damping { sigma } else { 1.0 };
    let gf = [sigma / (2.0 * PI * wn) * dsigma_dx, wd / (2.0 * PI * wn)];
    let gz = [wd * wd / wn.powi(3) * dsigma_dx, -sigma * wd / wn.powi(3)];
    let quad = |g: [f64; 2]| {
        let v = g[0] * (cov[0][0] * g[0] + cov[0][1] * g[1])
            + g[1] * (cov[1][0] * g[0] + cov[1][1] * g[1]);
        if v >= 0.0 {
            v.sqrt()
        } else {
            f64::NAN
        }
    };
    (quad(gf), quad(gz))
}

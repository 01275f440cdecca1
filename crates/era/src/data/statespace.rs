//! State-space models `x' = A x + B u`, `y = C x + D u`, in discrete or continuous time,
//! and the zero-order-hold conversions between them (docs/src/design.md §1.10).
//!
//! `c2d` uses the matrix exponential of the augmented matrix `[[A, B], [0, 0]]·Ts`.
//! `faer` has no matrix exponential, so `expm` is written here: Higham's (2005)
//! scaling-and-squaring with the degree-13 Padé approximant, every product and solve by
//! `faer`. `d2c` takes the principal logarithm through the eigendecomposition of `A`
//! (diagonalisable models, which ERA's distinct poles give) and then checks itself by
//! converting back.

use crate::error::{EraError, Result};
use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;
use num_complex::Complex64;

use crate::linalg::eigen::balanced_eigen;
use crate::linalg::expm::expm;

/// Continuous or discrete time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeDomain {
    /// `x[k+1] = A x[k] + B u[k]` with samples `sample_time_s` apart.
    Discrete {
        /// Sample time, s.
        sample_time_s: f64,
    },
    /// `ẋ = A x + B u`.
    Continuous,
}

/// A linear time-invariant state-space model.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// State matrix, n×n.
    pub a: Mat<f64>,
    /// Input matrix, n×p.
    pub b: Mat<f64>,
    /// Output matrix, q×n.
    pub c: Mat<f64>,
    /// Direct feed-through, q×p.
    pub d: Mat<f64>,
    /// Time domain.
    pub domain: TimeDomain,
}

impl StateSpace {
    /// Wraps matrices after checking that their shapes agree.
    ///
    /// # Panics
    /// On inconsistent shapes (a programmer error).
    #[track_caller]
    pub fn new(a: Mat<f64>, b: Mat<f64>, c: Mat<f64>, d: Mat<f64>, domain: TimeDomain) -> Self {
        let n = a.nrows();
        assert_eq!(a.ncols(), n, "A must be square");
        assert_eq!(b.nrows(), n, "B rows must equal states");
        assert_eq!(c.ncols(), n, "C columns must equal states");
        assert_eq!(d.nrows(), c.nrows(), "D rows must equal outputs");
        assert_eq!(d.ncols(), b.ncols(), "D columns must equal inputs");
        StateSpace { a, b, c, d, domain }
    }
    /// States `n`.
    pub fn states(&self) -> usize {
        self.a.nrows()
    }
    /// Outputs `q`.
    pub fn outputs(&self) -> usize {
        self.c.nrows()
    }
    /// Inputs `p`.
    pub fn inputs(&self) -> usize {
        self.b.ncols()
    }
    /// Sample time, when discrete.
    pub fn sample_time_s(&self) -> Option<f64> {
        match self.domain {
            TimeDomain::Discrete { sample_time_s } => Some(sample_time_s),
            TimeDomain::Continuous => None,
        }
    }
    /// Eigenvalues of `A` (poles).
    ///
    /// # Errors
    /// [`EraError::Numerical`] when the eigen solver does not converge.
    pub fn poles(&self) -> Result<Vec<Complex64>> {
        Ok(balanced_eigen(&self.a)?.0)
    }

    /// Zero-order-hold discretisation, `[[Ad, Bd], [0, I]] = exp([[A, B], [0, 0]]·Ts)`.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for a non-positive sample time, or when the model
    /// is already discrete.
    pub fn c2d(&self, sample_time_s: f64) -> Result<StateSpace> {
        if self.domain != TimeDomain::Continuous {
            return Err(EraError::InvalidParameter {
                name: "time_domain",
                value: "discrete".into(),
                reason: "c2d needs a continuous model".into(),
            });
        }
        positive_sample_time(sample_time_s)?;
        let (n, p) = (self.states(), self.inputs());
        let mut aug = Mat::<f64>::zeros(n + p, n + p);
        for i in 0..n {
            for j in 0..n {
                aug[(i, j)] = self.a[(i, j)] * sample_time_s;
            }
            for j in 0..p {
                aug[(i, n + j)] = self.b[(i, j)] * sample_time_s;
            }
        }
        let e = expm(&aug);
        let ad = Mat::from_fn(n, n, |i, j| e[(i, j)]);
        let bd = Mat::from_fn(n, p, |i, j| e[(i, n + j)]);
        Ok(StateSpace::new(
            ad,
            bd,
            self.c.clone(),
            self.d.clone(),
            TimeDomain::Discrete { sample_time_s },
        ))
    }

    /// Zero-order-hold inverse (docs/src/design.md §1.10): `Ac = log(Ad)/Ts` and
    /// `Bc = Ac (Ad − I)⁻¹ Bd`, both evaluated as `V f(Λ) V⁻¹` on the eigendecomposition
    /// `Ad = V Λ V⁻¹` with `f(λ) = ln λ / Ts` and `f(λ) = ln λ / (Ts (λ − 1))` (→ `1/Ts`
    /// at `λ = 1`). The result is converted back with [`StateSpace::c2d`] and must
    /// reproduce `Ad`, `Bd` to 1e-8 relative.
    ///
    /// # Errors
    /// [`EraError::NoRealLogarithm`] for a pole at zero or on the negative real axis;
    /// [`EraError::UnreliableContinuous`] when the model is not reliably diagonalisable.
    pub fn d2c(&self) -> Result<StateSpace> {
        let TimeDomain::Discrete { sample_time_s: ts } = self.domain else {
            return Err(EraError::InvalidParameter {
                name: "time_domain",
                value: "continuous".into(),
                reason: "d2c needs a discrete model".into(),
            });
        };
        let (lambda, v) = balanced_eigen(&self.a)?;
        for z in &lambda {
            let on_negative_axis = z.im.abs() <= 1e-14 * z.norm() && z.re <= 0.0;
            if z.norm() == 0.0 || on_negative_axis {
                return Err(EraError::NoRealLogarithm { re: z.re, im: z.im });
            }
        }
        let v_inv = v.partial_piv_lu().inverse();
        let log_over_ts: Vec<Complex64> = lambda.iter().map(|z| z.ln() / ts).collect();
        let input_factor: Vec<Complex64> = lambda
            .iter()
            .map(|z| {
                let d = z - 1.0;
                if d.norm() < 1e-12 {
                    Complex64::new(1.0 / ts, 0.0)
                } else {
                    z.ln() / (d * ts)
                }
            })
            .collect();
        let ac = spectral_function(&v, &v_inv, &log_over_ts, None)?;
        let bc = spectral_function(&v, &v_inv, &input_factor, Some(&self.b))?;
        let cont = StateSpace::new(
            ac,
            bc,
            self.c.clone(),
            self.d.clone(),
            TimeDomain::Continuous,
        );
        let back = cont.c2d(ts)?;
        let err = relative_difference(&back.a, &self.a).max(relative_difference(&back.b, &self.b));
        if err.is_nan() || err >= 1e-8 {
            return Err(EraError::UnreliableContinuous {
                round_trip_error: err,
            });
        }
        Ok(cont)
    }
}

fn positive_sample_time(ts: f64) -> Result<()> {
    if ts.is_finite() && ts > 0.0 {
        Ok(())
    } else {
        Err(EraError::InvalidParameter {
            name: "sample time",
            value: ts.to_string(),
            reason: "must be positive and finite".into(),
        })
    }
}

/// `Re(V diag(f) V⁻¹ X)` (X = I when `None`), requiring the imaginary part to vanish.
fn spectral_function(
    v: &Mat<Complex64>,
    v_inv: &Mat<Complex64>,
    f: &[Complex64],
    rhs: Option<&Mat<f64>>,
) -> Result<Mat<f64>> {
    let n = v.nrows();
    let mut right = match rhs {
        Some(x) => {
            let xc = Mat::from_fn(x.nrows(), x.ncols(), |i, j| Complex64::new(x[(i, j)], 0.0));
            v_inv * &xc
        }
        None => v_inv.clone(),
    };
    for i in 0..n {
        for j in 0..right.ncols() {
            right[(i, j)] *= f[i];
        }
    }
    let full = v * &right;
    let scale = full.norm_l2().max(f64::MIN_POSITIVE);
    let mut worst_imag: f64 = 0.0;
    let out = Mat::from_fn(full.nrows(), full.ncols(), |i, j| {
        worst_imag = worst_imag.max(full[(i, j)].im.abs());
        full[(i, j)].re
    });
    if worst_imag > 1e-8 * scale {
        return Err(EraError::Conversion(format!(
            "the matrix logarithm is not real (imaginary part {worst_imag:.2e} of {scale:.2e})"
        )));
    }
    Ok(out)
}

/// `‖X − Y‖_F / max(‖Y‖_F, tiny)`.
pub fn relative_difference(x: &Mat<f64>, y: &Mat<f64>) -> f64 {
    (x - y).norm_l2() / y.norm_l2().max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d2c_rejects_negative_real_pole() {
        let a = Mat::from_fn(1, 1, |_, _| -0.5);
        let m = StateSpace::new(
            a,
            Mat::from_fn(1, 1, |_, _| 1.0),
            Mat::from_fn(1, 1, |_, _| 1.0),
            Mat::zeros(1, 1),
            TimeDomain::Discrete { sample_time_s: 0.1 },
        );
        assert!(matches!(m.d2c(), Err(EraError::NoRealLogarithm { .. })));
    }
}

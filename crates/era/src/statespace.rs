//! State-space models `x' = A x + B u`, `y = C x + D u`, in discrete or continuous time,
//! and the zero-order-hold conversions between them (docs/src/design.md §1.10).
//!
//! `c2d` uses the matrix exponential of the augmented matrix `[[A, B], [0, 0]]·Ts`.
//! `faer` has no matrix exponential, so [`expm`] is written here: Higham's (2005)
//! scaling-and-squaring with the degree-13 Padé approximant, every product and solve by
//! `faer`. `d2c` takes the principal logarithm through the eigendecomposition of `A`
//! (diagonalisable models, which ERA's distinct poles give) and then checks itself by
//! converting back.

use crate::error::{EraError, Result};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::Mat;
use num_complex::Complex64;

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

/// Eigenvalues and right eigenvectors of `a`, computed on the balanced matrix
/// `D⁻¹ a D` (see [`expm`]) and mapped back, `V = D V_b`. `faer`'s eigen solver does not
/// balance, and a physical model with entries from 1 to 1e9 (the truth model) otherwise
/// loses 8 digits in its poles.
///
/// # Errors
/// [`EraError::Numerical`] when the eigen solver does not converge.
pub(crate) fn balanced_eigen(a: &Mat<f64>) -> Result<(Vec<Complex64>, Mat<Complex64>)> {
    let n = a.nrows();
    let d = balancing_scale(a);
    let ab = Mat::from_fn(n, n, |i, j| a[(i, j)] * d[j] / d[i]);
    let eig = ab
        .eigen()
        .map_err(|e| EraError::Numerical(format!("eigendecomposition of A: {e:?}")))?;
    let values = (0..n).map(|k| eig.S()[k]).collect();
    let vectors = Mat::from_fn(n, n, |i, k| eig.U()[(i, k)] * d[i]);
    Ok((values, vectors))
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

/// Matrix exponential by scaling and squaring with the degree-13 Padé approximant
/// (N. J. Higham, "The scaling and squaring method for the matrix exponential
/// revisited", SIAM J. Matrix Anal. Appl. 26(4), 2005, Algorithm 2.3 with m = 13).
///
/// # Panics
/// If `m` is not square.
#[track_caller]
pub fn expm(m: &Mat<f64>) -> Mat<f64> {
    assert_eq!(m.nrows(), m.ncols(), "expm needs a square matrix");
    const B: [f64; 14] = [
        64764752532480000.0,
        32382376266240000.0,
        7771770303897600.0,
        1187353796428800.0,
        129060195264000.0,
        10559470521600.0,
        670442572800.0,
        33522128640.0,
        1323241920.0,
        40840800.0,
        960960.0,
        16380.0,
        182.0,
        1.0,
    ];
    const THETA_13: f64 = 5.371920351148152;
    let n = m.nrows();
    // Balance first: D⁻¹ M D with D a diagonal of powers of 2 (exact in floating point),
    // then exp(M) = D exp(D⁻¹ M D) D⁻¹. A mechanical model such as the truth model has
    // entries from 1e-5 to 1e5 in `A·Ts`, and without balancing the squarings lose 8
    // digits.
    let scale = balancing_scale(m);
    let m = &Mat::from_fn(n, n, |i, j| m[(i, j)] * scale[j] / scale[i]);
    let norm1 = (0..n)
        .map(|j| (0..n).map(|i| m[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let squarings = if norm1 > THETA_13 {
        (norm1 / THETA_13).log2().ceil() as i32
    } else {
        0
    };
    let a = m * faer::Scale(0.5f64.powi(squarings));
    let ident = Mat::<f64>::identity(n, n);
    let a2 = &a * &a;
    let a4 = &a2 * &a2;
    let a6 = &a2 * &a4;
    let lin = |c6: f64, c4: f64, c2: f64, c0: f64| -> Mat<f64> {
        &a6 * faer::Scale(c6)
            + &a4 * faer::Scale(c4)
            + &a2 * faer::Scale(c2)
            + &ident * faer::Scale(c0)
    };
    let u_inner = &a6
        * (&a6 * faer::Scale(B[13]) + &a4 * faer::Scale(B[11]) + &a2 * faer::Scale(B[9]))
        + lin(B[7], B[5], B[3], B[1]);
    let u = &a * u_inner;
    let v = &a6 * (&a6 * faer::Scale(B[12]) + &a4 * faer::Scale(B[10]) + &a2 * faer::Scale(B[8]))
        + lin(B[6], B[4], B[2], B[0]);
    let denominator = &v - &u;
    let mut r = &v + &u;
    denominator.partial_piv_lu().solve_in_place(&mut r);
    for _ in 0..squarings {
        r = &r * &r;
    }
    Mat::from_fn(n, n, |i, j| r[(i, j)] * scale[i] / scale[j])
}

/// Diagonal scaling `d` (powers of 2) that makes the off-diagonal row and column norms
/// of `D⁻¹ M D` comparable: the scaling loop of LAPACK's `dgebal` (Parlett & Reinsch),
/// without the permutations.
pub(crate) fn balancing_scale(m: &Mat<f64>) -> Vec<f64> {
    let n = m.nrows();
    let mut d = vec![1.0f64; n];
    const RADIX: f64 = 2.0;
    // LAPACK's loop converges for finite matrices in a few sweeps; the cap (and the
    // skip of non-finite norms below, where halving infinity never ends) makes sure a
    // matrix with overflowed entries cannot keep it running.
    const MAX_SWEEPS: usize = 1000;
    for _ in 0..MAX_SWEEPS {
        let mut converged = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for k in (0..n).filter(|&k| k != i) {
                c += (m[(k, i)] * d[i] / d[k]).abs();
                r += (m[(i, k)] * d[k] / d[i]).abs();
            }
            if c == 0.0 || r == 0.0 || !(c + r).is_finite() {
                continue;
            }
            let total = c + r;
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / RADIX {
                cc *= RADIX;
                rr /= RADIX;
                f *= RADIX;
            }
            while cc >= rr * RADIX {
                cc /= RADIX;
                rr *= RADIX;
                f /= RADIX;
            }
            if cc + rr < 0.95 * total {
                d[i] *= f;
                converged = false;
            }
        }
        if converged {
            return d;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm_of_rotation_generator() {
        let t = 2.5;
        let m = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 1) => -t,
            (1, 0) => t,
            _ => 0.0,
        });
        let e = expm(&m);
        assert!((e[(0, 0)] - t.cos()).abs() < 1e-14);
        assert!((e[(1, 0)] - t.sin()).abs() < 1e-14);
        // A large norm exercises the squarings.
        let big = Mat::from_fn(1, 1, |_, _| 30.0);
        assert!((expm(&big)[(0, 0)] / 30f64.exp() - 1.0).abs() < 1e-13);
    }

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

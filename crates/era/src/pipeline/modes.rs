//! Modal parameters of a state-space model (docs/src/design.md §1.11).
//!
//! With `A = V Λ V⁻¹`, each eigenvalue `λ` maps to a continuous pole `s = ln(λ)/Ts`
//! (discrete model) or `s = λ` (continuous). A complex pair is one mode of natural
//! frequency `|s|/2π` Hz and damping ratio `ζ = −Re(s)/|s|` (a fraction). The mode shape
//! is `C φ` and the modal participation `ψ B`, with `φ` the column of `V` and `ψ` the row
//! of `V⁻¹`; their product is the residue `C φ ψ B` of the pole, which does not depend on
//! how `φ` is scaled. Shapes are scaled so their largest entry is `1 + 0i`.

use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::Result;
use crate::linalg::eigen::balanced_eigen;
use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;
use num_complex::Complex64;

/// The diagonal (modal) form of a model: every pole with its output and input vectors.
#[derive(Debug, Clone)]
pub struct ModalForm {
    /// Eigenvalues of `A`.
    pub eigenvalues: Vec<Complex64>,
    /// `C φ_k` per eigenvalue (length q each).
    pub shapes: Vec<Vec<Complex64>>,
    /// `ψ_k B` per eigenvalue (length p each).
    pub participations: Vec<Vec<Complex64>>,
    /// `‖V‖_F ‖V⁻¹‖_F`, an estimate of the eigenvector condition number.
    pub eigenvector_condition: f64,
    /// Right eigenvectors `φ_k` (columns), each divided by the entry of `C φ_k` that
    /// scales its shape, so that `shapes[k] = C φ_k`.
    pub right: Mat<Complex64>,
    /// Left eigenvectors `ψ_k` (rows of `V⁻¹`), scaled inversely, so that
    /// `participations[k] = ψ_k B` and `ψ_k φ_k = 1`.
    pub left: Mat<Complex64>,
}

impl ModalForm {
    /// Diagonalises `model.a` and projects `B` and `C` onto the eigenvectors.
    ///
    /// # Errors
    /// [`crate::EraError::Numerical`] when the eigen solver fails.
    pub fn new(model: &StateSpace) -> Result<Self> {
        let n = model.states();
        let (eigenvalues_of_a, v) = balanced_eigen(&model.a)?;
        let v_inv = v.partial_piv_lu().inverse();
        let complex = |m: &Mat<f64>| {
            Mat::from_fn(m.nrows(), m.ncols(), |i, j| Complex64::new(m[(i, j)], 0.0))
        };
        let cv = complex(&model.c) * &v;
        let vib = &v_inv * complex(&model.b);
        let (q, p) = (model.outputs(), model.inputs());
        let eigenvector_condition = v.norm_l2() * v_inv.norm_l2();
        let (mut right, mut left) = (v, v_inv);
        let mut eigenvalues = Vec::with_capacity(n);
        let mut shapes = Vec::with_capacity(n);
        let mut participations = Vec::with_capacity(n);
        for k in 0..n {
            eigenvalues.push(eigenvalues_of_a[k]);
            let mut shape: Vec<Complex64> = (0..q).map(|i| cv[(i, k)]).collect();
            let mut part: Vec<Complex64> = (0..p).map(|j| vib[(k, j)]).collect();
            let largest = shape
                .iter()
                .copied()
                .fold(Complex64::new(0.0, 0.0), |best, x| {
                    if x.norm() > best.norm() {
                        x
                    } else {
                        best
                    }
                });
            if largest.norm() > 0.0 {
                shape.iter_mut().for_each(|x| *x /= largest);
                part.iter_mut().for_each(|x| *x *= largest);
                for r in 0..n {
                    right[(r, k)] /= largest;
                    left[(k, r)] *= largest;
                }
            }
            shapes.push(shape);
            participations.push(part);
        }
        Ok(ModalForm {
            eigenvalues,
            shapes,
            participations,
            eigenvector_condition,
            right,
            left,
        })
    }
}

/// One vibration mode (a complex pole pair).
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Undamped natural frequency `|s|/2π`, Hz.
    pub frequency_hz: f64,
    /// Damping ratio `−Re(s)/|s|`, a fraction.
    pub damping_ratio: f64,
    /// Eigenvalue of `A` with positive imaginary part (discrete `z`, or continuous `s`).
    pub eigenvalue: Complex64,
    /// Continuous-time pole `s`, rad/s.
    pub continuous_pole: Complex64,
    /// Mode shape `C φ`, largest entry 1.
    pub shape: Vec<Complex64>,
    /// Modal participation `ψ B`.
    pub participation: Vec<Complex64>,
}

/// A real pole, listed apart from the modes.
#[derive(Debug, Clone, PartialEq)]
pub struct RealPole {
    /// Eigenvalue of `A` (imaginary part zero).
    pub eigenvalue: f64,
    /// Continuous pole `s` (complex `ln z / Ts` when `z < 0`: a pole at the Nyquist
    /// frequency).
    pub continuous_pole: Complex64,
    /// `|s|/2π`, Hz.
    pub frequency_hz: f64,
}

/// Modes sorted by frequency and real poles sorted by `|s|`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModalParameters {
    /// Complex pole pairs.
    pub modes: Vec<Mode>,
    /// Real poles.
    pub real_poles: Vec<RealPole>,
}

/// Continuous pole of an eigenvalue of a model in `domain`.
pub(crate) fn continuous_pole(eigenvalue: Complex64, domain: TimeDomain) -> Complex64 {
    match domain {
        TimeDomain::Discrete { sample_time_s } => eigenvalue.ln() / sample_time_s,
        TimeDomain::Continuous => eigenvalue,
    }
}

/// Modal parameters of a model (docs/src/design.md §1.11).
///
/// # Errors
/// [`crate::EraError::Numerical`] when the eigen solver fails.
pub fn modal_parameters(model: &StateSpace) -> Result<ModalParameters> {
    Ok(modal_parameters_of(&ModalForm::new(model)?, model.domain))
}

/// Modal parameters from an already computed [`ModalForm`].
pub(crate) fn modal_parameters_of(form: &ModalForm, domain: TimeDomain) -> ModalParameters {
    let mut out = ModalParameters::default();
    for (k, z) in form.eigenvalues.iter().enumerate() {
        let s = continuous_pole(*z, domain);
        if z.im > 0.0 {
            out.modes.push(Mode {
                frequency_hz: s.norm() / (2.0 * std::f64::consts::PI),
                damping_ratio: -s.re / s.norm(),
                eigenvalue: *z,
                continuous_pole: s,
                shape: form.shapes[k].clone(),
                participation: form.participations[k].clone(),
            });
        } else if z.im == 0.0 {
            out.real_poles.push(RealPole {
                eigenvalue: z.re,
                continuous_pole: s,
                frequency_hz: s.norm() / (2.0 * std::f64::consts::PI),
            });
        }
    }
    out.modes
        .sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out.real_poles
        .sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out
}

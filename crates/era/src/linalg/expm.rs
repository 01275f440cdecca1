//! The matrix exponential, for the zero-order-hold discretisation of a continuous model
//! (`StateSpace::c2d`) and the simulator's steps.

use super::eigen::balancing_scale;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Matrix exponential by scaling and squaring with the degree-13 Padé approximant
/// (N. J. Higham, "The scaling and squaring method for the matrix exponential
/// revisited", SIAM J. Matrix Anal. Appl. 26(4), 2005, Algorithm 2.3 with m = 13).
///
/// # Panics
/// If `m` is not square.
#[track_caller]
pub(crate) fn expm(m: &Mat<f64>) -> Mat<f64> {
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
}

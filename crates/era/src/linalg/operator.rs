//! A linear operator known through its products, which is all a truncated SVD needs.

use faer::{Mat, MatRef};

/// A linear operator known through its products (what a truncated SVD needs).
pub trait LinearOperator: Sync {
    /// Rows.
    fn nrows(&self) -> usize;
    /// Columns.
    fn ncols(&self) -> usize;
    /// `self · x`.
    fn apply(&self, x: MatRef<'_, f64>) -> Mat<f64>;
    /// `selfᵀ · y`.
    fn apply_transpose(&self, y: MatRef<'_, f64>) -> Mat<f64>;
}

impl LinearOperator for Mat<f64> {
    fn nrows(&self) -> usize {
        Mat::nrows(self)
    }
    fn ncols(&self) -> usize {
        Mat::ncols(self)
    }
    fn apply(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        self * x
    }
    fn apply_transpose(&self, y: MatRef<'_, f64>) -> Mat<f64> {
        self.transpose() * y
    }
}

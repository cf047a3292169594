//! Inline storage for the measures of a task space of at most [`MAX_TASK_DIM`] rows: a
//! vector ([`TaskVector`]) and a square matrix ([`TaskMatrix`]) without heap allocation.

use nalgebra::{DMatrixView, Matrix6, U1, U6};

use crate::Error;

/// Largest task-space dimension: the rows of a spatial Jacobian (vx vy vz wx wy wz). The
/// measures of up to this many rows are stored inline, without heap allocation.
pub const MAX_TASK_DIM: usize = 6;

/// Up to [`MAX_TASK_DIM`] values stored inline, one per task-space dimension; it derefs to
/// the slice of its values.
#[derive(Clone, Copy)]
pub struct TaskVector<T> {
    pub(super) len: usize,
    pub(super) values: [T; MAX_TASK_DIM],
}

impl<T: Copy + Default> TaskVector<T> {
    /// The values of `s`.
    ///
    /// # Panics
    /// When `s` has more than [`MAX_TASK_DIM`] values.
    pub fn from_slice(s: &[T]) -> TaskVector<T> {
        assert!(
            s.len() <= MAX_TASK_DIM,
            "at most {MAX_TASK_DIM} task dimensions"
        );
        let mut values = [T::default(); MAX_TASK_DIM];
        values[..s.len()].copy_from_slice(s);
        TaskVector {
            len: s.len(),
            values,
        }
    }
}

impl<T> std::ops::Deref for TaskVector<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.values[..self.len]
    }
}

impl<T: PartialEq> PartialEq for TaskVector<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for TaskVector<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        (**self).fmt(f)
    }
}

/// An m×m matrix, m ≤ [`MAX_TASK_DIM`], stored inline as the leading block of a 6×6.
#[derive(Clone, Copy)]
pub struct TaskMatrix {
    dim: usize,
    data: Matrix6<f64>,
}

impl TaskMatrix {
    /// The m×m matrix stored column-major in `s` (m² entries).
    ///
    /// # Panics
    /// When m exceeds [`MAX_TASK_DIM`].
    pub fn from_column_slice(m: usize, s: &[f64]) -> TaskMatrix {
        assert!(m <= MAX_TASK_DIM, "at most {MAX_TASK_DIM} task dimensions");
        assert_eq!(s.len(), m * m, "an m×m matrix");
        let mut data = Matrix6::zeros();
        for (c, col) in s.chunks_exact(m).enumerate() {
            data.as_mut_slice()[c * MAX_TASK_DIM..c * MAX_TASK_DIM + m].copy_from_slice(col);
        }
        TaskMatrix { dim: m, data }
    }

    /// m.
    pub fn nrows(&self) -> usize {
        self.dim
    }

    /// m.
    pub fn ncols(&self) -> usize {
        self.dim
    }

    /// Column `i` (m entries).
    pub fn column(&self, i: usize) -> &[f64] {
        assert!(i < self.dim, "column {i} of {}", self.dim);
        &self.data.as_slice()[i * MAX_TASK_DIM..i * MAX_TASK_DIM + self.dim]
    }

    /// The matrix as a nalgebra view (for arithmetic).
    pub fn view(&self) -> DMatrixView<'_, f64, U1, U6> {
        self.data.view((0, 0), (self.dim, self.dim))
    }
}

impl PartialEq for TaskMatrix {
    fn eq(&self, other: &Self) -> bool {
        self.view() == other.view()
    }
}

impl std::fmt::Debug for TaskMatrix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.view().fmt(f)
    }
}

/// A measured task space has at most [`MAX_TASK_DIM`] rows.
pub(crate) fn check_task_dim(m: usize) -> Result<(), Error> {
    if m > MAX_TASK_DIM {
        return Err(Error::InvalidRows {
            reason: format!("{m} rows; the measures take at most {MAX_TASK_DIM}"),
        });
    }
    Ok(())
}

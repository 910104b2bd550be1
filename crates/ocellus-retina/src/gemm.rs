//! Dense matrix products through `matrixmultiply` for f32 (the solvers) and f64 (the gradient
//! check), on strided views so that a transpose is a change of strides.

/// The floating-point types the model runs in: f32 for learning (twice the GEMM throughput),
/// f64 for checking the gradient against finite differences.
pub trait Real:
    Copy
    + Send
    + Sync
    + Default
    + PartialOrd
    + std::fmt::Debug
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::AddAssign
    + 'static
{
    /// From f64 (rounded for f32).
    fn from_f64(v: f64) -> Self;
    /// To f64.
    fn to_f64(self) -> f64;
    /// `c = alpha a b + beta c`; the caller guarantees the shapes and strides (see [`gemm`]).
    ///
    /// # Safety
    /// Every element addressed by the views must lie inside the slices behind the pointers.
    #[allow(clippy::missing_safety_doc)]
    unsafe fn gemm_raw(
        m: usize,
        k: usize,
        n: usize,
        alpha: Self,
        a: (*const Self, isize, isize),
        b: (*const Self, isize, isize),
        beta: Self,
        c: (*mut Self, isize, isize),
    );
}

/// `Real` for a float type through its `matrixmultiply` kernel.
macro_rules! real_impl {
    ($t:ty, $gemm:path) => {
        impl Real for $t {
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            unsafe fn gemm_raw(
                m: usize,
                k: usize,
                n: usize,
                alpha: $t,
                a: (*const $t, isize, isize),
                b: (*const $t, isize, isize),
                beta: $t,
                c: (*mut $t, isize, isize),
            ) {
                // SAFETY: forwarded from the caller's contract.
                unsafe { $gemm(m, k, n, alpha, a.0, a.1, a.2, b.0, b.1, b.2, beta, c.0, c.1, c.2) }
            }
        }
    };
}

real_impl!(f32, matrixmultiply::sgemm);
real_impl!(f64, matrixmultiply::dgemm);

/// A strided read-only matrix view.
#[derive(Clone, Copy)]
pub(crate) struct View<'a, T> {
    data: &'a [T],
    rows: usize,
    cols: usize,
    rs: usize,
    cs: usize,
}

impl<'a, T> View<'a, T> {
    /// A row-major `rows x cols` matrix at the start of `data`.
    pub(crate) fn rm(data: &'a [T], rows: usize, cols: usize) -> Self {
        Self { data, rows, cols, rs: cols, cs: 1 }
    }

    /// The transpose (no copy).
    pub(crate) fn t(self) -> Self {
        Self { data: self.data, rows: self.cols, cols: self.rows, rs: self.cs, cs: self.rs }
    }

    fn fits(&self) -> bool {
        self.rows == 0 || self.cols == 0 || (self.rows - 1) * self.rs + (self.cols - 1) * self.cs < self.data.len()
    }
}

/// `c = alpha a b + beta c`, `c` row-major `a.rows x b.cols` at the start of the slice.
///
/// The shapes are the crate's own (never a user's), so a mismatch is a bug: it panics
/// before any unsafe access.
pub(crate) fn gemm<T: Real>(alpha: T, a: View<T>, b: View<T>, beta: T, c: &mut [T]) {
    let (m, k, n) = (a.rows, a.cols, b.cols);
    assert!(
        b.rows == k && a.fits() && b.fits() && c.len() >= m * n,
        "gemm shapes: {m}x{k} by {}x{n} into {}",
        b.rows,
        c.len()
    );
    if m == 0 || n == 0 {
        return;
    }
    // SAFETY: the views were checked to lie inside their slices, and c holds m x n.
    unsafe {
        T::gemm_raw(
            m,
            k,
            n,
            alpha,
            (a.data.as_ptr(), a.rs as isize, a.cs as isize),
            (b.data.as_ptr(), b.rs as isize, b.cs as isize),
            beta,
            (c.as_mut_ptr(), n as isize, 1),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_match_the_direct_sums_with_transposes() {
        let a: Vec<f64> = (0..6).map(|v| v as f64 + 1.0).collect(); // 2x3
        let b: Vec<f64> = (0..12).map(|v| (v as f64) * 0.5 - 2.0).collect(); // 3x4
        let mut c = vec![1.0; 8];
        gemm(2.0, View::rm(&a, 2, 3), View::rm(&b, 3, 4), 0.5, &mut c);
        for i in 0..2 {
            for j in 0..4 {
                let d: f64 = (0..3).map(|k| a[i * 3 + k] * b[k * 4 + j]).sum();
                assert!((c[i * 4 + j] - (2.0 * d + 0.5)).abs() < 1e-12);
            }
        }
        // a^T a (3x3) through the transpose view.
        let mut g = vec![0.0f32; 9];
        let af: Vec<f32> = a.iter().map(|&v| v as f32).collect();
        gemm(1.0, View::rm(&af, 2, 3).t(), View::rm(&af, 2, 3), 0.0, &mut g);
        assert_eq!(g[0], 1.0 + 16.0);
        assert_eq!(g[3 + 2], 2.0 * 3.0 + 5.0 * 6.0);
    }
}

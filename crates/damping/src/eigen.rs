//! The dense real nonsymmetric eigensolver, in one place: the complex modes
//! solve their state matrix with it, and `frf`'s modal estimator the block
//! companion matrix of its denominator polynomial.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{Mat, MatRef, Par};

/// Eigenvalues and right eigenvectors of a real square matrix.
///
/// Eigenvalue `j` is `re[j] + j im[j]`. Complex eigenvalues come in
/// conjugate pairs at consecutive positions; for such a pair at `(j, j + 1)`
/// the eigenvector of `re[j] + j im[j]` is `vectors[:, j] + j vectors[:, j + 1]`
/// and that of its conjugate the conjugate (faer's real layout).
#[derive(Clone, Debug)]
pub struct RealEigen {
    /// Real parts of the eigenvalues.
    pub re: Vec<f64>,
    /// Imaginary parts of the eigenvalues.
    pub im: Vec<f64>,
    /// Right eigenvectors, one column per eigenvalue, in faer's real layout.
    pub vectors: Mat<f64>,
}

/// The eigensolver did not converge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoConvergence;

/// All eigenvalues and right eigenvectors of `a` (dense, sequential: the
/// callers' matrices are small, and parallelism belongs to them).
pub fn real_eigen(a: MatRef<'_, f64>) -> Result<RealEigen, NoConvergence> {
    let n = a.nrows();
    let mut s_re = Diag::<f64>::zeros(n);
    let mut s_im = Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let scratch =
        evd::evd_scratch::<f64>(n, ComputeEigenvectors::No, ComputeEigenvectors::Yes, Par::Seq, Default::default());
    evd::evd_real(
        a,
        s_re.as_mut(),
        s_im.as_mut(),
        None,
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|_| NoConvergence)?;
    Ok(RealEigen { re: (0..n).map(|i| s_re[i]).collect(), im: (0..n).map(|i| s_im[i]).collect(), vectors: u })
}

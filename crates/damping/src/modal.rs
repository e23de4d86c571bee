//! Modal analysis of the assembled model.
//!
//! [`normal_modes`] solves the undamped problem `K phi = w^2 M phi` densely,
//! for models of up to a few thousand DOFs. It works on the inverse problem
//! `L^-1 M L^-T y = (1 / w^2) y` with `K = L L^T`: the lowest modes are then
//! the largest eigenvalues and keep full relative accuracy even when very
//! stiff springs put other eigenvalues many orders of magnitude away, and
//! DOFs without mass simply give infinite frequencies (dropped). Mode shapes
//! are mass-normalised (`phi^T M phi = 1`).

use faer::linalg::triangular_solve;
use faer::{Mat, Par, Side};
use fe_model::{Assembly, MatrixKind};

/// Error of a modal computation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModalError {
    /// The stiffness matrix is not positive definite.
    #[error("the stiffness matrix is not positive definite: the structure is a mechanism or is not supported")]
    StiffnessNotPositive,
    /// The eigensolver did not converge.
    #[error("the eigenvalue solver did not converge")]
    NoConvergence,
    /// The dense state-space problem would be too large.
    #[error(
        "the model is too large for dense complex modal analysis: {dofs} DOFs give a state space of dimension {state_dimension} (at most {max})"
    )]
    TooLarge {
        /// Number of equations of the model.
        dofs: usize,
        /// `2 n +` the number of internal variables (just `2 n` when that
        /// alone exceeds the limit).
        state_dimension: usize,
        /// The limit.
        max: usize,
    },
    /// The eigensolver returned NaN or infinity (ill-posed input).
    #[error("the eigenvalue solver returned a non-finite result (are the model's matrices finite?)")]
    NotFinite,
}

/// Undamped natural frequencies and mass-normalised mode shapes.
#[derive(Clone, Debug)]
pub struct NormalModes {
    /// Natural frequencies (Hz), ascending (modes of massless DOFs omitted).
    pub frequencies_hz: Vec<f64>,
    /// Mode shapes: column `k` is mode `k`, rows are equations.
    pub shapes: Mat<f64>,
}

pub(crate) fn dense(assembly: &Assembly, kind: MatrixKind) -> Mat<f64> {
    let v = assembly.real_values(kind);
    let p = assembly.pattern();
    let mut m = Mat::zeros(p.n(), p.n());
    for c in 0..p.n() {
        for k in p.col_ptr()[c]..p.col_ptr()[c + 1] {
            m[(p.row_idx()[k], c)] = v[k];
        }
    }
    m
}

/// All undamped modes of an assembled model (dense; small models).
pub fn normal_modes(assembly: &Assembly) -> Result<NormalModes, ModalError> {
    let k = dense(assembly, MatrixKind::Stiffness);
    let m = dense(assembly, MatrixKind::Mass);
    let n = k.nrows();
    let llt = k.llt(Side::Lower).map_err(|_| ModalError::StiffnessNotPositive)?;
    let l = llt.L();
    // A = L^-1 M L^-T, symmetric positive semi-definite
    let mut a = m.clone();
    triangular_solve::solve_lower_triangular_in_place(l, a.as_mut(), Par::Seq);
    let mut a = a.transpose().to_owned();
    triangular_solve::solve_lower_triangular_in_place(l, a.as_mut(), Par::Seq);
    let eig = a.self_adjoint_eigen(Side::Lower).map_err(|_| ModalError::NoConvergence)?;
    let s = eig.S();
    let nu_max = (0..n).map(|i| s[i]).fold(0.0, f64::max);
    // eigenvalues ascend, so the lowest frequencies come last
    let keep: Vec<usize> = (0..n).rev().filter(|&i| s[i] > 1e-13 * nu_max).collect();
    let mut shapes = Mat::zeros(n, keep.len());
    let mut frequencies_hz = Vec::with_capacity(keep.len());
    for (col, &i) in keep.iter().enumerate() {
        frequencies_hz.push(1.0 / (s[i].sqrt() * 2.0 * std::f64::consts::PI));
        shapes.col_mut(col).copy_from(eig.U().col(i));
    }
    triangular_solve::solve_upper_triangular_in_place(l.transpose(), shapes.as_mut(), Par::Seq);
    for col in 0..keep.len() {
        let phi = shapes.col(col);
        let mphi = &m * phi;
        let modal_mass: f64 = (0..n).map(|r| phi[r] * mphi[r]).sum();
        let scale = 1.0 / modal_mass.sqrt();
        for r in 0..n {
            shapes[(r, col)] *= scale;
        }
    }
    Ok(NormalModes { frequencies_hz, shapes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::samples;

    #[test]
    fn two_dof_oscillator_matches_closed_form() {
        // k1 = 1000, k2 = 500, m1 = 1, m2 = 0.5:
        // det([1500 - w2, -500; -500, 500 - 0.5 w2]) = 0
        // 0.5 w^4 - 1250 w^2 + 500000 = 0  ->  w^2 = 1250 -+ sqrt(1250^2 - 1e6)
        let a = Assembly::new(&samples::two_dof_oscillator()).unwrap();
        let modes = normal_modes(&a).unwrap();
        let d = (1250.0f64.powi(2) - 1.0e6).sqrt();
        let expect = [(1250.0 - d).sqrt(), (1250.0 + d).sqrt()];
        for (f, w) in modes.frequencies_hz.iter().zip(expect) {
            let fw = w / (2.0 * std::f64::consts::PI);
            assert!((f - fw).abs() < 1e-10 * fw, "{f} vs {fw}");
        }
    }
}

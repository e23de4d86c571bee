//! Complex modes of the non-viscously damped model (dense; small models).
//!
//! The free vibration of the model satisfies `Z(s) phi = 0` with, in the
//! Laplace domain (`s = j w` on the frequency axis),
//!
//! ```text
//! Z(s) = K + s^2 M + s C_v + sum_g s mu_g / (mu_g + s) C_g
//! ```
//!
//! where `C_v` collects the viscous groups (and the imported viscous damping
//! matrices of any group) and the sum runs over the groups
//! with a finite relaxation parameter. `Z(s)` is rational in `s`, so the
//! problem is turned into a linear one by *internal variables*. Each
//! finite-`mu` group's damping matrix is factorised, on the equations the
//! group touches, by a symmetric eigendecomposition
//! `C_g = sum_i d_i r_i r_i^T` that keeps only the `r_g` eigenvalues with
//! `|d_i| > RANK_TOLERANCE max |d|` (a rank-revealing factorisation: a
//! rotational joint spring adds one variable, not the whole model). With
//! `v = s x` and one variable `q_i = mu_g / (mu_g + s) r_i^T v` per retained
//! direction,
//!
//! ```text
//! s x   = v
//! s M v = -K x - C_v v - sum_i d_i r_i q_i
//! s q_i = mu_g (r_i^T v - q_i)
//! ```
//!
//! is a linear eigenproblem of dimension `N = 2 n + sum_g r_g` (a viscous
//! model has no internal variables). When `K` and `M` are positive definite
//! (`K = L_K L_K^T`, `M = L_M L_M^T`) it is written in the variables
//! `y1 = L_K^T x`, `y2 = L_M^T v` and `q_i' = sqrt(|d_i| / mu_g) q_i` as a
//! standard eigenproblem `s y = A y` with
//!
//! ```text
//!     [ 0    G^T          0     ]     G  = L_M^-1 L_K
//! A = [ -G   -C~          -R~ S W ]   C~ = L_M^-1 C_v L_M^-T,  R~ = L_M^-1 [r_1 ...]
//!     [ 0    W R~^T       -mu   ]     W  = diag(sqrt(|d_i| mu_g)),  S = diag(sign d_i)
//! ```
//!
//! which, for positive `d_i`, is a negative semi-definite matrix plus a skew
//! one: its eigenvalues are well conditioned and a dense Hessenberg-QR
//! eigensolver gets them to near machine precision relative to the largest
//! one. The displacement part of each eigenvector is `x = L_K^-T y1`. When
//! `M` (DOFs without mass) or `K` is singular, the unreduced pencil
//! `A z = s B z` in `(w0 x, v, q')` with `B = diag(I, M, I)` and
//! `w0 = sqrt(|K|_F / |M|_F)` is solved by the QZ algorithm instead; DOFs
//! without mass then give infinite eigenvalues, which are dropped.
//!
//! Measured on the sample models, `|Z(s) phi| / (|Z(s)|_2 |phi|)` stays below
//! `1e-11` for every eigenpair, including the cluster of relaxation modes
//! that a stiffness-proportional kernel puts near `-mu_g (1 - alpha_g mu_g)`.
//!
//! Eigenvalues come as complex conjugate pairs (oscillatory modes; one of each
//! pair, with `Im s > 0`, is reported as a [`ComplexMode`]) or are real and
//! negative (a [`RealMode`]: the relaxation modes of the internal variables,
//! near `-mu_g`, and the two roots of any overdamped structural mode).
//!
//! **Normalisation.** Because `Z` is complex symmetric, the receptance near a
//! simple pole `s_k` is `R(s) ~ phi phi^T / ((s - s_k) phi^T Z'(s_k) phi)`.
//! Oscillatory shapes are scaled so that `phi^T Z'(s_k) phi = 1` with
//! `Z'(s) = 2 s M + C_v + sum_g mu_g^2 / (mu_g + s)^2 C_g`: the residue of
//! the receptance at `s_k` is then simply `phi phi^T`, and for a viscous
//! model this is the usual `phi^T (2 s_k M + C) phi = 1`. The remaining sign
//! is chosen so that the largest component has a non-negative real part.
//! Real modes are real vectors scaled to a largest component of `+1`, with
//! their `a = phi^T Z'(s_k) phi` stored beside them (residue
//! `phi phi^T / a`).
//!
//! **Size limit.** The dense eigensolvers cost `O(N^3)` time and `O(N^2)`
//! memory (0.5 s for the 90-DOF two-material cantilever, `N = 273`); state
//! dimensions above [`MAX_STATE_DIMENSION`] are refused with
//! [`ModalError::TooLarge`]. That allows a few hundred DOFs.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::ComputeEigenvectors;
use faer::linalg::gevd;
use faer::linalg::triangular_solve;
use faer::{Mat, Par, Side, Spec};
use fe_model::MatrixKind;
use num_complex::Complex64 as C64;

use crate::eigen::{RealEigen, real_eigen};
use crate::modal::ModalError;
use crate::system::DampedSystem;

/// Largest state-space dimension `2 n + sum_g r_g` that [`complex_modes`]
/// accepts (dense eigensolver: about a minute of one core at this size).
pub const MAX_STATE_DIMENSION: usize = 1500;

/// Relative threshold below which an eigenvalue of a group's damping matrix
/// is treated as zero when choosing its internal variables.
pub const RANK_TOLERANCE: f64 = 1e-12;

/// An eigenvalue is real when `|Im s| <= REAL_TOLERANCE |s|`.
const REAL_TOLERANCE: f64 = 1e-10;

/// One oscillatory (complex) mode, the member of its conjugate pair with
/// `Im s > 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct ComplexMode {
    /// Eigenvalue `s_k` (rad/s), `Re s_k < 0` for a damped mode.
    pub eigenvalue: C64,
    /// Natural frequency `|s_k| / (2 pi)` (Hz).
    pub frequency_hz: f64,
    /// Damping ratio `-Re(s_k) / |s_k|`.
    pub damping_ratio: f64,
    /// Mode shape over the model's equations, scaled so that
    /// `phi^T Z'(s_k) phi = 1` (see the module docs).
    pub shape: Vec<C64>,
}

impl ComplexMode {
    /// Damped natural frequency `Im(s_k) / (2 pi)` (Hz).
    pub fn damped_frequency_hz(&self) -> f64 {
        self.eigenvalue.im / (2.0 * std::f64::consts::PI)
    }

    /// Residue of the receptance `H_ij` at `s_k`: `phi_i phi_j`.
    pub fn residue(&self, i: usize, j: usize) -> C64 {
        self.shape[i] * self.shape[j]
    }
}

/// A real (non-oscillatory) mode: an internal-variable relaxation mode or one
/// root of an overdamped structural mode.
#[derive(Clone, Debug, PartialEq)]
pub struct RealMode {
    /// Real eigenvalue (rad/s), negative for a decaying mode.
    pub eigenvalue: f64,
    /// Mode shape over the model's equations, largest component `+1`.
    pub shape: Vec<f64>,
    /// `phi^T Z'(s_k) phi`; the receptance residue is `phi phi^T / a`.
    pub modal_a: f64,
}

/// All finite eigenvalues and modes of a damped model.
#[derive(Clone, Debug, PartialEq)]
pub struct ComplexModes {
    /// Oscillatory modes by increasing natural frequency.
    pub oscillatory: Vec<ComplexMode>,
    /// Real modes by increasing `|s|`.
    pub overdamped: Vec<RealMode>,
    /// Number of internal variables, `sum_g r_g`.
    pub internal_variables: usize,
    /// State-space dimension `2 n + sum_g r_g`.
    pub state_dimension: usize,
    /// Number of infinite eigenvalues dropped (DOFs without mass).
    pub infinite: usize,
}

/// The model's matrices as values on its sparsity pattern, split by kernel.
struct Operators<'a> {
    sys: &'a DampedSystem,
    k: Vec<f64>,
    m: Vec<f64>,
    /// Sum of the viscous groups' `C_g`.
    c_viscous: Vec<f64>,
    /// `(group, mu, C_g)` of every damped group with finite `mu`.
    relaxing: Vec<(usize, f64, Vec<f64>)>,
}

impl<'a> Operators<'a> {
    fn new(sys: &'a DampedSystem) -> Self {
        let a = sys.assembly();
        // the imported damping matrices are viscous whatever their group's kernel
        let mut c_viscous = a.real_values(MatrixKind::Damping);
        let mut relaxing = Vec::new();
        for (g, group) in sys.model().groups().iter().enumerate() {
            if group.alpha == 0.0 && group.beta == 0.0 {
                continue;
            }
            let kg = a.group_values(g, MatrixKind::Stiffness);
            let mg = a.group_values(g, MatrixKind::Mass);
            let c: Vec<f64> = kg.iter().zip(&mg).map(|(k, m)| group.alpha * k + group.beta * m).collect();
            match group.mu {
                None => c_viscous.iter_mut().zip(&c).for_each(|(s, v)| *s += v),
                Some(mu) => relaxing.push((g, mu, c)),
            }
        }
        Operators {
            sys,
            k: a.real_values(MatrixKind::Stiffness),
            m: a.real_values(MatrixKind::Mass),
            c_viscous,
            relaxing,
        }
    }

    fn n(&self) -> usize {
        self.sys.n()
    }

    /// Coefficients of `K`, `M`, `C_v` and each relaxing `C_g` in `Z(s)`.
    fn z_coefficients(&self, s: C64) -> (C64, C64, Vec<C64>) {
        let c = self.relaxing.iter().map(|&(_, mu, _)| s * mu / (mu + s)).collect();
        (s * s, s, c)
    }

    /// Coefficients of `M`, `C_v` and each relaxing `C_g` in `Z'(s)`.
    fn dz_coefficients(&self, s: C64) -> (C64, C64, Vec<C64>) {
        let c = self.relaxing.iter().map(|&(_, mu, _)| mu * mu / ((mu + s) * (mu + s))).collect();
        (2.0 * s, C64::new(1.0, 0.0), c)
    }

    /// Values on the pattern of `k0 K + cm M + cv C_v + sum cg_i C_i`.
    fn combine(&self, k0: f64, cm: C64, cv: C64, cg: &[C64]) -> Vec<C64> {
        (0..self.k.len())
            .map(|p| {
                let mut v = cm * self.m[p] + cv * self.c_viscous[p] + k0 * self.k[p];
                for (c, (_, _, values)) in cg.iter().zip(&self.relaxing) {
                    v += c * values[p];
                }
                v
            })
            .collect()
    }

    fn z_values(&self, s: C64) -> Vec<C64> {
        let (cm, cv, cg) = self.z_coefficients(s);
        self.combine(1.0, cm, cv, &cg)
    }

    fn dz_values(&self, s: C64) -> Vec<C64> {
        let (cm, cv, cg) = self.dz_coefficients(s);
        self.combine(0.0, cm, cv, &cg)
    }

    fn dense(&self, values: &[C64]) -> Mat<C64> {
        let p = self.sys.assembly().pattern();
        let mut z = Mat::<C64>::zeros(p.n(), p.n());
        for c in 0..p.n() {
            for k in p.col_ptr()[c]..p.col_ptr()[c + 1] {
                z[(p.row_idx()[k], c)] = values[k];
            }
        }
        z
    }

    /// `values * x` for values on the pattern.
    fn apply(&self, values: &[C64], x: &[C64]) -> Vec<C64> {
        let p = self.sys.assembly().pattern();
        let mut y = vec![C64::new(0.0, 0.0); p.n()];
        for c in 0..p.n() {
            for k in p.col_ptr()[c]..p.col_ptr()[c + 1] {
                y[p.row_idx()[k]] += values[k] * x[c];
            }
        }
        y
    }

    /// `x^T values x` (a bilinear form, no conjugation).
    fn bilinear(&self, values: &[C64], x: &[C64]) -> C64 {
        self.apply(values, x).iter().zip(x).map(|(a, b)| a * b).sum()
    }
}

/// The dynamic stiffness `Z(s)` at a complex Laplace variable `s`, dense
/// (small models). On the frequency axis, `Z(j w)` equals
/// [`DampedSystem::z_values`] at `w`.
pub fn dynamic_stiffness(sys: &DampedSystem, s: C64) -> Mat<C64> {
    let ops = Operators::new(sys);
    ops.dense(&ops.z_values(s))
}

/// `dZ/ds = 2 s M + C_v + sum_g mu_g^2 / (mu_g + s)^2 C_g`, dense.
pub fn dynamic_stiffness_derivative(sys: &DampedSystem, s: C64) -> Mat<C64> {
    let ops = Operators::new(sys);
    ops.dense(&ops.dz_values(s))
}

/// The rank-revealing factorisation of a relaxing group's damping matrix:
/// retained `(d_i, r_i)` with `r_i` over the full equations.
fn internal_directions(ops: &Operators<'_>, group: usize, c: &[f64]) -> Result<Vec<(f64, Vec<f64>)>, ModalError> {
    let a = ops.sys.assembly();
    let mut eqs: Vec<usize> = a.group_blocks(group).iter().flat_map(|&b| a.blocks()[b].eqs().iter().copied()).collect();
    eqs.sort_unstable();
    eqs.dedup();
    let d = eqs.len();
    if d == 0 {
        return Ok(Vec::new());
    }
    let mut local = Mat::<f64>::zeros(d, d);
    for (i, &ei) in eqs.iter().enumerate() {
        for (j, &ej) in eqs.iter().enumerate() {
            if let Some(p) = a.pattern().position(ei, ej) {
                local[(i, j)] = c[p];
            }
        }
    }
    let eig = local.self_adjoint_eigen(Side::Lower).map_err(|_| ModalError::NoConvergence)?;
    let s = eig.S();
    let u = eig.U();
    let max = (0..d).map(|i| s[i].abs()).fold(0.0, f64::max);
    if !max.is_finite() {
        return Err(ModalError::NotFinite);
    }
    let mut out = Vec::new();
    for i in 0..d {
        if s[i].abs() > RANK_TOLERANCE * max {
            let mut r = vec![0.0; ops.n()];
            for (l, &e) in eqs.iter().enumerate() {
                r[e] = u[(l, i)];
            }
            out.push((s[i], r));
        }
    }
    Ok(out)
}

/// All finite complex eigenvalues and modes of a damped model; see the module
/// docs for the formulation, normalisation and size limit.
pub fn complex_modes(sys: &DampedSystem) -> Result<ComplexModes, ModalError> {
    let ops = Operators::new(sys);
    let n = ops.n();
    // internal variables: (mu, d_i, r_i)
    if 2 * n > MAX_STATE_DIMENSION {
        // no need to factorise the damping matrices of a model this large
        return Err(ModalError::TooLarge { dofs: n, state_dimension: 2 * n, max: MAX_STATE_DIMENSION });
    }
    let mut internal: Vec<(f64, f64, Vec<f64>)> = Vec::new();
    for (g, mu, c) in &ops.relaxing {
        for (d, r) in internal_directions(&ops, *g, c)? {
            internal.push((*mu, d, r));
        }
    }
    let big = 2 * n + internal.len();
    if big > MAX_STATE_DIMENSION {
        return Err(ModalError::TooLarge { dofs: n, state_dimension: big, max: MAX_STATE_DIMENSION });
    }

    let spectrum = match dissipative_form(&ops, &internal) {
        Some(a) => solve_standard(&ops, a)?,
        None => solve_pencil(&ops, &internal)?,
    };
    let Spectrum { s_re, s_im, s_b, x, w_ref } = spectrum;

    let mut oscillatory = Vec::new();
    let mut overdamped = Vec::new();
    let mut infinite = 0;
    let mut j = 0;
    while j < big {
        let pair = s_im[j] != 0.0 && j + 1 < big;
        let (alpha, beta) = (C64::new(s_re[j], s_im[j]), s_b[j]);
        let s = alpha / beta;
        let is_infinite = beta == 0.0 || !(s.norm() <= 1e8 * w_ref);
        if !(alpha.re.is_finite() && alpha.im.is_finite() && beta.is_finite()) {
            return Err(ModalError::NotFinite);
        }
        if is_infinite {
            infinite += if pair { 2 } else { 1 };
        } else {
            let mut phi: Vec<C64> = (0..n)
                .map(|i| if pair { C64::new(x[(i, j)], x[(i, j + 1)]) } else { C64::new(x[(i, j)], 0.0) })
                .collect();
            if phi.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return Err(ModalError::NotFinite);
            }
            let mut s = s;
            if s.im < 0.0 {
                s = s.conj();
                phi.iter_mut().for_each(|v| *v = v.conj());
            }
            if s.im.abs() > REAL_TOLERANCE * s.norm() {
                oscillatory.push(oscillatory_mode(&ops, s, phi));
            } else {
                overdamped.push(real_mode(&ops, s.re, &phi));
                if pair {
                    // a pair that the QZ left complex but is real to the
                    // tolerance: its partner is the same real root
                    overdamped.push(real_mode(&ops, s.re, &phi));
                }
            }
        }
        j += if pair { 2 } else { 1 };
    }
    oscillatory.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    overdamped.sort_by(|a, b| a.eigenvalue.abs().total_cmp(&b.eigenvalue.abs()));
    Ok(ComplexModes { oscillatory, overdamped, internal_variables: internal.len(), state_dimension: big, infinite })
}

/// Eigenvalues `(s_re + j s_im) / s_b` of the linearised problem and the
/// displacement part `x` of its (real-stored) eigenvectors, a complex pair
/// `j, j + 1` holding `x_j + i x_{j+1}` for the eigenvalue with `+s_im`.
struct Spectrum {
    s_re: Vec<f64>,
    s_im: Vec<f64>,
    s_b: Vec<f64>,
    x: Mat<f64>,
    /// A frequency scale beyond every finite eigenvalue of interest (rad/s).
    w_ref: f64,
}

/// The model's `K`, `M` or `C_v` as a dense matrix.
fn dense_real(ops: &Operators<'_>, values: &[f64]) -> Mat<f64> {
    let p = ops.sys.assembly().pattern();
    let mut m = Mat::<f64>::zeros(p.n(), p.n());
    for c in 0..p.n() {
        for k in p.col_ptr()[c]..p.col_ptr()[c + 1] {
            m[(p.row_idx()[k], c)] = values[k];
        }
    }
    m
}

/// The state matrix in the variables `y1 = L_K^T x`, `y2 = L_M^T v` and
/// scaled internal variables (`K = L_K L_K^T`, `M = L_M L_M^T`):
///
/// ```text
/// [ 0    G^T        0      ]      G  = L_M^-1 L_K
/// [ -G   -C~        -R~ S W ]     C~ = L_M^-1 C_v L_M^-T,  R~ = L_M^-1 R
/// [ 0    W R~^T     -mu    ]
/// ```
///
/// It is minus a positive semi-definite matrix plus a skew one (when every
/// retained `d_i > 0`), so its eigenvalues are well conditioned. Returns the
/// matrix and `L_K`, or `None` when `K` or `M` is not positive definite.
fn dissipative_form(ops: &Operators<'_>, internal: &[(f64, f64, Vec<f64>)]) -> Option<(Mat<f64>, Mat<f64>)> {
    let n = ops.n();
    let big = 2 * n + internal.len();
    let lk = dense_real(ops, &ops.k).llt(Side::Lower).ok()?.L().to_owned();
    let lm_llt = dense_real(ops, &ops.m).llt(Side::Lower).ok()?;
    let lm = lm_llt.L();
    // G = L_M^-1 L_K
    let mut g = lk.clone();
    triangular_solve::solve_lower_triangular_in_place(lm, g.as_mut(), Par::Seq);
    // C~ = L_M^-1 (L_M^-1 C_v)^T
    let mut ct = dense_real(ops, &ops.c_viscous);
    triangular_solve::solve_lower_triangular_in_place(lm, ct.as_mut(), Par::Seq);
    let mut ct = ct.transpose().to_owned();
    triangular_solve::solve_lower_triangular_in_place(lm, ct.as_mut(), Par::Seq);
    // R~ = L_M^-1 R, one column per internal variable
    let mut rt = Mat::<f64>::zeros(n, internal.len());
    for (i, (_, _, r)) in internal.iter().enumerate() {
        for e in 0..n {
            rt[(e, i)] = r[e];
        }
    }
    triangular_solve::solve_lower_triangular_in_place(lm, rt.as_mut(), Par::Seq);

    let mut a = Mat::<f64>::zeros(big, big);
    for r in 0..n {
        for c in 0..n {
            a[(c, n + r)] = g[(r, c)];
            a[(n + r, c)] = -g[(r, c)];
            a[(n + r, n + c)] = -ct[(r, c)];
        }
    }
    for (i, (mu, d, _)) in internal.iter().enumerate() {
        let q = 2 * n + i;
        let w = (d.abs() * mu).sqrt();
        for e in 0..n {
            a[(n + e, q)] = -d.signum() * w * rt[(e, i)];
            a[(q, n + e)] = w * rt[(e, i)];
        }
        a[(q, q)] = -mu;
    }
    Some((a, lk))
}

fn solve_standard(ops: &Operators<'_>, (a, lk): (Mat<f64>, Mat<f64>)) -> Result<Spectrum, ModalError> {
    let n = ops.n();
    let big = a.nrows();
    let w_ref = a.norm_max().max(f64::MIN_POSITIVE);
    let RealEigen { re: s_re, im: s_im, vectors: u } = real_eigen(a.as_ref()).map_err(|_| ModalError::NoConvergence)?;
    // x = L_K^-T y1
    let mut x = u.submatrix(0, 0, n, big).to_owned();
    triangular_solve::solve_upper_triangular_in_place(lk.transpose(), x.as_mut(), Par::Seq);
    Ok(Spectrum { s_re, s_im, s_b: vec![1.0; big], x, w_ref })
}

/// The pencil `A z = s B z` in the variables `(w0 x, v, q)`, for models
/// whose `K` or `M` is singular (DOFs without mass give infinite
/// eigenvalues).
fn solve_pencil(ops: &Operators<'_>, internal: &[(f64, f64, Vec<f64>)]) -> Result<Spectrum, ModalError> {
    let n = ops.n();
    let big = 2 * n + internal.len();
    let frob = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let w0 = (frob(&ops.k) / frob(&ops.m)).sqrt();
    let w0 = if w0.is_finite() && w0 > 0.0 { w0 } else { 1.0 };
    let mut a = Mat::<f64>::zeros(big, big);
    let mut b = Mat::<f64>::zeros(big, big);
    let pat = ops.sys.assembly().pattern();
    for i in 0..n {
        a[(i, n + i)] = w0;
        b[(i, i)] = 1.0;
    }
    for c in 0..n {
        for p in pat.col_ptr()[c]..pat.col_ptr()[c + 1] {
            let r = pat.row_idx()[p];
            a[(n + r, c)] = -ops.k[p] / w0;
            a[(n + r, n + c)] = -ops.c_viscous[p];
            b[(n + r, n + c)] = ops.m[p];
        }
    }
    for (i, (mu, d, r)) in internal.iter().enumerate() {
        let q = 2 * n + i;
        let w = (d.abs() * mu).sqrt();
        for e in 0..n {
            if r[e] != 0.0 {
                a[(n + e, q)] = -d.signum() * w * r[e];
                a[(q, n + e)] = w * r[e];
            }
        }
        a[(q, q)] = -mu;
        b[(q, q)] = 1.0;
    }
    let w_ref = a.norm_max().max(f64::MIN_POSITIVE) / b.norm_max().max(f64::MIN_POSITIVE);
    let mut s_re = Diag::<f64>::zeros(big);
    let mut s_im = Diag::<f64>::zeros(big);
    let mut s_b = Diag::<f64>::zeros(big);
    let mut u = Mat::<f64>::zeros(big, big);
    // faer 0.24's blocked QZ (aggressive early deflation) can underflow an
    // index on pencils of a few hundred rows; the unblocked double-shift QZ
    // is as accurate, only slower.
    let mut params: Spec<gevd::GevdParams, f64> = Default::default();
    params.schur.blocking_threshold = usize::MAX;
    let scratch = gevd::gevd_scratch::<f64>(big, ComputeEigenvectors::No, ComputeEigenvectors::Yes, Par::Seq, params);
    gevd::gevd_real(
        a.as_mut(),
        b.as_mut(),
        s_re.as_mut(),
        s_im.as_mut(),
        s_b.as_mut(),
        None,
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        params,
    )
    .map_err(|_| ModalError::NoConvergence)?;
    Ok(Spectrum {
        s_re: (0..big).map(|i| s_re[i]).collect(),
        s_im: (0..big).map(|i| s_im[i]).collect(),
        s_b: (0..big).map(|i| s_b[i]).collect(),
        x: u.submatrix(0, 0, n, big).to_owned(),
        w_ref,
    })
}

fn oscillatory_mode(ops: &Operators<'_>, s: C64, mut phi: Vec<C64>) -> ComplexMode {
    let a = ops.bilinear(&ops.dz_values(s), &phi);
    let big = phi.iter().copied().max_by(|x, y| x.norm().total_cmp(&y.norm())).unwrap_or_default();
    // a vanishing phi^T Z' phi would mean a defective eigenvalue, where no
    // residue scaling exists: the largest component is then set to 1
    let mut scale = if a.norm() > 0.0 && a.re.is_finite() && a.im.is_finite() { 1.0 / a.sqrt() } else { 1.0 / big };
    if (big * scale).re < 0.0 {
        scale = -scale;
    }
    phi.iter_mut().for_each(|v| *v *= scale);
    let w = s.norm();
    ComplexMode { eigenvalue: s, frequency_hz: w / (2.0 * std::f64::consts::PI), damping_ratio: -s.re / w, shape: phi }
}

fn real_mode(ops: &Operators<'_>, s: f64, phi: &[C64]) -> RealMode {
    // the null vector of a real symmetric Z(s) is real up to a complex factor
    let big = phi.iter().copied().max_by(|x, y| x.norm().total_cmp(&y.norm())).unwrap_or_default();
    let rot = if big.norm() > 0.0 { big.conj() / big.norm_sqr() } else { C64::new(1.0, 0.0) };
    let shape: Vec<f64> = phi.iter().map(|v| (v * rot).re).collect();
    let as_c: Vec<C64> = shape.iter().map(|&v| C64::new(v, 0.0)).collect();
    let modal_a = ops.bilinear(&ops.dz_values(C64::new(s, 0.0)), &as_c).re;
    RealMode { eigenvalue: s, shape, modal_a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::samples;

    #[test]
    fn dense_z_on_the_frequency_axis_equals_the_sparse_z() {
        let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        for w in [5.0, 300.0, 4000.0] {
            let dense = dynamic_stiffness(&sys, C64::new(0.0, w));
            let sparse = sys.z_values(w);
            let p = sys.assembly().pattern();
            let scale = sparse.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for c in 0..p.n() {
                for k in p.col_ptr()[c]..p.col_ptr()[c + 1] {
                    assert!((dense[(p.row_idx()[k], c)] - sparse[k]).norm() <= 1e-14 * scale);
                }
            }
        }
    }

    #[test]
    fn derivative_matches_a_complex_central_difference() {
        let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        let s = C64::new(-20.0, 350.0);
        let h = C64::new(1e-3, 1e-3);
        let d = dynamic_stiffness_derivative(&sys, s);
        let zp = dynamic_stiffness(&sys, s + h);
        let zm = dynamic_stiffness(&sys, s - h);
        let n = sys.n();
        let scale = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| d[(i, j)].norm()).fold(0.0, f64::max);
        for i in 0..n {
            for j in 0..n {
                let fd = (zp[(i, j)] - zm[(i, j)]) / (2.0 * h);
                assert!((fd - d[(i, j)]).norm() <= 1e-6 * scale, "({i},{j}): {fd} vs {}", d[(i, j)]);
            }
        }
    }

    #[test]
    fn a_rotational_joint_spring_adds_one_internal_variable() {
        // frame_with_joint: the joint group is a single rotational spring
        // between two rz equations (rank 1); the frame group is viscous.
        let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
        let modes = complex_modes(&sys).unwrap();
        assert_eq!(modes.internal_variables, 1);
        assert_eq!(modes.state_dimension, 2 * sys.n() + 1);
        assert_eq!(2 * modes.oscillatory.len() + modes.overdamped.len() + modes.infinite, modes.state_dimension);
    }
}

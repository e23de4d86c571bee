//! Modal parameters from measured FRFs: the (poly-reference) least-squares
//! complex frequency-domain estimator with a stabilisation check, followed by
//! a least-squares frequency-domain fit of the residues.
//!
//! # Poles: LSCF / pLSCF
//!
//! Within the chosen band, the receptances of each response `o` to the `m`
//! references form a row `H_o(w)` (`1 x m`). It is modelled by a right matrix
//! fraction in the discrete-time variable `z = exp(j w dt)`, `dt = 1 / (2 f_max)`
//! with `f_max` the top of the band:
//!
//! ```text
//! H_o(w) ~ B_o(z) A(z)^-1,   B_o(z) = sum_{r=0..p} z^r beta_{o,r},   A(z) = sum_{r=0..p} z^r alpha_r
//! ```
//!
//! with real `1 x m` rows `beta_{o,r}` and real `m x m` matrices `alpha_r` (real
//! coefficients give conjugate pole pairs). The linearised equation error
//! `E_o(w) = W_o(w) [B_o(z) - H_o(w) A(z)]` is minimised over all lines and
//! responses in the least-squares sense. Eliminating each `beta_o` leaves the
//! reduced normal equations
//!
//! ```text
//! M = sum_o (T_o - S_o^T R_o^-1 S_o),   R_o = Re(X_o^H X_o), S_o = Re(X_o^H Y_o), T_o = Re(Y_o^H Y_o)
//! ```
//!
//! whose blocks depend only on the lag between polynomial powers (they are
//! block-Toeplitz), so the sums over lines are computed once for the highest
//! order and reused for every order. With the constraint `alpha_p = I`,
//! `[alpha_0; ...; alpha_{p-1}] = -M_aa^-1 M_ab`. The poles are the
//! eigenvalues `z_i` of the block companion matrix of `A(z)^T`, mapped by
//! `s_i = ln(z_i) / dt`; the last block of each eigenvector is the
//! participation vector `l_i` (`A(z_i)^T l_i = 0`, so `l_i^T` is the row
//! structure of the residue). A pole is *physical* when `Im s > 0`,
//! `Re s < 0`, its frequency lies in the band and its damping ratio is below
//! [`LscfOptions::max_damping`].
//!
//! The weight `W_o(w)` is `1 / rms_o`, the RMS of response `o`'s row over the
//! band ([`Weighting::PerResponse`], the default: every response counts
//! equally), or `1 / |H_o(w)|` per line ([`Weighting::InverseMagnitude`]).
//! With 2 % relative noise on the two-material cantilever the per-response
//! weighting gave damping ratios within 0.2 %, the per-line one was biased
//! by about 11 % on the first two modes.
//!
//! # Stabilisation
//!
//! The estimator runs for every order `p` in [`LscfOptions::orders`]. Each
//! physical pole of order `p` is compared with the nearest (in frequency)
//! physical pole of order `p - 1`: it is stable in frequency when they differ
//! by at most `tol_frequency` (relative), also in damping when the damping
//! ratios differ by at most `tol_damping` (relative), and fully
//! [`PoleStatus::Stable`] when, in addition, the participation vectors have a
//! MAC of at least `1 - tol_vector` (always true with one reference).
//! Following each pole back to its nearest predecessor gives runs of
//! consecutive stable orders; a run of at least `min_stable_orders` orders
//! and at least `min_stable_fraction` of the orders analysed is a mode,
//! represented by the pole at the run's highest order (of two runs within
//! `tol_frequency` of each other, the longer is kept). Physical modes stay
//! stable once the order suffices; the poles that fit noise stabilise only
//! for a few orders. Every pole of every order, with its status, is kept in
//! [`ModalEstimate::stabilisation`] for a stabilisation diagram.
//!
//! # Residues: LSFD
//!
//! With the selected poles `lambda_k` fixed, every channel is fitted
//! linearly over the band:
//!
//! ```text
//! H(w) = sum_k [ R_k / (j w - lambda_k) + conj(R_k) / (j w - conj(lambda_k)) ] + UR + LR / (j w)^2
//! ```
//!
//! with complex residues `R_k`, an upper residual `UR` (modes above the band
//! act as a stiffness) and a lower residual `LR` (modes below the band act as
//! a mass). For the model's normalisation (`damping::complex_modes`), the
//! receptance residue is `R_k = phi_o phi_i`; the mode shape at the measured
//! responses is the rank-one factor of the residues `R_k[o, i] = psi_o l_i`,
//! scaled with the driving points (responses that are also references) so
//! that `l_i = psi_i`, which makes it comparable with the model's shape
//! including its scale.

use std::ops::RangeInclusive;

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::linalg::solvers::{Solve, SolveLstsq};
use faer::{Mat, Par, Side};
use fe_model::DofRef;
use num_complex::Complex64 as C64;

use crate::set::{Channel, FrfKind, FrfSet};

/// Error of the modal estimation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LscfError {
    /// The FRFs are not receptances.
    #[error("the modal estimator needs receptance FRFs, got {kind} (convert with FrfSet::to_receptance)")]
    NotReceptance {
        /// What the set holds.
        kind: FrfKind,
    },
    /// The band is empty, inverted or holds too few lines.
    #[error("the band {lo_hz} to {hi_hz} Hz holds {lines} lines; at least {needed} are needed for these orders")]
    Band {
        /// Lower edge (Hz).
        lo_hz: f64,
        /// Upper edge (Hz).
        hi_hz: f64,
        /// Lines inside.
        lines: usize,
        /// Lines needed.
        needed: usize,
    },
    /// pLSCF needs every response measured for every reference.
    #[error("the FRFs do not form a full grid: {response} is not measured for reference {reference}")]
    IncompleteGrid {
        /// The response.
        response: DofRef,
        /// The reference.
        reference: DofRef,
    },
    /// A value that is not finite in the data.
    #[error("channel {channel} has a non-finite value at {freq_hz} Hz")]
    NotFinite {
        /// The channel.
        channel: Channel,
        /// The frequency.
        freq_hz: f64,
    },
    /// The options are inconsistent.
    #[error("invalid option: {0}")]
    Options(String),
    /// The residue least-squares problem is singular (two selected poles
    /// coincide, or the band is too narrow for the residual terms).
    #[error("the residue least-squares fit is singular")]
    ResidueFit,
    /// A linear-algebra step failed (singular normal equations or no
    /// convergence of an eigensolver) at a model order.
    #[error("the estimator failed at order {order}: {what}")]
    Numerical {
        /// The model order.
        order: usize,
        /// What failed.
        what: &'static str,
    },
}

/// The weighting of each response's equation error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// `1 / |H_o(w)|` per line: every line counts in relative terms.
    InverseMagnitude,
    /// `1 / rms_o` per response: every response counts equally.
    PerResponse,
}

/// Options of [`lscf`]; [`LscfOptions::new`] gives the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct LscfOptions {
    /// Band `(lo, hi)` in Hz; lines outside it are ignored.
    pub band_hz: (f64, f64),
    /// Model orders `p` (poles per order: `m p`, `m` references).
    pub orders: RangeInclusive<usize>,
    /// Equation-error weighting.
    pub weighting: Weighting,
    /// Relative frequency tolerance between consecutive orders (default 0.01).
    pub tol_frequency: f64,
    /// Relative damping tolerance between consecutive orders (default 0.05).
    pub tol_damping: f64,
    /// `1 - MAC` tolerance of participation vectors (default 0.02).
    pub tol_vector: f64,
    /// Consecutive orders in which a pole must be stable to be selected
    /// (default 5) ...
    pub min_stable_orders: usize,
    /// ... and at least this fraction of the number of orders analysed
    /// (default 0.25), which rejects the short-lived noise poles that
    /// stabilise briefly at high orders.
    pub min_stable_fraction: f64,
    /// Largest damping ratio of a physical pole (default 0.2).
    pub max_damping: f64,
}

impl LscfOptions {
    /// Default options over a band (Hz): orders 4 to 40, per-response
    /// weighting, tolerances 1 % in frequency, 5 % in damping, MAC 0.98,
    /// stable in at least 5 consecutive orders and a quarter of the orders,
    /// damping ratios below 0.2.
    pub fn new(lo_hz: f64, hi_hz: f64) -> Self {
        LscfOptions {
            band_hz: (lo_hz, hi_hz),
            orders: 4..=40,
            weighting: Weighting::PerResponse,
            tol_frequency: 0.01,
            tol_damping: 0.05,
            tol_vector: 0.02,
            min_stable_orders: 5,
            min_stable_fraction: 0.25,
            max_damping: 0.2,
        }
    }
}

/// How a pole compares with the nearest pole of the previous order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PoleStatus {
    /// No pole of the previous order is within the frequency tolerance.
    New,
    /// Stable in frequency only.
    Frequency,
    /// Stable in frequency and damping, not in participation.
    Damping,
    /// Stable in frequency, damping and participation.
    Stable,
}

/// One physical pole of one model order.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilisationPole {
    /// Pole (rad/s).
    pub pole: C64,
    /// Natural frequency `|s| / (2 pi)` (Hz).
    pub frequency_hz: f64,
    /// Damping ratio `-Re s / |s|`.
    pub damping_ratio: f64,
    /// Participation vector (one entry per reference), unit norm.
    pub participation: Vec<C64>,
    /// Comparison with the previous order.
    pub status: PoleStatus,
}

/// The physical poles of one model order.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderPoles {
    /// Model order `p`.
    pub order: usize,
    /// Its physical poles by increasing frequency.
    pub poles: Vec<StabilisationPole>,
}

/// One identified mode.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatedMode {
    /// Pole `lambda` (rad/s), `Im > 0`.
    pub pole: C64,
    /// Natural frequency `|lambda| / (2 pi)` (Hz).
    pub frequency_hz: f64,
    /// Damping ratio `-Re lambda / |lambda|`.
    pub damping_ratio: f64,
    /// Number of orders in which the pole was stable.
    pub stable_orders: usize,
    /// Participation vector of the selected pole (per reference).
    pub participation: Vec<C64>,
    /// Residue `R_k` of each channel (same order as the set's channels).
    pub residues: Vec<C64>,
    /// Mode shape at [`ModalEstimate::responses`]; see the module docs.
    pub shape: Vec<C64>,
    /// True when the shape carries the model's scale (`phi^T Z' phi = 1`),
    /// which needs at least one driving point; otherwise its largest
    /// component is 1.
    pub scaled: bool,
}

/// The outcome of [`lscf`].
#[derive(Clone, Debug, PartialEq)]
pub struct ModalEstimate {
    /// Identified modes by increasing frequency.
    pub modes: Vec<EstimatedMode>,
    /// Physical poles of every order, for a stabilisation diagram.
    pub stabilisation: Vec<OrderPoles>,
    /// The channels fitted (those of the input set).
    pub channels: Vec<Channel>,
    /// Distinct responses (rows of the shapes).
    pub responses: Vec<DofRef>,
    /// Distinct references.
    pub references: Vec<DofRef>,
    /// The band actually used (first and last line inside it, Hz).
    pub band_hz: (f64, f64),
    /// Upper residual `UR` of each channel.
    pub upper_residuals: Vec<C64>,
    /// Lower residual `LR` of each channel (`LR / (j w)^2`).
    pub lower_residuals: Vec<C64>,
    /// Relative LSFD misfit of each channel, `|H - H_fit| / |H|` over the
    /// band (absolute for a channel of zeros).
    pub fit_error: Vec<f64>,
}

impl ModalEstimate {
    /// The LSFD synthesis of channel `c` at `freq_hz`.
    pub fn synthesize(&self, c: usize, freq_hz: f64) -> C64 {
        let jw = C64::new(0.0, 2.0 * std::f64::consts::PI * freq_hz);
        let mut h = self.upper_residuals[c] + self.lower_residuals[c] / (jw * jw);
        for m in &self.modes {
            let r = m.residues[c];
            h += r / (jw - m.pole) + r.conj() / (jw - m.pole.conj());
        }
        h
    }
}

/// The lines of the band and, per response, the channel of each reference.
struct Arranged {
    omega: Vec<f64>,
    /// Channel index of (response, reference).
    index: Vec<Vec<usize>>,
    responses: Vec<DofRef>,
    references: Vec<DofRef>,
    lines: Vec<usize>,
}

fn arrange(set: &FrfSet, opts: &LscfOptions) -> Result<Arranged, LscfError> {
    if set.kind() != FrfKind::Receptance {
        return Err(LscfError::NotReceptance { kind: set.kind() });
    }
    let (lo, hi) = opts.band_hz;
    let lines: Vec<usize> =
        (0..set.n_freq()).filter(|&k| set.frequencies_hz()[k] >= lo && set.frequencies_hz()[k] <= hi).collect();
    let max_order = *opts.orders.end();
    let references = set.references();
    let mut responses: Vec<DofRef> = Vec::new();
    for c in set.channels() {
        if !responses.contains(&c.response) {
            responses.push(c.response);
        }
    }
    // at least twice as many lines as denominator coefficients per column
    // (m (p + 1)), so that every order's normal equations are well posed
    let needed = 2 * (max_order + 1) * references.len().max(1);
    if !(lo < hi) || lines.len() < needed {
        return Err(LscfError::Band { lo_hz: lo, hi_hz: hi, lines: lines.len(), needed });
    }
    let mut index = Vec::with_capacity(responses.len());
    for &response in &responses {
        let mut row = Vec::with_capacity(references.len());
        for &reference in &references {
            let c =
                set.find(Channel::new(response, reference)).ok_or(LscfError::IncompleteGrid { response, reference })?;
            row.push(c);
        }
        index.push(row);
    }
    for (c, &channel) in set.channels().iter().enumerate() {
        for &k in &lines {
            let v = set.get(c, k);
            if !(v.re.is_finite() && v.im.is_finite()) {
                return Err(LscfError::NotFinite { channel, freq_hz: set.frequencies_hz()[k] });
            }
        }
    }
    let omega = lines.iter().map(|&k| 2.0 * std::f64::consts::PI * set.frequencies_hz()[k]).collect();
    Ok(Arranged { omega, index, responses, references, lines })
}

/// Lag sums of one response: `r[d]`, `s[d][i]`, `t[d][i][k]` for lags
/// `d = -p..=p` (stored at `d + p`); see the module docs.
struct LagSums {
    r: Vec<C64>,
    s: Vec<Vec<C64>>,
    t: Vec<Vec<C64>>,
}

fn lag_sums(set: &FrfSet, arr: &Arranged, o: usize, dt: f64, p: usize, weighting: Weighting) -> LagSums {
    let m = arr.references.len();
    let nl = 2 * p + 1;
    let mut r = vec![C64::new(0.0, 0.0); nl];
    let mut s = vec![vec![C64::new(0.0, 0.0); m]; nl];
    let mut t = vec![vec![C64::new(0.0, 0.0); m * m]; nl];
    let rows: Vec<Vec<C64>> =
        arr.lines.iter().map(|&k| arr.index[o].iter().map(|&c| set.get(c, k)).collect()).collect();
    let rms = (rows.iter().flatten().map(|v| v.norm_sqr()).sum::<f64>() / rows.len() as f64).sqrt();
    for (f, row) in rows.iter().enumerate() {
        let mag = row.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
        // a line (or response) of zeros carries no information: weight 0
        let w2 = match weighting {
            Weighting::InverseMagnitude if mag > 0.0 => 1.0 / (mag * mag),
            Weighting::PerResponse if rms > 0.0 => 1.0 / (rms * rms),
            _ => 0.0,
        };
        let theta = arr.omega[f] * dt;
        for (li, d) in (-(p as i64)..=(p as i64)).enumerate() {
            let e = C64::from_polar(w2, theta * d as f64);
            r[li] += e;
            for i in 0..m {
                s[li][i] += e * row[i];
                let ci = row[i].conj();
                for k in 0..m {
                    t[li][i * m + k] += e * ci * row[k];
                }
            }
        }
    }
    LagSums { r, s, t }
}

/// Physical poles and participation vectors of order `p` from the reduced
/// normal equations.
fn poles_of_order(
    sums: &[LagSums],
    m: usize,
    p: usize,
    pmax: usize,
    dt: f64,
) -> Result<Vec<(C64, Vec<C64>)>, &'static str> {
    let np = p + 1;
    let nm = m * np;
    let mut big = Mat::<f64>::zeros(nm, nm);
    for ls in sums {
        let lag = |d: i64| (d + pmax as i64) as usize;
        let mut rmat = Mat::<f64>::zeros(np, np);
        let mut smat = Mat::<f64>::zeros(np, nm);
        for r in 0..np {
            for q in 0..np {
                let d = lag(q as i64 - r as i64);
                rmat[(r, q)] = ls.r[d].re;
                for i in 0..m {
                    smat[(r, q * m + i)] = -ls.s[d][i].re;
                }
            }
        }
        let llt = rmat.llt(Side::Lower).map_err(|_| "the polynomial basis normal matrix is not positive definite")?;
        let rs = llt.solve(&smat);
        // T - S^T R^-1 S
        for r in 0..np {
            for i in 0..m {
                for q in 0..np {
                    let d = lag(q as i64 - r as i64);
                    for k in 0..m {
                        big[(r * m + i, q * m + k)] += ls.t[d][i * m + k].re;
                    }
                }
            }
        }
        let sts = smat.transpose() * &rs;
        big -= &sts;
    }
    let na = m * p;
    let maa = big.submatrix(0, 0, na, na).to_owned();
    let mab = big.submatrix(0, na, na, m).to_owned();
    // symmetric positive (semi-)definite: Cholesky, with LU as a fallback
    let alpha = match maa.llt(Side::Lower) {
        Ok(l) => -l.solve(&mab),
        Err(_) => -maa.partial_piv_lu().solve(&mab),
    };
    if alpha.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err("the reduced normal equations are singular");
    }
    // block companion of A(z)^T: first block row -alpha_{p-1}^T ... -alpha_0^T
    let mut comp = Mat::<f64>::zeros(na, na);
    for blk in 0..p {
        let r = p - 1 - blk; // power held by block column `blk`
        for i in 0..m {
            for k in 0..m {
                // alpha_r^T[i, k] = alpha_r[k, i]
                comp[(i, blk * m + k)] = -alpha[(r * m + k, i)];
            }
        }
    }
    for blk in 1..p {
        for i in 0..m {
            comp[(blk * m + i, (blk - 1) * m + i)] = 1.0;
        }
    }
    let mut s_re = Diag::<f64>::zeros(na);
    let mut s_im = Diag::<f64>::zeros(na);
    let mut u = Mat::<f64>::zeros(na, na);
    let scratch =
        evd::evd_scratch::<f64>(na, ComputeEigenvectors::No, ComputeEigenvectors::Yes, Par::Seq, Default::default());
    evd::evd_real(
        comp.as_ref(),
        s_re.as_mut(),
        s_im.as_mut(),
        None,
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|_| "the companion eigensolver did not converge")?;
    let mut out = Vec::new();
    let mut j = 0;
    while j < na {
        let pair = s_im[j] != 0.0 && j + 1 < na;
        let z = C64::new(s_re[j], s_im[j]);
        if !(z.re.is_finite() && z.im.is_finite()) {
            return Err("the companion eigensolver returned a non-finite value");
        }
        if pair {
            // eigenvector of z = s_re + j s_im: u_j + j u_{j+1}; of conj(z): its conjugate
            let (z, sign) = if z.im > 0.0 { (z, 1.0) } else { (z.conj(), -1.0) };
            let l: Vec<C64> = (0..m)
                .map(|i| {
                    let row = (p - 1) * m + i;
                    C64::new(u[(row, j)], sign * u[(row, j + 1)])
                })
                .collect();
            if z.norm() > 0.0 {
                out.push((z.ln() / dt, unit(l)));
            }
        }
        j += if pair { 2 } else { 1 };
    }
    Ok(out)
}

fn unit(mut v: Vec<C64>) -> Vec<C64> {
    let n = v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
    if n > 0.0 {
        v.iter_mut().for_each(|x| *x /= n);
    }
    v
}

/// `|a^H b|^2 / (|a|^2 |b|^2)`.
fn mac(a: &[C64], b: &[C64]) -> f64 {
    let dot: C64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let na: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let nb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if na == 0.0 || nb == 0.0 { 0.0 } else { dot.norm_sqr() / (na * nb) }
}

fn check_options(opts: &LscfOptions) -> Result<(), LscfError> {
    let (lo, hi) = opts.band_hz;
    if !(lo >= 0.0 && hi > lo && hi.is_finite()) {
        return Err(LscfError::Options(format!("band {lo} to {hi} Hz")));
    }
    if *opts.orders.start() < 1 || opts.orders.is_empty() {
        return Err(LscfError::Options(format!("orders {:?} (need 1 <= min <= max)", opts.orders)));
    }
    for (name, v) in [
        ("tol_frequency", opts.tol_frequency),
        ("tol_damping", opts.tol_damping),
        ("tol_vector", opts.tol_vector),
        ("max_damping", opts.max_damping),
    ] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(LscfError::Options(format!("{name} = {v} (must be positive)")));
        }
    }
    if opts.min_stable_orders == 0 {
        return Err(LscfError::Options("min_stable_orders = 0".into()));
    }
    if !(0.0..=1.0).contains(&opts.min_stable_fraction) {
        return Err(LscfError::Options(format!(
            "min_stable_fraction = {} (must be in [0, 1])",
            opts.min_stable_fraction
        )));
    }
    Ok(())
}

/// Estimates poles, residues and mode shapes from receptance FRFs; see the
/// module docs for the method and the stabilisation criteria.
pub fn lscf(set: &FrfSet, opts: &LscfOptions) -> Result<ModalEstimate, LscfError> {
    check_options(opts)?;
    let arr = arrange(set, opts)?;
    let m = arr.references.len();
    let pmax = *opts.orders.end();
    let f_first = set.frequencies_hz()[arr.lines[0]];
    let f_last = set.frequencies_hz()[*arr.lines.last().unwrap()];
    let dt = 1.0 / (2.0 * f_last);
    // responses without any signal add nothing (and would make R_o singular)
    let sums: Vec<LagSums> = (0..arr.responses.len())
        .map(|o| lag_sums(set, &arr, o, dt, pmax, opts.weighting))
        .filter(|ls| ls.r[pmax].re > 0.0)
        .collect();

    let two_pi = 2.0 * std::f64::consts::PI;
    let mut stabilisation: Vec<OrderPoles> = Vec::new();
    for p in opts.orders.clone() {
        let raw = poles_of_order(&sums, m, p, pmax, dt).map_err(|what| LscfError::Numerical { order: p, what })?;
        let mut poles: Vec<StabilisationPole> = raw
            .into_iter()
            .filter_map(|(s, participation)| {
                let w = s.norm();
                let frequency_hz = w / two_pi;
                let damping_ratio = -s.re / w;
                let physical = s.im > 0.0
                    && s.re < 0.0
                    && frequency_hz >= f_first
                    && frequency_hz <= f_last
                    && damping_ratio < opts.max_damping;
                physical.then_some(StabilisationPole {
                    pole: s,
                    frequency_hz,
                    damping_ratio,
                    participation,
                    status: PoleStatus::New,
                })
            })
            .collect();
        poles.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        if let Some(prev) = stabilisation.last() {
            for pole in &mut poles {
                pole.status = status(pole, &prev.poles, opts);
            }
        }
        stabilisation.push(OrderPoles { order: p, poles });
    }

    let selected = select(&stabilisation, opts);
    lsfd(set, &arr, selected, stabilisation, (f_first, f_last))
}

fn status(pole: &StabilisationPole, prev: &[StabilisationPole], opts: &LscfOptions) -> PoleStatus {
    let Some(near) = nearest(prev, pole.frequency_hz).map(|k| &prev[k]) else {
        return PoleStatus::New;
    };
    if (near.frequency_hz - pole.frequency_hz).abs() > opts.tol_frequency * near.frequency_hz {
        return PoleStatus::New;
    }
    if (near.damping_ratio - pole.damping_ratio).abs() > opts.tol_damping * near.damping_ratio {
        return PoleStatus::Frequency;
    }
    if mac(&near.participation, &pole.participation) < 1.0 - opts.tol_vector {
        return PoleStatus::Damping;
    }
    PoleStatus::Stable
}

/// Index of the pole of `prev` nearest in frequency to `f`.
fn nearest(prev: &[StabilisationPole], f: f64) -> Option<usize> {
    (0..prev.len()).min_by(|&a, &b| (prev[a].frequency_hz - f).abs().total_cmp(&(prev[b].frequency_hz - f).abs()))
}

/// Follows each pole back through the orders (to the nearest pole of the
/// previous order) and keeps the unbroken runs of [`PoleStatus::Stable`]
/// at least `min_stable_orders` long, one per mode: `(pole, participation,
/// run length)` of the run's last (highest-order) pole.
fn select(stab: &[OrderPoles], opts: &LscfOptions) -> Vec<(C64, Vec<C64>, usize)> {
    // run[i][j]: consecutive orders, ending at pole j of order i, in which
    // the pole was stable with respect to its predecessor
    let mut run: Vec<Vec<usize>> = Vec::with_capacity(stab.len());
    for (i, order) in stab.iter().enumerate() {
        let row = order
            .poles
            .iter()
            .map(|p| match (p.status, i.checked_sub(1)) {
                (PoleStatus::Stable, Some(h)) => 1 + nearest(&stab[h].poles, p.frequency_hz).map_or(0, |k| run[h][k]),
                _ => 0,
            })
            .collect();
        run.push(row);
    }
    let min_run = opts.min_stable_orders.max((opts.min_stable_fraction * stab.len() as f64).ceil() as usize);
    // the ends of runs: not continued by a stable pole of the next order
    let mut ends: Vec<(usize, usize, usize)> = Vec::new();
    for (i, order) in stab.iter().enumerate() {
        for (j, _) in order.poles.iter().enumerate() {
            let continued = stab.get(i + 1).is_some_and(|next| {
                next.poles
                    .iter()
                    .enumerate()
                    .any(|(k, q)| run[i + 1][k] > 0 && nearest(&order.poles, q.frequency_hz) == Some(j))
            });
            if run[i][j] >= min_run && !continued {
                ends.push((run[i][j], i, j));
            }
        }
    }
    // longest runs first; a shorter run of the same mode (broken once) is dropped
    ends.sort_by(|a, b| b.0.cmp(&a.0).then(b.1.cmp(&a.1)));
    let mut out: Vec<(C64, Vec<C64>, usize)> = Vec::new();
    for (len, i, j) in ends {
        let p = &stab[i].poles[j];
        let f = p.frequency_hz;
        if out.iter().all(|(q, _, _)| (q.norm() / (2.0 * std::f64::consts::PI) - f).abs() > opts.tol_frequency * f) {
            out.push((p.pole, p.participation.clone(), len));
        }
    }
    out.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
    out
}

/// The least-squares frequency-domain fit of residues and residual terms.
fn lsfd(
    set: &FrfSet,
    arr: &Arranged,
    selected: Vec<(C64, Vec<C64>, usize)>,
    stabilisation: Vec<OrderPoles>,
    band_hz: (f64, f64),
) -> Result<ModalEstimate, LscfError> {
    let nf = arr.lines.len();
    let nk = selected.len();
    let ncol = 2 * nk + 4;
    let nch = set.channels().len();
    // real design matrix: rows (Re, Im) of each line
    let mut a = Mat::<f64>::zeros(2 * nf, ncol);
    for (f, &w) in arr.omega.iter().enumerate() {
        let jw = C64::new(0.0, w);
        let mut put = |col: usize, v: C64| {
            a[(2 * f, col)] = v.re;
            a[(2 * f + 1, col)] = v.im;
        };
        for (k, (lambda, _, _)) in selected.iter().enumerate() {
            let g = 1.0 / (jw - lambda);
            let gc = 1.0 / (jw - lambda.conj());
            put(2 * k, g + gc);
            put(2 * k + 1, C64::new(0.0, 1.0) * (g - gc));
        }
        put(2 * nk, C64::new(1.0, 0.0));
        put(2 * nk + 1, C64::new(0.0, 1.0));
        put(2 * nk + 2, 1.0 / (jw * jw));
        put(2 * nk + 3, C64::new(0.0, 1.0) / (jw * jw));
    }
    // unit-norm columns keep the least-squares problem well conditioned
    let scale: Vec<f64> = (0..ncol).map(|c| a.col(c).norm_l2()).collect();
    for c in 0..ncol {
        if scale[c] > 0.0 {
            for r in 0..2 * nf {
                a[(r, c)] /= scale[c];
            }
        }
    }
    let mut b = Mat::<f64>::zeros(2 * nf, nch);
    for c in 0..nch {
        for (f, &k) in arr.lines.iter().enumerate() {
            let v = set.get(c, k);
            b[(2 * f, c)] = v.re;
            b[(2 * f + 1, c)] = v.im;
        }
    }
    let x = a.qr().solve_lstsq(&b);
    if x.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err(LscfError::ResidueFit);
    }
    let coef = |col: usize, c: usize| x[(col, c)] / if scale[col] > 0.0 { scale[col] } else { 1.0 };
    let upper_residuals: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * nk, c), coef(2 * nk + 1, c))).collect();
    let lower_residuals: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * nk + 2, c), coef(2 * nk + 3, c))).collect();

    let mut modes = Vec::with_capacity(nk);
    for (k, (pole, participation, stable_orders)) in selected.into_iter().enumerate() {
        let residues: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * k, c), coef(2 * k + 1, c))).collect();
        let (shape, scaled) = shape_from_residues(arr, &residues, &participation);
        let w = pole.norm();
        modes.push(EstimatedMode {
            pole,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            damping_ratio: -pole.re / w,
            stable_orders,
            participation,
            residues,
            shape,
            scaled,
        });
    }
    let mut out = ModalEstimate {
        modes,
        stabilisation,
        channels: set.channels().to_vec(),
        responses: arr.responses.clone(),
        references: arr.references.clone(),
        band_hz,
        upper_residuals,
        lower_residuals,
        fit_error: Vec::new(),
    };
    out.fit_error = (0..nch)
        .map(|c| {
            let (mut num, mut den) = (0.0, 0.0);
            for &k in &arr.lines {
                let h = set.get(c, k);
                num += (h - out.synthesize(c, set.frequencies_hz()[k])).norm_sqr();
                den += h.norm_sqr();
            }
            if den > 0.0 { (num / den).sqrt() } else { num.sqrt() }
        })
        .collect();
    Ok(out)
}

/// The rank-one factor `psi` of the residues `R[o, i] = psi_o l_i`, scaled
/// with the driving points when there are any.
fn shape_from_residues(arr: &Arranged, residues: &[C64], participation: &[C64]) -> (Vec<C64>, bool) {
    let ll: f64 = participation.iter().map(|v| v.norm_sqr()).sum();
    let mut psi: Vec<C64> = arr
        .index
        .iter()
        .map(|row| row.iter().zip(participation).map(|(&c, l)| residues[c] * l.conj()).sum::<C64>() / ll)
        .collect();
    // driving points: l_i = c psi_ref(i), choose c^2 in the least-squares sense
    let (mut num, mut den) = (C64::new(0.0, 0.0), 0.0);
    for (i, r) in arr.references.iter().enumerate() {
        if let Some(o) = arr.responses.iter().position(|x| x == r) {
            num += psi[o].conj() * participation[i];
            den += psi[o].norm_sqr();
        }
    }
    let big = |v: &[C64]| v.iter().copied().max_by(|x, y| x.norm().total_cmp(&y.norm())).unwrap_or_default();
    if den > 0.0 && num.norm() > 0.0 {
        // psi' = psi sqrt(c2) makes psi'_ref = l'_i with l' = l / sqrt(c2)
        let c2 = num / den;
        let mut f = c2.sqrt();
        if (big(&psi) * f).re < 0.0 {
            f = -f;
        }
        psi.iter_mut().for_each(|v| *v *= f);
        (psi, true)
    } else {
        let b = big(&psi);
        if b.norm() > 0.0 {
            psi.iter_mut().for_each(|v| *v /= b);
        }
        (psi, false)
    }
}

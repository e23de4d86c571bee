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
//!
//! The estimator's steps have a file each: `poles.rs` (lag sums, reduced
//! normal equations and the companion matrix, per order), `stabilisation.rs`
//! (status of each pole against the previous order, selection of the
//! modes) and `lsfd.rs` (residues, residuals and shapes).

use std::ops::RangeInclusive;

use fe_model::DofRef;
use num_complex::Complex64 as C64;

use crate::set::{Channel, FrfKind, FrfSet};

mod lsfd;
mod poles;
mod stabilisation;

use lsfd::lsfd;
use poles::{LagSums, lag_sums, poles_of_order};
use stabilisation::{select, status};

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
    /// The lines of the band (indices into the set's lines).
    lines: std::ops::Range<usize>,
}

fn arrange(set: &FrfSet, opts: &LscfOptions) -> Result<Arranged, LscfError> {
    if set.kind() != FrfKind::Receptance {
        return Err(LscfError::NotReceptance { kind: set.kind() });
    }
    let (lo, hi) = opts.band_hz;
    // the lines of a set increase: those of the band are one run
    let f = set.frequencies_hz();
    let lines = f.partition_point(|&x| x < lo)..f.partition_point(|&x| x <= hi);
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
        for k in lines.clone() {
            let v = set.get(c, k);
            if !(v.re.is_finite() && v.im.is_finite()) {
                return Err(LscfError::NotFinite { channel, freq_hz: set.frequencies_hz()[k] });
            }
        }
    }
    let omega = lines.clone().map(|k| 2.0 * std::f64::consts::PI * set.frequencies_hz()[k]).collect();
    Ok(Arranged { omega, index, responses, references, lines })
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
    let f_first = set.frequencies_hz()[arr.lines.start];
    let f_last = set.frequencies_hz()[arr.lines.end - 1];
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

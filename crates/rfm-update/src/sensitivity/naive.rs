//! The dense textbook formulation of [`super::assemble`]: a reference
//! implementation for tests and benchmarks, never for real work.
//!
//! Per frequency it forms `Z` as a dense `N x N` matrix, inverts it
//! (`R = Z^-1`, dense LU with partial pivoting), and for every parameter forms
//! `(dZ/dp_i) p_i` densely; then, for each channel (response `m`, reference
//! `v`), `S[channel, i] = R[m, :] (dZ/dp_i p_i) x` with `x` the reference's
//! column of `R`, its measured rows replaced by the measured values for
//! [`Hybrid::Measured`]. Channels are resolved to equations here, from the
//! plan's public channel list, independently of the fast path.
//!
//! Cost `O(N^3)` per frequency and `O(N^2)` memory (three dense complex
//! matrices): the paper's formulation, as in a NumPy script. Frequencies run
//! one after the other; faer's dense kernels use its global parallelism.

use damping::DampedSystem;
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use fe_model::Quantity;
use frf::equation_of;
use num_complex::Complex64 as C64;

use super::{ChannelPlan, FrequencyBlock, Hybrid};
use crate::error::UpdateError;

/// Values on the assembly's pattern as a dense matrix.
fn dense(sys: &DampedSystem, values: &[C64]) -> Mat<C64> {
    let pat = sys.assembly().pattern();
    let mut m = Mat::<C64>::zeros(sys.n(), sys.n());
    for c in 0..pat.n() {
        for p in pat.col_ptr()[c]..pat.col_ptr()[c + 1] {
            m[(pat.row_idx()[p], c)] += values[p];
        }
    }
    m
}

/// Same result as [`super::assemble`], by dense inversion; see the module docs.
pub fn assemble(
    sys: &DampedSystem,
    plan: &ChannelPlan,
    params: &[Quantity],
    freqs_hz: &[f64],
    hybrid: Hybrid<'_>,
) -> Result<Vec<FrequencyBlock>, UpdateError> {
    let eqs: Vec<(usize, usize)> = plan
        .channels
        .iter()
        .map(|c| Ok((equation_of(sys, c.response)?, equation_of(sys, c.reference)?)))
        .collect::<Result<_, UpdateError>>()?;
    let n = sys.n();
    let mut blocks = Vec::with_capacity(freqs_hz.len());
    for (line, &freq_hz) in freqs_hz.iter().enumerate() {
        let omega = 2.0 * std::f64::consts::PI * freq_hz;
        let r = dense(sys, &sys.z_values(omega)).partial_piv_lu().inverse();
        let model: Vec<C64> = eqs.iter().map(|&(m, v)| r[(m, v)]).collect();
        // x for each channel's reference: R[:, v], measured rows replaced
        let mut xs: Vec<(usize, Mat<C64>)> = Vec::new();
        for &(_, v) in &eqs {
            if xs.iter().all(|&(e, _)| e != v) {
                let mut x = Mat::<C64>::from_fn(n, 1, |i, _| r[(i, v)]);
                if let Hybrid::Measured(meas) = hybrid {
                    for (c, &(m, v2)) in eqs.iter().enumerate() {
                        if v2 == v {
                            x[(m, 0)] = meas.get(c, line);
                        }
                    }
                }
                xs.push((v, x));
            }
        }
        let mut sens = Mat::<C64>::zeros(eqs.len(), params.len());
        for (i, &q) in params.iter().enumerate() {
            let dz = dense(sys, &sys.derivative(q, omega).values(sys.assembly()));
            for (v, x) in &xs {
                let w = &dz * x;
                let s = r.as_ref() * &w;
                for (c, &(m, v2)) in eqs.iter().enumerate() {
                    if v2 == *v {
                        sens[(c, i)] = s[(m, 0)];
                    }
                }
            }
        }
        blocks.push(FrequencyBlock { freq_hz, model, sens });
    }
    Ok(blocks)
}

//! Measured modes without a partner in the model.

use damping::DampedSystem;
use frf::FrfSet;

use super::{Finding, FindingKind};
use crate::error::UpdateError;

/// Pairs below this MAC are no pairs.
const MIN_MAC: f64 = 0.5;

/// A model mode this close in frequency (relative) may be the unpaired
/// measured mode's partner, its shape spoilt by a model error.
const NEARBY: f64 = 0.15;

/// Measured modes are taken as real up to this damping ratio.
const MAX_DAMPING: f64 = 0.2;

/// The LSCF's model orders. A resonator's mode is often far more damped
/// than the structure's (a rubber mount, a tuned-mass damper), and beside
/// lightly damped modes its pole settles only at high orders: a 77 g
/// resonator at 20 Hz with 3.4 % damping on the lab's 20-element cantilever
/// (lab study, trial 20, 1 Hz lines) was stable from order 32 on, short of
/// the quarter of the default orders (4 to 40) a mode needs, and was found
/// in 25 orders of 4 to 60 (the structure's modes in 44 to 50).
const ORDERS: std::ops::RangeInclusive<usize> = 4..=60;

/// The measured modes the model lacks: modes of an LSCF estimate of the
/// data (receptances, model orders 4 to 60) that pair with no model mode by MAC (0.5 or more),
/// and that have no unpaired model mode within 15 % of their frequency
/// (which would be their partner with a shape a model error spoils). An
/// attached resonator makes one: the data show a mode more than the
/// model, or two where the model has one. Nothing is found, rather than
/// the loop stopped, where the modes cannot be estimated (too few lines,
/// a model too large for its dense complex modes).
pub fn extra_modes(sys: &DampedSystem, measured: &FrfSet) -> Result<Vec<Finding>, UpdateError> {
    let Ok(cmp) = frf::compare_modes_with(sys, measured, MIN_MAC, ORDERS) else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for &i in &cmp.pairing.unpaired_measured {
        let m = &cmp.measured[i];
        if !(m.damping_ratio > 0.0 && m.damping_ratio < MAX_DAMPING) {
            continue;
        }
        let f = m.frequency_hz;
        let near_free =
            cmp.pairing.unpaired_model.iter().any(|&j| (cmp.model[j].frequency_hz / f - 1.0).abs() < NEARBY);
        if near_free {
            continue;
        }
        let best_mac = cmp.pairing.mac[i].iter().copied().fold(0.0, f64::max);
        let in_band = |x: f64| x >= cmp.band_hz.0 && x <= cmp.band_hz.1;
        let model_in_band = cmp.model.iter().filter(|x| in_band(x.frequency_hz)).count();
        out.push(Finding {
            kind: FindingKind::ExtraMode,
            channels: Vec::new(),
            summary: format!(
                "the data show a mode at {f:.1} Hz that the model lacks (an attached resonator, a loose part or a \
                 fixture?)"
            ),
            evidence: format!(
                "{} measured modes against {model_in_band} of the model in {:.1}-{:.1} Hz; this one ({:.2} % damping) \
                 pairs with none (best MAC {best_mac:.2}) and no unpaired model mode lies within {:.0} % of it",
                cmp.measured.len(),
                cmp.band_hz.0,
                cmp.band_hz.1,
                100.0 * m.damping_ratio,
                100.0 * NEARBY
            ),
            corrections: Vec::new(),
            misfit_before: f64::NAN,
            misfit_after: f64::NAN,
            frequency_hz: Some(f),
            found_after_step: 0,
        });
    }
    Ok(out)
}

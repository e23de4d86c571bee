//! A model's modes against the measured ones: the measured modes estimated
//! from the FRFs ([`crate::lscf()`] over the measured band), the model's
//! complex modes in that band with shapes at every free DOF, and the
//! one-to-one pairing by MAC over the measured responses
//! ([`compare_modes`]); and the real shapes to draw of a pair
//! ([`real_shape`], [`measured_on_model`]).
//!
//! The model's shapes are kept at every free DOF, not only the measured
//! ones, so that a paired mode can be drawn on the whole structure; the MAC
//! is taken over the DOFs both sides have, the measured responses.

use std::collections::HashMap;

use damping::DampedSystem;
use fe_model::{DofRef, Slot};

use crate::lscf::{LscfError, LscfOptions, ModalEstimate, lscf};
use crate::modal::{Mode, ModeError, Pairing, measured_modes, model_modes, pair_modes};
use crate::{C64, FrfSet};

/// Measured modes and a model's, paired.
#[derive(Debug, Clone)]
pub struct ModalComparison {
    /// The LSCF estimate of the measured modes (every order's poles kept,
    /// for a stabilisation diagram).
    pub estimate: ModalEstimate,
    /// The measured modes, shapes at the measured responses.
    pub measured: Vec<Mode>,
    /// The model's modes up to [`MODEL_REACH`] times the band's top, shapes at every free DOF.
    pub model: Vec<Mode>,
    /// The pairing (MAC over the measured responses).
    pub pairing: Pairing,
    /// The band of the estimate (Hz): the measured lines' first and last.
    pub band_hz: (f64, f64),
}

/// Error of [`compare_modes`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ComparisonError {
    /// The measured set has no lines.
    #[error("the measurement has no frequency lines")]
    NoLines,
    /// The modal estimation of the measured FRFs failed.
    #[error("modal estimation: {0}")]
    Estimate(#[from] LscfError),
    /// The model's modes could not be computed.
    #[error("model modes: {0}")]
    Model(#[from] ModeError),
}

/// Model modes are computed up to this multiple of the measured band's top.
pub const MODEL_REACH: f64 = 2.0;

/// Every free DOF of a system, node by node.
pub fn free_dofs(system: &DampedSystem) -> Vec<DofRef> {
    let dofs = system.assembly().dofs();
    let model = system.model();
    model
        .nodes()
        .iter()
        .flat_map(|n| model.node_dofs().iter().map(|&d| DofRef::new(n.id.0, d)))
        .filter(|&r| matches!(dofs.slot(r), Some(Slot::Free(_))))
        .collect()
}

/// Estimates the measured modes (LSCF over the measured band, default
/// options) and pairs them with the system's complex modes by MAC at the
/// measured responses, pairs of MAC below `min_mac` left unpaired.
pub fn compare_modes(
    system: &DampedSystem,
    measured: &FrfSet,
    min_mac: f64,
) -> Result<ModalComparison, ComparisonError> {
    compare_modes_with(system, measured, min_mac, LscfOptions::new(0.0, 0.0).orders)
}

/// As [`compare_modes`], the LSCF run over the model `orders` given (the
/// other options the defaults): a heavily damped mode beside lightly damped
/// ones needs higher orders to stabilise than the defaults reach.
pub fn compare_modes_with(
    system: &DampedSystem,
    measured: &FrfSet,
    min_mac: f64,
    orders: std::ops::RangeInclusive<usize>,
) -> Result<ModalComparison, ComparisonError> {
    let rec = measured.to_receptance();
    let f = rec.frequencies_hz();
    let band = match (f.first(), f.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Err(ComparisonError::NoLines),
    };
    let estimate = lscf(&rec, &LscfOptions { orders, ..LscfOptions::new(band.0, band.1) })?;
    let meas = measured_modes(&estimate);
    // model modes above the band too, so that a measured mode near its top
    // is paired with a partner the model has moved out of it (and says so)
    let model = model_modes(system, &free_dofs(system), MODEL_REACH * band.1)?;
    let pairing = pair_modes(&model, &meas, min_mac);
    Ok(ModalComparison { estimate, measured: meas, model, pairing, band_hz: band })
}

/// The real shape to draw of a complex one: turned by the angle that makes
/// it most nearly real (half the angle of `sum phi_i^2` over its
/// translations), then its real part. Returns that angle as well, so that a
/// partner can be turned the same way ([`measured_on_model`]).
pub fn real_shape(dofs: &[DofRef], shape: &[C64]) -> (f64, Vec<f64>) {
    let sum: C64 = dofs.iter().zip(shape).filter(|(d, _)| d.dof.is_translation()).map(|(_, v)| v * v).sum();
    let theta = 0.5 * sum.arg();
    let turn = C64::from_polar(1.0, -theta);
    (theta, shape.iter().map(|v| (v * turn).re).collect())
}

/// The measured shape scaled and turned onto the model's at the DOFs they
/// share (the modal scale factor `a = psi^H phi / psi^H psi`), then made
/// real by the model's angle `theta` from [`real_shape`]: one value per
/// measured DOF.
pub fn measured_on_model(measured: &Mode, model: &Mode, theta: f64) -> Vec<(DofRef, f64)> {
    let index: HashMap<DofRef, usize> = model.dofs.iter().enumerate().map(|(i, d)| (*d, i)).collect();
    let (mut num, mut den) = (C64::new(0.0, 0.0), 0.0);
    for (d, psi) in measured.dofs.iter().zip(&measured.shape) {
        if let Some(&i) = index.get(d) {
            num += psi.conj() * model.shape[i];
            den += psi.norm_sqr();
        }
    }
    let a = if den > 0.0 { num / den } else { C64::new(0.0, 0.0) };
    let turn = C64::from_polar(1.0, -theta);
    measured.dofs.iter().zip(&measured.shape).map(|(d, psi)| (*d, (a * psi * turn).re)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    #[test]
    fn a_shape_turned_by_any_angle_comes_back_real_and_the_measured_one_onto_it() {
        let dofs: Vec<DofRef> = (1..=4).map(|n| DofRef::new(n, Dof::Uy)).collect();
        let real = [0.1, 0.4, -0.3, 1.0];
        let turn = C64::from_polar(2.0, 1.1);
        let shape: Vec<C64> = real.iter().map(|&v| turn * v).collect();
        let (theta, back) = real_shape(&dofs, &shape);
        // real up to the sign, scaled by |turn|
        let sign = back[3].signum();
        for (b, r) in back.iter().zip(real) {
            assert!((b - sign * 2.0 * r).abs() < 1e-12, "{back:?}");
        }
        let model = Mode { frequency_hz: 1.0, damping_ratio: 0.01, dofs: dofs.clone(), shape: shape.clone() };
        // measured at two of the DOFs, with another scale and phase
        let other = C64::from_polar(0.3, -2.0);
        let meas = Mode {
            frequency_hz: 1.0,
            damping_ratio: 0.01,
            dofs: vec![dofs[1], dofs[3]],
            shape: vec![other * real[1], other * real[3]],
        };
        let on = measured_on_model(&meas, &model, theta);
        assert!((on[0].1 - back[1]).abs() < 1e-12 && (on[1].1 - back[3]).abs() < 1e-12, "{on:?} {back:?}");
    }

    #[test]
    fn a_model_compared_with_its_own_frfs_pairs_every_mode_with_itself() {
        let sys = DampedSystem::new(fe_model::samples::cantilever(8)).unwrap();
        let n = sys.model().nodes().len() as u32;
        let tip = DofRef::new(n, Dof::Uy);
        let responses: Vec<DofRef> = (2..=n).map(|k| DofRef::new(k, Dof::Uy)).collect();
        let first = model_modes(&sys, &responses, 1e6).unwrap();
        assert!(first.len() >= 3, "{} modes", first.len());
        let hi = 0.5 * (first[2].frequency_hz + first.get(3).map_or(2.0 * first[2].frequency_hz, |m| m.frequency_hz));
        let lines: Vec<f64> = (0..600).map(|k| 0.5 * first[0].frequency_hz + k as f64 * hi / 600.0).collect();
        let channels: Vec<crate::Channel> = responses.iter().map(|&r| crate::Channel::new(r, tip)).collect();
        let set = crate::synthesize(&sys, &channels, &lines).unwrap();
        let c = compare_modes(&sys, &set, 0.5).unwrap();
        assert_eq!(c.measured.len(), 3, "{:?}", c.measured.iter().map(|m| m.frequency_hz).collect::<Vec<_>>());
        assert_eq!(c.pairing.pairs.len(), 3);
        for p in &c.pairing.pairs {
            assert_eq!(p.measured, p.model, "modes in order");
            assert!(p.mac > 0.99 && p.frequency_error_pct.abs() < 0.5, "{p:?}");
        }
        // the model's shapes cover every free DOF, not only the measured ones
        assert_eq!(c.model[0].dofs, free_dofs(&sys));
        assert!(c.model[0].dofs.len() > responses.len());
        let none = FrfSet::zeros(Vec::new(), channels, crate::FrfKind::Receptance);
        if let Ok(set) = none {
            assert_eq!(compare_modes(&sys, &set, 0.5).unwrap_err(), ComparisonError::NoLines);
        }
    }
}

//! Modal correlation: model and measured modes side by side, the modal
//! assurance criterion and mode pairing.
//!
//! A [`Mode`] is what both sides can provide: a natural frequency, a damping
//! ratio and a complex shape at a list of DOFs. [`model_modes`] takes the
//! model's exact complex modes ([`damping::complex_modes()`]) at the measured
//! DOFs; [`measured_modes`] takes those of an LSCF estimate
//! ([`crate::lscf()`]). For complex shapes the MAC is
//!
//! ```text
//! MAC(a, b) = |a^H b|^2 / ((a^H a) (b^H b))
//! ```
//!
//! which is 1 for shapes that differ by any complex factor and 0 for
//! orthogonal ones. Between two modes it is taken over the DOFs they share.
//! [`pair_modes`] pairs each measured mode with at most one model mode and
//! each model mode with at most one measured mode, greedily by decreasing
//! MAC (above a threshold), and reports the frequency and damping errors of
//! each pair and the modes left unpaired.

use damping::DampedSystem;
use fe_model::DofRef;
use num_complex::Complex64 as C64;

use crate::error::FrfError;
use crate::lscf::ModalEstimate;
pub use crate::mac::mac;
use crate::synth::equation_of;

/// A mode for comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// The DOFs of the shape.
    pub dofs: Vec<DofRef>,
    /// Complex shape, one value per DOF.
    pub shape: Vec<C64>,
}

/// Error of [`model_modes`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModeError {
    /// The modal analysis failed.
    #[error(transparent)]
    Modal(#[from] damping::ModalError),
    /// A DOF is unknown or fixed.
    #[error(transparent)]
    Dof(#[from] FrfError),
}

/// The model's oscillatory complex modes up to `max_hz`, with shapes at
/// `dofs` (scaled as in [`damping::complex_modes()`]: `phi^T Z'(s) phi = 1`).
pub fn model_modes(sys: &DampedSystem, dofs: &[DofRef], max_hz: f64) -> Result<Vec<Mode>, ModeError> {
    let eqs: Vec<usize> = dofs.iter().map(|&d| equation_of(sys, d)).collect::<Result<_, _>>()?;
    let modes = damping::complex_modes(sys)?;
    Ok(modes
        .oscillatory
        .iter()
        .filter(|m| m.frequency_hz <= max_hz)
        .map(|m| Mode {
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            dofs: dofs.to_vec(),
            shape: eqs.iter().map(|&e| m.shape[e]).collect(),
        })
        .collect())
}

/// The modes of an LSCF estimate, with shapes at its responses.
pub fn measured_modes(estimate: &ModalEstimate) -> Vec<Mode> {
    estimate
        .modes
        .iter()
        .map(|m| Mode {
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            dofs: estimate.responses.clone(),
            shape: m.shape.clone(),
        })
        .collect()
}

/// MAC of two modes over the DOFs they share (0 when they share none).
pub fn mode_mac(a: &Mode, b: &Mode) -> f64 {
    let (mut va, mut vb) = (Vec::new(), Vec::new());
    for (i, d) in a.dofs.iter().enumerate() {
        if let Some(j) = b.dofs.iter().position(|x| x == d) {
            va.push(a.shape[i]);
            vb.push(b.shape[j]);
        }
    }
    mac(&va, &vb)
}

/// `mac[i][j] = MAC(a[i], b[j])`.
pub fn mac_matrix(a: &[Mode], b: &[Mode]) -> Vec<Vec<f64>> {
    a.iter().map(|x| b.iter().map(|y| mode_mac(x, y)).collect()).collect()
}

/// One measured mode paired with one model mode.
#[derive(Clone, Debug, PartialEq)]
pub struct ModePair {
    /// Index in the measured list.
    pub measured: usize,
    /// Index in the model list.
    pub model: usize,
    /// Their MAC.
    pub mac: f64,
    /// `100 (f_model - f_measured) / f_measured`.
    pub frequency_error_pct: f64,
    /// `100 (zeta_model - zeta_measured) / zeta_measured`.
    pub damping_error_pct: f64,
}

/// The outcome of [`pair_modes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Pairing {
    /// Pairs by increasing measured index.
    pub pairs: Vec<ModePair>,
    /// Measured modes without a partner.
    pub unpaired_measured: Vec<usize>,
    /// Model modes without a partner.
    pub unpaired_model: Vec<usize>,
    /// `mac[i][j]`: measured mode `i` against model mode `j`.
    pub mac: Vec<Vec<f64>>,
}

/// Pairs measured with model modes by MAC: repeatedly the pair with the
/// highest MAC among the modes not yet paired, as long as it is at least
/// `min_mac`.
pub fn pair_modes(model: &[Mode], measured: &[Mode], min_mac: f64) -> Pairing {
    let table = mac_matrix(measured, model);
    let mut used_meas = vec![false; measured.len()];
    let mut used_model = vec![false; model.len()];
    let mut pairs = Vec::new();
    loop {
        let mut best: Option<(usize, usize, f64)> = None;
        for (i, row) in table.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if !used_meas[i] && !used_model[j] && v >= min_mac && best.is_none_or(|b| v > b.2) {
                    best = Some((i, j, v));
                }
            }
        }
        let Some((i, j, v)) = best else { break };
        used_meas[i] = true;
        used_model[j] = true;
        let (fm, fx) = (model[j].frequency_hz, measured[i].frequency_hz);
        let (zm, zx) = (model[j].damping_ratio, measured[i].damping_ratio);
        pairs.push(ModePair {
            measured: i,
            model: j,
            mac: v,
            frequency_error_pct: 100.0 * (fm - fx) / fx,
            damping_error_pct: 100.0 * (zm - zx) / zx,
        });
    }
    pairs.sort_by_key(|p| p.measured);
    Pairing {
        pairs,
        unpaired_measured: (0..measured.len()).filter(|&i| !used_meas[i]).collect(),
        unpaired_model: (0..model.len()).filter(|&j| !used_model[j]).collect(),
        mac: table,
    }
}

/// What a paired mode's differences suggest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symptom {
    /// Frequency, damping and shape agree.
    Matches,
    /// The model's resonance is shifted by more than the measured peak's
    /// width: a stiffness or mass error.
    FrequencyShift,
    /// The frequency agrees but the peak's height and width do not: a
    /// damping error.
    Damping,
    /// Both the frequency and the damping differ.
    FrequencyAndDamping,
    /// Frequency and damping agree but the shape does not (MAC below 0.9):
    /// a stiffness or mass error in the wrong place, or a sensor problem.
    Shape,
}

impl Symptom {
    /// One line a user can act on.
    pub fn reading(self) -> &'static str {
        match self {
            Symptom::Matches => "matches",
            Symptom::FrequencyShift => "frequency shift: a stiffness or mass error",
            Symptom::Damping => "peak height and width: a damping error",
            Symptom::FrequencyAndDamping => "frequency shift and peak width: stiffness or mass, and damping",
            Symptom::Shape => "mode shape: an error in the distribution of stiffness or mass, or a sensor",
        }
    }
}

/// Reads a pair of modes. The frequency differs when the model's natural
/// frequency lies outside twice the measured half-power half-width
/// (`|f_model - f_meas| > 2 zeta_meas f_meas`, the resonance has moved by
/// more than its peak is wide); the damping differs when the damping ratios
/// differ by more than 25 %; the shape differs when the MAC is below 0.9.
pub fn symptom(model: &Mode, measured: &Mode, mac: f64) -> Symptom {
    let half_width = measured.damping_ratio.abs() * measured.frequency_hz;
    let shifted = (model.frequency_hz - measured.frequency_hz).abs() > 2.0 * half_width;
    let damping = (model.damping_ratio - measured.damping_ratio).abs() > 0.25 * measured.damping_ratio.abs();
    match (shifted, damping) {
        (true, true) => Symptom::FrequencyAndDamping,
        (true, false) => Symptom::FrequencyShift,
        (false, true) => Symptom::Damping,
        (false, false) if mac < 0.9 => Symptom::Shape,
        (false, false) => Symptom::Matches,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    fn mode(f: f64, z: f64) -> Mode {
        Mode { frequency_hz: f, damping_ratio: z, dofs: vec![], shape: vec![] }
    }

    #[test]
    fn symptoms_compare_the_shift_with_the_peak_width() {
        // measured 100 Hz at 1 %: half-power half-width 1 Hz
        let meas = mode(100.0, 0.01);
        assert_eq!(symptom(&mode(101.5, 0.0105), &meas, 0.99), Symptom::Matches);
        assert_eq!(symptom(&mode(103.0, 0.0105), &meas, 0.99), Symptom::FrequencyShift);
        assert_eq!(symptom(&mode(100.5, 0.02), &meas, 0.99), Symptom::Damping);
        assert_eq!(symptom(&mode(97.0, 0.005), &meas, 0.99), Symptom::FrequencyAndDamping);
        assert_eq!(symptom(&mode(100.2, 0.01), &meas, 0.5), Symptom::Shape);
    }

    #[test]
    fn mac_is_one_for_complex_multiples_and_zero_for_orthogonal_vectors() {
        let a = [C64::new(1.0, 0.5), C64::new(-2.0, 0.1), C64::new(0.3, -0.7)];
        let k = C64::new(-3.2, 1.7);
        let b: Vec<C64> = a.iter().map(|v| v * k).collect();
        assert!((mac(&a, &a) - 1.0).abs() < 1e-15);
        assert!((mac(&a, &b) - 1.0).abs() < 1e-14);
        // orthogonal in the Hermitian sense: a^H c = 0
        let c = [C64::new(0.0, 1.0), C64::new(0.0, 0.0), C64::new(0.0, 0.0)];
        let d = [C64::new(0.0, 0.0), C64::new(2.0, -1.0), C64::new(0.0, 0.0)];
        assert_eq!(mac(&c, &d), 0.0);
        assert_eq!(mac(&a, &[C64::new(0.0, 0.0); 3]), 0.0);
    }

    #[test]
    fn mode_mac_uses_the_shared_dofs_in_any_order() {
        let d = |n| DofRef::new(n, Dof::Uy);
        let a = Mode {
            frequency_hz: 1.0,
            damping_ratio: 0.01,
            dofs: vec![d(1), d(2), d(3)],
            shape: vec![C64::new(1.0, 0.0), C64::new(2.0, 0.0), C64::new(3.0, 0.0)],
        };
        let b = Mode {
            frequency_hz: 1.0,
            damping_ratio: 0.01,
            dofs: vec![d(3), d(9), d(1)],
            shape: vec![C64::new(0.0, 6.0), C64::new(5.0, 5.0), C64::new(0.0, 2.0)],
        };
        assert!((mode_mac(&a, &b) - 1.0).abs() < 1e-14);
    }
}

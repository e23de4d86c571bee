//! The natural frequencies a study reports: of the damped model's complex
//! modes, undamped ones for larger models, none for the largest.

use damping::DampedSystem;

use super::Study;

/// Natural frequencies (Hz) of the initial, updated and truth models within
/// the measured band, and the paper's, side by side: `|s| / 2 pi` of the
/// damped model's complex modes, which include the stiffening a slow
/// exponential kernel adds; undamped frequencies for models too large for
/// the dense complex modal analysis (see `kind`).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FrequencyTable {
    /// Initial model.
    pub initial: Vec<f64>,
    /// Updated model.
    pub updated: Vec<f64>,
    /// Truth model, when known.
    pub truth: Option<Vec<f64>>,
    /// Published values, when quoted.
    pub paper: Option<Vec<f64>>,
    /// `damped` (complex modes), `undamped` (normal modes), `none` when
    /// the model is too large for the dense modal analyses
    /// ([`MAX_UNDAMPED_DOFS`]; the lists are then empty), or `not computed`
    /// when the run was not asked for them ([`Study::fit_output_error`];
    /// empty too).
    pub kind: String,
}

impl FrequencyTable {
    /// The table of a run that was not asked for natural frequencies.
    pub fn not_computed() -> Self {
        FrequencyTable {
            initial: Vec::new(),
            updated: Vec::new(),
            truth: None,
            paper: None,
            kind: "not computed".into(),
        }
    }
}

/// Equations above which no natural frequencies are computed for reports:
/// the dense undamped eigensolution costs `O(N^3)` (a minute at 9,000).
pub const MAX_UNDAMPED_DOFS: usize = 2000;

/// Natural frequencies of a system up to `max_hz`: of the damped model's
/// complex modes when the dense analysis allows, else undamped (up to
/// [`MAX_UNDAMPED_DOFS`] equations, else none); the flag says which.
pub fn natural_frequencies(sys: &DampedSystem, max_hz: f64) -> (Vec<f64>, bool) {
    if let Ok(m) = damping::complex_modes(sys) {
        return (m.oscillatory.iter().map(|m| m.frequency_hz).filter(|&f| f <= max_hz).collect(), true);
    }
    if sys.n() > MAX_UNDAMPED_DOFS {
        // a dense eigensolution of this size would take minutes
        return (Vec::new(), false);
    }
    let f = damping::normal_modes(sys.assembly())
        .map(|m| m.frequencies_hz.into_iter().filter(|&f| f <= max_hz).collect())
        .unwrap_or_default();
    (f, false)
}

impl Study {
    /// Natural frequencies of the initial, given and truth models in the measured band.
    pub fn frequency_table(&self, updated: &DampedSystem) -> FrequencyTable {
        let top = self.measured.frequencies_hz().last().copied().unwrap_or(0.0);
        let (initial, damped_i) = natural_frequencies(&self.system, top);
        let (updated, damped_u) = natural_frequencies(updated, top);
        let truth = self.truth.as_ref().map(|t| natural_frequencies(t, top));
        let damped = damped_i && damped_u && truth.as_ref().is_none_or(|t| t.1);
        let kind = if damped {
            "damped".to_string()
        } else if self.system.n() > MAX_UNDAMPED_DOFS {
            "none".to_string()
        } else {
            "undamped".to_string()
        };
        FrequencyTable {
            initial,
            updated,
            truth: truth.map(|t| t.0),
            paper: self.case.paper.as_ref().filter(|p| !p.frequencies_hz.is_empty()).map(|p| p.frequencies_hz.clone()),
            kind,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_frequencies_are_skipped_above_the_dense_limit_and_computed_below() {
        let big = DampedSystem::new(fe_model::samples::long_beam(690)).unwrap();
        assert!(big.n() > MAX_UNDAMPED_DOFS);
        assert_eq!(natural_frequencies(&big, 1e3), (Vec::new(), false));
        let small = DampedSystem::new(fe_model::samples::long_beam(40)).unwrap();
        let (f, _) = natural_frequencies(&small, 1e3);
        assert!(!f.is_empty() && f.windows(2).all(|w| w[0] <= w[1]), "{f:?}");
    }
}

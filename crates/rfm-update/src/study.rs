//! A study: a case file turned into a model, measured data and an updating
//! set-up, ready for a solver.

use damping::DampedSystem;
use fe_model::case::{FrequencyChoice, MeasurementSpec};
use fe_model::{CaseFile, Quantity};
use frf::{Channel, FrfSet, NoiseModel};
use serde::Serialize;

use crate::error::UpdateError;
use crate::freqsel;
use crate::rfm::{self, IterationRecord, RfmOptions, Status};

/// A case made ready for updating.
#[derive(Clone, Debug)]
pub struct Study {
    /// The case file.
    pub case: CaseFile,
    /// The initial model.
    pub system: DampedSystem,
    /// The truth model of a simulated study.
    pub truth: Option<DampedSystem>,
    /// Measured receptances on the measurement lines.
    pub measured: FrfSet,
    /// Parameters to update (empty when the case has no `[update]`).
    pub parameters: Vec<Quantity>,
    /// Lines used for updating (Hz).
    pub update_frequencies_hz: Vec<f64>,
}

/// One parameter's values for reporting.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterReport {
    /// Dotted name.
    pub name: String,
    /// Initial value.
    pub initial: f64,
    /// Updated value.
    pub updated: f64,
    /// True value, when the case synthesises its data.
    pub truth: Option<f64>,
    /// Published value, when the case quotes a paper.
    pub paper: Option<f64>,
}

impl ParameterReport {
    /// `|updated - truth| / |truth|`, when the truth is known.
    pub fn relative_error(&self) -> Option<f64> {
        self.truth.map(|t| ((self.updated - t) / t).abs())
    }
}

/// Undamped natural frequencies (Hz) of the initial, updated and truth
/// models within the measured band, and the paper's, side by side.
#[derive(Clone, Debug, Serialize)]
pub struct FrequencyTable {
    /// Initial model.
    pub initial: Vec<f64>,
    /// Updated model.
    pub updated: Vec<f64>,
    /// Truth model, when known.
    pub truth: Option<Vec<f64>>,
    /// Published values, when quoted.
    pub paper: Option<Vec<f64>>,
}

/// Undamped natural frequencies of a system up to `max_hz` (dense modal
/// analysis; models of up to a few thousand DOFs).
pub fn natural_frequencies(sys: &DampedSystem, max_hz: f64) -> Vec<f64> {
    damping::normal_modes(sys.assembly())
        .map(|m| m.frequencies_hz.into_iter().filter(|&f| f <= max_hz).collect())
        .unwrap_or_default()
}

/// The outcome of an updating run on a study.
#[derive(Clone, Debug, Serialize)]
pub struct UpdateOutcome {
    /// Method used.
    pub method: String,
    /// How the iteration ended.
    pub status: Status,
    /// Per-parameter values.
    pub parameters: Vec<ParameterReport>,
    /// Iteration history.
    pub history: Vec<IterationRecord>,
    /// Final residual (relative, over the updating lines).
    pub residual: f64,
    /// Lines used (Hz).
    pub frequencies_hz: Vec<f64>,
    /// Natural frequencies before and after.
    pub natural_frequencies_hz: FrequencyTable,
    /// The updated model.
    #[serde(skip)]
    pub system: DampedSystem,
}

fn channels_of(m: &MeasurementSpec) -> Vec<Channel> {
    m.references.iter().flat_map(|&r| m.responses.iter().map(move |&resp| Channel::new(resp, r))).collect()
}

impl Study {
    /// Loads a case file and prepares the study.
    pub fn load(path: &std::path::Path) -> Result<Self, UpdateError> {
        Self::from_case(CaseFile::load(path)?)
    }

    /// Prepares a study from a loaded case: synthesises measured data from the
    /// truth (with noise) or reads it from the data file, and resolves the
    /// updating lines.
    pub fn from_case(case: CaseFile) -> Result<Self, UpdateError> {
        let system = DampedSystem::new(case.model.clone())?;
        let spec = case
            .measurement
            .as_ref()
            .ok_or_else(|| UpdateError::Case(case.error(None, "the case has no [measurement] section")))?;
        let truth = case.truth.as_ref().map(|t| DampedSystem::new(t.model.clone())).transpose()?;
        let channels = channels_of(spec);
        let mut grid = spec.frequencies_hz.clone();
        if let (Some(update), None) = (&case.update, &spec.data) {
            // synthesised data: make sure the chosen points are lines of it
            if let FrequencyChoice::List(points) = &update.frequencies {
                grid.extend(points.iter().copied());
                grid.sort_by(f64::total_cmp);
                grid.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs());
            }
        }
        let measured = match (&spec.data, &case.truth, &truth) {
            (Some(path), _, _) => {
                let set = frf::io::read_measured(path, &spec.map)?.to_receptance();
                for c in &channels {
                    if set.find(*c).is_none() {
                        return Err(UpdateError::Setup(format!(
                            "{}: the data has no channel {c} that the case lists",
                            path.display()
                        )));
                    }
                }
                let idx: Vec<usize> = channels.iter().map(|c| set.find(*c).unwrap()).collect();
                set.select_channels(&idx)
            }
            (None, Some(spec_t), Some(truth)) => {
                let mut set = frf::synthesize(truth, &channels, &grid)?;
                NoiseModel { relative: spec_t.noise, floor: spec_t.floor, seed: spec_t.seed }.apply(&mut set);
                set
            }
            _ => unreachable!("the case loader requires data or a truth"),
        };
        let parameters = case.update.as_ref().map(|u| u.parameters.clone()).unwrap_or_default();
        let update_frequencies_hz = match case.update.as_ref().map(|u| &u.frequencies) {
            None => Vec::new(),
            Some(FrequencyChoice::All) => measured.frequencies_hz().to_vec(),
            Some(FrequencyChoice::List(points)) => {
                for &p in points {
                    if measured.line_of(p).is_none() {
                        return Err(UpdateError::Setup(format!(
                            "updating point {p} Hz is not a line of the measured data"
                        )));
                    }
                }
                points.clone()
            }
            Some(FrequencyChoice::Auto(n)) => {
                let model = frf::synthesize(&system, &channels, measured.frequencies_hz())?;
                let mut avoid = freqsel::features(&model);
                avoid.extend(freqsel::features(&measured));
                freqsel::choose(measured.frequencies_hz(), &avoid, *n)
            }
        };
        Ok(Study { case, system, truth, measured, parameters, update_frequencies_hz })
    }

    /// Parameter names.
    pub fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(|&q| self.system.model().quantity_name(q).to_string()).collect()
    }

    /// The measured data at the updating lines.
    pub fn measured_at_update_lines(&self) -> Result<FrfSet, UpdateError> {
        Ok(self.measured.at_frequencies(&self.update_frequencies_hz)?)
    }

    /// Runs the response function method from the initial model.
    pub fn run_rfm(
        &self,
        opts: &RfmOptions,
        on_iteration: impl FnMut(&IterationRecord),
    ) -> Result<UpdateOutcome, UpdateError> {
        if self.parameters.is_empty() {
            return Err(UpdateError::Setup("the case has no [update] parameters".into()));
        }
        let measured = self.measured_at_update_lines()?;
        let mut sys = self.system.clone();
        let result = rfm::run(&mut sys, &self.parameters, &measured, opts, on_iteration)?;
        let natural_frequencies_hz = self.frequency_table(&sys);
        Ok(UpdateOutcome {
            natural_frequencies_hz,
            method: "rfm".into(),
            status: result.status,
            parameters: self.reports(&result.values),
            history: result.history,
            residual: result.residual,
            frequencies_hz: self.update_frequencies_hz.clone(),
            system: sys,
        })
    }

    /// Natural frequencies of the initial, given and truth models in the measured band.
    pub fn frequency_table(&self, updated: &DampedSystem) -> FrequencyTable {
        let top = self.measured.frequencies_hz().last().copied().unwrap_or(0.0);
        FrequencyTable {
            initial: natural_frequencies(&self.system, top),
            updated: natural_frequencies(updated, top),
            truth: self.truth.as_ref().map(|t| natural_frequencies(t, top)),
            paper: self.case.paper.as_ref().filter(|p| !p.frequencies_hz.is_empty()).map(|p| p.frequencies_hz.clone()),
        }
    }

    /// Reports for the given updated values.
    pub fn reports(&self, updated: &[f64]) -> Vec<ParameterReport> {
        let paper = self.case.paper.as_ref();
        self.parameters
            .iter()
            .zip(updated)
            .map(|(&q, &u)| ParameterReport {
                name: self.system.model().quantity_name(q).to_string(),
                initial: self.system.get(q),
                updated: u,
                truth: self.truth.as_ref().map(|t| t.get(q)),
                paper: paper.and_then(|p| p.values.iter().find(|(pq, _)| *pq == q).map(|&(_, v)| v)),
            })
            .collect()
    }
}

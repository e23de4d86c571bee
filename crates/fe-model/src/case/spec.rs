//! What a loaded case says besides its model: the truth of a simulated
//! study, what to update and how, published values, the history of steps and
//! the acceptance checks. Plain data, checked when read.

use std::ops::Range;
use std::path::PathBuf;

use crate::model::Model;
use crate::quantity::{Parameter, Quantity};

/// The truth of a simulated study: the model that generates "measured" data.
#[derive(Clone, Debug)]
pub struct TruthSpec {
    /// The truth model (the case's model with the truth's values and extra items).
    pub model: Model,
    /// Quantities set by the truth, in the *case model's* indexing, with values.
    pub values: Vec<(Quantity, f64)>,
    /// Relative complex noise level (0.01 = 1 %).
    pub noise: f64,
    /// Additive noise floor relative to each channel's RMS magnitude.
    pub floor: f64,
    /// Random seed.
    pub seed: u64,
}

/// Frequency points for updating.
#[derive(Clone, Debug, PartialEq)]
pub enum FrequencyChoice {
    /// This many lines spread evenly over the measured band.
    Lines(usize),
    /// Explicit points (Hz).
    List(Vec<f64>),
    /// Choose this many points automatically, away from resonances and anti-resonances.
    Auto(usize),
    /// Every measured line.
    All,
}

/// A weight on the measured lines of a frequency band (0 masks the band).
#[derive(Clone, Debug, PartialEq)]
pub struct BandWeight {
    /// Lower edge (Hz).
    pub from: f64,
    /// Upper edge (Hz).
    pub to: f64,
    /// Weight of the band's lines (1 is neutral).
    pub weight: f64,
}

/// What to update and how.
#[derive(Clone, Debug)]
pub struct UpdateSpec {
    /// Parameters to update.
    pub parameters: Vec<Parameter>,
    /// Optional bounds per parameter (same order), in physical units.
    pub bounds: Vec<Option<(f64, f64)>>,
    /// Frequency points (`None`: the method's default).
    pub frequencies: Option<FrequencyChoice>,
    /// Method name as written (checked by the solver crate).
    pub method: Option<(String, Range<usize>)>,
    /// Iteration limit.
    pub max_iterations: Option<u32>,
    /// Convergence tolerance on the largest relative correction.
    pub tolerance: Option<f64>,
    /// Tikhonov regularisation weight on the log-parameter changes.
    pub regularization: Option<f64>,
    /// Estimate an unknown complex gain per reference.
    pub gains: bool,
    /// Misfit form as written (`relative` or `log`), checked by the solver crate.
    pub misfit: Option<(String, Range<usize>)>,
    /// Weight lines by the measured coherence: `Some(false)` turns off the
    /// default (on whenever the data carry coherence), `Some(true)` requires
    /// coherence in the data.
    pub coherence: Option<bool>,
    /// Weights per frequency band.
    pub weights: Vec<BandWeight>,
}

/// Published values to print beside the tool's (for reproducing a paper).
#[derive(Clone, Debug)]
pub struct PaperSpec {
    /// Which table or figure.
    pub source: String,
    /// Published parameter values.
    pub values: Vec<(Quantity, f64)>,
    /// Published natural frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// A remark printed with the table.
    pub note: Option<String>,
}

/// One step of a case's history, written by rfm when it adds an effect or
/// updates (`[[history]]`): what the model was and how far it was from the
/// data, so that a later run can show the fall of the misfit from the
/// nominal model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HistoryEntry {
    /// What the step did (`nominal`, `+ flexible, lossy joint at node 13`, `updated`).
    pub step: String,
    /// RMS of `ln(model / measured)` per complex value after the step.
    pub misfit: f64,
    /// The data's estimated relative noise level, when known.
    pub noise: Option<f64>,
    /// The kind of effect the step added (one of [`EFFECT_KINDS`]), for a
    /// step that added one: reports mark it on the structure.
    pub effect: Option<String>,
    /// The nodes where the added effect acts (nodes of the model).
    pub nodes: Vec<u32>,
    /// The elements where the added effect acts (beams of the model).
    pub elements: Vec<u32>,
}

/// The kinds of effect a history entry may name (the names of
/// `rfm_update::diagnose::EffectKind`, whose tests keep the two lists equal).
pub const EFFECT_KINDS: [&str; 10] = [
    "flexible_support",
    "flexible_joint",
    "lumped_mass",
    "stiffness_change",
    "mass_change",
    "viscous_damping",
    "non_viscous_damping",
    "resonator",
    "shaker",
    "sensor_masses",
];

/// How an updating run may end, as its results name it (the statuses of
/// `rfm_update::status::Status`, whose tests keep the two lists equal).
pub const RUN_STATUSES: [&str; 7] =
    ["converged", "model_inadequate", "local_minimum", "stalled", "max_iterations", "runaway", "failed"];

/// What `cargo xtask reproduce` requires of a case's results (`[check]`):
/// the case's acceptance, as data. See `docs/case-files.md`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckSpec {
    /// Of the run with the response function method (`[check.rfm]`).
    pub rfm: Option<RunCheck>,
    /// Of the run with the output-error estimator (`[check.output-error]`);
    /// its presence also asks `reproduce` to make that run.
    pub output_error: Option<RunCheck>,
    /// Of the diagnosis loop (`[check.diagnosis]`).
    pub diagnosis: Option<DiagnosisCheck>,
}

/// What one updating run must achieve.
#[derive(Clone, Debug, PartialEq)]
pub struct RunCheck {
    /// The statuses it may end with (names of [`RUN_STATUSES`]).
    pub status: Vec<String>,
    /// Largest `|updated - truth| / |truth|` allowed over the parameters.
    pub max_error: Option<f64>,
    /// Largest `|ln(updated / truth)|` allowed, in the run's own standard
    /// deviations of `ln p`, over the parameters it reports as well
    /// determined.
    pub within_sd: Option<f64>,
    /// Parameters the run must report as weakly determined.
    pub weak: Vec<String>,
    /// Largest relative distance allowed between the residual RMS the fit
    /// leaves and the truth's noise level: the check that its standard
    /// deviations are scaled honestly.
    pub noise: Option<f64>,
}

/// What the diagnosis of the case must find.
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnosisCheck {
    /// Text the leading candidate's description must contain.
    pub leader: String,
    /// How many times at least the misfit must fall once the leading
    /// candidate is added and updated.
    pub misfit_fall: Option<f64>,
    /// The statuses the update with the leader added may end with (names
    /// of [`RUN_STATUSES`]; empty: any). `converged` says that the residual
    /// is consistent with the noise of the data.
    pub status: Vec<String>,
    /// The case whose `[truth]` made the data (a case that reads its data
    /// from a file keeps its truth apart), resolved from the case's folder:
    /// what `compare`, `within_sd` and `noise` compare with.
    pub truth: Option<PathBuf>,
    /// Parameters of the update with the leader added, each with the
    /// quantity of the truth's model that holds its true value.
    pub compare: Vec<(String, String)>,
    /// Largest `|ln(updated / truth)|` of each compared parameter, in the
    /// update's own standard deviations of `ln p`.
    pub within_sd: Option<f64>,
    /// Largest relative distance between the residual RMS the update
    /// leaves and the truth's noise level.
    pub noise: Option<f64>,
}

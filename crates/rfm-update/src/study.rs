//! A study: a case file turned into a model, measured data and an updating
//! set-up, ready for a solver.

use damping::DampedSystem;
use fe_model::case::{FrequencyChoice, Gains, MeasurementSpec};
use fe_model::{CaseFile, DofRef, Parameter};
use frf::{Channel, FrfKind, FrfSet, NoiseModel};
use serde::Serialize;

pub use crate::measured::read_measured_for;

use crate::error::UpdateError;
use crate::freqsel;
use crate::gain;
use crate::oe::{self, Gain, Misfit, OeData, OeOptions};
use crate::params::ParameterSet;
use crate::rfm::{self, IterationRecord, RfmOptions, Status};
use crate::uncertainty::{self, UncertaintyReport};
use crate::verdict;

/// An updating method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The response function method (the paper's).
    Rfm,
    /// Output-error Levenberg-Marquardt with uncertainty.
    OutputError,
}

impl Method {
    /// Parses `rfm` or `output-error`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "rfm" => Some(Method::Rfm),
            "output-error" | "oe" => Some(Method::OutputError),
            _ => None,
        }
    }

    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rfm => "rfm",
            Method::OutputError => "output-error",
        }
    }
}

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
    pub parameters: Vec<Parameter>,
    /// Lines used for updating (Hz).
    pub update_frequencies_hz: Vec<f64>,
    /// What the case's `[measurement] mask` left out of the measured file.
    pub masked: Vec<frf::io::Masked>,
    /// What reading the measured file changed or passed over (lines at
    /// 0 Hz dropped, units scaled, kinds converted, datasets skipped), one
    /// line each, to be shown and stored with the results.
    pub notes: Vec<String>,
    /// The kind of the measured data as read (`measured` itself is
    /// receptance, for the updating methods); comparisons are made in it,
    /// whichever way the data arrive.
    pub measured_kind: FrfKind,
    /// The unknown gains every comparison and fit of this study applies to
    /// the model's FRFs ([`crate::gain`]): `Gains::None` for per-newton data
    /// unless the case asks for gains.
    pub gains: Gains,
    /// Why those gains, in words (for the notes and reports).
    pub gains_reason: String,
    /// The references whose data are per volt (uncalibrated).
    pub per_volt: Vec<DofRef>,
    /// How the test nodes were paired with the model's by coordinates
    /// (empty unless the case asks for it).
    pub pairing: Vec<PairingReport>,
}

/// A test node paired with a model node by coordinates, as stored with the
/// results (`[measurement] pair = "coordinates"`).
#[derive(Clone, Debug, Serialize)]
pub struct PairingReport {
    /// Test node label.
    pub test_node: i64,
    /// Model node.
    pub model_node: u32,
    /// Distance in the model's plane (m).
    pub distance_m: f64,
    /// Its test directions as model DOFs (`+Z -> uy`).
    pub directions: Vec<String>,
}

impl PairingReport {
    /// The reports of a reader's pairing.
    pub fn of(paired: &[frf::io::uff::PairedNode]) -> Vec<PairingReport> {
        paired
            .iter()
            .map(|p| PairingReport {
                test_node: p.test_node,
                model_node: p.model_node,
                distance_m: p.distance_m,
                directions: p.directions.clone(),
            })
            .collect()
    }
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

/// Natural frequencies (Hz) of the initial, updated and truth models within
/// the measured band, and the paper's, side by side: `|s| / 2 pi` of the
/// damped model's complex modes, which include the stiffening a slow
/// exponential kernel adds; undamped frequencies for models too large for
/// the dense complex modal analysis (see `kind`).
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
    /// `damped` (complex modes), `undamped` (normal modes), or `none` when
    /// the model is too large for the dense modal analyses
    /// ([`MAX_UNDAMPED_DOFS`]; the lists are then empty).
    pub kind: String,
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
    /// Parameter uncertainty and identifiability (output-error method).
    pub uncertainty: Option<UncertaintyReport>,
    /// Fitted gain per reference, when requested.
    pub gains: Vec<Gain>,
    /// Relative noise level of the measured data, estimated from their
    /// roughness (see [`crate::diagnose::estimate_noise`]).
    pub noise_estimate: Option<f64>,
    /// What the case's mask rules left out of the measured data, one line
    /// each (`non-finite: line 17, columns 4-5: H(3:uy,2:uy) at 20 Hz is NaN`).
    pub masked: Vec<String>,
    /// What reading the measured data changed or passed over, one line each
    /// (see [`Study::notes`]).
    pub notes: Vec<String>,
    /// What the data leave undetermined, for methods without an uncertainty
    /// report (the RFM): parameters that ended on a bound, the combination
    /// of parameters the sensitivity cannot separate; and for the RFM, why
    /// its result may not be trusted (noise above its limit, parameters
    /// that ran away, no uncertainty, a misfit worse than the start).
    pub warnings: Vec<String>,
    /// The final residual as a multiple of the estimated noise (what the
    /// status is decided on; `None` when the noise is unknown).
    pub noise_ratio: Option<f64>,
    /// The restarts of the output-error fit (empty when none were needed).
    pub restarts: Vec<Restart>,
    /// The update ended with a larger misfit than the initial model's.
    pub worse_than_start: bool,
    /// The gains fitted (`none`, `per-reference`, `per-channel`) and why.
    pub gain_setting: String,
    /// Whether the lines were weighted by the measured coherence.
    pub coherence_weighted: bool,
    /// How test nodes were paired with model nodes by coordinates.
    pub pairing: Vec<PairingReport>,
    /// The updated model.
    #[serde(skip)]
    pub system: DampedSystem,
}

/// One restart of the output-error fit from a spread start.
#[derive(Clone, Debug, Serialize)]
pub struct Restart {
    /// Residual RMS at the start.
    pub start_residual: f64,
    /// Residual RMS where it ended.
    pub residual: f64,
    /// Whether it was run to the end (the best of the short ones are).
    pub refined: bool,
}

/// Restart fits of a few steps each; the best are then run to the end.
const RESTART_STEPS: usize = 15;
/// How many of the short restarts are run to the end.
const RESTARTS_REFINED: usize = 2;
/// Restart starts spread by up to this factor either way from the initial values.
const RESTART_SPREAD: f64 = 10.0;

/// One line per thing a mask rule left out: the rule, then where and why.
pub fn describe_masked(masked: &[frf::io::Masked]) -> Vec<String> {
    masked.iter().map(|m| format!("{}: {}", m.rule, m.detail)).collect()
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
            if let Some(FrequencyChoice::List(points)) = &update.frequencies {
                grid.extend(points.iter().copied());
                grid.sort_by(f64::total_cmp);
                grid.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs());
            }
        }
        let mut masked = Vec::new();
        let mut notes = Vec::new();
        let mut measured_kind = FrfKind::Receptance;
        let mut per_volt = Vec::new();
        let mut pairing = Vec::new();
        let measured = match (&spec.data, &case.truth, &truth) {
            (Some(path), _, _) => {
                let read = read_measured_for(&system, path, Some(spec))?;
                masked = read.masked.clone();
                notes = read.notes.iter().map(|n| format!("{}: {n}", path.display())).collect();
                measured_kind = read.set.kind();
                per_volt = read.per_volt_references();
                pairing = PairingReport::of(&read.pairing);
                let set = read.set.to_receptance();
                let index = set.channel_indices();
                let idx = channels
                    .iter()
                    .map(|c| {
                        index.get(c).copied().ok_or_else(|| {
                            UpdateError::Data(format!(
                                "{}: the data has no channel {c} that the case lists",
                                path.display()
                            ))
                        })
                    })
                    .collect::<Result<Vec<usize>, _>>()?;
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
        let (gains, gains_reason) = gain::decide(Some(spec), case.update.as_ref(), &per_volt)?;
        if gains != Gains::None {
            notes.push(format!("model FRFs are multiplied by fitted gains ({gains}): {gains_reason}"));
        }
        let mut study = Study {
            case,
            system,
            truth,
            measured,
            parameters,
            update_frequencies_hz: Vec::new(),
            masked,
            notes,
            measured_kind,
            gains,
            gains_reason,
            per_volt,
            pairing,
        };
        if study.case.update.is_some() {
            study.update_frequencies_hz = study.lines_for(study.method())?;
        }
        Ok(study)
    }

    /// Prepares a study from a loaded case and measured receptances that the
    /// caller holds (the loop of [`crate::fix`] keeps one data set while the
    /// model grows). The channels must be those of the case's measurement.
    /// The case's truth, if any, is not built: the data are given.
    pub fn with_measured(case: CaseFile, measured: FrfSet) -> Result<Self, UpdateError> {
        let system = DampedSystem::new(case.model.clone())?;
        let parameters = case.update.as_ref().map(|u| u.parameters.clone()).unwrap_or_default();
        // the data's per-volt references are not known here: the caller that
        // read them sets `gains` (see `gain::decide`) when they differ
        let (gains, gains_reason) = gain::decide(case.measurement.as_ref(), case.update.as_ref(), &[])?;
        let mut study = Study {
            case,
            system,
            truth: None,
            measured,
            parameters,
            update_frequencies_hz: Vec::new(),
            masked: Vec::new(),
            notes: Vec::new(),
            measured_kind: FrfKind::Receptance,
            gains,
            gains_reason,
            per_volt: Vec::new(),
            pairing: Vec::new(),
        };
        if study.case.update.is_some() {
            study.update_frequencies_hz = study.lines_for(study.method())?;
        }
        Ok(study)
    }

    /// The updating method the case asks for (`rfm` when it does not say).
    pub fn method(&self) -> Method {
        match self.case.update.as_ref().and_then(|u| u.method.as_ref()).map(|m| m.0.as_str()) {
            Some("output-error") => Method::OutputError,
            _ => Method::Rfm,
        }
    }

    /// Checks the case's method name; returns it parsed.
    pub fn checked_method(&self) -> Result<Method, UpdateError> {
        match self.case.update.as_ref().and_then(|u| u.method.as_ref()) {
            None => Ok(Method::Rfm),
            Some((m, span)) => Method::parse(m).ok_or_else(|| {
                UpdateError::Case(
                    self.case.error(Some(span.clone()), format!("unknown method `{m}` (available: rfm, output-error)")),
                )
            }),
        }
    }

    /// Updating lines for a method: the case's choice, else the method's
    /// default (RFM: points away from resonances, two per parameter and at
    /// least ten; output-error: 200 lines spread over the band).
    pub fn lines_for(&self, method: Method) -> Result<Vec<f64>, UpdateError> {
        let given = self.case.update.as_ref().and_then(|u| u.frequencies.clone());
        let choice = given.unwrap_or(match method {
            Method::Rfm => FrequencyChoice::Auto(2 * self.parameters.len().max(5)),
            Method::OutputError => FrequencyChoice::Lines(200),
        });
        let lines = self.choose_lines(&choice)?;
        if lines.is_empty() {
            return Err(UpdateError::Lines(format!(
                "no measured line to fit: the [update] frequencies designate none of the {} measured lines",
                self.measured.n_freq()
            )));
        }
        Ok(lines)
    }

    /// The measured lines a frequency choice designates.
    pub fn choose_lines(&self, choice: &FrequencyChoice) -> Result<Vec<f64>, UpdateError> {
        let lines = self.measured.frequencies_hz();
        Ok(match choice {
            FrequencyChoice::All => lines.to_vec(),
            FrequencyChoice::Lines(n) => {
                let n = (*n).min(lines.len());
                if n == lines.len() {
                    lines.to_vec()
                } else {
                    // evenly spread, first and last included
                    let mut idx: Vec<usize> = (0..n)
                        .map(|i| (i as f64 * (lines.len() - 1) as f64 / (n - 1).max(1) as f64).round() as usize)
                        .collect();
                    idx.dedup();
                    idx.iter().map(|&k| lines[k]).collect()
                }
            }
            FrequencyChoice::List(points) => {
                for &p in points {
                    if self.measured.line_of(p).is_none() {
                        return Err(UpdateError::Lines(format!(
                            "updating point {p} Hz is not a line of the measured data"
                        )));
                    }
                }
                points.clone()
            }
            FrequencyChoice::Auto(n) => {
                let model = frf::synthesize(&self.system, self.measured.channels(), lines)?;
                let mut avoid = freqsel::features(&model);
                avoid.extend(freqsel::features(&self.measured));
                freqsel::choose(lines, &avoid, *n)
            }
        })
    }

    /// Parameter names.
    pub fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(|p| p.name.clone()).collect()
    }

    /// The parameters as a set for the solvers.
    pub fn parameter_set(&self) -> ParameterSet {
        ParameterSet::new(self.parameters.clone())
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
            return Err(UpdateError::NoParameters);
        }
        if self.gains != Gains::None {
            return Err(UpdateError::Method(format!(
                "the response function method fits no gain, and this case needs {} gains ({}); update with the \
                 output-error method (`method = \"output-error\"` in [update], or --method output-error)",
                self.gains, self.gains_reason
            )));
        }
        let lines = self.lines_for(Method::Rfm)?;
        let measured = self.measured.at_frequencies(&lines)?;
        self.check_initial(&measured)?;
        let mut sys = self.system.clone();
        let mut opts = opts.clone();
        if let Some(spec) = &self.case.update {
            opts.bounds = spec.bounds.clone();
        }
        let result = rfm::run(&mut sys, &self.parameter_set(), &measured, &opts, on_iteration)?;
        let mut warnings: Vec<String> = self
            .parameters
            .iter()
            .enumerate()
            .filter(|&(i, _)| result.at_bound[i])
            .map(|(i, p)| {
                let (lo, hi) = result.bounds[i];
                if opts.bounds.get(i).copied().flatten().is_some() {
                    format!("{} ended on its bound [{lo:e}, {hi:e}]", p.name)
                } else {
                    format!(
                        "{} ended a factor of {:e} from its initial value, the most the RFM allows without bounds of its own: the data do not determine it",
                        p.name,
                        rfm::DEFAULT_RANGE
                    )
                }
            })
            .collect();
        warnings.extend(result.unresolved.clone());
        let noise = crate::diagnose::estimate_noise(&self.measured);
        if let Some(s) = noise.filter(|&s| s > verdict::RFM_NOISE_LIMIT) {
            warnings.push(format!(
                "the data's noise ({:.2} %) is above the {:.1} % where the RFM is biased (its equations have \
                 measured data on both sides): its values cannot be trusted; use --method output-error",
                100.0 * s,
                100.0 * verdict::RFM_NOISE_LIMIT
            ));
        }
        warnings.extend(verdict::runaways(&self.parameter_names(), &self.system_values(), &result.values));
        let first = result.history.first().map_or(f64::NAN, |r| r.residual);
        let worse_than_start = result.residual > first;
        if worse_than_start {
            warnings.push(format!(
                "the RFM made the misfit worse than the initial model's ({:.3e} -> {:.3e}): the updated model \
                 is not an improvement",
                first, result.residual
            ));
        }
        let noise_ratio = noise.filter(|&s| s > 0.0).map(|s| result.residual / s);
        let natural_frequencies_hz = self.frequency_table(&sys);
        Ok(UpdateOutcome {
            natural_frequencies_hz,
            uncertainty: None,
            gains: Vec::new(),
            noise_estimate: noise,
            masked: describe_masked(&self.masked),
            notes: self.notes.clone(),
            warnings,
            noise_ratio,
            restarts: Vec::new(),
            worse_than_start,
            gain_setting: format!("{} ({})", self.gains, self.gains_reason),
            coherence_weighted: false,
            pairing: self.pairing.clone(),
            method: "rfm".into(),
            status: verdict::classify(&result.status, noise_ratio, None),
            parameters: self.reports(&result.values),
            history: result.history,
            residual: result.residual,
            frequencies_hz: lines,
            system: sys,
        })
    }

    /// Evaluates the initial model at the lines of `measured`, so that a
    /// model that cannot be evaluated is refused with the reason and the
    /// line before any iteration (the solvers would only see that the
    /// misfit is not a number).
    pub fn check_initial(&self, measured: &FrfSet) -> Result<(), UpdateError> {
        let model = frf::synthesize(&self.system, measured.channels(), measured.frequencies_hz())?;
        for (c, channel) in model.channels().iter().enumerate() {
            if let Some(k) = model.channel(c).iter().position(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return Err(UpdateError::Numerics(format!(
                    "the initial model's receptance {channel} at {} Hz is {}: a value of the model is out of the \
                     range double precision holds (a modulus, density, stiffness or damping coefficient many \
                     orders of magnitude off?)",
                    model.frequencies_hz()[k],
                    model.get(c, k)
                )));
            }
        }
        if model.values().iter().all(|v| v.norm_sqr() == 0.0) {
            return Err(UpdateError::Numerics(format!(
                "the initial model's receptances are zero at every updating line ({} to {} Hz): a value of the \
                 model is out of the range double precision holds (a modulus or stiffness many orders of \
                 magnitude too large?)",
                model.frequencies_hz()[0],
                model.frequencies_hz()[model.n_freq() - 1]
            )));
        }
        let synthesised = self.case.measurement.as_ref().is_some_and(|m| m.data.is_none());
        for (c, channel) in measured.channels().iter().enumerate() {
            if synthesised && measured.channel(c).iter().all(|v| v.norm_sqr() == 0.0) {
                return Err(UpdateError::Numerics(format!(
                    "the FRF {channel} synthesised from the case's truth model is zero at every updating line: a \
                     value of the truth model is out of the range double precision holds"
                )));
            }
            if measured.channel(c).iter().all(|v| v.norm_sqr() == 0.0) {
                return Err(UpdateError::Data(format!(
                    "the measured FRF {channel} is zero at every updating line: a relative misfit cannot be formed"
                )));
            }
        }
        Ok(())
    }

    /// Whether the fits weight lines by the measured coherence: by default
    /// whenever the data carry it, unless `[update] coherence = false`.
    pub fn weighs_coherence(&self) -> bool {
        let asked = self.case.update.as_ref().and_then(|u| u.coherence);
        asked.unwrap_or(true) && (0..self.measured.channels().len()).any(|c| self.measured.coherence(c).is_some())
    }

    /// Residual weights for `measured` (lines of this study's data): the
    /// `[update]` band weights times the coherence weight
    /// `sqrt(g / (1 - g))`, the inverse of an FRF estimate's relative
    /// standard deviation up to a constant (capped at coherence 0.999 and
    /// scaled to 1 there); channel-major, `None` when all are 1. Used by the
    /// output-error fit, the gain fits and the comparison.
    pub fn line_weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        line_weights_for(&self.case, measured)
    }

    /// Decides the gains again for measured data read from another file
    /// (`--measured`): from the case and that file's per-volt references,
    /// as [`Study::from_case`] does for the case's own data.
    pub fn set_gains_for(&mut self, read: &frf::io::Measured) -> Result<(), UpdateError> {
        self.per_volt = read.per_volt_references();
        (self.gains, self.gains_reason) =
            gain::decide(self.case.measurement.as_ref(), self.case.update.as_ref(), &self.per_volt)?;
        Ok(())
    }

    /// The diagnosis options of this study: the defaults, with a gain per
    /// reference fitted with every candidate when the study has gains. A
    /// gain per channel is refused: the diagnosis fits them per reference.
    pub fn diagnose_options(&self) -> Result<crate::diagnose::DiagnoseOptions, UpdateError> {
        let gains = match self.gains {
            Gains::None => false,
            Gains::PerReference => true,
            Gains::PerChannel => {
                return Err(UpdateError::Method(
                    "`gains = \"per-channel\"`: the diagnosis and the output-error update fit one gain per \
                     reference (compare fits them per channel); diagnose with `gains = \"per-reference\"`"
                        .into(),
                ));
            }
        };
        Ok(crate::diagnose::DiagnoseOptions { gains, ..Default::default() })
    }

    /// Line weights of the output-error fit (see [`Study::line_weights`]).
    pub fn weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        self.line_weights(measured)
    }

    /// The measured FRFs in the kind they were measured in (`measured` is
    /// receptance): what comparisons show.
    pub fn measured_as_read(&self) -> FrfSet {
        self.measured.converted(self.measured_kind)
    }

    /// Fits this study's gains ([`Study::gains`]) to `model` (the model's
    /// FRFs on the channels and lines of `measured`, in any kind) against
    /// `measured`, weighted by [`Study::line_weights`].
    pub fn fit_gains(&self, model: &FrfSet, measured: &FrfSet) -> Result<gain::FittedGains, UpdateError> {
        let model = if model.kind() == measured.kind() { model.clone() } else { model.converted(measured.kind()) };
        let weights = self.line_weights(measured)?;
        gain::fit_gains(&model, measured, weights.as_deref(), self.gains)
    }

    /// Runs the output-error estimator from the initial model, with the
    /// case's options (bounds, regularisation, gains, weights, misfit form).
    pub fn run_output_error(
        &self,
        opts: &OeOptions,
        on_iteration: impl FnMut(&IterationRecord),
    ) -> Result<UpdateOutcome, UpdateError> {
        if self.parameters.is_empty() {
            return Err(UpdateError::NoParameters);
        }
        let lines = self.lines_for(Method::OutputError)?;
        let measured = self.measured.at_frequencies(&lines)?;
        self.check_initial(&measured)?;
        let weights = self.weights(&measured)?;
        let params = self.parameter_set();
        let mut sys = self.system.clone();
        let data = OeData { measured: &measured, weights: weights.as_deref() };
        let noise = crate::diagnose::estimate_noise(&self.measured);
        let ratio = |r: &oe::OeResult| noise.filter(|&s| s > 0.0).map(|s| (2.0 * r.sigma2).sqrt() / s);
        let first = oe::run(&mut sys, &params, &data, opts, on_iteration)?;
        let settled =
            |r: &oe::OeResult| r.status == Status::Converged && ratio(r).is_none_or(|x| x <= verdict::RESTART_ABOVE);
        let mut restarts = Vec::new();
        let mut agree = None;
        let mut history = first.history.clone();
        let mut result = first;
        if !settled(&result) && opts.restarts > 0 && !matches!(result.status, Status::Failed(_)) {
            // restarts spread in log space around the initial values, a few
            // steps each; the best are run to the end and the lowest kept
            let p_init = params.values(&self.system);
            let bounds: Vec<(f64, f64)> = p_init
                .iter()
                .enumerate()
                .map(|(i, &p)| opts.bounds.get(i).copied().flatten().unwrap_or((p / 1e6, p * 1e6)))
                .collect();
            let fit = |start: &[f64], o: &OeOptions| -> Option<oe::OeResult> {
                let mut s = self.system.clone();
                params.set_values(&mut s, start).ok()?;
                oe::run(&mut s, &params, &data, o, |_| {}).ok().filter(|r| r.cost.is_finite())
            };
            let short = OeOptions { max_iterations: RESTART_STEPS, ..opts.clone() };
            let mut tried: Vec<oe::OeResult> = (1..=opts.restarts)
                .filter_map(|i| fit(&verdict::spread_start(&p_init, &bounds, i, RESTART_SPREAD), &short))
                .collect();
            tried.sort_by(|a, b| a.cost.total_cmp(&b.cost));
            for t in &tried[RESTARTS_REFINED.min(tried.len())..] {
                restarts.push(Restart {
                    start_residual: t.history[0].residual,
                    residual: t.history.last().map_or(f64::NAN, |r| r.residual),
                    refined: false,
                });
            }
            let mut ends = vec![result.cost];
            for t in tried.into_iter().take(RESTARTS_REFINED) {
                let Some(r) = fit(&t.values, opts) else { continue };
                restarts.push(Restart {
                    start_residual: t.history[0].residual,
                    residual: r.history.last().map_or(f64::NAN, |x| x.residual),
                    refined: true,
                });
                ends.push(r.cost);
                if r.cost < result.cost {
                    let offset = history.len();
                    history.extend(r.history.iter().cloned().map(|mut rec| {
                        rec.iteration += offset;
                        rec
                    }));
                    result = r;
                }
            }
            let best = result.cost;
            let same = ends.iter().filter(|&&c| (c - best) <= verdict::SAME_MINIMUM * best).count();
            agree = Some(same >= 2);
            params.set_values(&mut sys, &result.values)?;
        }
        let noise_ratio = ratio(&result);
        let status = verdict::classify(&result.status, noise_ratio, agree);
        let band = (lines[0], lines[lines.len() - 1]);
        let report = uncertainty::analyse(&params, &result, band, noise);
        let natural_frequencies_hz = self.frequency_table(&sys);
        let first_residual = history.first().map_or(f64::NAN, |r| r.residual);
        let residual = result.history.last().map_or(f64::NAN, |r| r.residual);
        Ok(UpdateOutcome {
            method: "output-error".into(),
            status,
            parameters: self.reports(&result.values),
            residual,
            history,
            frequencies_hz: lines,
            natural_frequencies_hz,
            uncertainty: Some(report),
            gains: result.gains,
            noise_estimate: noise,
            masked: describe_masked(&self.masked),
            notes: self.notes.clone(),
            warnings: Vec::new(),
            noise_ratio,
            restarts,
            worse_than_start: residual > first_residual,
            gain_setting: format!("{} ({})", self.gains, self.gains_reason),
            coherence_weighted: weights.is_some() && self.weighs_coherence(),
            pairing: self.pairing.clone(),
            system: sys,
        })
    }

    /// The initial values of the updating parameters.
    pub fn system_values(&self) -> Vec<f64> {
        self.parameter_set().values(&self.system)
    }

    /// RFM options from the case's `[update]` section (iteration limit,
    /// tolerance; [`Self::run_rfm`] adds the bounds).
    pub fn rfm_options(&self) -> RfmOptions {
        let mut opts = RfmOptions::default();
        if let Some(spec) = self.case.update.as_ref() {
            if let Some(n) = spec.max_iterations {
                opts.max_iterations = n as usize;
            }
            if let Some(t) = spec.tolerance {
                opts.tolerance = t;
            }
        }
        opts
    }

    /// Output-error options from the case's `[update]` section, with the
    /// study's gains ([`Study::gains`]; the estimator fits them per reference).
    pub fn output_error_options(&self) -> Result<OeOptions, UpdateError> {
        let gains = match self.gains {
            Gains::None => false,
            Gains::PerReference => true,
            Gains::PerChannel => {
                return Err(UpdateError::Method(
                    "`gains = \"per-channel\"`: the output-error update fits one gain per reference (compare fits \
                     them per channel); update with `gains = \"per-reference\"`"
                        .into(),
                ));
            }
        };
        let mut opts = OeOptions { gains, ..OeOptions::default() };
        if let Some(spec) = self.case.update.as_ref() {
            if let Some(n) = spec.max_iterations {
                opts.max_iterations = n as usize;
            }
            if let Some(t) = spec.tolerance {
                opts.tolerance = t;
            }
            opts.regularization = spec.regularization.unwrap_or(0.0);
            opts.bounds = spec.bounds.clone();
            if let Some((m, span)) = &spec.misfit {
                opts.misfit = Misfit::parse(m).ok_or_else(|| {
                    UpdateError::Case(
                        self.case.error(Some(span.clone()), format!("unknown misfit `{m}` (relative or log)")),
                    )
                })?;
            }
        }
        Ok(opts)
    }

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

    /// Reports for the given updated values.
    pub fn reports(&self, updated: &[f64]) -> Vec<ParameterReport> {
        let paper = self.case.paper.as_ref();
        self.parameters
            .iter()
            .zip(updated)
            .map(|(p, &u)| {
                let q = p.quantities[0];
                ParameterReport {
                    name: p.name.clone(),
                    initial: self.system.get(q),
                    updated: u,
                    truth: self.truth.as_ref().map(|t| t.get(q)),
                    paper: paper.and_then(|pp| pp.values.iter().find(|(pq, _)| *pq == q).map(|&(_, v)| v)),
                }
            })
            .collect()
    }
}

/// The residual weights of a case's measured data `measured` (see
/// [`Study::line_weights`]): band weights times the coherence weight,
/// whenever the data carry coherence unless `[update] coherence = false`.
pub fn line_weights_for(case: &CaseFile, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
    let bands = case.update.as_ref().map_or(&[][..], |u| &u.weights[..]);
    let asked = case.update.as_ref().and_then(|u| u.coherence);
    let has = (0..measured.channels().len()).any(|c| measured.coherence(c).is_some());
    if asked == Some(true) && !has {
        return Err(UpdateError::Data(
            "coherence weighting is requested ([update] coherence = true) but the measured data carry no \
             coherence"
                .into(),
        ));
    }
    let coherence = asked.unwrap_or(true) && has;
    if bands.is_empty() && !coherence {
        return Ok(None);
    }
    let nf = measured.n_freq();
    let mut w = vec![1.0; nf * measured.channels().len()];
    for (c, chunk) in w.chunks_mut(nf).enumerate() {
        for (k, wk) in chunk.iter_mut().enumerate() {
            let f = measured.frequencies_hz()[k];
            for b in bands.iter().filter(|b| b.from <= f && f <= b.to) {
                *wk *= b.weight;
            }
            if coherence && let Some(coh) = measured.coherence(c) {
                let g = coh[k].clamp(0.0, 0.999);
                *wk *= (g / (1.0 - g)).sqrt().min(30.0) / 30.0;
            }
        }
    }
    Ok(Some(w))
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

//! Closing the loop: check the data, update the case's own parameters,
//! then diagnose, add an effect, update everything, and again, while the
//! evidence asks for it.
//!
//! This is what `rfm fix` runs. One rule decides every step:
//!
//! > **each step keeps the model that the evidence prefers over the
//! > previous one, with every parameter counted, and nothing else.**
//!
//! The evidence is the change of the information criterion
//! ([`diagnose::delta_bic`]) from the model before the step to the model
//! after it, both updated, judged against what the model after leaves (the
//! noise, or a lack of fit that no candidate explains) and counting every
//! parameter the step adds; a step is kept when that is below the
//! diagnosis's significance (-10), the values its update reaches are
//! plausible (none at or past the limits of its effect's plausible range),
//! and its update reached a stationary point. Steps are tried in this order:
//!
//! 0. **The data's own errors.** The channels are checked for what test
//!    set-ups get wrong ([`crate::checks`]: an inverted sensor, swapped
//!    cables, a sensor at another node or axis, a wrong sensitivity, and
//!    measured modes the model lacks). A correction found is applied to the
//!    data and written into the case (`[[measurement.corrections]]`): the
//!    model is fitted to the corrected data, and nothing is blamed on it
//!    that the set-up made. The channels are checked again after each
//!    step (a model error can hide a sensor's error from the first check);
//!    a correction found then makes the step again on the corrected data,
//!    since it was chosen on data that were wrong (`REDONE`).
//! 1. **The case's declared parameters.** When the case lists parameters
//!    under `[update]`, they are updated first (step 0 of the report): an
//!    effect is blamed on missing physics only after the user's own
//!    uncertain parameters have had their chance.
//! 2. **One effect at a time.** The current model is diagnosed; each of a
//!    few distinct leaders (significant and plausible, of different kinds
//!    or places) is added and every parameter updated jointly; the best by
//!    its own evidence is kept, when it also explains at least half of
//!    what the model before it leaves above the noise ([`SHARE`]): an
//!    effect that lowers a large misfit a little everywhere is not singled
//!    out by the data, however significant. When several leaders at different places
//!    are as good as each other (their evidence within the significance of
//!    each other), the loop stops and lists them: the data cannot tell them
//!    apart. Two leaders may also be kept together, as two steps, when
//!    neither alone explains the data (two effects that mislead one at a
//!    time): the pair is kept only when each of the two passes the rule
//!    against the model with the other alone.
//! 3. **Revisions.** When the effects leave more than the noise, each is
//!    revised with the others in place (its other forms, a kind that stands
//!    in for it, or nothing; `fix/revise.rs`), and effects added early are
//!    left out and replaced (`fix/swap.rs`): each replacement is a step kept
//!    by the same rule, and an effect is taken out when, added to the model
//!    without it, it would no longer be significant.
//!
//! The loop stops when no step passes the rule: with the data explained to
//! their noise ([`FixStop::NothingSignificant`]), or with something the
//! candidates cannot explain, described in the user's terms (an extra mode,
//! a channel, a band, a damping form: [`FixOutcome::remains`];
//! [`FixStop::ModelInadequate`]), or when several effects explain the data
//! equally well ([`FixStop::Ambiguous`]).

use fe_model::{CaseEditor, CaseFile, HistoryEntry};
use frf::FrfSet;

use crate::checks::{self, CheckOptions, Finding, FindingKind};
use crate::diagnose::{self, DiagnoseOptions, Diagnosis, EffectKind, MisfitStats, Ranked};
use crate::error::UpdateError;
use crate::status::Status;
use crate::study::{ParameterReport, Study};
use crate::uncertainty::UncertaintyReport;

mod explains;
mod judge;
mod pairs;
mod remains;
mod revise;
mod swap;

use judge::Evidence;

/// Options of the loop.
#[derive(Clone, Debug)]
pub struct FixOptions {
    /// Most effects to add.
    pub max_steps: usize,
    /// Options of each diagnosis (its `lines` are also the update's).
    pub diagnose: DiagnoseOptions,
    /// Iteration limit of each update.
    pub update_iterations: usize,
    /// Where the data a case synthesises from its `[truth]` are written:
    /// the cases of the steps read them from there, without the truth
    /// ([`Diagnosis::apply_with_data`]).
    pub data: Option<std::path::PathBuf>,
    /// Check the data for set-up errors first and fit the corrected data
    /// ([`crate::checks`]); on by default.
    pub check_data: bool,
}

impl Default for FixOptions {
    fn default() -> Self {
        FixOptions {
            max_steps: 3,
            diagnose: DiagnoseOptions::default(),
            update_iterations: 100,
            data: None,
            check_data: true,
        }
    }
}

/// A stage updated again from a better start: the next step's effect,
/// added and updated, left no more than the parameters before it at the
/// values its fit reached (it was not needed at its own fit: the first
/// update had stopped in a local minimum, and the effect only led the
/// optimiser out). The stage's misfit, parameters and case are those of
/// the update from that start.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Refit {
    /// The misfit the stage's first update ended at.
    pub first_misfit: f64,
    /// The effect whose fit found the lower minimum.
    pub found_by: String,
    /// The misfit with that effect, updated.
    pub misfit_with_it: f64,
    /// The evidence for that effect at its own fit: the change of the
    /// information criterion from the parameters before it at the values
    /// its fit reached to the model with it (not below the significance:
    /// it was not needed).
    pub delta_bic_there: f64,
}

/// Step 0: the case's own `[update]` parameters updated before any effect is added.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct DeclaredStep {
    /// The misfit before (the case as given, on the corrected data).
    pub misfit_before: f64,
    /// The misfit after the update.
    pub misfit_updated: f64,
    /// The evidence for the updated values over the given ones.
    pub delta_bic: f64,
    /// How the update ended.
    pub status: Status,
    /// The updated parameters.
    pub parameters: Vec<ParameterReport>,
    /// Their uncertainty.
    pub uncertainty: Option<UncertaintyReport>,
    /// Updated again from a better start ([`Refit`]); `misfit_updated`,
    /// `status`, `parameters` and `case` are then that update's.
    pub refit: Option<Refit>,
    /// The case after it.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub case: CaseEditor,
}

/// One step of the loop: the effect added and the update after it.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FixStep {
    /// The effect added, as the diagnosis ranked it.
    pub effect: Ranked,
    /// The misfit with the effect at its diagnosed values (RMS of
    /// `ln(model / measured)` per value; see [`diagnose::log_misfit`]).
    pub misfit_added: f64,
    /// The misfit after the update.
    pub misfit_updated: f64,
    /// The step's own evidence: the change of the information criterion
    /// from the model before the step to the model after it, both updated,
    /// every parameter counted ([`diagnose::delta_bic`]).
    pub delta_bic: f64,
    /// Parameters the model has after the step (the case's `[update]`).
    pub parameter_count: usize,
    /// How the update ended ([`step_status`]).
    pub status: Status,
    /// The updated parameters (every effect added so far, and the case's own).
    pub parameters: Vec<ParameterReport>,
    /// Their uncertainty.
    pub uncertainty: Option<UncertaintyReport>,
    /// The other effects tried at this step, each added and updated, with
    /// the evidence for it and why it was not kept.
    pub alternatives: Vec<LookAhead>,
    /// The effects of earlier steps this one replaced, with any that follow
    /// it (left out, the others kept, and these added instead; see [`fix`]),
    /// when it did: their descriptions joined by " and ".
    pub replaced: Option<String>,
    /// The effect was taken out again, not added: with the others revised,
    /// added to the model without it, it would no longer be significant
    /// (`fix/revise.rs`); `misfit_added`
    /// and `misfit_updated` are both the misfit without it, updated.
    pub removed: bool,
    /// Why the effect was taken out (with `removed`): its evidence added to
    /// the model without it.
    pub removed_because: Option<String>,
    /// The misfit after the data found wrong once this step was kept were
    /// corrected and every parameter updated again (see [`FixOutcome::findings`],
    /// `found_after_step`); `case`, `parameters` and `status` are then that
    /// update's. Only when the loop has made steps again `REDONE` times
    /// already: otherwise a correction found after a step makes that step
    /// again on the corrected data.
    pub corrected_misfit: Option<f64>,
    /// Updated again from a better start ([`Refit`]): the misfit, status,
    /// parameters and case above are then that update's (after any data
    /// correction, `corrected_misfit` is its misfit).
    pub refit: Option<Refit>,
    /// The case after this step (write it with [`CaseEditor::text_at`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub case: CaseEditor,
}

/// The status a step shows: its update's, except that an update which
/// reached a stationary point above the noise (the loop keeps no other) is
/// [`Status::ModelInadequate`], what the loop then looks for, not
/// [`Status::Stalled`], which the study names a fit without restarts that
/// stops above the noise (the loop's updates restart only where the first
/// fit is doubtful): a kept step's update did not stall.
pub fn step_status(outcome: &crate::study::UpdateOutcome) -> Status {
    match outcome.status {
        Status::Stalled if outcome.iteration_end == Status::Converged => Status::ModelInadequate,
        ref s => s.clone(),
    }
}

impl FixStep {
    /// The misfit the step ends at: after the late correction of the data
    /// when there was one, else after its update.
    pub fn final_misfit(&self) -> f64 {
        self.corrected_misfit.unwrap_or(self.misfit_updated)
    }

    /// The step updated again on data a late check corrected: its case
    /// `editor` holds, at `misfit`, with the update's `outcome`.
    fn corrected(&mut self, editor: CaseEditor, misfit: f64, outcome: crate::study::UpdateOutcome) {
        self.corrected_misfit = Some(misfit);
        self.case = editor;
        self.status = step_status(&outcome);
        self.parameters = outcome.parameters;
        self.uncertainty = outcome.uncertainty;
    }

    fn of(a: Added, delta_bic: f64, alternatives: Vec<LookAhead>, replaced: Option<String>) -> FixStep {
        FixStep {
            misfit_added: a.effect.misfit,
            effect: a.effect,
            misfit_updated: a.stats.misfit,
            delta_bic,
            parameter_count: a.outcome.parameters.len(),
            status: step_status(&a.outcome),
            parameters: a.outcome.parameters,
            uncertainty: a.outcome.uncertainty,
            alternatives,
            replaced,
            removed: false,
            removed_because: None,
            corrected_misfit: None,
            refit: None,
            case: a.editor,
        }
    }
}

/// An effect (or a pair) tried at a step: added, every parameter updated,
/// and judged.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LookAhead {
    /// The effect.
    pub effect: String,
    /// The misfit after it and its update (NaN when it could not be added
    /// and updated, see `failed`).
    pub misfit_ahead: f64,
    /// The evidence for it over the model before the step (NaN when it
    /// could not be added).
    pub delta_bic: f64,
    /// Why adding and updating it failed (an update that drove a spring to
    /// zero and left a mechanism, say), when it did.
    pub failed: Option<String>,
    /// Why it was not kept, when it passed nothing or lost to another
    /// (`None` for the step kept).
    pub rejected: Option<String>,
    /// The second effect, when this is a pair fitted together.
    pub with: Option<String>,
    /// As good as the effect kept: the data cannot tell the two apart.
    pub equally_good: bool,
}

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum FixStop {
    /// The model explains the data down to their noise, and no candidate is
    /// significant.
    NothingSignificant,
    /// More than the noise remains, and no candidate passes the rule
    /// (significant on its own, plausible after its update, updated to a
    /// stationary point): what remains is described in
    /// [`FixOutcome::remains`].
    ModelInadequate,
    /// Several effects at different places explain the data equally well
    /// (listed in [`FixOutcome::equally_good`]): the data cannot tell them
    /// apart, and none is added.
    Ambiguous,
    /// The number of steps asked for was done; something significant may remain.
    StepsDone,
    /// The diagnosis of the model after the last step failed (see
    /// [`FixOutcome::diagnosis_error`]); the steps before it stand.
    DiagnosisFailed,
    /// The model's mesh is too coarse for the band: the same model with
    /// every element cut in two explains the data to their noise
    /// ([`FixOutcome::mesh`]), before the first step or after one, so no
    /// effect is added for what the mesh decides.
    MeshTooCoarse,
}

impl FixStop {
    /// Plain-language reason.
    pub fn describe(self) -> &'static str {
        match self {
            FixStop::NothingSignificant => "nothing significant remains: the model explains the data to their noise",
            FixStop::ModelInadequate => {
                "the model is inadequate: more than the noise remains and no candidate effect explains it on its own \
                 evidence"
            }
            FixStop::Ambiguous => {
                "several effects at different places explain the data equally well; the data cannot tell them apart"
            }
            FixStop::StepsDone => "the number of steps asked for is done",
            FixStop::DiagnosisFailed => "the diagnosis of the model after the last step failed",
            FixStop::MeshTooCoarse => {
                "what the model leaves is its mesh's: the same model with every element cut in two explains the data \
                 to their noise, so no effect is added for it; refine the mesh"
            }
        }
    }
}

/// The outcome of the loop.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FixOutcome {
    /// The data's estimated relative noise (RMS per value).
    pub noise: f64,
    /// The nominal model's misfit (on the data as measured).
    pub nominal_misfit: f64,
    /// What the checks found wrong with the data, corrected before the
    /// model was fitted when they propose a correction (see [`crate::checks`]).
    pub findings: Vec<Finding>,
    /// The nominal model's misfit on the corrected data (equal to
    /// `nominal_misfit` when nothing was corrected).
    pub corrected_misfit: f64,
    /// Step 0: the case's own `[update]` parameters, updated first.
    pub declared: Option<DeclaredStep>,
    /// The steps, in order.
    pub steps: Vec<FixStep>,
    /// The effects in the final model, in the order they were added.
    pub effects: Vec<Ranked>,
    /// Why the loop stopped.
    pub stop: FixStop,
    /// The reason in full: the stop's meaning and what decided it.
    pub stop_reason: String,
    /// What the final model leaves unexplained, in the user's terms (an
    /// extra mode at f Hz, a channel, a band, a damping form); empty when
    /// it explains the data to their noise.
    pub remains: Vec<String>,
    /// Effects at different places as good as each other, each with its
    /// evidence: at the stop [`FixStop::Ambiguous`] (none added), or at an
    /// earlier step when the loop ends without explaining the data (the
    /// first listed was kept; nothing after told them apart).
    pub equally_good: Vec<LookAhead>,
    /// The diagnosis of the final model (top of its ranking only).
    pub remaining: Vec<Ranked>,
    /// Whether something significant remains in the final diagnosis (true
    /// when that diagnosis failed: nothing says the model is consistent).
    pub significant_remains: bool,
    /// Why the diagnosis of the final model failed, when it did.
    pub diagnosis_error: Option<String>,
    /// The model against itself with a finer mesh: the last check made,
    /// before the first step (the model corrected, its own parameters
    /// updated) and before every step after it; `None` for a model without
    /// beams or too large to refine ([`diagnose::mesh_check`]).
    pub mesh: Option<diagnose::MeshCheck>,
}

impl FixOutcome {
    /// The misfit after every stage: the nominal model, the corrected data,
    /// step 0, then per step with the effect added and after the update,
    /// labelled.
    pub fn stages(&self) -> Vec<(String, f64)> {
        let mut v = vec![("nominal".to_string(), self.nominal_misfit)];
        if self.findings.iter().any(|f| !f.corrections.is_empty()) {
            v.push(("nominal, on the corrected data".to_string(), self.corrected_misfit));
        }
        if let Some(d) = &self.declared {
            v.push(("the case's own parameters updated (step 0)".to_string(), d.misfit_updated));
        }
        for (k, s) in self.steps.iter().enumerate() {
            let label = match &s.replaced {
                _ if s.removed => format!("- {}", s.effect.description),
                Some(r) => format!("+ {} instead of {r}", s.effect.description),
                None => format!("+ {}", s.effect.description),
            };
            v.push((label, s.misfit_added));
            v.push((format!("updated after step {}", k + 1), s.misfit_updated));
            if let Some(m) = s.corrected_misfit {
                v.push((format!("data corrected after step {} and updated", k + 1), m));
            }
        }
        v
    }

    /// The final misfit.
    pub fn final_misfit(&self) -> f64 {
        match (self.steps.last(), &self.declared) {
            (Some(s), _) => s.final_misfit(),
            (None, Some(d)) => d.misfit_updated,
            (None, None) => self.corrected_misfit,
        }
    }

    /// The model explains the data to their noise: the final misfit within
    /// [`CONSISTENT`] times the noise, and nothing significant left or
    /// what is left the mesh's ([`FixStop::MeshTooCoarse`]).
    pub fn explained(&self) -> bool {
        matches!(self.stop, FixStop::NothingSignificant | FixStop::MeshTooCoarse)
            && self.final_misfit() <= CONSISTENT * self.noise
    }

    /// The case the loop ends with: the last step's, or step 0's.
    pub fn final_case(&self) -> Option<&CaseEditor> {
        self.steps.last().map(|s| &s.case).or(self.declared.as_ref().map(|d| &d.case))
    }
}

/// What the loop reports as it goes.
#[derive(Clone, Debug)]
pub enum FixProgress<'a> {
    /// The data were checked for set-up errors.
    Checked {
        /// What was found (corrected when a correction is given).
        findings: &'a [Finding],
    },
    /// The case's own parameters were updated (step 0).
    Declared {
        /// The step.
        step: &'a DeclaredStep,
    },
    /// A diagnosis is done.
    Diagnosed {
        /// Effects added before it.
        step: usize,
        /// The diagnosis.
        diagnosis: &'a Diagnosis,
    },
    /// An effect (or a pair) was tried: added, updated and judged.
    LookedAhead {
        /// Effects added before it.
        step: usize,
        /// The effect, the misfit after it and the verdict.
        ahead: &'a LookAhead,
    },
    /// A step was kept.
    Updated {
        /// Effects added before this one.
        step: usize,
        /// The effect added (or, with `removed`, taken out).
        effect: &'a str,
        /// The effect was taken out, not added ([`FixStep::removed`]).
        removed: bool,
        /// The misfit after the update.
        misfit: f64,
        /// How the update ended.
        status: &'a Status,
    },
    /// The stage before (step 0, or the last step) was updated again from
    /// the start an effect's fit found, the effect not being needed there
    /// ([`Refit`]); a `Declared` or `StepDone` with the stage follows.
    Refitted {
        /// Effects added before the effect tried.
        step: usize,
        /// What was found.
        refit: &'a Refit,
        /// The misfit after the update from the better start.
        misfit: f64,
        /// How that update ended.
        status: &'a Status,
    },
    /// The steps from `step` on were undone: a check of the data after them
    /// found a set-up error and corrected it, and they had been chosen on
    /// the data as they were; the loop makes them again on the corrected
    /// data, from the model before them (a `Diagnosed` with the same `step`
    /// follows).
    Redone {
        /// Effects added before the first step undone.
        step: usize,
        /// The effects of the steps undone.
        effects: Vec<String>,
    },
    /// A step is finished and will stay in the outcome: its effect added (or
    /// taken out), every parameter updated, and the data checked again after
    /// it. It carries the whole step, its case among it, so that a caller
    /// can keep it (write its case) before the loop goes on: an interrupted
    /// loop then loses only the step under way.
    StepDone {
        /// Its place among the steps (0-based).
        index: usize,
        /// The step.
        done: &'a FixStep,
    },
}

/// A final misfit within this multiple of the noise is consistent with it:
/// the model explains the data down to their noise (what `rfm fix` calls
/// success, and the band its report shades).
pub const CONSISTENT: f64 = 1.5;

/// Above this multiple of the noise, the misfit the best single effect
/// leaves suggests that more than one effect is missing, and pairs of
/// leaders are fitted together.
const PAIRS_ABOVE: f64 = 3.0;

/// Above this multiple of the noise the effects' forms are revised
/// (`fix/revise.rs`), even when the misfit is consistent with the noise:
/// 10 % above the noise on thousands of values is far beyond chance, and an
/// effect of the right kind in the wrong damping form leaves about that
/// while its stiffness and mass are biased beyond their uncertainty (the
/// tutorial's lab frame: a non-viscous resonator added viscous leaves 1.29
/// times the noise and its stiffness 5 % high; revised, 0.9 times and
/// within 0.1 %). A revision is kept by the loop's rule, so below the
/// noise's own reach it finds nothing to keep.
const REVISE_ABOVE: f64 = 1.1;

/// The channels are checked again after every step; within this multiple
/// of the noise a correction the checks single out is made when its update
/// succeeds, and above it only when the corrected data's update explains
/// [`SHARE`] of what the model left above the noise: far from the data the
/// other channels of a reference are a poor yardstick for one of them (a
/// fin's cantilever at 78 times the noise after two steps made a channel
/// look 34 % low), yet a sensor at the next node beside a model error
/// leaves 15 to 50 times the noise once that error is fitted, which the
/// corrected channel alone then explains (the lab study's wrong-node
/// trials with a model error).
const LATE_CHECKS_BELOW: f64 = 5.0;

/// How many times a step is made again on data the checks corrected after
/// it. Each step is judged on the data the model is fitted to: a
/// correction found only once a model error is fitted (a sensor at the
/// next node, a sensitivity, hidden beside a lumped mass at 44 times the
/// noise) changes which effect the data prefer, and the step chosen before
/// it was chosen on data that were wrong (the lab study's trial 64: a mass
/// change of two elements chosen over the lumped mass with its rotary
/// inertia, then a stiffness change and a mass added to make up for its
/// form). The step is undone and the model before it diagnosed again on
/// the corrected data; beyond this many times, the step is kept and
/// updated on the corrected data instead (each time a channel is
/// corrected, so this only bounds the loop's work).
const REDONE: usize = 2;

/// How many distinct leaders are added and updated at each step.
const WIDTH: usize = 5;

/// The part of what the model before a step leaves above the noise (its
/// misfit's variance less the noise's) that a new effect, or a pair, must
/// explain to be added; the excess is read above the step's floor (the
/// lower of the loop's reading and the roughness of the residual of the
/// model before the step), so that a model near the data is not taken for
/// one within the noise, and a model within the loop's reading of the
/// noise takes nothing more. A missing effect explains its own part of the data
/// (alone, all of it; one of two, about its half, and the pair together
/// all); an effect that only bends a model toward an error of another form
/// (a member at another angle, a delay in the acquisition, a fin) lowers
/// the misfit a little everywhere and explains a small part of it, however
/// significant that part is on thousands of values. Such a step is not
/// singled out by the evidence, and the loop stops and says what remains
/// instead (lab study, `tests/it/lab_study.rs`).
pub const SHARE: f64 = 0.5;

/// The part of `before`'s excess over the noise that a model leaving
/// `after` explains (1: all; negative: it leaves more); `None` when
/// `before` leaves nothing above the noise.
fn share(before: f64, after: f64, noise: f64) -> Option<f64> {
    let excess = before.powi(2) - noise.powi(2);
    (excess > 0.0).then(|| 1.0 - (after.powi(2) - noise.powi(2)) / excess)
}

/// Why a step that leaves `after` from `before` is not singled out: the
/// model before it is within the loop's reading of the noise (`noise`), or
/// the step explains less than [`SHARE`] of the excess over the step's
/// floor (`floor`, at most `noise`: see [`SHARE`]). Each reading is taken
/// on the side that makes a step harder to keep: the higher to say that
/// the model is already within the noise, the lower to measure what is
/// left above it (against the lower alone, a model a percent above it
/// would leave an excess that any step reaching the noise "explains all
/// of": the lab study's trials 29, 56 and 71 then took a stiffness change,
/// a shaker and a joint from 1.01 to 1.03 times the floor).
fn small_share(before: f64, after: f64, noise: f64, floor: f64) -> Option<String> {
    if before <= noise {
        return Some("the model before it is already within the noise".into());
    }
    match share(before, after, floor.min(noise)) {
        None => Some("the model before it is already within the noise".into()),
        Some(s) if s < SHARE => Some(format!(
            "it explains {:.0} % of what the model before it leaves above the noise (a missing effect explains \
             at least {:.0} %)",
            100.0 * s.max(0.0),
            100.0 * SHARE
        )),
        Some(_) => None,
    }
}

/// An effect added to a case and every parameter updated.
#[derive(Clone)]
struct Added {
    effect: Ranked,
    /// Its rank in the diagnosis it came from.
    rank: usize,
    editor: CaseEditor,
    case: CaseFile,
    stats: MisfitStats,
    outcome: crate::study::UpdateOutcome,
}

/// An update's result: the case's editor holding the updated values, the
/// case it holds, its misfit statistics and the update's outcome.
type Updated = (CaseEditor, CaseFile, MisfitStats, crate::study::UpdateOutcome);

/// The loop's state shared by its parts: the data, options and evidence.
struct Loop<'a> {
    /// The data the models are fitted to (corrected).
    data: FrfSet,
    opts: &'a FixOptions,
    evidence: Evidence,
    /// Frequencies (Hz) of the measured modes the model lacked before any
    /// step or after one: the modes resonators are offered for, and judged
    /// by (`fix/explains.rs`).
    modes_hz: Vec<f64>,
}

impl Loop<'_> {
    /// The noise level read again against the model a diagnosis started
    /// from: the lower of the loop's and the diagnosis's (which reads the
    /// residual's roughness against its model where that is clearly below
    /// the data's own, `diagnose::estimate_noise_against`). The data's own
    /// roughness reads high over dense modes and antiresonances (a frame in
    /// space at 44 channels and 461 lines: 2.1 % against 1 % injected, so
    /// that a model at the noise was reported at 0.48 times it); a model
    /// near the structure leaves only the noise in its residual, and a model
    /// of a few parameters cannot follow the noise from line to line, so the
    /// lower reading is the surer.
    fn read_noise_again(&mut self, d: &Diagnosis) -> f64 {
        if d.noise.is_finite() && d.noise > 0.0 && d.noise < self.evidence.noise {
            self.evidence.noise = d.noise;
        }
        self.evidence.noise
    }
}

impl Loop<'_> {
    /// The noise level the share of a step ([`SHARE`]) is read against: the
    /// lower of the loop's reading and the roughness of the residual of
    /// the model before the step on every line
    /// ([`diagnose::residual_roughness`]). The share of an excess depends on
    /// the noise most where the model before is near it: the data's own
    /// roughness reads 6 to 9 % high on the lab study's cantilevers, and a
    /// model at 1.02 times that reading (1.08 times the noise injected)
    /// left an excess of 3 % of the noise's variance instead of 17 %, which
    /// any effect that took up part of it then explained "all of" (a
    /// shaker beside a lumped mass that the data hold with the structure's
    /// damping: 174 % of the excess at the loop's reading, 36 % at the
    /// residual's, trial 68 of the lab study). The loop's reading stays the one the evidence, the stop
    /// and whether the model before is already within the noise are judged
    /// against: there a higher noise is the cautious one, as a lower one is
    /// here (see `small_share`). The residual's reading costs a synthesis at
    /// every line: it is made only for a model whose misfit, `misfit`, is
    /// above the loop's noise (within it, `small_share` keeps nothing).
    fn floor(&self, misfit: f64, current: &CaseFile) -> f64 {
        let noise = self.evidence.noise;
        if !(misfit > noise) {
            return noise;
        }
        let read = damping::DampedSystem::new(current.model.clone()).ok().and_then(|sys| {
            diagnose::residual_roughness(&sys, &self.data, self.opts.diagnose.weights.as_deref()).ok().flatten()
        });
        match read {
            Some(r) if r > 0.0 && r < noise => r,
            _ => noise,
        }
    }

    /// The verdict of the loop's rule on `after` (see [`Evidence::judge`]),
    /// and, for a step that passes it with resonators, whether each
    /// explains the mode it was offered for (`fix/explains.rs`): one that
    /// leaves that mode's lines far above the noise is the wrong form.
    fn judge(&self, before: State, after: &Added, effects: &[(&Diagnosis, usize)]) -> judge::Verdict {
        let mut v = self.evidence.judge(before, after, effects);
        if v.rejected.is_none() {
            let noise = self.evidence.noise;
            match explains::unexplained(after, effects, &self.data, &self.opts.diagnose, noise, &self.modes_hz) {
                Ok(Some(u)) => {
                    v.rejected = Some(u.reason());
                    v.unexplained = Some(u);
                }
                Ok(None) => {}
                Err(e) => v.rejected = Some(format!("its resonator's mode could not be compared with the data: {e}")),
            }
        }
        v
    }

    /// Adds ranked effect `rank` of `d` to `current` and updates every
    /// parameter of the case's `[update]` by output error on the diagnosis's
    /// lines; the updated values and the misfit go into the case's history
    /// as step `step`. `last`: the model is the loop's answer, and its
    /// update restarts (see [`Loop::update_case`]).
    fn add_and_update(
        &self,
        current: &CaseFile,
        d: &Diagnosis,
        rank: usize,
        step: usize,
        last: bool,
    ) -> Result<Added, UpdateError> {
        let editor = d.apply_with_data(current, rank, self.opts.data.as_deref())?;
        let (editor, case, stats, outcome) = self.update_case(current, editor, step, last)?;
        Ok(Added { effect: d.ranking[rank - 1].clone(), rank, editor, case, stats, outcome })
    }

    /// Whether the effect `a` added to `current` (at misfit `state`) was
    /// needed at its own fit: the parameters of `current` set to the values
    /// `a`'s update reached, without the effect, must leave more than `a`
    /// by the significance. When they do not (the update before it had
    /// stopped in a local minimum, and the effect only led the optimiser
    /// out: a modulus 20 % high declared on a frame's band of 30 modes
    /// stalled at 217 times the noise, and a damping patch whose update
    /// moved the modulus reached the noise), `current` is updated again
    /// from those values and returned with the [`Refit`] record (`None`:
    /// the effect was needed, or the start is no better than `state`).
    fn not_needed(
        &self,
        current: &CaseFile,
        state: State,
        a: &Added,
        step: usize,
        last: bool,
    ) -> Result<Option<(Refit, Updated)>, UpdateError> {
        if state.k == 0 {
            return Ok(None);
        }
        let Some(update) = current.update.as_ref() else { return Ok(None) };
        let reached = a.outcome.system.model();
        let mut values = Vec::new();
        for (name, _) in crate::params::quantity_values(&update.parameters, &current.model) {
            let Ok(q) = reached.quantity(&name) else { return Ok(None) };
            values.push((name, reached.get(q)));
        }
        let mut editor = current.editor()?;
        editor.set_values(&values, &format!("from where the fit with {} ended", a.effect.description))?;
        let start = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
        let without = self.stats(&damping::DampedSystem::new(start.model.clone())?)?;
        let k_with = a.outcome.parameters.len();
        let there = diagnose::delta_bic(without.misfit, state.k, &a.stats, k_with, self.evidence.noise);
        let better = diagnose::delta_bic(state.misfit, state.k, &without, state.k, self.evidence.noise);
        if there < -self.evidence.significance || better >= -self.evidence.significance {
            return Ok(None);
        }
        let again = self.update_case(current, editor, step, last)?;
        if again.2.misfit > without.misfit {
            return Ok(None);
        }
        let refit = Refit {
            first_misfit: state.misfit,
            found_by: a.effect.description.clone(),
            misfit_with_it: a.stats.misfit,
            delta_bic_there: there,
        };
        Ok(Some((refit, again)))
    }

    /// Updates every parameter of the `[update]` of the case `editor` holds
    /// by output error on the diagnosis's lines; returns the editor with the
    /// updated values and the misfit in the case's history (as step
    /// `step`), the case it now holds, the misfit's statistics and the
    /// outcome. An update that ends short of a stationary point is run
    /// again with the parameters it could not determine held at their
    /// start; the outcome says how the last run ended. `last`: the model is
    /// the loop's answer, and its fit restarts when it leaves more than the
    /// noise.
    fn update_case(
        &self,
        current: &CaseFile,
        editor: CaseEditor,
        step: usize,
        last: bool,
    ) -> Result<Updated, UpdateError> {
        let first = self.update_once(current, editor.clone(), step, last)?;
        if judge::stationary(&first.3) {
            return Ok(first);
        }
        // hold what the data do not determine, and try once more
        let loose = judge::undetermined(&first.3);
        if loose.is_empty() || loose.len() == first.3.parameters.len() {
            return Ok(first);
        }
        let added = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
        let Some(update) = added.update.as_ref() else { return Ok(first) };
        let kept: Vec<String> =
            update.parameters.iter().map(|p| p.name.clone()).filter(|n| !loose.contains(n)).collect();
        let method = update.method.as_ref().map_or("output-error", |(m, _)| m.as_str());
        let mut held = editor;
        held.set_update(&kept, method)?;
        match self.update_once(current, held, step, last) {
            Ok(again) if judge::stationary(&again.3) => Ok(again),
            _ => Ok(first),
        }
    }

    /// One output-error update of the case `editor` holds (see [`Loop::update_case`]).
    fn update_once(
        &self,
        current: &CaseFile,
        mut editor: CaseEditor,
        step: usize,
        last: bool,
    ) -> Result<Updated, UpdateError> {
        let opts = self.opts;
        let lines = opts.diagnose.lines;
        let added = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
        let mut study = Study::with_measured(added, self.data.clone())?;
        if study.case().update.is_some() {
            // the lines the misfit is measured on (see `diagnose::log_misfit`)
            study.set_update_frequencies(fe_model::case::FrequencyChoice::List(diagnose::informative_lines(
                &self.data, lines,
            )))?;
        }
        let mut oe_opts = study.output_error_options()?;
        oe_opts.max_iterations = opts.update_iterations;
        // the loop decides from the evidence; restarting each intermediate
        // (knowingly incomplete) model would only cost time. The last
        // step's model is the answer: when its fit leaves more than the
        // noise, restarts tell an optimiser stuck in a local minimum (they
        // find a lower one) from a model that lacks something (they do not).
        if !last {
            oe_opts.restarts = 0;
        }
        // the loop reads the fit and its judgement, not the natural
        // frequencies a report would show
        let outcome = study.fit_output_error(&oe_opts)?;
        let stats = self.stats(&outcome.system)?;
        let values = crate::params::quantity_values(study.parameters(), outcome.system.model());
        editor.set_values(&values, &format!("updated by rfm fix, step {step}"))?;
        editor.push_history(&HistoryEntry {
            step: if step == 0 {
                "the case's own parameters updated".into()
            } else {
                format!("updated after step {step}")
            },
            misfit: stats.misfit,
            noise: Some(self.evidence.noise),
            ..HistoryEntry::default()
        })?;
        let case = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
        Ok((editor, case, stats, outcome))
    }

    /// The misfit statistics of a model on the diagnosis's lines.
    fn stats(&self, sys: &damping::DampedSystem) -> Result<MisfitStats, UpdateError> {
        let d = &self.opts.diagnose;
        diagnose::misfit_stats(sys, &self.data, d.lines, d.gains, d.weights.as_deref())
    }

    /// The diagnosis of `current`'s model, reported as that of step `step`,
    /// with resonators tried at the modes the data hold and the model lacks.
    fn diagnosed(
        &self,
        current: &CaseFile,
        extra_modes_hz: &[f64],
        step: usize,
        progress: &mut impl FnMut(FixProgress<'_>),
    ) -> Result<Diagnosis, UpdateError> {
        let mut opts = self.opts.diagnose.clone();
        opts.candidates.resonator_hz = extra_modes_hz.to_vec();
        let d = diagnose::diagnose(&current.model, &self.data, &opts)?;
        progress(FixProgress::Diagnosed { step, diagnosis: &d });
        Ok(d)
    }
}

/// Writes the history of a step the loop made by rebuilding its case from
/// the nominal one (a revision, a swap: each effect applied again from its
/// diagnosis, which writes it at its screening fit): the history of the
/// case before the step (`before`), the step's own entry (`what` added at
/// the misfit it started from, or taken out) and its update as step `n`,
/// in place of what the rebuilt case holds (the lab frame's revised
/// resonator read "+ resonator (10.0 Hz; non-viscous)" at its screening
/// fit's misfit and "updated after step 3" for step 2).
fn rebuilt_history(
    before: &CaseFile,
    a: &mut Added,
    what: &str,
    removed: bool,
    n: usize,
    noise: f64,
) -> Result<(), UpdateError> {
    let mut h = before.history.clone();
    h.push(if removed {
        HistoryEntry {
            step: format!("- {what} (taken out)"),
            misfit: a.stats.misfit,
            noise: Some(noise),
            ..Default::default()
        }
    } else {
        HistoryEntry {
            step: format!("+ {what}"),
            misfit: a.effect.misfit,
            noise: Some(noise),
            effect: Some(a.effect.kind.name().into()),
            nodes: a.effect.nodes.clone(),
            elements: a.effect.elements.clone(),
        }
    });
    h.push(HistoryEntry {
        step: format!("updated after step {n}"),
        misfit: a.stats.misfit,
        noise: Some(noise),
        ..Default::default()
    });
    a.editor.set_history(&h)?;
    a.case.history = h;
    Ok(())
}

/// The ranks of up to `width` recommendable effects (significant and
/// plausible, fully fitted or screened) that differ from each other in kind
/// or place, best first, with the test's own hardware (a shaker, the
/// sensors' masses) among them where it ranks but not counted in `width`:
/// it is another class of explanation, and the structure's leaders keep
/// their places beside it (held-out pair trial 75, a stiffness loss and a
/// splice: with the sensor masses taking the fifth place, the pair tried
/// was a joint and a support, and the loop ended at 57 times the noise).
/// So is something attached to the structure: the best resonator is not
/// counted in `width` either (resonators tuned to a band of broad residual
/// took the fifth place of the same trial, with the same end at 57 times
/// the noise); the others are counted as any leader.
fn distinct_leaders(d: &Diagnosis, model: &fe_model::Model, width: usize) -> Vec<usize> {
    let set_up = |k: EffectKind| matches!(k, EffectKind::Shaker | EffectKind::SensorMasses);
    let mut out: Vec<usize> = Vec::new();
    for (i, r) in d.ranking.iter().enumerate() {
        let first_resonator = out.iter().copied().find(|&k| d.ranking[k - 1].kind == EffectKind::Resonator);
        let aside = |k: usize| set_up(d.ranking[k - 1].kind) || Some(k) == first_resonator;
        if out.iter().filter(|&&k| !aside(k)).count() == width {
            break;
        }
        if !(r.significant && r.plausible) {
            continue;
        }
        let c = &d.candidates[r.candidate];
        let same = out.iter().any(|&k| {
            let o = &d.ranking[k - 1];
            o.kind == r.kind && c.near(model, &o.nodes, &o.elements)
        });
        if !same {
            out.push(i + 1);
        }
    }
    out
}

/// A move tried at a step: one effect, or a pair kept as two steps.
struct Move {
    /// The steps it makes (one or two), each with its own evidence.
    steps: Vec<(Added, f64)>,
    /// What it reads as in the report.
    record: LookAhead,
}

impl Move {
    /// The model the move ends with.
    fn last(&self) -> &Added {
        &self.steps.last().expect("a move makes a step").0
    }
}

/// The model a step starts from: its misfit and parameter count.
#[derive(Clone, Copy, Debug)]
struct State {
    misfit: f64,
    k: usize,
}

/// What the loop starts from once the data are checked and the case's own
/// parameters updated (steps 0 and 1 of the module docs): what `rfm fix`
/// runs first, and what `rfm diagnose` diagnoses.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The data's estimated relative noise (RMS per value).
    pub noise: f64,
    /// The nominal model's misfit on the data as measured.
    pub nominal_misfit: f64,
    /// The nominal model's misfit on the corrected data.
    pub corrected_misfit: f64,
    /// What the checks found (see [`crate::checks`]).
    pub findings: Vec<Finding>,
    /// The data, corrected as the findings say.
    pub data: FrfSet,
    /// The case with the corrections written and its own parameters updated.
    pub case: CaseFile,
    /// Step 0, when the case declares parameters.
    pub declared: Option<DeclaredStep>,
    /// Frequencies (Hz) of measured modes the model lacks.
    pub extra_modes_hz: Vec<f64>,
    /// The model after these steps against itself with a finer mesh
    /// ([`diagnose::mesh_check`]).
    pub mesh: Option<diagnose::MeshCheck>,
    /// The model's misfit and parameter count after these steps.
    state: State,
}

/// Checks the data for set-up errors and corrects them, then updates the
/// case's own `[update]` parameters (see the module docs).
pub fn prepare(
    case: &CaseFile,
    measured: &FrfSet,
    opts: &FixOptions,
    progress: &mut impl FnMut(FixProgress<'_>),
) -> Result<Prepared, UpdateError> {
    // what the diagnosis needs, said before the checks and the noise
    // estimate need it too
    let lines = measured.frequencies_hz().len();
    if lines < 10 {
        return Err(UpdateError::Data(format!("diagnosis needs at least 10 measured lines, the data have {lines}")));
    }
    let nominal_sys = damping::DampedSystem::new(case.model.clone())?;
    let d_opts = &opts.diagnose;
    let noise = diagnose::estimate_noise_against_weighted(&nominal_sys, measured, d_opts.weights.as_deref())?
        .ok_or_else(|| UpdateError::Data("too few usable measured values to estimate the noise level".into()))?;
    let nominal =
        diagnose::misfit_stats(&nominal_sys, measured, d_opts.lines, d_opts.gains, d_opts.weights.as_deref())?;
    let evidence = Evidence { noise, significance: d_opts.significance };
    // the data's own errors first
    let mut findings: Vec<Finding> = Vec::new();
    let mut data = measured.clone();
    let mut current = case.clone();
    if opts.check_data {
        findings = checks::check(&nominal_sys, measured, &check_options(opts, noise))?;
        progress(FixProgress::Checked { findings: &findings });
        if findings.iter().any(|f| !f.corrections.is_empty()) {
            data = checks::corrected(measured, &findings)?;
            current = with_corrections(case, &findings, opts)?;
        }
    }
    let fl = Loop { data, opts, evidence, modes_hz: Vec::new() };
    let corrected = if fl.data == *measured { nominal } else { fl.stats(&nominal_sys)? };
    let mut state = State { misfit: corrected.misfit, k: 0 };
    // the case's own parameters next
    let mut declared = None;
    if current.update.as_ref().is_some_and(|u| !u.parameters.is_empty()) {
        let (editor, case_after, stats, outcome) = fl.update_case(&current, current.editor()?, 0, false)?;
        let k = outcome.parameters.len();
        // the user's own parameters are kept unless their update made things worse
        if stats.misfit <= state.misfit {
            let step = DeclaredStep {
                misfit_before: state.misfit,
                misfit_updated: stats.misfit,
                delta_bic: diagnose::delta_bic(state.misfit, 0, &stats, k, noise),
                status: outcome.status.clone(),
                parameters: outcome.parameters.clone(),
                uncertainty: outcome.uncertainty.clone(),
                refit: None,
                case: editor,
            };
            progress(FixProgress::Declared { step: &step });
            declared = Some(step);
            current = case_after;
            state = State { misfit: stats.misfit, k };
            // the modes the case's own model lacks, once its own parameters are updated
            if opts.check_data {
                findings.retain(|f| f.kind != FindingKind::ExtraMode);
                findings.extend(checks::extra_modes(&outcome.system, &fl.data)?);
            }
        }
    }
    // a mesh too coarse for the band is a model error that no effect is
    let mesh = diagnose::mesh_check(&current.model, &fl.data, d_opts.lines, d_opts.gains, d_opts.weights.as_deref());
    Ok(Prepared {
        noise,
        nominal_misfit: nominal.misfit,
        corrected_misfit: corrected.misfit,
        extra_modes_hz: findings.iter().filter_map(|f| f.frequency_hz).collect(),
        findings,
        data: fl.data,
        case: current,
        declared,
        mesh,
        state,
    })
}

/// What `rfm diagnose` reports: the findings about the data, step 0 (the
/// case's own parameters updated), and the diagnosis of the model after
/// them, as one JSON object (the diagnosis's fields at its top level).
#[derive(Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CheckedDiagnosis<'a> {
    /// What the checks found about the data (corrected before the diagnosis).
    pub findings: &'a [Finding],
    /// Step 0, when the case declares parameters.
    pub declared: Option<&'a DeclaredStep>,
    /// The model after them against itself with a finer mesh.
    pub mesh: Option<&'a diagnose::MeshCheck>,
    /// The diagnosis of the model after them, on the corrected data.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub diagnosis: &'a Diagnosis,
}

/// The diagnosis `rfm diagnose` makes: the data checked and corrected, the
/// case's own parameters updated ([`prepare`]), then the model diagnosed
/// against the corrected data, resonators tried at the modes it lacks.
/// `stage` hears of each stage of the diagnosis.
pub fn diagnose_prepared(
    case: &CaseFile,
    measured: &FrfSet,
    opts: &FixOptions,
    progress: &mut impl FnMut(FixProgress<'_>),
    stage: impl FnMut(&str),
) -> Result<(Prepared, Diagnosis), UpdateError> {
    let p = prepare(case, measured, opts, progress)?;
    let mut d_opts = opts.diagnose.clone();
    d_opts.candidates.resonator_hz = p.extra_modes_hz.clone();
    let d = diagnose::diagnose_with(&p.case.model, &p.data, &d_opts, stage)?;
    Ok((p, d))
}

/// The checks' options for the loop's data.
fn check_options(opts: &FixOptions, noise: f64) -> CheckOptions {
    let d = &opts.diagnose;
    CheckOptions { lines: d.lines, gains: d.gains, weights: d.weights.clone(), noise }
}

/// Runs the loop on a case against its measured receptances (all lines);
/// see the module docs.
pub fn fix(
    case: &CaseFile,
    measured: &FrfSet,
    opts: &FixOptions,
    mut progress: impl FnMut(FixProgress<'_>),
) -> Result<FixOutcome, UpdateError> {
    if opts.max_steps == 0 {
        return Err(UpdateError::Method("the loop needs at least one step".into()));
    }
    let p = prepare(case, measured, opts, &mut progress)?;
    let d_opts = &opts.diagnose;
    let mut noise = p.noise;
    let mut fl = Loop {
        data: p.data,
        opts,
        evidence: Evidence { noise, significance: d_opts.significance },
        modes_hz: p.extra_modes_hz.clone(),
    };
    let (nominal, corrected) = (p.nominal_misfit, p.corrected_misfit);
    let mut findings = p.findings;
    let mut extra_hz = p.extra_modes_hz;
    let mut declared = p.declared;
    let mut current = p.case;
    let mut state = p.state;
    // the last mesh check: prepare's, then one before every step after it
    let mut mesh = p.mesh;

    // the case every effect is added to: corrected, its own parameters updated
    let mut base = current.clone();
    let mut steps: Vec<FixStep> = Vec::new();
    // the diagnosis and rank of each effect added, to rebuild without one
    let mut applied: Vec<(Diagnosis, usize)> = Vec::new();
    let mut equally_good: Vec<LookAhead> = Vec::new();
    // the first step at which effects elsewhere were as good as the one kept
    let mut undecided: Vec<LookAhead> = Vec::new();
    let mut last_diagnosis: Option<Result<Diagnosis, String>>;
    let mut rejected_all: Vec<LookAhead> = Vec::new();
    // the modes that a resonator tuned to them left unexplained
    let mut unexplained: Vec<explains::Unexplained> = Vec::new();
    // steps made again on data corrected after them
    let mut redone = 0;
    let stop = loop {
        // what is left, the same model meshed finer may explain: then
        // nothing is added for it, before the first step or after any
        if !steps.is_empty() {
            mesh =
                diagnose::mesh_check(&current.model, &fl.data, d_opts.lines, d_opts.gains, d_opts.weights.as_deref());
        }
        if mesh.as_ref().is_some_and(|m| m.explains(noise, CONSISTENT)) {
            last_diagnosis = None;
            break FixStop::MeshTooCoarse;
        }
        let d = match fl.diagnosed(&current, &extra_hz, steps.len(), &mut progress) {
            Ok(d) => d,
            Err(e) if !steps.is_empty() || declared.is_some() => {
                last_diagnosis = Some(Err(e.to_string()));
                break FixStop::DiagnosisFailed;
            }
            Err(e) => return Err(e),
        };
        noise = fl.read_noise_again(&d);
        let leaders = distinct_leaders(&d, &current.model, WIDTH);
        if leaders.is_empty() || steps.len() == opts.max_steps {
            let stop = if !leaders.is_empty() {
                FixStop::StepsDone
            } else if state.misfit <= CONSISTENT * noise {
                FixStop::NothingSignificant
            } else {
                FixStop::ModelInadequate
            };
            last_diagnosis = Some(Ok(d));
            break stop;
        }
        let step = steps.len() + 1;
        let last = step >= opts.max_steps;
        let floor = fl.floor(state.misfit, &current);
        let mut moves: Vec<Move> = Vec::new();
        let mut singles: Vec<(usize, Added)> = Vec::new();
        let mut tried: Vec<LookAhead> = Vec::new();
        for (i, &r) in leaders.iter().enumerate() {
            let name = d.ranking[r - 1].description.clone();
            match fl.add_and_update(&current, &d, r, step, last) {
                Ok(a) => {
                    let mut verdict = fl.judge(state, &a, &applied_with(&applied, &d, r));
                    if let Some(u) = verdict.unexplained.take()
                        && !unexplained.iter().any(|x: &explains::Unexplained| x.hz == u.hz)
                    {
                        unexplained.push(u);
                    }
                    if verdict.rejected.is_none() {
                        verdict.rejected = small_share(state.misfit, a.stats.misfit, noise, floor);
                    }
                    let record = LookAhead {
                        effect: name,
                        misfit_ahead: a.stats.misfit,
                        delta_bic: verdict.delta_bic,
                        failed: None,
                        rejected: verdict.rejected.clone(),
                        with: None,
                        equally_good: false,
                    };
                    progress(FixProgress::LookedAhead { step: steps.len(), ahead: &record });
                    let reaches = a.stats.misfit <= CONSISTENT * noise;
                    if verdict.rejected.is_none() {
                        moves.push(Move { steps: vec![(a.clone(), verdict.delta_bic)], record });
                    } else {
                        tried.push(record);
                    }
                    singles.push((r, a));
                    // the first leader reaching the noise on its own evidence
                    // needs no rival unless the diagnosis saw one as good
                    if i == 0
                        && reaches
                        && moves.len() == 1
                        && !close_rival(&d, &leaders, &current.model, fl.evidence.significance)
                    {
                        break;
                    }
                }
                Err(e) => {
                    let record = LookAhead {
                        effect: name,
                        misfit_ahead: f64::NAN,
                        delta_bic: f64::NAN,
                        failed: Some(e.to_string()),
                        rejected: Some(format!("it could not be added and updated: {e}")),
                        with: None,
                        equally_good: false,
                    };
                    progress(FixProgress::LookedAhead { step: steps.len(), ahead: &record });
                    tried.push(record);
                }
            }
        }
        // two effects that mislead one at a time, fitted together
        let best_single = singles.iter().map(|(_, a)| a.stats.misfit).fold(f64::INFINITY, f64::min);
        if best_single > PAIRS_ABOVE * noise && steps.len() + 2 <= opts.max_steps {
            let pair_leaders = distinct_leaders(&d, &current.model, pairs::PAIR_WIDTH);
            if let Some(mut m) =
                pairs::best_pair(&fl, &current, &d, &pair_leaders, &singles, state, (step, last), &applied)
            {
                if m.record.rejected.is_none() {
                    m.record.rejected = small_share(state.misfit, m.last().stats.misfit, noise, floor);
                }
                progress(FixProgress::LookedAhead { step: steps.len(), ahead: &m.record });
                if m.record.rejected.is_none() {
                    moves.push(m);
                } else {
                    tried.push(m.record);
                }
            }
        }
        if moves.is_empty() {
            rejected_all = tried;
            last_diagnosis = Some(Ok(d));
            break if state.misfit <= CONSISTENT * noise {
                FixStop::NothingSignificant
            } else {
                FixStop::ModelInadequate
            };
        }
        // the best move by the criterion against one variance for all: what
        // the best of them leaves (each move's own dBIC is against its own)
        let v = moves.iter().map(|m| m.last().stats.lack_of_fit(noise)).fold(f64::INFINITY, f64::min);
        let score = |m: &Move| {
            let a = m.last();
            let n = a.stats.n as f64;
            n * a.stats.misfit.powi(2) / v + a.outcome.parameters.len() as f64 * n.ln()
        };
        moves.sort_by(|a, b| score(a).total_cmp(&score(b)));
        let best = moves.remove(0);
        // an effect not needed at its own fit: the stage before had stopped
        // in a local minimum, and is updated again from where this fit
        // ended (the effect is not added; the diagnosis is made again)
        if let [(a, _)] = best.steps.as_slice()
            && let Some((refit, (mut editor, mut case, stats, outcome))) =
                fl.not_needed(&current, state, a, steps.len(), last).ok().flatten()
        {
            let status = step_status(&outcome);
            progress(FixProgress::Refitted { step: steps.len(), refit: &refit, misfit: stats.misfit, status: &status });
            let mut h = case.history.clone();
            if let Some(e) = h.last_mut() {
                e.step = format!("{} again, from where the fit with {} ended", e.step, refit.found_by);
            }
            editor.set_history(&h)?;
            case.history = h;
            let k = outcome.parameters.len();
            let n = steps.len();
            if n > 0 {
                let (before, k_before) = match n {
                    1 => declared.as_ref().map_or((corrected, 0), |d| (d.misfit_updated, d.parameters.len())),
                    _ => {
                        let p = &steps[n - 2];
                        (p.final_misfit(), p.parameter_count)
                    }
                };
                let s = steps.last_mut().expect("a step");
                s.delta_bic = diagnose::delta_bic(before, k_before, &stats, k, noise);
                if s.corrected_misfit.is_some() {
                    s.corrected_misfit = Some(stats.misfit);
                } else {
                    s.misfit_updated = stats.misfit;
                }
                s.status = status;
                s.parameters = outcome.parameters;
                s.uncertainty = outcome.uncertainty;
                s.case = editor;
                s.refit = Some(refit);
                progress(FixProgress::StepDone { index: n - 1, done: s });
            } else if let Some(d) = declared.as_mut() {
                d.misfit_updated = stats.misfit;
                d.delta_bic = diagnose::delta_bic(d.misfit_before, 0, &stats, k, noise);
                d.status = status;
                d.parameters = outcome.parameters;
                d.uncertainty = outcome.uncertainty;
                d.case = editor;
                d.refit = Some(refit);
                progress(FixProgress::Declared { step: d });
                base = case.clone();
            }
            current = case;
            state = State { misfit: stats.misfit, k };
            continue;
        }
        // alternatives at other places that the evidence cannot tell from the best
        let first = best.last();
        let mut alternatives: Vec<LookAhead> = Vec::new();
        for m in moves {
            let other = m.last();
            let mut rec = m.record.clone();
            let elsewhere = !near(&d, first, other, &current.model);
            let between = fl.evidence.between(first, other);
            if elsewhere && between < -fl.evidence.significance {
                rec.equally_good = true;
                rec.rejected = Some(format!(
                    "as good as {} (the evidence between them {between:.1}, not below {})",
                    best.record.effect, fl.evidence.significance
                ));
            } else {
                rec.rejected = Some(format!(
                    "{} is better (the evidence for it over this one {:.1})",
                    best.record.effect, -between
                ));
            }
            alternatives.push(rec);
        }
        if alternatives.iter().any(|a| a.equally_good) {
            let mut listed = vec![best.record.clone()];
            listed[0].equally_good = true;
            listed.extend(alternatives.iter().filter(|a| a.equally_good).cloned());
            // where the best would be the last effect (it explains the data
            // to their noise) the data cannot choose, and none is added;
            // before that, later steps and the revisions may tell them apart,
            // and the list is kept for the end
            if first.stats.misfit <= CONSISTENT * noise {
                equally_good = listed;
                last_diagnosis = Some(Ok(d));
                break FixStop::Ambiguous;
            }
            if undecided.is_empty() {
                undecided = listed;
            }
        }
        alternatives.extend(tried);
        let first_new = steps.len();
        // the model before the step, to make it again should the data be
        // corrected after it
        let (before_step, state_before) = (current.clone(), state);
        let undecided_before = undecided.len();
        for (k, (added, delta_bic)) in best.steps.into_iter().enumerate() {
            progress(FixProgress::Updated {
                step: steps.len(),
                effect: &added.effect.description,
                removed: false,
                misfit: added.stats.misfit,
                status: &step_status(&added.outcome),
            });
            current = added.case.clone();
            state = State { misfit: added.stats.misfit, k: added.outcome.parameters.len() };
            applied.push((d.clone(), added.rank));
            let alts = if k == 0 { std::mem::take(&mut alternatives) } else { Vec::new() };
            steps.push(FixStep::of(added, delta_bic, alts, None));
        }
        // the data's own errors again, against the model the evidence now
        // prefers: a large model error can hide a misplaced or miscalibrated
        // sensor from the first check; and the modes it still lacks (a
        // resonator added explains its mode, which is not offered again)
        if opts.check_data {
            let sys = damping::DampedSystem::new(current.model.clone())?;
            extra_hz = checks::extra_modes(&sys, &fl.data)?.iter().filter_map(|f| f.frequency_hz).collect();
            for &f in &extra_hz {
                if !fl.modes_hz.iter().any(|&g| (g / f - 1.0).abs() < 0.01) {
                    fl.modes_hz.push(f);
                }
            }
            let late = late_findings(&sys, &fl.data, opts, noise, steps.len())?;
            // the case names a channel moved earlier by its own response
            let written = as_the_case_names(&late, &findings);
            let corrected_update = |fl: &Loop<'_>| -> Result<_, UpdateError> {
                let base = with_corrections(&base, &written, opts)?;
                let last = steps.len() >= opts.max_steps;
                let (data, updated) = update_corrected(fl, &current, (&late, &written), (steps.len(), last), noise)?;
                Ok((data, base, updated))
            };
            // a correction whose update fails is not made (the step stands)
            if let Some((data, new_base, (editor, case_after, stats, outcome))) =
                (!late.is_empty()).then(|| corrected_update(&fl).ok()).flatten()
                && correction_kept(state.misfit, stats.misfit, noise)
            {
                progress(FixProgress::Checked { findings: &late });
                fl.data = data;
                base = new_base;
                // the step was chosen on data now corrected: it is made
                // again on the corrected data, from the model before it
                // (see REDONE)
                if redone < REDONE {
                    redone += 1;
                    progress(FixProgress::Redone {
                        step: first_new,
                        effects: steps[first_new..].iter().map(|s| s.effect.description.clone()).collect(),
                    });
                    findings.extend(late);
                    current = with_corrections(&before_step, &written, opts)?;
                    let sys = damping::DampedSystem::new(current.model.clone())?;
                    state = State { misfit: fl.stats(&sys)?.misfit, k: state_before.k };
                    steps.truncate(first_new);
                    applied.truncate(first_new);
                    undecided.truncate(undecided_before);
                    extra_hz = checks::extra_modes(&sys, &fl.data)?.iter().filter_map(|f| f.frequency_hz).collect();
                    continue;
                }
                current = case_after;
                state = State { misfit: stats.misfit, k: outcome.parameters.len() };
                steps.last_mut().expect("a step was kept").corrected(editor, stats.misfit, outcome);
                findings.extend(late);
            }
        }
        // announced only now: a late correction above rewrites the last step
        for (index, done) in steps.iter().enumerate().skip(first_new) {
            progress(FixProgress::StepDone { index, done });
        }
    };
    let mut effects: Vec<Ranked> = steps.iter().map(|s| s.effect.clone()).collect();
    // revisions and replacements, each kept by the same rule
    let revisable = !matches!(stop, FixStop::Ambiguous | FixStop::MeshTooCoarse);
    // whether a revision or a swap changed the model after the loop's steps
    let mut mended = false;
    if !applied.is_empty() && state.misfit > REVISE_ABOVE * noise && revisable {
        let (kept, revised) = revise::revise(&fl, &base, &applied, &current, state, steps.len() + 1);
        if !kept.is_empty() {
            for mut r in kept {
                let effect = if r.removed {
                    r.replaced.clone()
                } else {
                    format!("{} instead of {}", r.added.effect.description, r.replaced)
                };
                progress(FixProgress::Updated {
                    step: steps.len(),
                    effect: &effect,
                    removed: r.removed,
                    misfit: r.added.stats.misfit,
                    status: &step_status(&r.added.outcome),
                });
                rebuilt_history(&current, &mut r.added, &effect, r.removed, steps.len() + 1, noise)?;
                current = r.added.case.clone();
                state = State { misfit: r.added.stats.misfit, k: r.added.outcome.parameters.len() };
                if r.removed {
                    effects.remove(r.index);
                    let mut s = FixStep::of(r.added, r.delta_bic, Vec::new(), None);
                    // nothing was added: the misfit without it is the updated one
                    s.misfit_added = s.misfit_updated;
                    s.removed = true;
                    s.removed_because = r.why;
                    steps.push(s);
                } else {
                    effects[r.index] = r.added.effect.clone();
                    steps.push(FixStep::of(r.added, r.delta_bic, Vec::new(), Some(r.replaced)));
                }
                progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
            }
            applied = revised;
            last_diagnosis = None;
            mended = true;
        }
    }
    if applied.len() >= 2
        && state.misfit > CONSISTENT * noise
        && revisable
        && let Some((outs, added)) = swap::swap(&fl, &base, &applied, state, steps.len() + 1)
    {
        let removed: Vec<String> = outs.iter().map(|&i| effects[i].description.clone()).collect();
        for &i in outs.iter().rev() {
            effects.remove(i);
        }
        let replaced = removed.join(" and ");
        for (k, (mut a, delta_bic)) in added.into_iter().enumerate() {
            let effect = if k == 0 {
                format!("{} instead of {replaced}", a.effect.description)
            } else {
                a.effect.description.clone()
            };
            progress(FixProgress::Updated {
                step: steps.len(),
                effect: &effect,
                removed: false,
                misfit: a.stats.misfit,
                status: &step_status(&a.outcome),
            });
            rebuilt_history(&current, &mut a, &effect, false, steps.len() + 1, noise)?;
            effects.push(a.effect.clone());
            current = a.case.clone();
            state = State { misfit: a.stats.misfit, k: a.outcome.parameters.len() };
            steps.push(FixStep::of(a, delta_bic, Vec::new(), (k == 0).then(|| replaced.clone())));
            progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
        }
        last_diagnosis = None;
        mended = true;
    }
    // the data's own errors once more, against the model the revisions
    // mended: a model error that only a revision removes hides a
    // miscalibrated sensor from the checks after each step (a portal frame
    // whose lossy clamp and motor the revisions found at 3.9 times the
    // noise, one channel reading 20 % low, which then held 95 % of the
    // misfit); a correction is kept as one after a step is, and a check
    // that fails leaves the loop's answer as it is
    if opts.check_data && mended && state.misfit > CONSISTENT * noise && !steps.is_empty() {
        let late = damping::DampedSystem::new(current.model.clone())
            .ok()
            .and_then(|sys| late_findings(&sys, &fl.data, opts, noise, steps.len()).ok())
            .unwrap_or_default();
        let written = as_the_case_names(&late, &findings);
        if !late.is_empty()
            && let Ok((data, (editor, case_after, stats, outcome))) =
                update_corrected(&fl, &current, (&late, &written), (steps.len(), true), noise)
            && correction_kept(state.misfit, stats.misfit, noise)
        {
            progress(FixProgress::Checked { findings: &late });
            fl.data = data;
            current = case_after;
            state = State { misfit: stats.misfit, k: outcome.parameters.len() };
            steps.last_mut().expect("a step was made").corrected(editor, stats.misfit, outcome);
            findings.extend(late);
            last_diagnosis = None;
        }
    }
    let last = last_diagnosis
        .unwrap_or_else(|| fl.diagnosed(&current, &extra_hz, steps.len(), &mut progress).map_err(|e| e.to_string()));
    let (last, diagnosis_error) = match last {
        Ok(d) => {
            noise = fl.read_noise_again(&d);
            (Some(d), None)
        }
        Err(e) => (None, Some(e)),
    };
    // a stop decided before revisions that mended the model is decided
    // again: within the noise, with nothing left that is both significant
    // and plausible, nothing more is to be had (not "inadequate" beside a
    // final misfit below the noise: held-out pair trial 75 ended so at 0.94
    // times the noise, an implausible candidate the only significant one)
    let nothing_credible = |d: &Diagnosis| !d.ranking.iter().any(|r| r.fully_fitted && r.significant && r.plausible);
    let stop = match stop {
        FixStop::ModelInadequate | FixStop::StepsDone | FixStop::NothingSignificant
            if state.misfit <= CONSISTENT * noise && last.as_ref().is_some_and(nothing_credible) =>
        {
            FixStop::NothingSignificant
        }
        FixStop::NothingSignificant if state.misfit > CONSISTENT * noise => FixStop::ModelInadequate,
        s => s,
    };
    // effects as good as each other at a step, not told apart by the end
    if equally_good.is_empty() && !(state.misfit <= CONSISTENT * noise && stop == FixStop::NothingSignificant) {
        equally_good = undecided;
    }
    let final_sys = damping::DampedSystem::new(current.model.clone())?;
    let remains = match &mesh {
        _ if state.misfit <= CONSISTENT * noise => Vec::new(),
        Some(m) if stop == FixStop::MeshTooCoarse => vec![m.describe(noise)],
        _ => remains::describe(&final_sys, &fl.data, d_opts, noise, &findings, &unexplained),
    };
    let stop_reason =
        remains::stop_reason(stop, &rejected_all, &equally_good, diagnosis_error.as_deref(), state.misfit, noise);
    Ok(FixOutcome {
        noise,
        nominal_misfit: nominal,
        findings,
        corrected_misfit: corrected,
        declared,
        effects,
        steps,
        stop,
        stop_reason,
        remains,
        equally_good,
        significant_remains: last.as_ref().is_none_or(|d| !d.consistent()),
        remaining: last.map_or(Vec::new(), |d| d.ranking.into_iter().filter(|r| r.fully_fitted).take(5).collect()),
        diagnosis_error,
        mesh,
    })
}

/// The channel findings against `sys` that come with a correction, as
/// found after `step` steps.
fn late_findings(
    sys: &damping::DampedSystem,
    data: &FrfSet,
    opts: &FixOptions,
    noise: f64,
    step: usize,
) -> Result<Vec<Finding>, UpdateError> {
    let found = checks::check_channels(sys, data, &check_options(opts, noise))?;
    Ok(found
        .into_iter()
        .filter(|f| !f.corrections.is_empty())
        .map(|mut f| {
            f.found_after_step = step;
            f
        })
        .collect())
}

/// Whether a late correction is kept: near the data (within
/// [`LATE_CHECKS_BELOW`] times the noise) when its update succeeds, and
/// farther only when it explains [`SHARE`] of what the model left above
/// the noise (`before` and `after`: the misfits without and with it).
fn correction_kept(before: f64, after: f64, noise: f64) -> bool {
    before <= LATE_CHECKS_BELOW * noise || share(before, after, noise).is_some_and(|s| s >= SHARE)
}

/// The model of `current` updated again on the loop's data with the
/// corrections of the `late` findings (`written`: as the case names their
/// channels), its history saying so: the corrected data and the update.
/// `step`: the number of steps made, and whether the model is the loop's
/// answer (its fit then restarts when it leaves more than the noise).
fn update_corrected(
    fl: &Loop<'_>,
    current: &CaseFile,
    (late, written): (&[Finding], &[Finding]),
    (step, last): (usize, bool),
    noise: f64,
) -> Result<(FrfSet, Updated), UpdateError> {
    let data = checks::corrected(&fl.data, late)?;
    let current = with_corrections(current, written, fl.opts)?;
    let trial = Loop { data, opts: fl.opts, evidence: fl.evidence, modes_hz: fl.modes_hz.clone() };
    let (mut editor, mut case, stats, outcome) = trial.update_case(&current, current.editor()?, step, last)?;
    // the step's history, and this update as what it is
    let mut h = current.history.clone();
    h.push(HistoryEntry {
        step: format!("updated after step {step} with the data corrected"),
        misfit: stats.misfit,
        noise: Some(noise),
        ..HistoryEntry::default()
    });
    editor.set_history(&h)?;
    case.history = h;
    Ok((trial.data, (editor, case, stats, outcome)))
}

/// Whether the diagnosis ranks another distinct leader, elsewhere, as good
/// as the first (their dBIC within the significance of each other): then
/// the first is not kept without updating the other too.
fn close_rival(d: &Diagnosis, leaders: &[usize], model: &fe_model::Model, significance: f64) -> bool {
    let first = &d.ranking[leaders[0] - 1];
    leaders[1..].iter().any(|&r| {
        let o = &d.ranking[r - 1];
        o.delta_bic - first.delta_bic < -significance
            && !d.candidates[o.candidate].near(model, &first.nodes, &first.elements)
    })
}

/// Whether two effects tried at one step act at the same place (one node
/// or element of slack), whatever their kinds.
fn near(d: &Diagnosis, a: &Added, b: &Added, model: &fe_model::Model) -> bool {
    let cand =
        |x: &Added| d.ranking.get(x.rank - 1).filter(|r| r.description == x.effect.description).map(|r| r.candidate);
    match cand(b) {
        Some(c) => d.candidates[c].near(model, &a.effect.nodes, &a.effect.elements),
        None => {
            a.effect.nodes.iter().any(|n| b.effect.nodes.contains(n))
                || a.effect.elements.iter().any(|e| b.effect.elements.contains(e))
        }
    }
}

/// The effects applied so far and the one tried now (diagnosis and rank).
fn applied_with<'a>(applied: &'a [(Diagnosis, usize)], d: &'a Diagnosis, r: usize) -> Vec<(&'a Diagnosis, usize)> {
    applied.iter().map(|(d, r)| (d, *r)).chain(std::iter::once((d, r))).collect()
}

/// The case with the findings' corrections written into its
/// `[[measurement.corrections]]` (reading its data from the file the loop
/// writes, when it synthesises them from a truth); the case as it is when
/// it has no data file to correct.
/// `late` (found on data already corrected by `earlier`) with each
/// correction of a channel an earlier one moved named as the case names
/// it: by the response it was read at, not the DOF it was moved to (its
/// entry then composes with the earlier one).
fn as_the_case_names(late: &[Finding], earlier: &[Finding]) -> Vec<Finding> {
    let moved: Vec<&checks::Correction> =
        earlier.iter().flat_map(|f| &f.corrections).filter(|c| c.measured_at.is_some()).collect();
    late.iter()
        .map(|f| {
            let mut f = f.clone();
            for c in &mut f.corrections {
                if let Some(e) = moved.iter().find(|e| e.measured_at == Some(c.response) && e.reference == c.reference)
                {
                    c.response = e.response;
                }
            }
            f
        })
        .collect()
}

fn with_corrections(case: &CaseFile, findings: &[Finding], opts: &FixOptions) -> Result<CaseFile, UpdateError> {
    let mut editor = case.editor()?;
    let has_data = case.measurement.as_ref().is_some_and(|m| m.data.is_some());
    match (&opts.data, case.truth.is_some()) {
        (Some(path), true) => editor.use_data(path),
        _ if has_data => {}
        _ => return Ok(case.clone()),
    }
    for f in findings {
        f.write(&mut editor)?;
    }
    Ok(CaseFile::parse(&case.path, &editor.text_at(&case.path)?)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The share of an excess worked by hand, and each noise reading taken
    /// on the side that makes a step harder to keep, with the numbers of the
    /// lab study's trials 56 and 68 (misfits in hundredths).
    #[test]
    fn a_step_is_judged_on_the_side_of_each_noise_reading_that_makes_it_harder_to_keep() {
        // a model at twice the noise leaves 3 noise variances above it, one
        // at 1.5 times leaves 1.25: the step explains 1 - 1.25 / 3
        assert!((share(2.0, 1.5, 1.0).expect("an excess") - (1.0 - 1.25 / 3.0)).abs() < 1e-12);
        assert_eq!(small_share(2.0, 1.0, 1.0, 1.0), None, "a missing effect explains all of a large excess");
        // within the loop's reading (1.094), nothing more is taken, though a
        // floor of 1.004 leaves an excess that 0.996 "explains all of"
        let r = small_share(1.013, 0.996, 1.094, 1.004).expect("not kept");
        assert!(r.contains("already within the noise"), "{r}");
        // above the loop's reading (1.064) the share is read above the
        // floor (1.002): (1.080^2 - 1.052^2) / (1.080^2 - 1.002^2) = 37 %,
        // where at the loop's reading alone it would be 174 %
        let r = small_share(1.080, 1.052, 1.064, 1.002).expect("not kept");
        assert!(r.contains("it explains 37 %"), "{r}");
        assert_eq!(small_share(1.080, 1.052, 1.064, 1.064), None);
        // a floor above the loop's reading is not used
        assert_eq!(small_share(1.080, 1.052, 1.064, 1.2), None);
    }
}

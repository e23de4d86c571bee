//! Closing the loop: diagnose, add the recommended effect, update every
//! added parameter, and again, until nothing significant remains.
//!
//! This is what `rfm fix` runs. Each step
//!
//! 1. diagnoses the current model against the data ([`crate::diagnose`]),
//! 2. adds the recommended effect (the first significant, plausible one) at
//!    its fitted values ([`Diagnosis::apply`]),
//! 3. updates, by output error on the diagnosis's lines, every parameter of
//!    the case's `[update]`, which now holds the parameters of every effect
//!    added so far: an effect fitted while another was still missing is
//!    biased, and the joint update removes that bias,
//!
//! and records the misfit after 2 and after 3 in the case's history. When
//! the best single effect leaves far more than the noise, two effects fitted
//! together may be added as two steps instead ([`fix`], `pairs.rs`). The
//! loop stops when no candidate is significant (the model is consistent
//! with the data), when the significant ones are all implausible (the
//! missing effect is not among the candidates), when an update does not
//! lower the misfit, or after the given number of steps. When it then
//! leaves more than 1.5 times the noise, the form of each effect is revised
//! with the others in place (its other variants, a kind that stands in for
//! it, or nothing; `fix/revise.rs`), and if the misfit still stays above that,
//! each effect but the last, and each
//! pair of effects, is left out in turn and the data diagnosed again
//! without them, adding as many effects as were left out: an effect added
//! early may only have mimicked the missing one, and another added later
//! may only have made up for it (`fix/swap.rs`). The best replacement is kept
//! when it lowers the misfit (last steps that name what they replaced).
//! A last diagnosis of the final model says what, if anything, still stands
//! out.

use fe_model::{CaseEditor, CaseFile, HistoryEntry};
use frf::FrfSet;

use crate::diagnose::{self, DiagnoseOptions, Diagnosis, Ranked};
use crate::error::UpdateError;
use crate::status::Status;
use crate::study::{ParameterReport, Study};
use crate::uncertainty::UncertaintyReport;

mod pairs;
mod revise;
mod swap;

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
}

impl Default for FixOptions {
    fn default() -> Self {
        FixOptions { max_steps: 3, diagnose: DiagnoseOptions::default(), update_iterations: 100, data: None }
    }
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
    /// How the update ended.
    pub status: Status,
    /// The updated parameters (every effect added so far, and the case's own).
    pub parameters: Vec<ParameterReport>,
    /// Their uncertainty.
    pub uncertainty: Option<UncertaintyReport>,
    /// The best pair fitted together and the first effects tried by looking
    /// one step ahead (when the best single effect left more than three
    /// times the noise), with the misfit each left after its best follower
    /// (both updated jointly); empty when there was no need.
    pub alternatives: Vec<LookAhead>,
    /// The effects of earlier steps this one replaced, with any that follow
    /// it (left out, the others kept, and these added instead; see [`fix`]),
    /// when it did: their descriptions joined by " and ".
    pub replaced: Option<String>,
    /// The effect was taken out again, not added: with the others revised
    /// it no longer paid for its parameters (`fix/revise.rs`); `misfit_added`
    /// and `misfit_updated` are both the misfit without it, updated.
    pub removed: bool,
    /// The case after this step (write it with [`CaseEditor::text_at`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub case: CaseEditor,
}

impl FixStep {
    fn of(a: Added, alternatives: Vec<LookAhead>, replaced: Option<String>) -> FixStep {
        FixStep {
            misfit_added: a.effect.misfit,
            effect: a.effect,
            misfit_updated: a.misfit_updated,
            status: a.outcome.status,
            parameters: a.outcome.parameters,
            uncertainty: a.outcome.uncertainty,
            alternatives,
            replaced,
            removed: false,
            case: a.editor,
        }
    }
}

/// A first effect tried by looking one step ahead.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LookAhead {
    /// The effect.
    pub effect: String,
    /// The misfit after it, its update and its best follower (NaN when it
    /// could not be added and updated, see `failed`).
    pub misfit_ahead: f64,
    /// Why adding and updating it failed (an update that drove a spring to
    /// zero and left a mechanism, say), when it did.
    pub failed: Option<String>,
    /// The second effect, when this is a pair fitted together: `effect` and
    /// it were added and updated jointly, and `misfit_ahead` is the misfit
    /// they leave (no follower diagnosed).
    pub with: Option<String>,
}

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum FixStop {
    /// No candidate explains the remaining misfit beyond the noise.
    NothingSignificant,
    /// Significant candidates remain, but none at plausible values: the
    /// missing effect is not among the candidates.
    NoPlausibleCandidate,
    /// The last update did not lower the misfit.
    NoImprovement,
    /// The number of steps asked for was done; something significant may remain.
    StepsDone,
    /// No leading effect could be added and updated: each update left a
    /// model that cannot be evaluated (a spring driven to zero, say).
    CannotAdd,
    /// The diagnosis of the model after the last step failed (see
    /// [`FixOutcome::diagnosis_error`]); the steps before it stand.
    DiagnosisFailed,
}

impl FixStop {
    /// Plain-language reason.
    pub fn describe(self) -> &'static str {
        match self {
            FixStop::NothingSignificant => "nothing significant remains: the model is consistent with the data",
            FixStop::NoPlausibleCandidate => {
                "significant effects remain, but none at plausible values: the missing effect may not be among the candidates"
            }
            FixStop::NoImprovement => "the last update did not lower the misfit",
            FixStop::StepsDone => "the number of steps asked for is done",
            FixStop::CannotAdd => {
                "no leading effect could be added and updated: each update left a model that cannot be evaluated"
            }
            FixStop::DiagnosisFailed => "the diagnosis of the model after the last step failed",
        }
    }
}

/// The outcome of the loop.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FixOutcome {
    /// The data's estimated relative noise (RMS per value).
    pub noise: f64,
    /// The nominal model's misfit.
    pub nominal_misfit: f64,
    /// The steps, in order.
    pub steps: Vec<FixStep>,
    /// The effects in the final model, in the order they were added.
    pub effects: Vec<Ranked>,
    /// Why the loop stopped.
    pub stop: FixStop,
    /// The diagnosis of the final model (top of its ranking only).
    pub remaining: Vec<Ranked>,
    /// Whether something significant remains in the final diagnosis (true
    /// when that diagnosis failed: nothing says the model is consistent).
    pub significant_remains: bool,
    /// Why the diagnosis of the final model failed, when it did: the steps
    /// and their cases stand, but what remains is not known. An update can
    /// leave a spring the data do not determine so stiff against the rest
    /// that the solver calls a line singular (held-out trial 34 of the full
    /// study: a joint's ky at 4e14 N/m beside 1e8).
    pub diagnosis_error: Option<String>,
}

impl FixOutcome {
    /// The misfit after every stage: the nominal model, then per step with
    /// the effect added and after the update, labelled.
    pub fn stages(&self) -> Vec<(String, f64)> {
        let mut v = vec![("nominal".to_string(), self.nominal_misfit)];
        for (k, s) in self.steps.iter().enumerate() {
            let label = match &s.replaced {
                _ if s.removed => format!("- {}", s.effect.description),
                Some(r) => format!("+ {} instead of {r}", s.effect.description),
                None => format!("+ {}", s.effect.description),
            };
            v.push((label, s.misfit_added));
            v.push((format!("updated after step {}", k + 1), s.misfit_updated));
        }
        v
    }

    /// The final misfit.
    pub fn final_misfit(&self) -> f64 {
        self.steps.last().map_or(self.nominal_misfit, |s| s.misfit_updated)
    }
}

/// What the loop reports as it goes.
#[derive(Clone, Debug)]
pub enum FixProgress<'a> {
    /// A diagnosis is done.
    Diagnosed {
        /// Effects added before it.
        step: usize,
        /// The diagnosis.
        diagnosis: &'a Diagnosis,
    },
    /// A first effect was tried by looking one step ahead.
    LookedAhead {
        /// Effects added before it.
        step: usize,
        /// The effect and the misfit after it and its best follower.
        ahead: &'a LookAhead,
    },
    /// The update after adding an effect is done.
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
    /// A step is finished and will stay in the outcome: its effect added (or
    /// taken out) and every parameter updated. It carries the whole step,
    /// its case among it, so that a caller can keep it (write its case)
    /// before the loop goes on: an interrupted loop then loses only the
    /// step under way.
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
/// leaves suggests that more than one effect is missing, and the first is
/// chosen by looking one step ahead.
const LOOK_AHEAD_ABOVE: f64 = 3.0;

/// How many distinct first effects the look-ahead tries.
const LOOK_AHEAD_WIDTH: usize = 5;

/// An effect added to a case and every parameter updated.
struct Added {
    effect: Ranked,
    /// Its rank in the diagnosis it came from.
    rank: usize,
    editor: CaseEditor,
    case: CaseFile,
    misfit_updated: f64,
    outcome: crate::study::UpdateOutcome,
}

/// Adds ranked effect `rank` of `d` to `current` and updates every parameter
/// of the case's `[update]` by output error on the diagnosis's lines; the
/// updated values and the misfit go into the case's history as step `step`.
/// `last`: the model is the loop's answer, and its update restarts (see
/// [`update_case`]).
fn add_and_update(
    current: &CaseFile,
    d: &Diagnosis,
    rank: usize,
    measured: &FrfSet,
    opts: &FixOptions,
    step: usize,
    last: bool,
) -> Result<Added, UpdateError> {
    let editor = d.apply_with_data(current, rank, opts.data.as_deref())?;
    let (editor, case, misfit_updated, outcome) = update_case(current, editor, d, measured, opts, step, last)?;
    Ok(Added { effect: d.ranking[rank - 1].clone(), rank, editor, case, misfit_updated, outcome })
}

/// Updates every parameter of the `[update]` of the case `editor` holds by
/// output error on the diagnosis's lines; returns the editor with the
/// updated values and the misfit in the case's history (as step `step`),
/// the case it now holds, the misfit and the outcome. `last`: the model is
/// the loop's answer, and its fit restarts when it leaves more than the noise.
fn update_case(
    current: &CaseFile,
    mut editor: CaseEditor,
    d: &Diagnosis,
    measured: &FrfSet,
    opts: &FixOptions,
    step: usize,
    last: bool,
) -> Result<(CaseEditor, CaseFile, f64, crate::study::UpdateOutcome), UpdateError> {
    let lines = opts.diagnose.lines;
    let added = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
    let mut study = Study::with_measured(added, measured.clone())?;
    if study.case().update.is_some() {
        // the lines the misfit is measured on (see `diagnose::log_misfit`)
        study.set_update_frequencies(fe_model::case::FrequencyChoice::List(diagnose::informative_lines(
            measured, lines,
        )))?;
    }
    let mut oe_opts = study.output_error_options()?;
    oe_opts.max_iterations = opts.update_iterations;
    // the loop decides from the misfit against the noise; restarting each
    // intermediate (knowingly incomplete) model would only cost time. The
    // last step's model is the answer: when its fit leaves more than the
    // noise, restarts tell an optimiser stuck in a local minimum (they find
    // a lower one) from a model that lacks something (they do not).
    if !last {
        oe_opts.restarts = 0;
    }
    let outcome = study.run_output_error(&oe_opts, |_| {})?;
    let weights = opts.diagnose.weights.as_deref();
    let misfit_updated = diagnose::log_misfit_with(&outcome.system, measured, lines, d.gains, weights)?;
    let values = crate::params::quantity_values(study.parameters(), outcome.system.model());
    editor.set_values(&values, &format!("updated by rfm fix, step {step}"))?;
    editor.push_history(&HistoryEntry {
        step: format!("updated after step {step}"),
        misfit: misfit_updated,
        noise: Some(d.noise),
        ..HistoryEntry::default()
    })?;
    let case = CaseFile::parse(&current.path, &editor.text_at(&current.path)?)?;
    Ok((editor, case, misfit_updated, outcome))
}

/// The diagnosis of `current`'s model, reported as that of step `step`.
fn diagnosed(
    current: &CaseFile,
    measured: &FrfSet,
    opts: &FixOptions,
    step: usize,
    progress: &mut impl FnMut(FixProgress<'_>),
) -> Result<Diagnosis, UpdateError> {
    let d = diagnose::diagnose(&current.model, measured, &opts.diagnose)?;
    progress(FixProgress::Diagnosed { step, diagnosis: &d });
    Ok(d)
}

/// The ranks of up to `width` recommendable effects (significant and
/// plausible, fully fitted or screened) that differ from each other in kind
/// or place, best first: the full fits cover only the best of each kind, and
/// when two effects hide at once the right first one can be a screened one.
fn distinct_leaders(d: &Diagnosis, model: &fe_model::Model, width: usize) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for (i, r) in d.ranking.iter().enumerate() {
        if out.len() == width {
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

/// Runs the loop on a case against its measured receptances (all lines).
/// The case's own `[update]` parameters, if any, are updated together with
/// the added effects' at every step.
///
/// When the best single effect would leave more than three times the noise
/// (two effects may hide at once, and a single candidate that mimics both
/// may lead), every pair of a few distinct leaders is added and updated
/// jointly (`fix/pairs.rs`); unless the best pair reaches the noise, the first
/// effect is also sought by looking one step ahead: each of a few distinct
/// leaders is added and updated, the data diagnosed again, and its best
/// follower added and everything updated jointly. The best pair is added as
/// two steps when it leaves less than every leader with its follower, else
/// the best leader as one.
pub fn fix(
    case: &CaseFile,
    measured: &FrfSet,
    opts: &FixOptions,
    mut progress: impl FnMut(FixProgress<'_>),
) -> Result<FixOutcome, UpdateError> {
    if opts.max_steps == 0 {
        return Err(UpdateError::Method("the loop needs at least one step".into()));
    }
    let mut current = case.clone();
    let mut steps: Vec<FixStep> = Vec::new();
    let (mut noise, mut nominal_misfit) = (f64::NAN, f64::NAN);
    let mut next: Option<Diagnosis> = None;
    // the diagnosis and rank of each effect added, to rebuild without one
    let mut applied: Vec<(Diagnosis, usize)> = Vec::new();
    // the loop ends with the last diagnosis when it has one (`None`: the
    // final model is still to be diagnosed), or with why it failed
    let stop = loop {
        let d = match next.take() {
            Some(d) => d,
            None => match diagnosed(&current, measured, opts, steps.len(), &mut progress) {
                Ok(d) => d,
                // the nominal model's failure is the user's to see; a later
                // one must not discard the steps done
                Err(e) if !steps.is_empty() => break (FixStop::DiagnosisFailed, Some(Err(e.to_string()))),
                Err(e) => return Err(e),
            },
        };
        if steps.is_empty() {
            (noise, nominal_misfit) = (d.noise, d.nominal_misfit);
        }
        let Some(rank) = d.recommended else {
            let stop = if d.consistent() { FixStop::NothingSignificant } else { FixStop::NoPlausibleCandidate };
            break (stop, Some(Ok(d)));
        };
        if steps.len() == opts.max_steps {
            break (FixStop::StepsDone, Some(Ok(d)));
        }
        let step = steps.len() + 1;
        let leader_misfit = d.ranking[rank - 1].misfit;
        let mut alternatives = Vec::new();
        let added: Vec<(Added, Diagnosis)> = if leader_misfit > LOOK_AHEAD_ABOVE * noise
            && steps.len() + 2 <= opts.max_steps
        {
            // pairs of distinct leaders fitted together first: when the best
            // reaches the noise, nothing is left to look ahead for
            let leaders = distinct_leaders(&d, &current.model, pairs::PAIR_WIDTH);
            let pair = pairs::best_pair(&current, &d, &leaders, measured, opts, step);
            if let Some(p) = &pair {
                alternatives.push(LookAhead {
                    effect: d.ranking[p.ranks.0 - 1].description.clone(),
                    misfit_ahead: p.misfit,
                    failed: None,
                    with: Some(d.ranking[p.ranks.1 - 1].description.clone()),
                });
                progress(FixProgress::LookedAhead { step: steps.len(), ahead: alternatives.last().expect("pushed") });
            }
            let mut best: Option<(f64, Added, Diagnosis)> = None;
            let singles = if pair.as_ref().is_none_or(|p| p.misfit > swap::SWAP_ABOVE * noise) {
                distinct_leaders(&d, &current.model, LOOK_AHEAD_WIDTH)
            } else {
                Vec::new()
            };
            for r in singles {
                // one alternative that cannot be added (its update left a
                // mechanism, say) must not end the loop: the others can
                let tried =
                    add_and_update(&current, &d, r, measured, opts, step, step >= opts.max_steps).and_then(|a| {
                        let ahead = diagnose::diagnose(&a.case.model, measured, &opts.diagnose)?;
                        // the follower added and everything updated jointly,
                        // as the pairs are: a first effect that absorbed part
                        // of the other is corrected by the joint update
                        let joint = ahead
                            .recommended
                            .and_then(|r| add_and_update(&a.case, &ahead, r, measured, opts, step + 1, false).ok());
                        Ok((a, ahead, joint.map(|j| j.misfit_updated)))
                    });
                let (a, ahead, joint) = match tried {
                    Ok(x) => x,
                    Err(e) => {
                        let effect = d.ranking[r - 1].description.clone();
                        alternatives.push(LookAhead {
                            effect,
                            misfit_ahead: f64::NAN,
                            failed: Some(e.to_string()),
                            with: None,
                        });
                        progress(FixProgress::LookedAhead {
                            step: steps.len(),
                            ahead: alternatives.last().expect("pushed"),
                        });
                        continue;
                    }
                };
                let alone = ahead.leader().map_or(a.misfit_updated, |l| l.misfit.min(a.misfit_updated));
                let score = joint.map_or(alone, |j| j.min(alone));
                alternatives.push(LookAhead {
                    effect: a.effect.description.clone(),
                    misfit_ahead: score,
                    failed: None,
                    with: None,
                });
                progress(FixProgress::LookedAhead { step: steps.len(), ahead: alternatives.last().expect("pushed") });
                if best.as_ref().is_none_or(|(b, ..)| score < *b) {
                    best = Some((score, a, ahead));
                }
            }
            // the pair, when it beats every single effect with its follower:
            // its first effect is a step of its own, then the second is added
            let pair = pair.filter(|p| best.as_ref().is_none_or(|(b, ..)| p.misfit < *b));
            let both = pair.and_then(|p| {
                let (a, b) = p.ranks;
                let first = add_and_update(&current, &d, a, measured, opts, step, false).ok()?;
                let last = step + 1 >= opts.max_steps;
                let second = add_and_update(&first.case, &d, b, measured, opts, step + 1, last).ok()?;
                Some([first, second])
            });
            match (both, best) {
                (Some([first, second]), _) => vec![(first, d.clone()), (second, d)],
                (None, Some((_, a, ahead))) => {
                    next = Some(ahead);
                    vec![(a, d)]
                }
                (None, None) => break (FixStop::CannotAdd, Some(Ok(d))),
            }
        } else {
            // the recommended effect, else the next distinct leaders in turn
            // when adding and updating one fails
            let added = std::iter::once(rank)
                .chain(distinct_leaders(&d, &current.model, LOOK_AHEAD_WIDTH))
                .find_map(|r| add_and_update(&current, &d, r, measured, opts, step, step >= opts.max_steps).ok());
            let Some(a) = added else {
                break (FixStop::CannotAdd, Some(Ok(d)));
            };
            vec![(a, d)]
        };
        let mut improved = true;
        for (k, (added, d)) in added.into_iter().enumerate() {
            progress(FixProgress::Updated {
                step: steps.len(),
                effect: &added.effect.description,
                removed: false,
                misfit: added.misfit_updated,
                status: &added.outcome.status,
            });
            current = added.case.clone();
            improved = added.misfit_updated < steps.last().map_or(nominal_misfit, |s: &FixStep| s.misfit_updated);
            applied.push((d, added.rank));
            let tried = if k == 0 { std::mem::take(&mut alternatives) } else { Vec::new() };
            steps.push(FixStep::of(added, tried, None));
            progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
        }
        if let Some(ahead) = &next {
            progress(FixProgress::Diagnosed { step: steps.len(), diagnosis: ahead });
        }
        if !improved {
            break (FixStop::NoImprovement, next.take().map(Ok));
        }
    };
    let (stop, mut last) = stop;
    let mut effects: Vec<Ranked> = steps.iter().map(|s| s.effect.clone()).collect();
    let mut misfit = steps.last().map_or(nominal_misfit, |s| s.misfit_updated);
    if !applied.is_empty() && misfit > CONSISTENT * noise {
        let (kept, revised) = revise::revise(case, &applied, &current, measured, opts, (misfit, noise));
        if !kept.is_empty() {
            for r in kept {
                let effect = if r.removed {
                    r.replaced.clone()
                } else {
                    format!("{} instead of {}", r.added.effect.description, r.replaced)
                };
                progress(FixProgress::Updated {
                    step: steps.len(),
                    effect: &effect,
                    removed: r.removed,
                    misfit: r.added.misfit_updated,
                    status: &r.added.outcome.status,
                });
                current = r.added.case.clone();
                misfit = r.added.misfit_updated;
                if r.removed {
                    effects.remove(r.index);
                    let mut s = FixStep::of(r.added, Vec::new(), None);
                    // nothing was added: the misfit without it is the updated one
                    s.misfit_added = s.misfit_updated;
                    s.removed = true;
                    steps.push(s);
                    progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
                } else {
                    effects[r.index] = r.added.effect.clone();
                    steps.push(FixStep::of(r.added, Vec::new(), Some(r.replaced)));
                    progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
                }
            }
            applied = revised;
            last = None;
        }
    }
    if applied.len() >= 2
        && misfit > swap::SWAP_ABOVE * noise
        && let Some((outs, added)) = swap::swap(case, &applied, measured, opts, misfit)
    {
        let removed: Vec<String> = outs.iter().map(|&i| effects[i].description.clone()).collect();
        for &i in outs.iter().rev() {
            effects.remove(i);
        }
        let replaced = removed.join(" and ");
        for (k, a) in added.into_iter().enumerate() {
            let effect = if k == 0 {
                format!("{} instead of {replaced}", a.effect.description)
            } else {
                a.effect.description.clone()
            };
            progress(FixProgress::Updated {
                step: steps.len(),
                effect: &effect,
                removed: false,
                misfit: a.misfit_updated,
                status: &a.outcome.status,
            });
            effects.push(a.effect.clone());
            current = a.case.clone();
            steps.push(FixStep::of(a, Vec::new(), (k == 0).then(|| replaced.clone())));
            progress(FixProgress::StepDone { index: steps.len() - 1, done: steps.last().expect("pushed") });
        }
        last = None;
    }
    let last = last
        .unwrap_or_else(|| diagnosed(&current, measured, opts, steps.len(), &mut progress).map_err(|e| e.to_string()));
    let (last, diagnosis_error) = match last {
        Ok(d) => (Some(d), None),
        Err(e) => (None, Some(e)),
    };
    Ok(FixOutcome {
        noise,
        nominal_misfit,
        effects,
        steps,
        stop,
        significant_remains: last.as_ref().is_none_or(|d| !d.consistent()),
        remaining: last.map_or(Vec::new(), |d| d.ranking.into_iter().filter(|r| r.fully_fitted).take(5).collect()),
        diagnosis_error,
    })
}

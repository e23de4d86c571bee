//! Revising the form of each effect once the others are in the model.
//!
//! Each effect was chosen, with its variant (viscous or non-viscous
//! damping, which springs, a rotary inertia or not, its window of
//! elements), by a diagnosis of a model that still lacked the effects added
//! after it. Those later effects change what fits best: on an L-frame with
//! a mass on the column and a non-viscous corner joint, the joint is
//! chosen viscous while the mass is missing, and with the mass added the
//! viscous joint leaves 6.8 times the noise where the non-viscous one
//! reaches it (held-out trial 25 of a study at 4 trials per family and 6
//! pairs). The joint update of every parameter cannot mend that: it changes
//! values, not forms.
//!
//! So, when the loop leaves more than the noise, each effect in turn is
//! replaced by each of the few best other candidates of the diagnosis it
//! came from that act at its place (any kind: a mass change of two
//! elements is a lumped mass's neighbour), the others kept, and everything
//! updated jointly. A replacement is kept by the loop's one rule
//! (`fix/judge.rs`): the evidence for the model with it over the model
//! before, every parameter counted, plausible values and an update that
//! reached a stationary point; the next effect is then revised with it in
//! place. The same evidence read backwards takes an effect out: it stays
//! only while, added to the model without it, it would be significant on
//! its own, its parameters counted (`unneeded`). When it would not, the
//! model without it is the one its replacements must beat, by the rule a
//! new effect must pass (significant, and explaining [`super::SHARE`] of
//! what that model leaves above the noise): the data no longer call for
//! it, so what takes its place is an addition.

use fe_model::{CaseEditor, CaseFile};

use super::{Added, Loop, State};
use crate::diagnose::{self, Diagnosis, EffectKind, Ranked};
use crate::error::UpdateError;

/// How many other candidates at an effect's place are tried in its stead.
const REVISE_WIDTH: usize = 6;

/// Passes over the effects, at most.
const PASSES: usize = 2;

/// One replacement kept: effect `index` of the loop's effects (as revised
/// so far), and the case with its replacement, updated; or, when
/// `removed`, the case without it, updated (`added.effect` is then the
/// effect taken out).
pub(super) struct Replacement {
    pub index: usize,
    pub removed: bool,
    pub added: Added,
    /// The description of the effect it replaced.
    pub replaced: String,
    /// Its evidence over the model before it.
    pub delta_bic: f64,
    /// Why the effect it replaced was not needed, when it was not (see
    /// `unneeded`).
    pub why: Option<String>,
}

/// Kinds that stand in for one another: a joint and a short stiffness
/// change, a lumped mass and a short mass change (and the test's hardware,
/// a shaker's armature or a sensor's mass), the two damping forms.
fn family(kind: EffectKind) -> u8 {
    match kind {
        EffectKind::FlexibleJoint | EffectKind::StiffnessChange => 0,
        EffectKind::LumpedMass | EffectKind::MassChange | EffectKind::Shaker | EffectKind::SensorMasses => 1,
        EffectKind::ViscousDamping | EffectKind::NonViscousDamping => 2,
        EffectKind::FlexibleSupport => 3,
        // a mode of its own: nothing else stands in for it
        EffectKind::Resonator => 4,
    }
}

/// Whether `r` is `own` in its other damping form: the same kind at the
/// same nodes, elements and directions.
fn other_form(r: &Ranked, own: &Ranked) -> bool {
    r.kind == own.kind
        && r.nodes == own.nodes
        && r.elements == own.elements
        && r.dof == own.dof
        && r.damping != own.damping
}

/// `own`'s description in `other`'s damping form.
fn retitled(own: &Ranked, other: &Ranked) -> String {
    match (own.damping, other.damping) {
        (Some(a), Some(b)) if own.description.contains(a) => own.description.replacen(a, b, 1),
        _ => other.description.clone(),
    }
}

/// The candidates of `d` (ranks) at the place of `own`: significant,
/// plausible and near it, `own` itself left out; `own` in its other
/// damping form first (its screening fit, started alone, can miss the
/// tuning or the stiffness the update of `own` found: the tutorial's lab
/// frame has a non-viscous resonator whose non-viscous candidate ranks
/// 21st at 10 Hz, while the viscous one, updated, sits at 72 Hz), then the best three of its
/// kind (its other variants and windows), the best two of a kind that
/// stands in for it, the best of another kind, then the best of the rest
/// up to [`REVISE_WIDTH`]. A diagnosis ranks the variant the data prefer
/// once the other effects are in below windows of another kind when they
/// are not (trial 25: the non-viscous joint 11th, behind eight stiffness
/// changes at the corner), and windows of a mass change can fill every
/// place before the lumped mass they stand for (trial 27).
fn neighbours(d: &Diagnosis, own: &Ranked, model: &fe_model::Model) -> Vec<usize> {
    let near: Vec<(i8, usize)> = d
        .ranking
        .iter()
        .enumerate()
        .filter(|&(_, r)| {
            r.significant
                && r.plausible
                && r.description != own.description
                && d.candidates[r.candidate].near(model, &own.nodes, &own.elements)
        })
        .map(|(i, r)| {
            let order = if other_form(r, own) {
                -1
            } else if r.kind == own.kind {
                0
            } else if family(r.kind) == family(own.kind) {
                1
            } else {
                2
            };
            (order, i + 1)
        })
        .collect();
    let mut out: Vec<usize> = Vec::new();
    for (order, quota) in [(-1, 1), (0, 3), (1, 2), (2, 1)] {
        out.extend(near.iter().filter(|(o, _)| *o == order).map(|&(_, r)| r).take(quota));
    }
    for &(_, r) in &near {
        if out.len() >= REVISE_WIDTH {
            break;
        }
        if !out.contains(&r) {
            out.push(r);
        }
    }
    out
}

/// The nominal case with the effects `applied` (diagnosis and rank of
/// each) added in order, as an editor on the new case, and that case. With
/// `warm`, the parameters of the case's `[update]` start from their values
/// in that model, except those named in `fresh` (the parameters of an
/// effect just put in, which start from its diagnosed values): the effects
/// kept were updated together, and starting them there spares the update
/// the way back from their first, biased fits.
pub(super) fn build(
    nominal: &CaseFile,
    applied: &[(&Diagnosis, usize)],
    warm: Option<&fe_model::Model>,
    fresh: &[String],
    carry: &[String],
    fl: &Loop<'_>,
) -> Result<(CaseFile, CaseEditor), UpdateError> {
    let mut case = nominal.clone();
    let mut editor = None;
    for (d, r) in applied {
        let e = d.apply_with_data(&case, *r, fl.opts.data.as_deref())?;
        case = CaseFile::parse(&nominal.path, &e.text_at(&nominal.path)?)?;
        editor = Some(e);
    }
    let mut editor = editor.ok_or_else(|| UpdateError::Method("no effect to add".into()))?;
    if let (Some(warm), Some(update)) = (warm, &case.update) {
        // the parameters `carry` names join the update (an effect's other
        // form keeps updating what the effect did, from where it stopped,
        // though its screening held some of them at its own fit)
        let listed: Vec<String> = update.parameters.iter().map(|p| p.name.clone()).collect();
        let carried: Vec<String> = carry.iter().filter(|n| !listed.contains(n)).cloned().collect();
        if !carried.is_empty() {
            let all: Vec<String> = listed.iter().chain(&carried).cloned().collect();
            let method = update.method.as_ref().map_or("output-error", |(m, _)| m.as_str());
            editor.set_update(&all, method)?;
        }
        let carried: Vec<fe_model::Parameter> = carried.iter().filter_map(|n| warm.parameter(n).ok()).collect();
        let kept: Vec<&fe_model::Parameter> =
            update.parameters.iter().chain(&carried).filter(|p| !fresh.contains(&p.name)).collect();
        let params: Vec<fe_model::Parameter> = kept.iter().filter_map(|p| warm.parameter(&p.name).ok()).collect();
        // the mu of a group the warm model holds viscous
        let viscous_mu: Vec<String> = kept
            .iter()
            .filter(|p| {
                p.name.strip_suffix(".mu").is_some_and(|g| warm.parameter(&format!("{g}.alpha")).is_ok())
                    && warm.parameter(&p.name).is_err()
            })
            .map(|p| p.name.clone())
            .collect();
        // a viscous group's mu is infinite: its non-viscous form starts
        // from a kernel relaxing ten times faster than the highest line,
        // which damps as the viscous one did over the band, so that the
        // update starts at the fit the viscous form reached and moves mu
        // down as the data ask (its own screening fit, started alone, can
        // stop far from it: the lab frame's resonator at 10 Hz)
        let fast = 10.0 * std::f64::consts::TAU * fl.data.frequencies_hz().iter().copied().fold(0.0, f64::max);
        let values: Vec<(String, f64)> = crate::params::quantity_values(&params, warm)
            .into_iter()
            .map(|(name, v)| if v.is_infinite() && name.ends_with(".mu") { (name, fast) } else { (name, v) })
            .filter(|(_, v)| v.is_finite())
            .chain(viscous_mu.into_iter().map(|name| (name, fast)))
            .collect();
        editor.set_values(&values, "started where the loop left them")?;
        case = CaseFile::parse(&nominal.path, &editor.text_at(&nominal.path)?)?;
    }
    Ok((case, editor))
}

/// [`build`] and every parameter updated (no restarts unless `last`); the
/// added effect reported is the one at `index`.
fn with_effects(
    fl: &Loop<'_>,
    nominal: &CaseFile,
    applied: &[(&Diagnosis, usize)],
    index: usize,
    warm: Option<&fe_model::Model>,
    (fresh, carry): (&[String], &[String]),
    (step, last): (usize, bool),
) -> Result<Added, UpdateError> {
    let (case, editor) = build(nominal, applied, warm, fresh, carry, fl)?;
    let (d, rank) = applied[index];
    let (editor, case, stats, outcome) = fl.update_case(&case, editor, step, last)?;
    Ok(Added { effect: d.ranking[rank - 1].clone(), rank, editor, case, stats, outcome })
}

/// The effects as references.
fn refs(a: &[(Diagnosis, usize)]) -> Vec<(&Diagnosis, usize)> {
    a.iter().map(|(d, r)| (d, *r)).collect()
}

/// Why the effect taken out of the model `state` to leave `without` (its
/// update, `a`, whose evidence over `state` is `delta_bic`) is not needed:
/// added to the model without it, it would not be significant on its own,
/// its parameters counted. An effect kept only because taking it out was
/// not strongly preferred is one the evidence never singled out (the fix
/// bench's beam: a lumped mass of 21 mg ± 240 % at the tip, left from
/// before the joint's place was mended, whose removal the evidence
/// preferred by 3.5, then replaced by a mass change of 0.05 % over eight
/// elements). The share of the excess an addition must explain
/// ([`super::SHARE`]) is not asked of an effect already in: against a
/// model that still lacks another effect, or data that hold an error not
/// yet found, a right effect or a fair stand-in for
/// one explains only part of what is left (the damping-form test's clamp
/// with a motor beside it and a sensor 20 % low, at 38 times the noise: a
/// stiffness change standing in for the motor explained 28 %, and taken
/// out, the revision never reached the motor). `None` when it is needed,
/// or when the model without it cannot be judged (an update short of a
/// stationary point, or implausible values).
fn unneeded(a: &Added, without: &[(&Diagnosis, usize)], delta_bic: f64, significance: f64) -> Option<String> {
    if !super::judge::stationary(&a.outcome) || super::judge::implausible_after(without, &a.outcome).is_some() {
        return None;
    }
    let own = -delta_bic;
    (!(own < significance)).then(|| {
        format!(
            "added to the model without it, its dBIC would be {}, not below {significance}",
            crate::quantities::dbic_text(own)
        )
    })
}

/// Revises the effects `applied` (diagnosis and rank of each, in the order
/// added to `nominal`), which leave the model `before` in the case
/// `current`; see the module docs. Returns the replacements kept, in order
/// (each updated with the ones before it in place; the last again with
/// restarts, as the loop's answer), and the effects as revised.
pub(super) fn revise(
    fl: &Loop<'_>,
    nominal: &CaseFile,
    applied: &[(Diagnosis, usize)],
    current: &CaseFile,
    before: State,
    next_step: usize,
) -> (Vec<Replacement>, Vec<(Diagnosis, usize)>) {
    let mut applied: Vec<(Diagnosis, usize)> = applied.to_vec();
    let mut warm = current.model.clone();
    let mut state = before;
    let mut kept: Vec<Replacement> = Vec::new();
    // the number the loop gives the first revision kept (its update's
    // comment in the case; the loop writes the history anew)
    let step = next_step;
    // a second pass when the first changed something: an effect revised
    // early was revised against others not yet mended (trial 27: the mass
    // before the damping window)
    let mut index = 0;
    let mut pass_changed = false;
    let mut passes = 1;
    loop {
        if index == applied.len() {
            if !pass_changed || passes == PASSES {
                break;
            }
            (index, pass_changed, passes) = (0, false, passes + 1);
        }
        let own = applied[index].0.ranking[applied[index].1 - 1].clone();
        // the others at their values, this one left out: what the data
        // call for at its place with the others in
        let mut without = refs(&applied);
        without.remove(index);
        let mut best: Option<(f64, Option<usize>, Added)> = None;
        // built once: updated for the effect taken out, diagnosed for its
        // replacements
        let without_built = if without.is_empty() {
            Err(UpdateError::Method("no effect left".into()))
        } else {
            build(nominal, &without, Some(&warm), &[], &[], fl)
        };
        // taken out: an effect added to make up for a wrong form of
        // another may not be needed once that is mended (trial 25: a stiff
        // in-line joint beside the corner joint). It stays only while it
        // would be significant added to the model without it (`unneeded`);
        // when it would not, the model without it is the base every
        // replacement is judged against (with its floor, see `small_share`)
        let mut base: Option<(State, f64)> = None;
        let mut why: Option<String> = None;
        if let Ok((case, editor)) = &without_built
            && let Ok((editor, case, stats, outcome)) = fl.update_case(case, editor.clone(), step, false)
            && stats.misfit.is_finite()
        {
            let a = Added { effect: own.clone(), rank: applied[index].1, editor, case, stats, outcome };
            let v = fl.judge(state, &a, &without);
            if let Some(reason) = unneeded(&a, &without, v.delta_bic, fl.evidence.significance) {
                why = Some(reason);
                let floor = fl.floor(a.stats.misfit, &a.case);
                base = Some((State { misfit: a.stats.misfit, k: a.outcome.parameters.len() }, floor));
                best = Some((v.delta_bic, None, a));
            }
        }
        // an effect alone: the diagnosis it came from is that of the model
        // without it (its other form is the revision it may need); an
        // effect not needed: the diagnosis of the model without it,
        // updated, since its replacement is an addition to that model (at
        // the others' values with it, a candidate near it takes up what
        // their update would: on the fix bench's beam, the model without a
        // tip mass of 21 mg, updated, leaves nothing significant, and a mass
        // change of 0.05 % over eight elements diagnosed at the values
        // before was kept)
        let d = match (&best, base) {
            _ if without.is_empty() => Ok((applied[index].0.clone(), nominal.clone())),
            (Some((_, _, a)), Some(_)) => {
                diagnose::diagnose(&a.case.model, &fl.data, &fl.opts.diagnose).map(|d| (d, a.case.clone()))
            }
            _ => without_built
                .and_then(|(case, _)| diagnose::diagnose(&case.model, &fl.data, &fl.opts.diagnose).map(|d| (d, case))),
        };
        if let Ok((d, without_case)) = &d {
            for other in neighbours(d, &own, &without_case.model) {
                let mut tried = refs(&applied);
                tried[index] = (d, other);
                // the other form starts from the values `own` was updated to
                // (the names it shares), the rest from the diagnosis
                let names = |r: &Ranked| r.parameters.iter().map(|p| p.name.clone()).collect::<Vec<String>>();
                let (fresh, carry) = if other_form(&d.ranking[other - 1], &own) {
                    (Vec::new(), names(&own))
                } else {
                    (names(&d.ranking[other - 1]), Vec::new())
                };
                let Ok(mut a) = with_effects(fl, nominal, &tried, index, Some(&warm), (&fresh, &carry), (step, false))
                else {
                    continue;
                };
                if !carry.is_empty() {
                    // it was started from `own`'s values, not its screening
                    // fit's (whose tuning its description may give), with a
                    // kernel that damps as the viscous one did: where the
                    // update started is the misfit `own` left
                    a.effect.description = retitled(&own, &a.effect);
                    a.effect.misfit = state.misfit;
                }
                // judged against the model before the revision, or, when the
                // effect it replaces is not needed, as an addition to the
                // model without it: a replacement of what the data no longer
                // call for is a new effect and needs its own evidence
                let v = match base {
                    Some((b, floor)) => {
                        let mut v = fl.judge(b, &a, &tried);
                        if v.rejected.is_none() {
                            v.rejected = super::small_share(b.misfit, a.stats.misfit, fl.evidence.noise, floor);
                        }
                        // its evidence over the model before the revision,
                        // as every step reports it
                        v.delta_bic = diagnose::delta_bic(
                            state.misfit,
                            state.k,
                            &a.stats,
                            a.outcome.parameters.len(),
                            fl.evidence.noise,
                        );
                        v
                    }
                    None => fl.judge(state, &a, &tried),
                };
                if v.rejected.is_none() && best.as_ref().is_none_or(|(b, ..)| v.delta_bic < *b) {
                    best = Some((v.delta_bic, Some(other), a));
                }
            }
        }
        let Some((delta_bic, other, added)) = best else {
            index += 1;
            continue;
        };
        warm = added.case.model.clone();
        state = State { misfit: added.stats.misfit, k: added.outcome.parameters.len() };
        pass_changed = true;
        kept.push(Replacement {
            index,
            removed: other.is_none(),
            added,
            replaced: own.description.clone(),
            delta_bic,
            why,
        });
        match (other, d) {
            (Some(other), Ok((d, _))) => {
                applied[index] = (d, other);
                index += 1;
            }
            _ => {
                applied.remove(index);
            }
        }
    }
    // the last replacement's model is the loop's answer: its fit restarts
    // when it leaves more than the noise
    if let Some(last) = kept.last_mut()
        && !applied.is_empty()
        && let Ok((case, editor)) = build(nominal, &refs(&applied), Some(&warm), &[], &[], fl)
        && let Ok((editor, case, stats, outcome)) = fl.update_case(&case, editor, step, true)
        && stats.misfit <= last.added.stats.misfit
    {
        (last.added.editor, last.added.case, last.added.stats, last.added.outcome) = (editor, case, stats, outcome);
    }
    (kept, applied)
}

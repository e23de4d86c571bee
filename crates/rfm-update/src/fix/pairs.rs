//! Two effects fitted together when one alone leaves far more than the noise.
//!
//! With two effects hidden at once, each single candidate is fitted while
//! the other effect is still missing, and the best of them is often neither:
//! a splice near an arm's end and a mass on the column are best explained,
//! one at a time, by a flexible support at the base (held-out trial 76 of
//! the full study), and the right mass ranks eleventh, the splice twentieth.
//! Fitted together, the right pair explains the data and a wrong one does
//! not, so the pairs of a few distinct leaders are each added to the case
//! and updated jointly, and the pair that leaves the least misfit is
//! judged. It becomes two steps, and each must pass the loop's rule on its
//! own: the first (the better of the two alone) against the model before
//! it, the second against the model with the first, and the first against
//! the model with the second alone. A partner that only rides along with
//! a strong effect is never kept.

use fe_model::CaseFile;

use super::{Added, LookAhead, Loop, Move, State, applied_with};
use crate::diagnose::Diagnosis;
use crate::error::UpdateError;

/// How many distinct leaders are paired (each with each: 15 pairs).
pub(super) const PAIR_WIDTH: usize = 6;

/// The case `current` with ranked effects `ranks` of `d` added, in turn, at
/// their diagnosed values (each written as the diagnosis would write it
/// alone; the two must not touch the same nodes or elements, or the second
/// edit fails and the pair is skipped).
fn with_both(
    fl: &Loop<'_>,
    current: &CaseFile,
    d: &Diagnosis,
    ranks: (usize, usize),
) -> Result<(CaseFile, fe_model::CaseEditor), UpdateError> {
    let first = d.apply_with_data(current, ranks.0, fl.opts.data.as_deref())?;
    let case = CaseFile::parse(&current.path, &first.text_at(&current.path)?)?;
    let second = d.apply_with_data(&case, ranks.1, fl.opts.data.as_deref())?;
    Ok((case, second))
}

/// Every pair of the distinct `leaders` (ranks of `d`, best first) added to
/// `current` and updated jointly on the diagnosis's lines; the pair that
/// leaves the least misfit, judged as a move of two steps from `before`
/// (see the module docs), when any pair could be added. `singles` holds the
/// leaders already added alone and updated (rank, model); a member of the
/// best pair missing there is added alone now.
#[allow(clippy::too_many_arguments)]
pub(super) fn best_pair(
    fl: &Loop<'_>,
    current: &CaseFile,
    d: &Diagnosis,
    leaders: &[usize],
    singles: &[(usize, Added)],
    before: State,
    (step, last): (usize, bool),
    applied: &[(Diagnosis, usize)],
) -> Option<Move> {
    let mut best: Option<((usize, usize), Added)> = None;
    for (k, &a) in leaders.iter().enumerate() {
        for &b in &leaders[k + 1..] {
            let second_last = last || step + 1 >= fl.opts.max_steps;
            let tried = with_both(fl, current, d, (a, b)).and_then(|(case, editor)| {
                let (editor, case, stats, outcome) = fl.update_case(&case, editor, step + 1, second_last)?;
                Ok(Added { effect: d.ranking[b - 1].clone(), rank: b, editor, case, stats, outcome })
            });
            let Ok(pair) = tried else { continue };
            if pair.stats.misfit.is_finite() && best.as_ref().is_none_or(|(_, p)| pair.stats.misfit < p.stats.misfit) {
                best = Some(((a, b), pair));
            }
        }
    }
    let ((a, b), pair) = best?;
    let alone = |r: usize| -> Option<Added> {
        singles
            .iter()
            .find(|(x, _)| *x == r)
            .map(|(_, s)| s.clone())
            .or_else(|| fl.add_and_update(current, d, r, step, false).ok())
    };
    let (sa, sb) = (alone(a), alone(b));
    let name = |r: usize| d.ranking[r - 1].description.clone();
    let judge_first = |s: &Added, r: usize| fl.judge(before, s, &applied_with(applied, d, r));
    // the first step: whichever of the two alone has the better evidence
    let firsts: Vec<(usize, Added, super::judge::Verdict)> = [(a, sa.clone()), (b, sb.clone())]
        .into_iter()
        .filter_map(|(r, s)| s.map(|s| (r, s)))
        .map(|(r, s)| {
            let v = judge_first(&s, r);
            (r, s, v)
        })
        .collect();
    let first = firsts.iter().min_by(|x, y| x.2.delta_bic.total_cmp(&y.2.delta_bic)).cloned();
    let mut effects = applied_with(applied, d, a);
    effects.push((d, b));
    let total = fl.judge(before, &pair, &effects);
    let mut record = LookAhead {
        effect: name(a),
        misfit_ahead: pair.stats.misfit,
        delta_bic: total.delta_bic,
        failed: None,
        rejected: None,
        with: Some(name(b)),
        equally_good: false,
    };
    let k_pair = pair.outcome.parameters.len();
    let over = |s: &Added| {
        crate::diagnose::delta_bic(s.stats.misfit, s.outcome.parameters.len(), &pair.stats, k_pair, fl.evidence.noise)
    };
    let reject = |why: String| Some(why);
    record.rejected = match (&first, &sa, &sb) {
        _ if total.rejected.is_some() => total.rejected.clone(),
        (None, ..) => reject("neither effect of the pair could be added alone".into()),
        (Some((_, _, v)), ..) if v.rejected.is_some() => {
            reject(format!("its first step fails on its own: {}", v.rejected.as_deref().unwrap_or_default()))
        }
        (_, Some(sa), Some(sb)) => {
            let (with_a, with_b) = (over(sa), over(sb));
            let s = fl.evidence.significance;
            if !(with_a < s) {
                reject(format!(
                    "{} adds nothing significant to {} alone (dBIC {})",
                    name(b),
                    name(a),
                    crate::quantities::dbic_text(with_a)
                ))
            } else if !(with_b < s) {
                reject(format!(
                    "{} adds nothing significant to {} alone (dBIC {})",
                    name(a),
                    name(b),
                    crate::quantities::dbic_text(with_b)
                ))
            } else {
                None
            }
        }
        _ => reject("one effect of the pair could not be added alone".into()),
    };
    let (r1, s1, v1) = first?;
    let second_evidence = over(&s1);
    // the pair's first step is the better of the two alone; the pair case
    // adds `a` then `b`, and reports `b` as the effect of its step unless
    // `b` came first
    let mut pair = pair;
    if r1 == b {
        pair.effect = d.ranking[a - 1].clone();
        pair.rank = a;
    }
    Some(Move { steps: vec![(s1, v1.delta_bic), (pair, second_evidence)], record })
}

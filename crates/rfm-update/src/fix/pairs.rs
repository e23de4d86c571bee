//! Two effects fitted together when one alone leaves far more than the noise.
//!
//! With two effects hidden at once, each single candidate is fitted while
//! the other effect is still missing, and the best of them is often neither:
//! a splice near an arm's end and a mass on the column are best explained,
//! one at a time, by a flexible support at the base (held-out trial 76 of
//! the full study), and the right mass ranks eleventh, the splice twentieth.
//! Looking one step ahead ([`super::fix`]) does not mend that when the
//! right first effect, updated alone, absorbs part of the other: its
//! follower is then fitted against a biased model. Fitted together, the
//! right pair explains the data and a wrong one does not, so the pairs of a
//! few distinct leaders are each added to the case and updated jointly, and
//! the pair that leaves the least misfit is offered to the loop.

use fe_model::CaseFile;
use frf::FrfSet;

use super::{FixOptions, update_case};
use crate::diagnose::Diagnosis;
use crate::error::UpdateError;

/// How many distinct leaders are paired (each with each: 15 pairs).
pub(super) const PAIR_WIDTH: usize = 6;

/// A pair of ranked effects of one diagnosis and the misfit they leave
/// when both are added and every parameter is updated jointly.
#[derive(Clone, Debug)]
pub(super) struct Pair {
    /// Ranks (1-based) in the diagnosis, the better ranked first.
    pub ranks: (usize, usize),
    /// The misfit after the joint update.
    pub misfit: f64,
}

/// The case `current` with ranked effects `ranks` of `d` added, in turn, at
/// their diagnosed values (each written as the diagnosis would write it
/// alone; the two must not touch the same nodes or elements, or the second
/// edit fails and the pair is skipped).
fn with_both(
    current: &CaseFile,
    d: &Diagnosis,
    ranks: (usize, usize),
    opts: &FixOptions,
) -> Result<(CaseFile, fe_model::CaseEditor), UpdateError> {
    let first = d.apply_with_data(current, ranks.0, opts.data.as_deref())?;
    let case = CaseFile::parse(&current.path, &first.text_at(&current.path)?)?;
    let second = d.apply_with_data(&case, ranks.1, opts.data.as_deref())?;
    Ok((case, second))
}

/// Every pair of the distinct `leaders` (ranks of `d`, best first) added to
/// `current` and updated jointly on the diagnosis's lines (no restarts: the
/// score only ranks the pairs); the best pair, when any could be added.
pub(super) fn best_pair(
    current: &CaseFile,
    d: &Diagnosis,
    leaders: &[usize],
    measured: &FrfSet,
    opts: &FixOptions,
    step: usize,
) -> Option<Pair> {
    let mut best: Option<Pair> = None;
    for (k, &a) in leaders.iter().enumerate() {
        for &b in &leaders[k + 1..] {
            let tried = with_both(current, d, (a, b), opts)
                .and_then(|(case, editor)| update_case(&case, editor, d, measured, opts, step + 1, false));
            let Ok((_, _, misfit, _)) = tried else { continue };
            if misfit.is_finite() && best.as_ref().is_none_or(|p| misfit < p.misfit) {
                best = Some(Pair { ranks: (a, b), misfit });
            }
        }
    }
    best
}

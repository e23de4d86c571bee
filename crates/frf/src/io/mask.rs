//! Defects of measured data that a case accepts by leaving values out
//! (`[measurement] mask = [...]`, see [`MaskRule`]), and the checks that
//! refuse them otherwise.
//!
//! Masking works on whole frequency lines (a NaN in one channel removes the
//! line from every channel) and whole channels, so that the updating
//! methods, which need every measured channel at every line they use, see
//! only complete data and need no weights. Everything left out is listed
//! in [`Masked`] records for the report.

use std::path::Path;

use fe_model::case::MaskRule;
use fe_model::{DofMap, DofRef, Slot};

use crate::error::{FileError, FrfError};
use crate::set::{Channel, FrfSet};

/// Something left out of measured data by a mask rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Masked {
    /// The rule that left it out.
    pub rule: MaskRule,
    /// The frequency line left out (Hz), for line rules.
    pub freq_hz: Option<f64>,
    /// The channel left out, for channel rules; for a line rule, the first
    /// channel whose value caused it.
    pub channel: Option<Channel>,
    /// Where in the file and why, e.g. `line 17: H(31:uy,31:uy) is NaN`.
    pub detail: String,
}

/// Where a channel comes from in its file, for messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Origin {
    /// 1-based line of the record (UFF) or of the header (CSV).
    pub line: usize,
    /// `record 3 (line 90)` or `columns 4-5`.
    pub label: String,
}

/// The suggestion appended to a refusal that a rule could turn into masking.
pub(crate) fn hint(rule: MaskRule, what: &str) -> String {
    format!("fix the file, or add `mask = [\"{rule}\"]` to the case's [measurement] to leave {what} out")
}

/// Leaves out the lines where any channel is not finite (`allow`), or
/// refuses the first such value. `locate(c, k)` gives the file line and a
/// label of value `k` of channel `c` for messages.
pub(crate) fn non_finite_lines(
    path: &Path,
    set: FrfSet,
    allow: bool,
    locate: &dyn Fn(usize, usize) -> (usize, String),
) -> Result<(FrfSet, Vec<Masked>), FrfError> {
    let nf = set.n_freq();
    let mut bad: Vec<(usize, usize)> = Vec::new(); // (line index, first channel)
    for k in 0..nf {
        if let Some(c) = (0..set.channels().len()).find(|&c| {
            let v = set.get(c, k);
            !(v.re.is_finite() && v.im.is_finite())
        }) {
            bad.push((k, c));
        }
    }
    if bad.is_empty() {
        return Ok((set, Vec::new()));
    }
    let describe = |k: usize, c: usize| {
        let v = set.get(c, k);
        let (line, label) = locate(c, k);
        let value = if v.re.is_nan() || v.im.is_nan() { "NaN".to_string() } else { format!("{v}") };
        (line, format!("{label}: {} at {} Hz is {value}", set.channels()[c], set.frequencies_hz()[k]))
    };
    if !allow {
        let (k, c) = bad[0];
        let (line, what) = describe(k, c);
        let more = if bad.len() > 1 { format!(" ({} lines have such values)", bad.len()) } else { String::new() };
        return Err(FrfError::File(FileError::Parse {
            path: path.to_path_buf(),
            line,
            message: format!("{what}{more}; {}", hint(MaskRule::NonFinite, "such lines")),
        }));
    }
    let masked = bad
        .iter()
        .map(|&(k, c)| Masked {
            rule: MaskRule::NonFinite,
            freq_hz: Some(set.frequencies_hz()[k]),
            channel: Some(set.channels()[c]),
            detail: describe(k, c).1,
        })
        .collect();
    let keep: Vec<usize> = (0..nf).filter(|k| bad.binary_search_by_key(k, |b| b.0).is_err()).collect();
    if keep.is_empty() {
        return Err(FrfError::File(FileError::Parse {
            path: path.to_path_buf(),
            line: locate(0, 0).0,
            message: "every frequency line has a non-finite value: nothing is left to compare".into(),
        }));
    }
    Ok((set.select_lines(&keep)?, masked))
}

/// Why a DOF cannot carry a measured channel, if it cannot.
fn unmodelled(dofs: &DofMap, dof: DofRef) -> Option<String> {
    match dofs.slot(dof) {
        Some(Slot::Free(_)) => None,
        Some(Slot::Fixed) => Some(format!("{dof} is held fixed by a support of the model")),
        None if fe_model::Dof::SPATIAL.iter().any(|&d| dofs.slot(DofRef { node: dof.node, dof: d }).is_some()) => {
            // the node exists, its DOF does not: a planar model's `uz`, `rx` or `ry`
            Some(format!(
                "the model's node {} has no `{}` (a planar model's nodes have ux, uy and rz; a frame in space needs \
                 `[model] dimension = 3`)",
                dof.node, dof.dof
            ))
        }
        None => Some(format!("the model has no node {}", dof.node)),
    }
}

/// Checks that every channel is at free DOFs of the model: a channel at a
/// node the model lacks or at a supported DOF is refused, or left out when
/// the rule [`MaskRule::UnmodelledChannels`] is given. `origins` (one per
/// channel) say where each channel comes from. Returns the channels kept,
/// their origins and what was left out.
pub fn check_channels(
    path: &Path,
    set: FrfSet,
    origins: &[Origin],
    dofs: &DofMap,
    rules: &[MaskRule],
) -> Result<(FrfSet, Vec<Origin>, Vec<Masked>), FrfError> {
    let allow = rules.contains(&MaskRule::UnmodelledChannels);
    let mut keep = Vec::new();
    let mut masked = Vec::new();
    for (c, ch) in set.channels().iter().enumerate() {
        let why = [("response", ch.response), ("reference", ch.reference)]
            .into_iter()
            .find_map(|(end, dof)| unmodelled(dofs, dof).map(|w| format!("its {end} {w}")));
        let Some(why) = why else {
            keep.push(c);
            continue;
        };
        let origin = origins.get(c).cloned().unwrap_or(Origin { line: 1, label: format!("channel {}", c + 1) });
        let detail = format!("{}: {ch}: {why}", origin.label);
        if !allow {
            return Err(FrfError::File(FileError::Parse {
                path: path.to_path_buf(),
                line: origin.line,
                message: format!(
                    "{detail}; map the test point to a model DOF with [[measurement.map]], {}",
                    hint(MaskRule::UnmodelledChannels, "such channels")
                ),
            }));
        }
        masked.push(Masked { rule: MaskRule::UnmodelledChannels, freq_hz: None, channel: Some(*ch), detail });
    }
    if keep.is_empty() {
        return Err(FrfError::File(FileError::Parse {
            path: path.to_path_buf(),
            line: origins.first().map_or(1, |o| o.line),
            message: "no channel of the file is at a free DOF of the model: nothing is left to compare".into(),
        }));
    }
    let kept = keep.iter().filter_map(|&c| origins.get(c).cloned()).collect();
    Ok((set.select_channels(&keep), kept, masked))
}

/// Lines that repeat the previous line's frequency: left out when `allow`
/// (the first of equal lines is kept), refused otherwise; lines that go
/// backwards are always refused. `at(k)` gives the file line of value `k`
/// and the prefix of messages about it. Returns the indices to keep and
/// what was left out.
pub(crate) fn duplicate_lines(
    path: &Path,
    freqs: &[f64],
    at: &dyn Fn(usize) -> (usize, String),
    allow: bool,
) -> Result<(Vec<usize>, Vec<Masked>), FrfError> {
    let err = |k: usize, message: String| {
        let (line, prefix) = at(k);
        FrfError::File(FileError::Parse { path: path.to_path_buf(), line, message: format!("{prefix}{message}") })
    };
    let mut keep: Vec<usize> = Vec::with_capacity(freqs.len());
    let mut masked = Vec::new();
    for (k, &f) in freqs.iter().enumerate() {
        if !f.is_finite() {
            return Err(err(k, format!("frequency {} is {f}", k + 1)));
        }
        if let Some(&prev) = keep.last() {
            let p = freqs[prev];
            if f == p {
                let what = format!("frequency {} repeats {f} Hz", k + 1);
                if !allow {
                    return Err(err(k, format!("{what}; {}", hint(MaskRule::DuplicateLines, "repeated lines"))));
                }
                let detail = format!("{}{what}", at(k).1);
                masked.push(Masked { rule: MaskRule::DuplicateLines, freq_hz: Some(f), channel: None, detail });
                continue;
            }
            if f < p {
                return Err(err(
                    k,
                    format!(
                        "frequency {} ({f} Hz) is below the one before it ({p} Hz): frequencies must increase",
                        k + 1
                    ),
                ));
            }
        }
        keep.push(k);
    }
    Ok((keep, masked))
}

#[cfg(test)]
mod tests {
    use fe_model::{Assembly, Dof, samples};

    use super::*;

    /// A channel at a DOF the model's dimension lacks says so, not that the
    /// node is missing.
    #[test]
    fn a_channel_at_a_dof_a_planar_model_lacks_is_named_as_such() {
        let a = Assembly::new(&samples::cantilever(2)).unwrap();
        let why = unmodelled(a.dofs(), DofRef::new(2, Dof::Uz)).unwrap();
        assert!(why.contains("node 2 has no `uz`") && why.contains("dimension = 3"), "{why}");
        assert_eq!(unmodelled(a.dofs(), DofRef::new(9, Dof::Uy)).unwrap(), "the model has no node 9");
        assert_eq!(
            unmodelled(a.dofs(), DofRef::new(1, Dof::Uy)).unwrap(),
            "1:uy is held fixed by a support of the model"
        );
        assert_eq!(unmodelled(a.dofs(), DofRef::new(2, Dof::Rz)), None);
    }
}

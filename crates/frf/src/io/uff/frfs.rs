//! Dataset 58 FRF records to an [`FrfSet`] on model DOFs.

use std::path::Path;

use fe_model::case::{ChannelMap, MaskRule};
use fe_model::{Dimension, DofRef};
use num_complex::Complex64 as C64;

use super::super::mask::{self, Masked, Origin};
use super::units::abscissa_to_hz;
use super::{
    FUNCTION_COHERENCE, FUNCTION_FRF, Header58, Record58, TestDof, UffFile, frf_units, function_type_name,
    map_test_dof, map_test_dof_in,
};
use crate::error::{FileError, FrfError};
use crate::set::{Channel, FrfKind, FrfSet};

/// The FRFs of a universal file on model DOFs, and what was done to get them.
#[derive(Clone, Debug, PartialEq)]
pub struct UffFrfs {
    /// The FRFs (in the kind of the file's first FRF record, in SI units),
    /// with coherence attached when the file has any.
    pub set: FrfSet,
    /// Where each channel of `set` came from, in the same order.
    pub sources: Vec<ChannelSource>,
    /// Things the user may want to know: skipped datasets, dropped 0 Hz
    /// lines, converted kinds or units, assumptions.
    pub notes: Vec<String>,
    /// What the mask rules left out (see [`read_uff_frfs_with`]).
    pub masked: Vec<Masked>,
}

/// Maps a test DOF of the file to a model DOF and its sign (see
/// [`map_test_dof`]), or says why it cannot.
pub type TestDofMapper<'m> = dyn Fn(TestDof) -> Result<(DofRef, f64), String> + 'm;

impl UffFrfs {
    /// The FRFs as a [`Measured`](crate::io::Measured) set.
    pub fn into_measured(self) -> crate::io::Measured {
        let origins = self.origins();
        let units = self
            .sources
            .iter()
            .map(|s| crate::io::ChannelUnits {
                per_volt: s.per_volt,
                test_reference: Some(s.reference),
                basis: s.units.clone(),
            })
            .collect();
        crate::io::Measured {
            set: self.set,
            format: crate::io::MeasuredFormat::Uff,
            notes: self.notes,
            origins,
            masked: self.masked,
            units,
            pairing: Vec::new(),
        }
    }

    /// Where each channel comes from (`record 3 (line 90)`), for messages.
    pub fn origins(&self) -> Vec<Origin> {
        self.sources
            .iter()
            .map(|s| Origin { line: s.line, label: format!("record {} (line {})", s.record, s.line) })
            .collect()
    }
}

/// The record behind one channel of a [`UffFrfs`].
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelSource {
    /// 1-based record number among the file's datasets 58.
    pub record: usize,
    /// Line of the record.
    pub line: usize,
    /// Response as written in the file.
    pub response: TestDof,
    /// Reference as written in the file.
    pub reference: TestDof,
    /// Factor applied to the file's values: the two direction signs and the
    /// units scale to SI.
    pub factor: f64,
    /// Whether the values are per volt (the reference is a voltage, see
    /// [`FrfUnits::per_volt`](super::FrfUnits::per_volt)).
    pub per_volt: bool,
    /// The units as read, for messages (`` `m/s^2` / `V` ``).
    pub units: String,
}

/// Reads the FRFs of a universal file (see [`frfs_from_uff`]). A record of
/// another function type is refused as soon as its header is read, before
/// its data.
pub fn read_uff_frfs(path: &Path, map: &[ChannelMap]) -> Result<UffFrfs, FrfError> {
    read_uff_frfs_with(path, map, &[])
}

/// Reads the FRFs of a universal file like [`read_uff_frfs`], leaving out
/// what `rules` allow (non-finite values, repeated lines) instead of
/// refusing the file; [`UffFrfs::masked`] lists what was left out.
pub fn read_uff_frfs_with(path: &Path, map: &[ChannelMap], rules: &[MaskRule]) -> Result<UffFrfs, FrfError> {
    read_uff_frfs_in(path, map, rules, Dimension::Planar)
}

/// As [`read_uff_frfs_with`], for a model of dimension `dim` (whose test
/// directions map by default as [`map_test_dof_in`] says).
pub fn read_uff_frfs_in(
    path: &Path,
    map: &[ChannelMap],
    rules: &[MaskRule],
    dim: Dimension,
) -> Result<UffFrfs, FrfError> {
    let bytes = super::read_bytes(path)?;
    let file = super::read::parse_with(path, &bytes, &mut |index, line, h| {
        check_function_type(h).map_err(|m| {
            FrfError::File(FileError::Parse {
                path: path.to_path_buf(),
                line,
                message: format!("record {index} (line {line}): {m}"),
            })
        })
    })?;
    frfs_from_uff_mapped(path, &file, rules, &|dof| map_test_dof_in(dof, map, dim))
}

fn check_function_type(h: &Header58) -> Result<(), String> {
    match h.function_type {
        FUNCTION_FRF | FUNCTION_COHERENCE => Ok(()),
        t => Err(format!(
            "function type {t} ({}) is not a frequency response function; the model can be compared with FRFs \
             (function type 4) and uses their coherence (type 6); export the FRFs from the test system",
            function_type_name(t)
        )),
    }
}

struct Frf {
    record: usize,
    line: usize,
    channel: Channel,
    source: ChannelSource,
    kind: FrfKind,
    freqs: Vec<f64>,
    values: Vec<C64>,
}

/// Turns the FRF records (function type 4) of a parsed file into an
/// [`FrfSet`] on model DOFs:
///
/// - response and reference map through `map` ([`map_test_dof`]), their
///   signs multiply the values;
/// - values are scaled to SI from the units labels ([`frf_units`]);
/// - every FRF must share the same frequency lines; lines at 0 Hz (or below)
///   are dropped, since FRFs are compared at positive frequencies;
/// - records of another kind than the first are converted to its kind by
///   powers of `j w`;
/// - coherence records (type 6) of the same test DOFs are attached, 1 where
///   a channel has none;
/// - other datasets are skipped with a note; other function types are refused.
pub fn frfs_from_uff(path: &Path, file: &UffFile, map: &[ChannelMap]) -> Result<UffFrfs, FrfError> {
    frfs_from_uff_with(path, file, map, &[])
}

/// As [`frfs_from_uff`], leaving out what `rules` allow: lines with a
/// non-finite value in any record, lines that repeat the previous line's
/// frequency within a record.
pub fn frfs_from_uff_with(
    path: &Path,
    file: &UffFile,
    map: &[ChannelMap],
    rules: &[MaskRule],
) -> Result<UffFrfs, FrfError> {
    frfs_from_uff_mapped(path, file, rules, &|dof| map_test_dof(dof, map))
}

/// As [`frfs_from_uff_with`], with test DOFs mapped by `mapper` (pairing
/// by coordinates, see [`super::Pairing`], maps them by position instead of
/// by node number).
pub fn frfs_from_uff_mapped(
    path: &Path,
    file: &UffFile,
    rules: &[MaskRule],
    mapper: &TestDofMapper<'_>,
) -> Result<UffFrfs, FrfError> {
    let err =
        |line: usize, message: String| FrfError::File(FileError::Parse { path: path.to_path_buf(), line, message });
    let mut notes: Vec<String> = file.notes.clone();
    notes.extend(
        file.skipped.iter().map(|d| format!("skipped dataset {} ({}) at line {}", d.number, d.description(), d.line)),
    );
    for r in &file.records {
        check_function_type(&r.function.header).map_err(|m| err(r.line, format!("{}: {m}", r.label())))?;
    }
    if !file.records.iter().any(|r| r.function.header.function_type == FUNCTION_FRF) {
        let held = if file.records.is_empty() && file.skipped.is_empty() {
            "it holds no dataset at all".to_string()
        } else if file.records.is_empty() {
            let mut list: Vec<String> = Vec::new();
            for d in &file.skipped {
                let s = format!("{} ({})", d.number, d.description());
                if !list.contains(&s) {
                    list.push(s);
                }
            }
            format!("it holds no dataset 58, only datasets {}", list.join(", "))
        } else {
            format!("its {} datasets 58 are coherence only", file.records.len())
        };
        return Err(err(1, format!("no frequency response function (dataset 58, function type 4): {held}")));
    }

    let mut frfs: Vec<Frf> = Vec::new();
    let mut masked: Vec<Masked> = Vec::new();
    let mut unstated_hz = Vec::new();
    let mut per_volt: Vec<String> = Vec::new();
    for r in file.records.iter().filter(|r| r.function.header.function_type == FUNCTION_FRF) {
        let h = &r.function.header;
        let at = |m: String| err(r.line, format!("{}: {m}", r.label()));
        let (to_hz, assumed_hz) = abscissa_to_hz(h).map_err(at)?;
        if assumed_hz {
            unstated_hz.push(r.index.to_string());
        }
        let units = frf_units(h).map_err(at)?;
        let (response, s_resp) = mapper(h.response).map_err(|m| at(format!("response {}: {m}", h.response)))?;
        let (reference, s_ref) = mapper(h.reference).map_err(|m| at(format!("reference {}: {m}", h.reference)))?;
        if !(units.scale.is_finite() && units.scale > 0.0) {
            return Err(at(format!("the units {} give a scale of {} to SI", units.basis, units.scale)));
        }
        let factor = s_resp * s_ref * units.scale;
        if units.per_volt {
            per_volt.push(format!("{} ({})", r.index, units.basis));
        }
        if units.assumed_si {
            notes.push(format!("{}: units not stated ({}); SI assumed", r.label(), units.basis));
        } else if units.scale != 1.0 {
            notes.push(format!("{}: values in {} scaled by {} to SI", r.label(), units.basis, units.scale));
        }
        let (freqs, values, dropped) = positive_lines(r, to_hz, |v| v * factor);
        if dropped > 0 && !freqs.is_empty() {
            notes.push(format!(
                "{}: dropped {dropped} line(s) at 0 Hz or below (FRFs are compared at positive frequencies)",
                r.label()
            ));
        }
        if freqs.is_empty() {
            let why = if r.function.is_empty() {
                "it declares no values (record 7 gives 0 data points)".to_string()
            } else {
                format!(
                    "its {} line(s) are all at 0 Hz or below, and FRFs are compared at positive frequencies",
                    dropped
                )
            };
            return Err(at(format!("no frequency line to compare: {why}")));
        }
        let place = |_: usize| (r.line, format!("{}: ", r.label()));
        let (keep, repeats) = mask::duplicate_lines(path, &freqs, &place, rules.contains(&MaskRule::DuplicateLines))?;
        let (freqs, values) = if repeats.is_empty() {
            (freqs, values)
        } else {
            masked.extend(repeats);
            (keep.iter().map(|&k| freqs[k]).collect(), keep.iter().map(|&k| values[k]).collect())
        };
        let channel = Channel::new(response, reference);
        let source = ChannelSource {
            record: r.index,
            line: r.line,
            response: h.response,
            reference: h.reference,
            factor,
            per_volt: units.per_volt,
            units: units.basis.clone(),
        };
        frfs.push(Frf { record: r.index, line: r.line, channel, source, kind: units.kind, freqs, values });
    }
    if !per_volt.is_empty() {
        notes.push(format!(
            "record(s) {} are per volt: their reference is a voltage, not a force; the case must fit a gain (the \
             default) or give a calibration",
            per_volt.join(", ")
        ));
    }
    if !unstated_hz.is_empty() {
        notes.push(format!("record(s) {} do not state the abscissa units; Hz assumed", unstated_hz.join(", ")));
    }

    // common lines, one kind, distinct channels
    let Some(first) = frfs.first() else {
        return Err(err(1, "no frequency response function (dataset 58, function type 4)".into()));
    };
    let (freqs, kind) = (first.freqs.clone(), first.kind);
    let mut seen: std::collections::HashMap<Channel, usize> = std::collections::HashMap::new();
    seen.insert(first.channel, 0);
    for (i, f) in frfs.iter().enumerate().skip(1) {
        if !same_lines(&f.freqs, &freqs) {
            return Err(err(
                f.line,
                format!(
                    "record {} (line {}): its {} lines ({}) differ from those of record {} ({}); every FRF of a file \
                     must share the same frequency lines",
                    f.record,
                    f.line,
                    f.freqs.len(),
                    span(&f.freqs),
                    first.record,
                    span(&freqs)
                ),
            ));
        }
        if let Some(other) = seen.get(&f.channel).map(|&i| &frfs[i]) {
            return Err(err(
                f.line,
                format!(
                    "record {} (line {}) and record {} (line {}) both give {}; map test DOFs to distinct model DOFs",
                    f.record, f.line, other.record, other.line, f.channel
                ),
            ));
        }
        seen.insert(f.channel, i);
    }
    let converted: Vec<usize> = frfs.iter().filter(|f| f.kind != kind).map(|f| f.record).collect();
    if !converted.is_empty() {
        notes.push(format!(
            "converted record(s) {} to {kind}, the kind of record {}, by powers of j w",
            converted.iter().map(ToString::to_string).collect::<Vec<_>>().join(", "),
            first.record
        ));
    }
    let channels: Vec<Channel> = frfs.iter().map(|f| f.channel).collect();
    let mut set = FrfSet::zeros(freqs.clone(), channels, kind)
        .map_err(|e| err(first.line, format!("record {} (line {}): {e}", first.record, first.line)))?;
    for (c, f) in frfs.iter().enumerate() {
        for (k, (&hz, &v)) in freqs.iter().zip(&f.values).enumerate() {
            // converted only when needed: (j w)^p / (j w)^p is not exactly 1 in floating point
            let v = if f.kind == kind {
                v
            } else {
                let w = 2.0 * std::f64::consts::PI * hz;
                v * kind.from_receptance_factor(w) / f.kind.from_receptance_factor(w)
            };
            set.set(c, k, v);
        }
    }

    attach_coherence(path, file, mapper, &mut set, &mut notes, &mut masked, rules.contains(&MaskRule::BadCoherence))?;
    let locate = |c: usize, _: usize| (frfs[c].line, format!("record {} (line {})", frfs[c].record, frfs[c].line));
    let (set, more) = mask::non_finite_lines(path, set, rules.contains(&MaskRule::NonFinite), &locate)?;
    masked.extend(more);
    let sources = frfs.into_iter().map(|f| f.source).collect();
    Ok(UffFrfs { set, sources, notes, masked })
}

/// The record's positive-frequency lines (Hz) and its values through `f`;
/// how many lines were dropped.
fn positive_lines(r: &Record58, to_hz: f64, f: impl Fn(C64) -> C64) -> (Vec<f64>, Vec<C64>, usize) {
    let mut freqs = Vec::with_capacity(r.function.len());
    let mut values = Vec::with_capacity(r.function.len());
    let mut dropped = 0;
    for k in 0..r.function.len() {
        let (Some(x), Some(v)) = (r.function.abscissa_at(k), r.function.ordinates.get(k)) else { continue };
        let hz = x * to_hz;
        // a NaN frequency is kept here to be refused, with its record, by the line checks
        if hz > 0.0 || hz.is_nan() {
            freqs.push(hz);
            values.push(f(v));
        } else {
            dropped += 1;
        }
    }
    (freqs, values, dropped)
}

fn same_lines(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()))
}

fn span(f: &[f64]) -> String {
    match (f.first(), f.last()) {
        (Some(a), Some(b)) => format!("{a} to {b} Hz"),
        _ => "none".into(),
    }
}

fn attach_coherence(
    path: &Path,
    file: &UffFile,
    mapper: &TestDofMapper<'_>,
    set: &mut FrfSet,
    notes: &mut Vec<String>,
    masked: &mut Vec<Masked>,
    allow_bad: bool,
) -> Result<(), FrfError> {
    let nf = set.n_freq();
    let nc = set.channels().len();
    let index = set.channel_indices();
    let mut coh: Vec<Option<Vec<f64>>> = vec![None; nc];
    for r in file.records.iter().filter(|r| r.function.header.function_type == FUNCTION_COHERENCE) {
        let h = &r.function.header;
        let label = r.label();
        let channel = match (mapper(h.response), mapper(h.reference)) {
            (Ok((a, _)), Ok((b, _))) => Channel::new(a, b),
            _ => {
                notes.push(format!(
                    "{label}: coherence of {} / {} ignored: its DOFs are not mapped",
                    h.response, h.reference
                ));
                continue;
            }
        };
        let Some(&c) = index.get(&channel) else {
            notes.push(format!("{label}: coherence of {channel} ignored: the file has no FRF for it"));
            continue;
        };
        let to_hz = abscissa_to_hz(h).map_or(1.0, |(s, _)| s);
        let (freqs, values, _) = positive_lines(r, to_hz, |v| v);
        if !same_lines(&freqs, set.frequencies_hz()) {
            notes.push(format!("{label}: coherence of {channel} ignored: its lines differ from the FRFs'"));
            continue;
        }
        let values: Vec<f64> = values.iter().map(|v| v.re).collect();
        // a coherence is a squared correlation: anything outside 0..1 (beyond
        // the rounding of a written file) or NaN is not one
        if let Some(k) = values.iter().position(|g| !(-1e-6..=1.0 + 1e-6).contains(g)) {
            let detail = format!("{label}: coherence of {channel} at {} Hz is {}, outside 0..1", freqs[k], values[k]);
            if !allow_bad {
                return Err(FrfError::File(FileError::Parse {
                    path: path.to_path_buf(),
                    line: r.line,
                    message: format!("{detail}; {}", mask::hint(MaskRule::BadCoherence, "such coherence records")),
                }));
            }
            masked.push(Masked {
                rule: MaskRule::BadCoherence,
                freq_hz: Some(freqs[k]),
                channel: Some(channel),
                detail,
            });
            continue;
        }
        if coh[c].is_some() {
            notes.push(format!("{label}: a second coherence of {channel} ignored"));
            continue;
        }
        coh[c] = Some(values.iter().map(|g| g.clamp(0.0, 1.0)).collect());
    }
    let have = coh.iter().filter(|c| c.is_some()).count();
    if have == 0 {
        return Ok(());
    }
    if have < nc {
        let missing: Vec<String> =
            coh.iter().zip(set.channels()).filter(|(c, _)| c.is_none()).map(|(_, ch)| ch.to_string()).collect();
        notes.push(format!("no coherence for {}; taken as 1", missing.join(", ")));
    }
    let values = coh.into_iter().flat_map(|c| c.unwrap_or_else(|| vec![1.0; nf])).collect();
    // lengths agree by construction (every attached vector has the FRFs' lines)
    if let Err(e) = set.set_coherence(values) {
        notes.push(format!("coherence not attached: {e}"));
    }
    Ok(())
}

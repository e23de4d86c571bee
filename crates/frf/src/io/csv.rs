//! Plain CSV FRF files.
//!
//! Layout (comma, semicolon or tab separated; lines starting with `#` are
//! comments, of which three are read):
//!
//! ```text
//! # kind = receptance
//! # units = SI
//! frequency_hz,"H(31:uy,31:uy).re","H(31:uy,31:uy).im","H(16:uy,31:uy).re","H(16:uy,31:uy).im"
//! 1.0,1.2e-5,-3.1e-8,6.0e-6,-1.4e-8
//! ```
//!
//! - `# units = g/N` (any label of the units parser: `m/N`, `mm/N`, `m/s/N`,
//!   `(m/s^2)/V`, ...) gives the kind and the scale to SI of every channel;
//!   `# units = SI` says that the values are in m, m/s or m/s^2 per N (rad
//!   and N m for rotations and moments). `# kind = accelerance` names the
//!   kind; with units it must agree with them. Without units, SI is assumed
//!   with a note; without kind or units, receptance in SI, with a note.
//! - The first column is the frequency. Its name says the units:
//!   `frequency_hz`, `freq (Hz)`, `frequency_khz`, `omega_rad_s`,
//!   `frequency [rad/s]`; a name without units (`freq`) is read in Hz with
//!   a note, and units rfm cannot read are refused.
//! - Each channel takes two columns, `.re` and `.im`, or `.mag` and
//!   `.phase_deg` (or `.phase_rad`). Channel names are
//!   `H(response,reference)` with DOFs written `node:dof`, quoted when the
//!   separator is a comma (rfm writes them quoted, so that standard CSV
//!   readers keep them whole; unquoted names are read too).
//! - A single channel may come as `freq,re,im` (or `real`/`imag`,
//!   `mag`/`phase_deg`): its channel is named by a `# channel = H(31:uy,1:uy)`
//!   line, or is the one channel the case measures.

use std::path::Path;

use fe_model::DofRef;
use fe_model::case::MaskRule;
use num_complex::Complex64 as C64;

use super::mask::{Masked, Origin};
use crate::error::{FileError, FrfError};
use crate::set::{Channel, FrfKind, FrfSet};

/// Writes a set as CSV (real and imaginary parts), atomically.
pub fn write_csv(set: &FrfSet, path: &Path) -> Result<(), FrfError> {
    super::atomic_write(path, to_csv_string(set).as_bytes(), &[])
}

/// The CSV text of a set: the kind, `# units = SI`, a header whose channel
/// names are quoted (they hold commas), and one row per line with every
/// digit a double needs.
pub fn to_csv_string(set: &FrfSet) -> String {
    to_csv_string_as(set, false)
}

/// The CSV text of a set (see [`to_csv_string`]) whose values are per volt
/// when `per_volt` (`# units = SI/V`), so that reading it back keeps the
/// fact that its level holds an unknown gain.
pub fn to_csv_string_as(set: &FrfSet, per_volt: bool) -> String {
    let mut s = String::new();
    s.push_str(&format!("# kind = {}\n# units = {}\n", set.kind(), if per_volt { "SI/V" } else { "SI" }));
    s.push_str("frequency_hz");
    for c in set.channels() {
        s.push_str(&format!(",\"{c}.re\",\"{c}.im\""));
    }
    s.push('\n');
    for (k, f) in set.frequencies_hz().iter().enumerate() {
        s.push_str(&format!("{f}"));
        for c in 0..set.channels().len() {
            let v = set.get(c, k);
            s.push_str(&format!(",{:e},{:e}", v.re, v.im));
        }
        s.push('\n');
    }
    s
}

/// Splits a line at `sep`, except inside parentheses or double quotes, so
/// that channel names like `H(31:uy,31:uy).re` stay whole.
fn split_fields(line: &str, sep: char) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut quoted, mut start) = (0i32, false, 0);
    for (i, ch) in line.char_indices() {
        match ch {
            '"' => quoted = !quoted,
            '(' if !quoted => depth += 1,
            ')' if !quoted => depth -= 1,
            c if c == sep && depth == 0 && !quoted => {
                out.push(&line[start..i]);
                start = i + ch.len_utf8();
            }
            _ => {}
        }
    }
    out.push(&line[start..]);
    out
}

#[derive(Clone, Copy)]
enum Pair {
    ReIm,
    MagPhase { radians: bool },
}

fn pair_of(p1: &str, p2: &str) -> Option<Pair> {
    let p1 = p1.trim().to_ascii_lowercase();
    let p2 = p2.trim().to_ascii_lowercase().replace([' ', '(', ')', '[', ']'], "_");
    let p2 = p2.trim_matches('_');
    match (p1.as_str(), p2) {
        ("re" | "real", "im" | "imag" | "imaginary") => Some(Pair::ReIm),
        ("mag" | "magnitude" | "abs", "phase_deg" | "phase__deg" | "phase_degrees") => {
            Some(Pair::MagPhase { radians: false })
        }
        ("mag" | "magnitude" | "abs", "phase_rad" | "phase__rad" | "phase_radians") => {
            Some(Pair::MagPhase { radians: true })
        }
        _ => None,
    }
}

fn parse_channel(name: &str) -> Option<(Channel, &str)> {
    let name = name.trim().trim_matches('"');
    let (head, part) = name.rsplit_once('.')?;
    let inner = head.strip_prefix("H(")?.strip_suffix(')')?;
    let (resp, reference) = inner.split_once(',')?;
    let response: DofRef = resp.trim().parse().ok()?;
    let reference: DofRef = reference.trim().parse().ok()?;
    Some((Channel::new(response, reference), part))
}

fn parse_channel_name(name: &str) -> Option<Channel> {
    let inner = name.trim().trim_matches('"').strip_prefix("H(")?.strip_suffix(')')?;
    let (resp, reference) = inner.split_once(',')?;
    Some(Channel::new(resp.trim().parse().ok()?, reference.trim().parse().ok()?))
}

/// The factor from a frequency column's units to Hz, read from its name,
/// and whether the name states none (Hz is then taken, with a note).
fn frequency_units(name: &str) -> Result<(f64, bool), String> {
    let lower = name.trim().trim_matches('"').to_ascii_lowercase();
    let rest = ["frequency", "freq", "omega", "f", "w"]
        .into_iter()
        .find_map(|p| lower.strip_prefix(p).map(|r| (p, r)))
        .filter(|(_, r)| r.is_empty() || r.starts_with(|c: char| !c.is_ascii_alphanumeric()));
    let Some((prefix, rest)) = rest else {
        return Err(format!("the first column must be the frequency (e.g. `frequency_hz`), found `{name}`"));
    };
    let units: String = rest.chars().filter(|c| !matches!(c, ' ' | '_' | '-' | '(' | ')' | '[' | ']' | ':')).collect();
    let angular = matches!(prefix, "omega" | "w");
    match units.as_str() {
        "" if angular => Ok((1.0 / (2.0 * std::f64::consts::PI), true)),
        "" => Ok((1.0, true)),
        "hz" if !angular => Ok((1.0, false)),
        "khz" if !angular => Ok((1e3, false)),
        "rad/s" | "rads" | "rad/sec" | "radpers" => Ok((1.0 / (2.0 * std::f64::consts::PI), false)),
        _ => Err(format!(
            "the frequency column `{name}` is in `{units}`, which rfm does not read as a frequency; name it \
             frequency_hz, frequency_khz or frequency_rad_s"
        )),
    }
}

/// Reads a CSV FRF file (see the module docs). Non-finite values and
/// repeated lines are refused; see [`read_csv_with`] to leave them out.
pub fn read_csv(path: &Path) -> Result<FrfSet, FrfError> {
    read_csv_with(path, &[]).map(|r| r.set)
}

/// A CSV file read with mask rules.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvFrfs {
    /// The FRFs, in SI units.
    pub set: FrfSet,
    /// Where each channel comes from (its columns), in the set's order.
    pub origins: Vec<Origin>,
    /// What the rules left out.
    pub masked: Vec<Masked>,
    /// What reading changed or assumed (units scaled, SI or Hz assumed).
    pub notes: Vec<String>,
    /// Whether the values are per volt (`# units = (m/s^2)/V`).
    pub per_volt: bool,
    /// The units as the file states them, for messages (`` `g/N` ``, or
    /// `SI assumed`).
    pub units: String,
}

/// Options of [`read_csv_opts`].
#[derive(Clone, Copy, Debug, Default)]
pub struct CsvOptions<'a> {
    /// What to leave out instead of refusing.
    pub rules: &'a [MaskRule],
    /// The channel of a single-channel file whose columns name none
    /// (`freq,re,im`) and that has no `# channel = ...` line.
    pub channel: Option<Channel>,
}

/// Reads a CSV FRF file, leaving out what `rules` allow (non-finite values,
/// repeated lines; see [`MaskRule`]).
pub fn read_csv_with(path: &Path, rules: &[MaskRule]) -> Result<CsvFrfs, FrfError> {
    read_csv_opts(path, &CsvOptions { rules, channel: None })
}

/// Reads a CSV FRF file with [`CsvOptions`].
pub fn read_csv_opts(path: &Path, opts: &CsvOptions<'_>) -> Result<CsvFrfs, FrfError> {
    let bytes = std::fs::read(path).map_err(|e| {
        FrfError::File(FileError::Io { path: path.to_path_buf(), message: format!("cannot read: {e}") })
    })?;
    let text = fe_model::text::decode(&bytes).map_err(|e| {
        FrfError::File(FileError::Parse { path: path.to_path_buf(), line: e.line, message: e.to_string() })
    })?;
    parse_csv_opts(path, text, opts)
}

/// Parses CSV text; `path` is used in messages.
pub fn parse_csv(path: &Path, text: &str) -> Result<FrfSet, FrfError> {
    parse_csv_with(path, text, &[]).map(|r| r.set)
}

/// A number of a data field: decimal, or `NaN`/`inf` (refused or masked later).
fn field_number(s: &str) -> Option<f64> {
    let t = s.trim().trim_matches('"');
    super::non_finite_word(t).or_else(|| if t.bytes().any(|b| b.is_ascii_digit()) { t.parse().ok() } else { None })
}

/// Parses CSV text with mask rules; `path` is used in messages.
pub fn parse_csv_with(path: &Path, text: &str, rules: &[MaskRule]) -> Result<CsvFrfs, FrfError> {
    parse_csv_opts(path, text, &CsvOptions { rules, channel: None })
}

/// What the comment lines declare, with their lines.
#[derive(Default)]
struct Declared {
    kind: Option<(usize, FrfKind)>,
    units: Option<(usize, String)>,
    channel: Option<(usize, Channel)>,
}

/// Parses CSV text with [`CsvOptions`]; `path` is used in messages.
pub fn parse_csv_opts(path: &Path, text: &str, opts: &CsvOptions<'_>) -> Result<CsvFrfs, FrfError> {
    let rules = opts.rules;
    let err =
        |line: usize, message: String| FrfError::File(FileError::Parse { path: path.to_path_buf(), line, message });
    let mut declared = Declared::default();
    let mut header: Option<(usize, Vec<String>, char)> = None;
    let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            if let Some((k, v)) = comment.split_once('=') {
                match k.trim() {
                    "kind" => {
                        let kind = FrfKind::parse(v).ok_or_else(|| {
                            err(line_no, format!("unknown kind `{}` (receptance, mobility or accelerance)", v.trim()))
                        })?;
                        declared.kind = Some((line_no, kind));
                    }
                    "units" => declared.units = Some((line_no, v.trim().to_string())),
                    "channel" => {
                        let c = parse_channel_name(v).ok_or_else(|| {
                            err(line_no, format!("`{}` is not a channel name like H(31:uy,1:uy)", v.trim()))
                        })?;
                        declared.channel = Some((line_no, c));
                    }
                    _ => {}
                }
            }
            continue;
        }
        match &header {
            None => {
                let sep = [';', '\t'].into_iter().find(|&c| line.contains(c)).unwrap_or(',');
                let cols: Vec<String> = split_fields(line, sep).into_iter().map(|s| s.trim().to_string()).collect();
                // checked here, before any data row, so that a file in another layout is
                // refused at its first line rather than at a row it cannot parse
                frequency_units(&cols[0]).map_err(|m| err(line_no, m))?;
                header = Some((line_no, cols, sep));
            }
            Some((_, cols, sep)) => {
                let fields: Vec<&str> = split_fields(line, *sep);
                if fields.len() != cols.len() {
                    return Err(err(line_no, format!("{} fields, but the header has {}", fields.len(), cols.len())));
                }
                let values = fields
                    .iter()
                    .enumerate()
                    .map(|(j, f)| {
                        field_number(f).ok_or_else(|| {
                            err(line_no, format!("column {} (`{}`): `{}` is not a number", j + 1, cols[j], f.trim()))
                        })
                    })
                    .collect::<Result<Vec<f64>, _>>()?;
                if !values[0].is_finite() {
                    return Err(err(line_no, format!("column 1 (`{}`): the frequency is {}", cols[0], values[0])));
                }
                rows.push((line_no, values));
            }
        }
    }
    let (hline, cols, _) = header.ok_or_else(|| err(1, "no header line".into()))?;
    let (to_hz, hz_unstated) = frequency_units(&cols[0]).map_err(|m| err(hline, m))?;
    let mut notes = Vec::new();
    if hz_unstated {
        let unit = if to_hz == 1.0 { "Hz" } else { "rad/s" };
        notes.push(format!("line {hline}: the frequency column `{}` states no units; {unit} assumed", cols[0]));
    }
    if cols.len() < 3 || (cols.len() - 1) % 2 != 0 {
        return Err(err(
            hline,
            "after the frequency column, each channel needs two columns (.re and .im, or .mag and .phase_deg)".into(),
        ));
    }
    let mut channels = Vec::new();
    let mut pairs = Vec::new();
    let mut origins = Vec::new();
    // where each channel was seen, so that a repeat is found in linear time
    let mut seen: std::collections::HashMap<Channel, usize> = std::collections::HashMap::new();
    // a single channel whose columns name none: `freq,re,im`
    if cols.len() == 3
        && parse_channel(&cols[1]).is_none()
        && let Some(pair) = pair_of(&cols[1], &cols[2])
    {
        let channel = match (declared.channel, opts.channel) {
            (Some((_, c)), _) => c,
            (None, Some(c)) => {
                notes.push(format!(
                    "line {hline}: columns `{}`, `{}` name no channel; taken as {c}, the one channel the case \
                     measures",
                    cols[1], cols[2]
                ));
                c
            }
            (None, None) => {
                return Err(err(
                    hline,
                    format!(
                        "columns `{}` and `{}` name no channel; add a line `# channel = H(response,reference)` \
                         (e.g. `# channel = H(31:uy,1:uy)`), or name the columns H(31:uy,1:uy).re and \
                         H(31:uy,1:uy).im",
                        cols[1], cols[2]
                    ),
                ));
            }
        };
        channels.push(channel);
        pairs.push(pair);
        origins.push(Origin { line: hline, label: "columns 2-3".into() });
    } else {
        if let Some((line, c)) = declared.channel {
            return Err(err(line, format!("`# channel = {c}` applies to a file with columns re and im only")));
        }
        for j in (1..cols.len()).step_by(2) {
            let (c1, p1) = parse_channel(&cols[j]).ok_or_else(|| {
                err(hline, format!("column {} `{}` is not a channel name like H(31:uy,31:uy).re", j + 1, cols[j]))
            })?;
            let (c2, p2) = parse_channel(&cols[j + 1]).ok_or_else(|| {
                err(hline, format!("column {} `{}` is not a channel name like H(31:uy,31:uy).im", j + 2, cols[j + 1]))
            })?;
            if c1 != c2 {
                return Err(err(hline, format!("columns {} and {} belong to different channels", j + 1, j + 2)));
            }
            let pair = pair_of(p1, p2).ok_or_else(|| {
                err(
                    hline,
                    format!(
                        "channel {c1}: expected .re/.im or .mag/.phase_deg (or .phase_rad) columns, found .{p1}/.{p2}"
                    ),
                )
            })?;
            if let Some(&other) = seen.get(&c1) {
                return Err(err(
                    hline,
                    format!("channel {c1} appears twice (columns {} and {})", 2 * other + 2, j + 1),
                ));
            }
            seen.insert(c1, channels.len());
            channels.push(c1);
            pairs.push(pair);
            origins.push(Origin { line: hline, label: format!("columns {}-{}", j + 1, j + 2) });
        }
    }
    let (kind, scale, per_volt, units) = units_of(&declared, &channels, &mut notes).map_err(|(l, m)| err(l, m))?;
    if rows.is_empty() {
        return Err(err(hline, "no data rows".into()));
    }
    for r in &mut rows {
        r.1[0] *= to_hz;
    }
    if let Some((line, r)) = rows.iter().find(|(_, r)| !(r[0] > 0.0)) {
        return Err(err(*line, format!("frequency {} Hz must be positive", r[0])));
    }
    let freqs: Vec<f64> = rows.iter().map(|(_, r)| r[0]).collect();
    let allow_repeats = rules.contains(&MaskRule::DuplicateLines);
    let at = |k: usize| (rows[k].0, format!("line {}: ", rows[k].0));
    let (keep, mut masked) = super::mask::duplicate_lines(path, &freqs, &at, allow_repeats)?;
    let rows: Vec<&(usize, Vec<f64>)> = keep.iter().map(|&k| &rows[k]).collect();
    let mut set = FrfSet::zeros(rows.iter().map(|(_, r)| r[0]).collect(), channels, kind)?;
    for (k, (_, r)) in rows.iter().enumerate() {
        for (c, pair) in pairs.iter().enumerate() {
            let (a, b) = (r[1 + 2 * c], r[2 + 2 * c]);
            let v = match pair {
                Pair::ReIm => C64::new(a, b),
                Pair::MagPhase { radians: false } => C64::from_polar(a, b.to_radians()),
                Pair::MagPhase { radians: true } => C64::from_polar(a, b),
            };
            set.set(c, k, v * scale);
        }
    }
    let locate = |c: usize, k: usize| {
        let line = rows[k].0;
        (line, format!("line {line}, columns {}-{}", 2 * c + 2, 2 * c + 3))
    };
    let (set, more) = super::mask::non_finite_lines(path, set, rules.contains(&MaskRule::NonFinite), &locate)?;
    masked.extend(more);
    Ok(CsvFrfs { set, origins, masked, notes, per_volt, units })
}

/// The kind, the factor to SI, whether per volt, and the units as stated,
/// from the `# kind` and `# units` lines; notes what was assumed. Errors
/// carry the line of the declaration they concern.
fn units_of(
    d: &Declared,
    channels: &[Channel],
    notes: &mut Vec<String>,
) -> Result<(FrfKind, f64, bool, String), (usize, String)> {
    let Some((line, label)) = &d.units else {
        return Ok(match d.kind {
            Some((_, kind)) => {
                notes.push(format!("no `# units` line: {kind} in SI (m, m/s or m/s^2 per N) assumed"));
                (kind, 1.0, false, "SI assumed".into())
            }
            None => {
                notes.push("no `# kind` or `# units` line: receptance in SI (m/N) assumed".into());
                (FrfKind::Receptance, 1.0, false, "SI assumed".into())
            }
        });
    };
    // `SI` (per newton) or `SI/V` (per volt): m, m/s or m/s^2 (rad for rotations) of the declared kind
    let si = label.replace(' ', "").to_ascii_lowercase();
    if si == "si" || si == "si/v" {
        let Some((_, kind)) = d.kind else {
            return Err((
                *line,
                format!("`# units = {label}` needs a `# kind = ...` line (receptance, mobility or accelerance)"),
            ));
        };
        let per_volt = si == "si/v";
        if per_volt {
            notes.push(format!(
                "the values are per volt ({label}): the reference is a voltage, not a force; the case must fit a \
                 gain (the default) or give a calibration"
            ));
        }
        return Ok((kind, 1.0, per_volt, label.clone()));
    }
    let (kind, scale, per_volt) = super::uff::units::label_units(label).map_err(|m| (*line, m))?;
    if let Some((kline, declared)) = d.kind
        && declared != kind
    {
        return Err((
            kline,
            format!("`# kind = {declared}` contradicts `# units = {label}` (line {line}), which say {kind}"),
        ));
    }
    // a scale of lengths cannot apply to angles or moments
    if scale != 1.0
        && let Some(c) = channels.iter().find(|c| !c.response.dof.is_translation() || !c.reference.dof.is_translation())
    {
        return Err((
            *line,
            format!(
                "`# units = {label}` scale lengths by {scale}, which does not apply to the rotation or moment of \
                 channel {c}; give rotational channels in a file of their own, in SI"
            ),
        ));
    }
    if scale != 1.0 {
        notes.push(format!("values in {label} scaled by {scale} to SI"));
    }
    if per_volt {
        notes.push(format!(
            "the values are per volt ({label}): the reference is a voltage, not a force; the case must fit a gain \
             (the default) or give a calibration"
        ));
    }
    Ok((kind, scale, per_volt, format!("`{label}`")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    #[test]
    fn csv_round_trips_exactly() {
        let ch = vec![
            Channel::new(DofRef::new(31, Dof::Uy), DofRef::new(31, Dof::Uy)),
            Channel::new(DofRef::new(16, Dof::Uy), DofRef::new(31, Dof::Uy)),
        ];
        let mut s = FrfSet::zeros(vec![1.0, 2.5, 400.0], ch, FrfKind::Accelerance).unwrap();
        for c in 0..2 {
            for k in 0..3 {
                s.set(c, k, C64::new(1.0 / 3.0 + c as f64, -(k as f64).exp() * 1e-7));
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("h.csv");
        write_csv(&s, &p).unwrap();
        assert_eq!(read_csv(&p).unwrap(), s);
    }

    #[test]
    fn magnitude_phase_columns_and_errors_with_line_numbers() {
        let p = Path::new("m.csv");
        let ok = "freq,H(2:uy,2:uy).mag,H(2:uy,2:uy).phase_deg\n10,2.0,90\n";
        let s = parse_csv(p, ok).unwrap();
        assert!((s.get(0, 0) - C64::new(0.0, 2.0)).norm() < 1e-12);
        let bad = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1,0\n9,1,0\n";
        let e = parse_csv(p, bad).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:3: line 3: frequency 2 (9 Hz) is below the one before it"), "{e}");
        let bad = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1,x\n";
        let e = parse_csv(p, bad).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:2:") && e.contains("`x` is not a number"), "{e}");
        let bad = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1,NaN\n";
        let e = parse_csv(p, bad).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:2: line 2, columns 2-3: H(2:uy,2:uy) at 10 Hz is NaN"), "{e}");
        assert!(e.contains("mask = [\"non-finite\"]"), "{e}");
    }

    #[test]
    fn masks_leave_out_non_finite_and_repeated_lines_and_say_which() {
        let p = Path::new("m.csv");
        let text = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im,H(3:uy,2:uy).re,H(3:uy,2:uy).im\n\
                    10,1,0,1,0\n20,2,0,inf,0\n20,2,0,2,0\n30,3,0,nan,0\n40,4,0,4,0\n";
        // the frequency axis is checked before the values
        for rules in [&[][..], &[MaskRule::NonFinite]] {
            let e = parse_csv_with(p, text, rules).unwrap_err().to_string();
            assert!(
                e.starts_with("m.csv:4: line 4: frequency 3 repeats 20 Hz") && e.contains("duplicate-lines"),
                "{e}"
            );
        }
        let e = parse_csv_with(p, text, &[MaskRule::DuplicateLines]).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:3: line 3, columns 4-5: H(3:uy,2:uy) at 20 Hz is inf+0i"), "{e}");
        assert!(e.contains("(2 lines have such values)") && e.contains("non-finite"), "{e}");
        let r = parse_csv_with(p, text, &[MaskRule::DuplicateLines, MaskRule::NonFinite]).unwrap();
        assert_eq!(r.set.frequencies_hz(), &[10.0, 40.0]);
        assert_eq!(r.set.get(1, 1), C64::new(4.0, 0.0));
        let what: Vec<(MaskRule, Option<f64>)> = r.masked.iter().map(|m| (m.rule, m.freq_hz)).collect();
        assert_eq!(
            what,
            vec![
                (MaskRule::DuplicateLines, Some(20.0)),
                (MaskRule::NonFinite, Some(20.0)),
                (MaskRule::NonFinite, Some(30.0))
            ]
        );
        assert_eq!(r.masked[0].detail, "line 4: frequency 3 repeats 20 Hz");
        assert_eq!(r.masked[2].detail, "line 5, columns 4-5: H(3:uy,2:uy) at 30 Hz is NaN");
        assert_eq!(r.origins[1], Origin { line: 1, label: "columns 4-5".into() });
    }

    #[test]
    fn units_lines_decide_kind_and_scale_and_a_missing_one_is_noted() {
        let p = Path::new("m.csv");
        let body = "frequency_hz,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1.5,-2\n";
        let r = parse_csv_with(p, &format!("# units = g/N\n{body}"), &[]).unwrap();
        assert_eq!(r.set.kind(), FrfKind::Accelerance);
        // g is the standard gravity: 9.80665 m/s^2 exactly
        assert_eq!(r.set.get(0, 0), C64::new(1.5 * 9.80665, -2.0 * 9.80665));
        assert_eq!(r.notes, vec!["values in g/N scaled by 9.80665 to SI".to_string()]);
        assert!(!r.per_volt);
        let r = parse_csv_with(p, &format!("# units = (m/s^2)/V\n{body}"), &[]).unwrap();
        assert!(r.per_volt && r.notes[0].contains("per volt"), "{:?}", r.notes);
        assert_eq!(r.set.get(0, 0), C64::new(1.5, -2.0));
        let r = parse_csv_with(p, &format!("# kind = mobility\n{body}"), &[]).unwrap();
        assert_eq!(r.notes, vec!["no `# units` line: mobility in SI (m, m/s or m/s^2 per N) assumed".to_string()]);
        let r = parse_csv_with(p, body, &[]).unwrap();
        assert!(r.notes[0].contains("receptance in SI (m/N) assumed"), "{:?}", r.notes);
        let e = parse_csv_with(p, &format!("# kind = receptance\n# units = g/N\n{body}"), &[]).unwrap_err();
        assert!(
            e.to_string().starts_with("m.csv:1: `# kind = receptance` contradicts `# units = g/N` (line 2)"),
            "{e}"
        );
        let e = parse_csv_with(p, &format!("# units = furlong/N\n{body}"), &[]).unwrap_err();
        assert!(e.to_string().starts_with("m.csv:1: `furlong/N` is not a units label rfm can read"), "{e}");
        let rot = "frequency_hz,H(2:rz,2:uy).re,H(2:rz,2:uy).im\n10,1,0\n";
        let e = parse_csv_with(p, &format!("# units = mm/N\n{rot}"), &[]).unwrap_err();
        assert!(e.to_string().contains("does not apply to the rotation or moment of channel H(2:rz,2:uy)"), "{e}");
    }

    #[test]
    fn frequency_columns_in_khz_or_rad_s_are_converted_and_unknown_units_refused() {
        let p = Path::new("m.csv");
        let rest = ",H(2:uy,2:uy).re,H(2:uy,2:uy).im\n0.5,1,0\n";
        let hz = |head: &str| parse_csv_with(p, &format!("# kind = receptance\n# units = SI\n{head}{rest}"), &[]);
        assert_eq!(hz("frequency_khz").unwrap().set.frequencies_hz(), &[500.0]);
        assert_eq!(hz("frequency (kHz)").unwrap().set.frequencies_hz(), &[500.0]);
        let w = hz("omega_rad_s").unwrap().set.frequencies_hz()[0];
        assert!((w - 0.5 / (2.0 * std::f64::consts::PI)).abs() < 1e-15, "{w}");
        assert_eq!(hz("frequency [rad/s]").unwrap().set.frequencies_hz()[0], w);
        let r = hz("freq").unwrap();
        assert_eq!(r.set.frequencies_hz(), &[0.5]);
        assert_eq!(r.notes, vec!["line 3: the frequency column `freq` states no units; Hz assumed".to_string()]);
        assert!(hz("frequency_hz").unwrap().notes.is_empty());
        for bad in ["frequency_cpm", "freq (MHz)", "frequency_rpm"] {
            let e = hz(bad).unwrap_err().to_string();
            assert!(e.starts_with("m.csv:3: the frequency column") && e.contains("frequency_khz"), "{bad}: {e}");
        }
        let e = hz("time_s").unwrap_err().to_string();
        assert!(e.contains("the first column must be the frequency"), "{e}");
    }

    #[test]
    fn a_single_channel_without_names_takes_the_declared_or_the_cases_channel() {
        let p = Path::new("m.csv");
        let body = "freq_hz,re,im\n10,1,2\n20,3,4\n";
        let c = Channel::new(DofRef::new(31, Dof::Uy), DofRef::new(1, Dof::Uy));
        let r = parse_csv_with(p, &format!("# units = m/N\n# channel = H(31:uy, 1:uy)\n{body}"), &[]).unwrap();
        assert_eq!(r.set.channels(), &[c]);
        assert_eq!(r.set.get(0, 1), C64::new(3.0, 4.0));
        let e = parse_csv_with(p, &format!("# units = m/N\n{body}"), &[]).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:2: columns `re` and `im` name no channel; add a line `# channel"), "{e}");
        let opts = CsvOptions { rules: &[], channel: Some(c) };
        let r = parse_csv_opts(p, &format!("# units = m/N\n{body}"), &opts).unwrap();
        assert_eq!(r.set.channels(), &[c]);
        assert!(r.notes[0].contains("taken as H(31:uy,1:uy), the one channel the case measures"), "{:?}", r.notes);
        let polar = "# units = m/N\n# channel = H(31:uy,1:uy)\nfrequency_hz,magnitude,phase (deg)\n10,2,90\n";
        let r = parse_csv_with(p, polar, &[]).unwrap();
        assert!((r.set.get(0, 0) - C64::new(0.0, 2.0)).norm() < 1e-12);
        let e = parse_csv_with(p, "# channel = H(1:uy,1:uy)\nfreq_hz,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n1,1,1\n", &[])
            .unwrap_err();
        assert!(e.to_string().contains("applies to a file with columns re and im only"), "{e}");
    }

    #[test]
    fn written_headers_quote_channel_names_and_state_the_units() {
        let ch = vec![Channel::new(DofRef::new(15, Dof::Uy), DofRef::new(23, Dof::Uy))];
        let s = FrfSet::zeros(vec![1.0], ch, FrfKind::Mobility).unwrap();
        let text = to_csv_string(&s);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[..3],
            ["# kind = mobility", "# units = SI", "frequency_hz,\"H(15:uy,23:uy).re\",\"H(15:uy,23:uy).im\""]
        );
        // a reader that splits at commas outside double quotes (RFC 4180) finds three fields
        let mut fields = 1;
        let mut quoted = false;
        for ch in lines[2].chars() {
            match ch {
                '"' => quoted = !quoted,
                ',' if !quoted => fields += 1,
                _ => {}
            }
        }
        assert_eq!(fields, 3);
        let back = parse_csv_with(Path::new("m.csv"), &text, &[]).unwrap();
        assert_eq!(back.set, s);
        assert!(back.notes.is_empty() && !back.per_volt, "{:?}", back.notes);
        let volts = parse_csv_with(Path::new("m.csv"), &to_csv_string_as(&s, true), &[]).unwrap();
        assert_eq!(volts.set, s);
        assert!(volts.per_volt && volts.notes[0].contains("per volt (SI/V)"), "{:?}", volts.notes);
    }
}

//! Plain CSV FRF files.
//!
//! Layout (comma, semicolon or tab separated; lines starting with `#` are
//! comments; `# kind = accelerance` declares the FRF kind, receptance by
//! default):
//!
//! ```text
//! # kind = receptance
//! frequency_hz,H(31:uy,31:uy).re,H(31:uy,31:uy).im,H(16:uy,31:uy).re,H(16:uy,31:uy).im
//! 1.0,1.2e-5,-3.1e-8,6.0e-6,-1.4e-8
//! ```
//!
//! Each channel takes two columns, either `.re` and `.im`, or `.mag` and
//! `.phase_deg` (magnitude and phase in degrees). Channel names are
//! `H(response,reference)` with DOFs written `node:dof`.

use std::path::Path;

use fe_model::DofRef;
use fe_model::case::MaskRule;
use num_complex::Complex64 as C64;

use super::mask::{Masked, Origin};
use crate::error::FrfError;
use crate::set::{Channel, FrfKind, FrfSet};

/// Writes a set as CSV (real and imaginary parts), atomically.
pub fn write_csv(set: &FrfSet, path: &Path) -> Result<(), FrfError> {
    super::atomic_write(path, to_csv_string(set).as_bytes(), &[])
}

/// The CSV text of a set.
pub fn to_csv_string(set: &FrfSet) -> String {
    let mut s = String::new();
    s.push_str(&format!("# kind = {}\n", set.kind()));
    s.push_str("frequency_hz");
    for c in set.channels() {
        s.push_str(&format!(",{c}.re,{c}.im"));
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

enum Pair {
    ReIm,
    MagPhase,
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

/// Reads a CSV FRF file (see the module docs). Non-finite values and
/// repeated lines are refused; see [`read_csv_with`] to leave them out.
pub fn read_csv(path: &Path) -> Result<FrfSet, FrfError> {
    read_csv_with(path, &[]).map(|r| r.set)
}

/// A CSV file read with mask rules.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvFrfs {
    /// The FRFs.
    pub set: FrfSet,
    /// Where each channel comes from (its columns), in the set's order.
    pub origins: Vec<Origin>,
    /// What the rules left out.
    pub masked: Vec<Masked>,
}

/// Reads a CSV FRF file, leaving out what `rules` allow (non-finite values,
/// repeated lines; see [`MaskRule`]).
pub fn read_csv_with(path: &Path, rules: &[MaskRule]) -> Result<CsvFrfs, FrfError> {
    let bytes = std::fs::read(path)
        .map_err(|e| FrfError::Io { path: path.to_path_buf(), message: format!("cannot read: {e}") })?;
    let text = fe_model::text::decode(&bytes).map_err(|e| FrfError::Parse {
        path: path.to_path_buf(),
        line: e.line,
        message: e.to_string(),
    })?;
    parse_csv_with(path, text, rules)
}

/// Parses CSV text; `path` is used in messages.
pub fn parse_csv(path: &Path, text: &str) -> Result<FrfSet, FrfError> {
    parse_csv_with(path, text, &[]).map(|r| r.set)
}

/// A number of a data field: decimal, or `NaN`/`inf` (refused or masked later).
fn field_number(s: &str) -> Option<f64> {
    let t = s.trim();
    super::non_finite_word(t).or_else(|| if t.bytes().any(|b| b.is_ascii_digit()) { t.parse().ok() } else { None })
}

/// Parses CSV text with mask rules; `path` is used in messages.
pub fn parse_csv_with(path: &Path, text: &str, rules: &[MaskRule]) -> Result<CsvFrfs, FrfError> {
    let err = |line: usize, message: String| FrfError::Parse { path: path.to_path_buf(), line, message };
    let mut kind = FrfKind::Receptance;
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
            if let Some((k, v)) = comment.split_once('=')
                && k.trim() == "kind"
            {
                kind = FrfKind::parse(v).ok_or_else(|| {
                    err(line_no, format!("unknown kind `{}` (receptance, mobility or accelerance)", v.trim()))
                })?;
            }
            continue;
        }
        match &header {
            None => {
                let sep = [';', '\t'].into_iter().find(|&c| line.contains(c)).unwrap_or(',');
                let cols: Vec<String> = split_fields(line, sep).into_iter().map(|s| s.trim().to_string()).collect();
                // checked here, before any data row, so that a file in another layout is
                // refused at its first line rather than at a row it cannot parse
                if !cols[0].to_ascii_lowercase().contains("freq") {
                    return Err(err(
                        line_no,
                        format!("the first column must be the frequency in Hz, found `{}`", cols[0]),
                    ));
                }
                header = Some((line_no, cols, sep));
            }
            Some((_, cols, sep)) => {
                let fields: Vec<&str> = line.split(*sep).collect();
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
        let pair = match (p1, p2) {
            ("re", "im") => Pair::ReIm,
            ("mag", "phase_deg") => Pair::MagPhase,
            _ => {
                return Err(err(
                    hline,
                    format!("channel {c1}: expected .re/.im or .mag/.phase_deg columns, found .{p1}/.{p2}"),
                ));
            }
        };
        if let Some(&other) = seen.get(&c1) {
            return Err(err(hline, format!("channel {c1} appears twice (columns {} and {})", 2 * other + 2, j + 1)));
        }
        seen.insert(c1, channels.len());
        channels.push(c1);
        pairs.push(pair);
        origins.push(Origin { line: hline, label: format!("columns {}-{}", j + 1, j + 2) });
    }
    if rows.is_empty() {
        return Err(err(hline, "no data rows".into()));
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
                Pair::MagPhase => C64::from_polar(a, b.to_radians()),
            };
            set.set(c, k, v);
        }
    }
    let locate = |c: usize, k: usize| {
        let line = rows[k].0;
        (line, format!("line {line}, columns {}-{}", 2 * c + 2, 2 * c + 3))
    };
    let (set, more) = super::mask::non_finite_lines(path, set, rules.contains(&MaskRule::NonFinite), &locate)?;
    masked.extend(more);
    Ok(CsvFrfs { set, origins, masked })
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
}

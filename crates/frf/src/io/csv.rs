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
use num_complex::Complex64 as C64;

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

/// Reads a CSV FRF file (see the module docs).
pub fn read_csv(path: &Path) -> Result<FrfSet, FrfError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| FrfError::Io { path: path.to_path_buf(), message: format!("cannot read: {e}") })?;
    parse_csv(path, &text)
}

/// Parses CSV text; `path` is used in messages.
pub fn parse_csv(path: &Path, text: &str) -> Result<FrfSet, FrfError> {
    let err = |line: usize, message: String| FrfError::Parse { path: path.to_path_buf(), line, message };
    let mut kind = FrfKind::Receptance;
    let mut header: Option<(usize, Vec<String>, char)> = None;
    let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
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
                        let v: f64 = f.trim().parse().map_err(|_| {
                            err(line_no, format!("column {} (`{}`): `{}` is not a number", j + 1, cols[j], f.trim()))
                        })?;
                        if !v.is_finite() {
                            return Err(err(line_no, format!("column {} (`{}`): value is {v}", j + 1, cols[j])));
                        }
                        Ok(v)
                    })
                    .collect::<Result<Vec<f64>, _>>()?;
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
        if channels.contains(&c1) {
            return Err(err(hline, format!("channel {c1} appears twice")));
        }
        channels.push(c1);
        pairs.push(pair);
    }
    if rows.is_empty() {
        return Err(err(hline, "no data rows".into()));
    }
    for w in rows.windows(2) {
        if !(w[1].1[0] > w[0].1[0]) {
            return Err(err(
                w[1].0,
                format!("frequency {} Hz does not increase (previous line has {} Hz)", w[1].1[0], w[0].1[0]),
            ));
        }
    }
    if let Some((line, r)) = rows.iter().find(|(_, r)| !(r[0] > 0.0)) {
        return Err(err(*line, format!("frequency {} Hz must be positive", r[0])));
    }
    let freqs: Vec<f64> = rows.iter().map(|(_, r)| r[0]).collect();
    let mut set = FrfSet::zeros(freqs, channels, kind)?;
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
    Ok(set)
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
        assert!(e.starts_with("m.csv:3:") && e.contains("does not increase"), "{e}");
        let bad = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1,x\n";
        let e = parse_csv(p, bad).unwrap_err().to_string();
        assert!(e.starts_with("m.csv:2:") && e.contains("`x` is not a number"), "{e}");
        let bad = "freq,H(2:uy,2:uy).re,H(2:uy,2:uy).im\n10,1,NaN\n";
        assert!(parse_csv(p, bad).unwrap_err().to_string().contains("NaN"));
    }
}

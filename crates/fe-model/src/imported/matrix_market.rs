//! Matrix Market coordinate files: the reader of the user's exported
//! stiffness and mass matrices, and a writer (for tests, examples and
//! round trips).
//!
//! The format (<https://math.nist.gov/MatrixMarket/formats.html>): a header
//! `%%MatrixMarket matrix coordinate real symmetric` (or `general`, or
//! `integer` values), comment lines starting with `%`, a size line `rows
//! cols entries`, then one `row col value` line per entry, 1-based. A
//! symmetric file stores one triangle. Entries that repeat a position add
//! up, as in any coordinate (triplet) format. A stiffness or mass matrix
//! is symmetric: a `general` file must be, to 1e-10 of its largest entry,
//! and is read as the mean of its two triangles.
//!
//! Written by hand rather than taken from a crate: the format is a few
//! lines, and what matters here is that every refusal names the line and
//! column of the file, which the general-purpose readers do not give.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::assembly::Pattern;

/// A square symmetric matrix as coordinate entries of its lower triangle
/// (`row >= col`, 0-based), each position once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SymmetricCoo {
    /// Number of rows (and columns).
    pub n: usize,
    /// `(row, col, value)` with `row >= col`, sorted by `(col, row)`.
    pub entries: Vec<(usize, usize, f64)>,
}

impl SymmetricCoo {
    /// The lower triangle of a matrix given as values on `pattern` (in its
    /// column-major order, as [`Assembly`](crate::Assembly) keeps them),
    /// zeros left out.
    pub fn lower_of(pattern: &Pattern, values: &[f64]) -> SymmetricCoo {
        let mut entries = Vec::new();
        for c in 0..pattern.n() {
            for k in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
                let r = pattern.row_idx()[k];
                if r >= c && values[k] != 0.0 {
                    entries.push((r, c, values[k]));
                }
            }
        }
        SymmetricCoo { n: pattern.n(), entries }
    }
}

/// A place in a text file and what is wrong there.
#[derive(Clone, Debug, PartialEq)]
pub struct TextError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl TextError {
    pub(crate) fn at(line: usize, column: usize, message: impl Into<String>) -> Self {
        TextError { line, column, message: message.into() }
    }
}

/// The whitespace-separated fields of a line with their 1-based columns.
pub(crate) fn fields(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, (byte, c)) in line.char_indices().enumerate() {
        let sep = c.is_whitespace() || c == ',';
        match (sep, start) {
            (false, None) => start = Some((i, byte)),
            (true, Some((col, b))) => {
                out.push((col + 1, &line[b..byte]));
                start = None;
            }
            _ => {}
        }
    }
    if let Some((col, b)) = start {
        out.push((col + 1, &line[b..]));
    }
    out
}

/// A number as exports write them: Rust and C syntax, and Fortran's `D`
/// exponent (`1.5D+03`).
pub(crate) fn number(text: &str) -> Option<f64> {
    text.parse::<f64>().ok().or_else(|| text.replace(['D', 'd'], "e").parse::<f64>().ok())
}

/// Reads a Matrix Market coordinate file's text (see the module docs).
pub fn read(text: &str) -> Result<SymmetricCoo, TextError> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (_, header) = lines.next().ok_or_else(|| TextError::at(1, 1, "the file is empty"))?;
    let words: Vec<String> = header.split_whitespace().map(str::to_ascii_lowercase).collect();
    if words.first().map(String::as_str) != Some("%%matrixmarket") {
        return Err(TextError::at(1, 1, "not a Matrix Market file: the first line must start with %%MatrixMarket"));
    }
    let word = |k: usize| words.get(k).map_or("", String::as_str);
    let column_of = |k: usize| fields(header).get(k).map_or(1, |f| f.0);
    if word(1) != "matrix" {
        return Err(TextError::at(1, column_of(1), format!("`{}` is not `matrix`", word(1))));
    }
    if word(2) != "coordinate" {
        return Err(TextError::at(
            1,
            column_of(2),
            format!(
                "`{}` storage is not read: export the matrix in coordinate form (scipy.io.mmwrite of a sparse matrix)",
                word(2)
            ),
        ));
    }
    if !matches!(word(3), "real" | "integer" | "double") {
        return Err(TextError::at(
            1,
            column_of(3),
            format!("`{}` values are not read: a stiffness or mass matrix is real", word(3)),
        ));
    }
    let symmetric = match word(4) {
        "symmetric" => true,
        "general" => false,
        other => {
            return Err(TextError::at(
                1,
                column_of(4),
                format!("`{other}` matrices are not read: a stiffness or mass matrix is `symmetric` (or `general`)"),
            ));
        }
    };
    // comments, then the size line
    let (size_line, size) = loop {
        let (no, line) = lines.next().ok_or_else(|| TextError::at(2, 1, "the file ends before its size line"))?;
        let t = line.trim_start();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        break (no, line);
    };
    let f = fields(size);
    let count = |k: usize, what: &str| -> Result<usize, TextError> {
        let (col, t) = f.get(k).copied().ok_or_else(|| {
            TextError::at(
                size_line,
                size.len() + 1,
                format!("the size line needs rows, columns and entries; {what} is missing"),
            )
        })?;
        t.parse::<usize>().map_err(|_| TextError::at(size_line, col, format!("`{t}` is not a number of {what}")))
    };
    let (rows, cols, nnz) = (count(0, "rows")?, count(1, "columns")?, count(2, "entries")?);
    if f.len() > 3 {
        return Err(TextError::at(size_line, f[3].0, "the size line of a coordinate file has three numbers"));
    }
    if rows != cols {
        return Err(TextError::at(
            size_line,
            f[0].0,
            format!("the matrix is {rows} x {cols}; a stiffness or mass matrix is square"),
        ));
    }
    let mut entries: Vec<(usize, usize, f64, usize)> = Vec::with_capacity(nnz);
    for (no, line) in lines {
        let t = line.trim_start();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let f = fields(line);
        if entries.len() == nnz {
            return Err(TextError::at(no, f[0].0, format!("more entries than the {nnz} the size line announces")));
        }
        if f.len() != 3 {
            let col = f.get(3).map_or(line.len() + 1, |x| x.0);
            return Err(TextError::at(
                no,
                col,
                format!("an entry is `row column value`; this line has {} fields", f.len()),
            ));
        }
        let index = |k: usize| -> Result<usize, TextError> {
            let (col, t) = f[k];
            match t.parse::<usize>() {
                Ok(i) if (1..=rows).contains(&i) => Ok(i - 1),
                _ => Err(TextError::at(no, col, format!("`{t}` is not an index from 1 to {rows}"))),
            }
        };
        let (r, c) = (index(0)?, index(1)?);
        let (col, t) = f[2];
        let v = number(t).ok_or_else(|| TextError::at(no, col, format!("`{t}` is not a number")))?;
        if !v.is_finite() {
            return Err(TextError::at(no, col, format!("the value {t} is not finite")));
        }
        if symmetric && r < c {
            return Err(TextError::at(
                no,
                f[0].0,
                format!(
                    "entry ({}, {}) lies above the diagonal; a symmetric file stores the lower triangle",
                    r + 1,
                    c + 1
                ),
            ));
        }
        entries.push((r, c, v, no));
    }
    if entries.len() < nnz {
        let last = text.lines().count().max(1);
        return Err(TextError::at(last, 1, format!("the file ends after {} of its {nnz} entries", entries.len())));
    }
    // the lower triangle, duplicates summed; a general file's upper
    // triangle summed apart and checked against it
    let mut sums: BTreeMap<(usize, usize), (f64, f64, usize)> = BTreeMap::new();
    for (r, c, v, no) in entries {
        // keyed by (col, row) of the lower triangle: column-major order
        let (key, upper) = if r >= c { ((c, r), false) } else { ((r, c), true) };
        let e = sums.entry(key).or_insert((0.0, 0.0, no));
        if upper {
            e.1 += v
        } else {
            e.0 += v
        }
        e.2 = e.2.max(no);
    }
    let scale = sums.values().map(|e| e.0.abs().max(e.1.abs())).fold(0.0, f64::max);
    let mut out = Vec::with_capacity(sums.len());
    for ((c, r), (lo, up, no)) in sums {
        let value = if symmetric || r == c {
            lo
        } else {
            if (lo - up).abs() > 1e-10 * scale {
                return Err(TextError::at(
                    no,
                    1,
                    format!(
                        "the matrix is not symmetric: entry ({}, {}) is {lo:e} and ({}, {}) is {up:e}; a stiffness or \
                         mass matrix is",
                        r + 1,
                        c + 1,
                        c + 1,
                        r + 1
                    ),
                ));
            }
            0.5 * (lo + up)
        };
        out.push((r, c, value));
    }
    Ok(SymmetricCoo { n: rows, entries: out })
}

/// The text of a symmetric coordinate file holding `m` (values written to
/// round-trip exactly).
pub fn write(m: &SymmetricCoo, comment: &str) -> String {
    let mut s = String::from("%%MatrixMarket matrix coordinate real symmetric\n");
    for line in comment.lines() {
        let _ = writeln!(s, "% {line}");
    }
    let _ = writeln!(s, "{} {} {}", m.n, m.n, m.entries.len());
    for &(r, c, v) in &m.entries {
        let _ = writeln!(s, "{} {} {v:e}", r + 1, c + 1);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_symmetric_file_round_trips_and_a_general_one_must_be_symmetric() {
        let m = SymmetricCoo { n: 3, entries: vec![(0, 0, 4.0), (1, 0, -1.5e-7), (1, 1, 2.0), (2, 2, 1.0 / 3.0)] };
        assert_eq!(read(&write(&m, "a test\nof two lines")), Ok(m.clone()));
        let general = "%%MatrixMarket matrix coordinate real general\n% c\n3 3 5\n1 1 4\n2 1 -1.5e-7\n1 2 -1.5D-7\n2 2 2\n3 3 0.3333333333333333\n";
        let g = read(general).unwrap();
        assert_eq!(g.entries[1], (1, 0, -1.5e-7));
        // duplicates add up
        let dup = "%%MatrixMarket matrix coordinate integer symmetric\n2 2 3\n1 1 1\n1 1 2\n2 2 5\n";
        assert_eq!(read(dup).unwrap().entries, vec![(0, 0, 3.0), (1, 1, 5.0)]);
    }

    #[test]
    fn every_refusal_names_its_line_and_column() {
        let h = "%%MatrixMarket matrix coordinate real symmetric\n";
        let cases = [
            ("%%MatrixMarket matrix array real general\n2 2\n", 1, 23, "`array` storage"),
            ("%%MatrixMarket matrix coordinate complex symmetric\n", 1, 34, "`complex` values"),
            ("%%MatrixMarket matrix coordinate real hermitian\n", 1, 39, "`hermitian` matrices"),
            ("% no header\n", 1, 1, "not a Matrix Market file"),
            (&format!("{h}2 3 1\n"), 2, 1, "is 2 x 3"),
            (&format!("{h}2 2 x\n"), 2, 5, "`x` is not a number of entries"),
            (&format!("{h}2 2 2\n1 1 1.0\n"), 3, 1, "ends after 1 of its 2 entries"),
            (&format!("{h}2 2 1\n1 1 1.0\n2 2 1.0\n"), 4, 1, "more entries than the 1"),
            (&format!("{h}2 2 1\n3 1 1.0\n"), 3, 1, "`3` is not an index from 1 to 2"),
            (&format!("{h}2 2 1\n2  1  abc\n"), 3, 7, "`abc` is not a number"),
            (&format!("{h}2 2 1\n1 2 1.0\n"), 3, 1, "lies above the diagonal"),
            (&format!("{h}2 2 1\n1 1 1.0 7\n"), 3, 9, "has 4 fields"),
            (&format!("{h}2 2 1\n1 1 nan\n"), 3, 5, "not finite"),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n2 1 1.0\n1 2 1.5\n",
                4,
                1,
                "not symmetric: entry (2, 1) is 1e0 and (1, 2) is 1.5e0",
            ),
        ];
        for (text, line, column, words) in cases {
            let e = read(text).unwrap_err();
            assert!(e.message.contains(words), "{text:?}: {e:?}");
            assert_eq!((e.line, e.column), (line, column), "{text:?}: {e:?}");
        }
    }
}

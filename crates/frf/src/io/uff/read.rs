//! Reading universal files: splitting into datasets, parsing dataset 58
//! headers and data (ASCII and binary). Every access to the input is
//! bounds-checked; malformed input becomes `FileError::Parse`.

use std::path::Path;

use num_complex::Complex64 as C64;

use super::numbers::numbers;
use super::{
    Abscissa, DataAxis, Direction, Encoding, Function58, Header58, OrdinateType, Ordinates, RawDataset, Record58,
    SkippedDataset, TestDof, UffFile,
};
use crate::error::{FileError, FrfError};

/// Reads a universal file: every dataset 58 with its data, and the list of
/// other datasets (skipped).
pub fn read_uff(path: &Path) -> Result<UffFile, FrfError> {
    parse_uff(path, &super::read_bytes(path)?)
}

/// Parses the bytes of a universal file; `path` is used in messages.
pub fn parse_uff(path: &Path, bytes: &[u8]) -> Result<UffFile, FrfError> {
    parse_with(path, bytes, &mut |_, _, _| Ok(()))
}

/// A check of a record's header: record number, line, header.
pub(crate) type HeaderCheck<'c> = dyn FnMut(usize, usize, &Header58) -> Result<(), FrfError> + 'c;

/// Parses, calling `check` on each dataset 58 header before its data is
/// read, so that a caller can refuse a record by its header (its function
/// type, say) before a problem in its data is reported.
pub(crate) fn parse_with(path: &Path, bytes: &[u8], check: &mut HeaderCheck<'_>) -> Result<UffFile, FrfError> {
    let mut p = Parser { path, cur: Cursor::new(bytes), notes: Vec::new() };
    let mut file = UffFile::default();
    while let Some(open) = p.cur.next_nonblank_line() {
        if open.text.trim_ascii() != b"-1" {
            let hint =
                if file.records.is_empty() && file.skipped.is_empty() { " (is this a universal file?)" } else { "" };
            return Err(
                p.err(open.no, format!("expected `    -1` opening a dataset, found `{}`{hint}", show(open.text)))
            );
        }
        // a `-1` right after `-1` is an empty dataset (some writers leave one): skip it
        let head = loop {
            match p.cur.next_line() {
                Some(l) if l.text.trim_ascii() == b"-1" => {
                    p.notes.push(format!("line {}: an empty dataset (`-1` after `-1`) skipped", l.no));
                }
                Some(l) => break l,
                None => return Err(p.err(open.no, "the file ends after `-1`; expected a dataset number".into())),
            }
        };
        let (number, binary) = dataset_number(head.text).ok_or_else(|| {
            p.err(head.no, format!("expected a dataset number after `-1`, found `{}`", show(head.text)))
        })?;
        if number == 58 {
            let index = file.records.len() + 1;
            let record = p.record58(index, head, binary, check)?;
            file.records.push(record);
        } else {
            let keep = super::geometry::GEOMETRY_DATASETS.contains(&number);
            let lines = p.skip_dataset(number, head.no, keep)?;
            if keep {
                file.geometry.push(RawDataset { number, line: head.no, lines });
            }
            file.skipped.push(SkippedDataset { number, line: head.no });
        }
    }
    file.notes = p.notes;
    Ok(file)
}

// ------------------------------------------------------------------ cursor

#[derive(Clone, Copy)]
struct Line<'a> {
    /// 1-based line number.
    no: usize,
    /// Byte offset of its first byte.
    offset: usize,
    /// Content without the line ending (`\n` or `\r\n`).
    text: &'a [u8],
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Number of the next line.
    line: usize,
}

impl<'a> Cursor<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Cursor { bytes, pos: 0, line: 1 }
    }

    fn next_line(&mut self) -> Option<Line<'a>> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let (text, used) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        let text = text.strip_suffix(b"\r").unwrap_or(text);
        let line = Line { no: self.line, offset: self.pos, text };
        self.pos += used;
        self.line += 1;
        Some(line)
    }

    fn next_nonblank_line(&mut self) -> Option<Line<'a>> {
        loop {
            let l = self.next_line()?;
            if !l.text.trim_ascii().is_empty() {
                return Some(l);
            }
        }
    }

    /// The next `n` bytes, or `None` (and nothing consumed) if fewer remain.
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let out = self.bytes.get(self.pos..end)?;
        self.pos = end;
        // keep line numbers true to what an editor shows, even after binary data
        self.line += out.iter().filter(|&&b| b == b'\n').count();
        Some(out)
    }

    /// Whether the bytes at `pos` are a line break (optional) and a `-1` line.
    fn closes_at(&self, pos: usize) -> bool {
        let Some(rest) = self.bytes.get(pos..) else { return false };
        let rest = rest.strip_prefix(b"\r\n").or_else(|| rest.strip_prefix(b"\n")).unwrap_or(rest);
        let line = rest.split(|&b| b == b'\n').next().unwrap_or_default();
        line.trim_ascii() == b"-1"
    }

    /// Number of the last line read (1 before any).
    fn last_line(&self) -> usize {
        self.line.saturating_sub(1).max(1)
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
}

// ------------------------------------------------------------------ parser

struct Parser<'a, 'p> {
    path: &'p Path,
    cur: Cursor<'a>,
    notes: Vec<String>,
}

impl<'a> Parser<'a, '_> {
    fn err(&self, line: usize, message: String) -> FrfError {
        FrfError::File(FileError::Parse { path: self.path.to_path_buf(), line, message })
    }

    /// Skips a dataset that is not 58 up to its closing `-1`; returns its
    /// lines (number and text) when `keep` (the datasets of test geometry,
    /// read only when a case pairs nodes by coordinates).
    fn skip_dataset(&mut self, number: i64, start: usize, keep: bool) -> Result<Vec<(usize, String)>, FrfError> {
        let mut lines = Vec::new();
        loop {
            match self.cur.next_line() {
                Some(l) if l.text.trim_ascii() == b"-1" => return Ok(lines),
                Some(l) if keep => lines.push((l.no, text(l.text))),
                Some(_) => {}
                None => {
                    return Err(self.err(
                        self.cur.last_line(),
                        format!(
                            "the file ends inside dataset {number} of line {start} (no closing `-1`); is it truncated?"
                        ),
                    ));
                }
            }
        }
    }

    fn record58(
        &mut self,
        index: usize,
        head: Line<'a>,
        binary: bool,
        check: &mut HeaderCheck<'_>,
    ) -> Result<Record58, FrfError> {
        let label = format!("record {index} (line {})", head.no);
        let binary_info = if binary { Some(self.binary_line(&label, head)?) } else { None };
        let mut lines = Vec::with_capacity(11);
        for k in 0..11 {
            let l = match self.cur.next_line() {
                Some(l) if binary || l.text.trim_ascii() != b"-1" => l,
                Some(l) => {
                    return Err(self.err(
                        l.no,
                        format!("{label}: the dataset ends after {k} of the 11 header lines (records 1-11)"),
                    ));
                }
                None => {
                    return Err(self.err(
                        self.cur.last_line(),
                        format!("{label}: the file ends after {k} of the 11 header lines (records 1-11)"),
                    ));
                }
            };
            lines.push(l);
        }
        let (header, n, spacing) = self.header(&label, &lines)?;
        check(index, head.no, &header)?;
        let (encoding, numbers) = match binary_info {
            Some(info) => {
                (Encoding::Binary { big_endian: info.big_endian }, self.binary_data(&label, &header, n, spacing, info)?)
            }
            None => (Encoding::Ascii, self.ascii_data(&label)?),
        };
        let function = assemble(header, n, spacing, numbers)
            .map_err(|m| self.err(numbers_line(head.no, &lines), format!("{label}: {m}")))?;
        Ok(Record58 { index, line: head.no, encoding, function })
    }

    /// The `58b` line: byte order, floating-point format, 11 ASCII lines, byte count.
    fn binary_line(&self, label: &str, head: Line<'a>) -> Result<BinaryInfo, FrfError> {
        let text = String::from_utf8_lossy(head.text);
        let rest = text.trim_start().trim_start_matches(|c: char| c.is_ascii_digit());
        let rest = rest.strip_prefix(['b', 'B']).unwrap_or(rest);
        let fields: Vec<&str> = rest.split_whitespace().collect();
        let field = |i: usize, what: &str| -> Result<i64, FrfError> {
            let f = fields
                .get(i)
                .ok_or_else(|| self.err(head.no, format!("{label}: the `58b` line lacks field {} ({what})", i + 3)))?;
            f.parse().map_err(|_| self.err(head.no, format!("{label}: {what} `{f}` is not an integer")))
        };
        let big_endian = match field(0, "byte ordering")? {
            1 => false,
            2 => true,
            o => {
                return Err(self.err(
                    head.no,
                    format!("{label}: byte ordering {o} is neither 1 (little-endian) nor 2 (big-endian)"),
                ));
            }
        };
        match field(1, "floating-point format")? {
            2 => {}
            1 => return Err(self.err(head.no, format!("{label}: DEC VMS floating point (format 1) is not supported"))),
            3 => return Err(self.err(head.no, format!("{label}: IBM 370 floating point (format 3) is not supported"))),
            f => return Err(self.err(head.no, format!("{label}: floating-point format {f} is not 2 (IEEE 754)"))),
        }
        let n_ascii = field(2, "number of ASCII header lines")?;
        if n_ascii != 11 {
            return Err(self.err(head.no, format!("{label}: {n_ascii} ASCII header lines; dataset 58b has 11")));
        }
        let n_bytes = field(3, "number of bytes")?;
        let n_bytes = usize::try_from(n_bytes)
            .map_err(|_| self.err(head.no, format!("{label}: negative byte count {n_bytes}")))?;
        Ok(BinaryInfo { big_endian, n_bytes })
    }

    fn header(&self, label: &str, lines: &[Line<'a>]) -> Result<(Header58, usize, Spacing), FrfError> {
        let line = |k: usize| lines.get(k).copied().unwrap_or(Line { no: 0, offset: 0, text: b"" });
        let ids = [0, 1, 2, 3, 4].map(|k| text(line(k).text));
        // record 6: 2(I5,I10),2(1X,10A1,I10,I4)
        let r6 = line(5);
        let int6 = |a: usize, b: usize, what: &str| self.fixed_int(label, r6, a, b, what, "record 6");
        let function_type = int6(0, 5, "function type")?;
        let function_id = int6(5, 15, "function id")?;
        let version = int6(15, 20, "version number")?;
        let load_case = int6(20, 30, "load case")?;
        let response_entity = text(cols(r6.text, 31, 41));
        let response_node = int6(41, 51, "response node")?;
        let response_dir = self.direction(label, r6, 51, 55, "response")?;
        let reference_entity = text(cols(r6.text, 56, 66));
        let reference_node = int6(66, 76, "reference node")?;
        let reference_dir = self.direction(label, r6, 76, 80, "reference")?;
        // record 7: 3I10,3E13
        let r7 = line(6);
        let nums = numbers(r7.text).map_err(|m| self.err(r7.no, format!("{label}: record 7: {m}")))?;
        if nums.len() < 5 {
            return Err(self.err(
                r7.no,
                format!(
                    "{label}: record 7 has {} numbers; expected data type, number of values, spacing, \
                     abscissa start and increment",
                    nums.len()
                ),
            ));
        }
        let as_int = |x: f64, what: &str| -> Result<i64, FrfError> {
            if x.fract() == 0.0 && x.abs() < 1e15 {
                Ok(x as i64)
            } else {
                Err(self.err(r7.no, format!("{label}: record 7: {what} `{x}` is not an integer")))
            }
        };
        let type_code = as_int(nums[0], "ordinate data type")?;
        let ordinate_type = OrdinateType::from_code(type_code).ok_or_else(|| {
            self.err(
                r7.no,
                format!(
                    "{label}: ordinate data type {type_code} is not supported \
                     (2 real single, 4 real double, 5 complex single, 6 complex double)"
                ),
            )
        })?;
        let n = as_int(nums[1], "number of values")?;
        let n = usize::try_from(n)
            .map_err(|_| self.err(r7.no, format!("{label}: record 7: negative number of values {n}")))?;
        let spacing = match as_int(nums[2], "abscissa spacing")? {
            1 => Spacing::Even { min: nums[3], step: nums[4] },
            0 => Spacing::Uneven,
            s => {
                return Err(
                    self.err(r7.no, format!("{label}: abscissa spacing {s} is neither 1 (even) nor 0 (uneven)"))
                );
            }
        };
        if let Spacing::Even { min, step } = spacing
            && !(min.is_finite() && step.is_finite())
        {
            return Err(self.err(r7.no, format!("{label}: abscissa start {min} or increment {step} is not finite")));
        }
        let z_value = nums.get(5).copied().unwrap_or(0.0);
        let axes = [7, 8, 9, 10].map(|k| self.data_axis(label, line(k), k + 1));
        let [abscissa_axis, numerator, denominator, z_axis] = axes;
        let header = Header58 {
            ids,
            function_type,
            function_id,
            version,
            load_case,
            response_entity,
            response: TestDof::new(response_node, response_dir),
            reference_entity,
            reference: TestDof::new(reference_node, reference_dir),
            ordinate_type,
            z_value,
            abscissa_axis: abscissa_axis?,
            numerator: numerator?,
            denominator: denominator?,
            z_axis: z_axis?,
        };
        Ok((header, n, spacing))
    }

    /// Records 8-11: I10,3I5,2(1X,A20).
    fn data_axis(&self, label: &str, l: Line<'a>, record: usize) -> Result<DataAxis, FrfError> {
        let rec = format!("record {record}");
        Ok(DataAxis {
            specific_type: self.fixed_int(label, l, 0, 10, "specific data type", &rec)?,
            length_exp: self.fixed_int(label, l, 10, 15, "length units exponent", &rec)?,
            force_exp: self.fixed_int(label, l, 15, 20, "force units exponent", &rec)?,
            temperature_exp: self.fixed_int(label, l, 20, 25, "temperature units exponent", &rec)?,
            label: text(cols(l.text, 26, 46)),
            // the units label is the last field: take the rest of the line, so
            // that a multi-byte character or a wider field does not cut it
            units: text(cols(l.text, 47, usize::MAX)),
        })
    }

    fn fixed_int(&self, label: &str, l: Line<'a>, a: usize, b: usize, what: &str, rec: &str) -> Result<i64, FrfError> {
        let field = cols(l.text, a, b).trim_ascii();
        if field.is_empty() {
            return Ok(0);
        }
        std::str::from_utf8(field).ok().and_then(|s| s.parse().ok()).ok_or_else(|| {
            self.err(
                l.no,
                format!("{label}: {rec}, columns {}-{}: {what} `{}` is not an integer", a + 1, b, show(field)),
            )
        })
    }

    fn direction(&self, label: &str, l: Line<'a>, a: usize, b: usize, which: &str) -> Result<Direction, FrfError> {
        let code = self.fixed_int(label, l, a, b, &format!("{which} direction"), "record 6")?;
        Direction::from_code(code).ok_or_else(|| {
            self.err(
                l.no,
                format!(
                    "{label}: record 6: {which} direction {code} is not one of -6..6 \
                     (0 scalar, 1 X, 2 Y, 3 Z, 4 RX, 5 RY, 6 RZ, negative for -)"
                ),
            )
        })
    }

    /// ASCII data lines up to the closing `-1`, as numbers.
    fn ascii_data(&mut self, label: &str) -> Result<Numbers, FrfError> {
        let mut values = Vec::new();
        let mut first_line = None;
        loop {
            let Some(l) = self.cur.next_line() else {
                return Err(self.err(
                    self.cur.last_line(),
                    format!("{label}: the file ends inside the data (no closing `-1`); is it truncated?"),
                ));
            };
            if l.text.trim_ascii() == b"-1" {
                return Ok(Numbers { values, first_line: first_line.unwrap_or(l.no), end_line: l.no });
            }
            first_line.get_or_insert(l.no);
            let nums = numbers(l.text).map_err(|m| self.err(l.no, format!("{label}: data: {m}")))?;
            values.extend(nums);
        }
    }

    /// `info.n_bytes` bytes of IEEE floats, then the closing `-1`.
    fn binary_data(
        &mut self,
        label: &str,
        h: &Header58,
        n: usize,
        spacing: Spacing,
        info: BinaryInfo,
    ) -> Result<Numbers, FrfError> {
        let start = self.cur.pos;
        let data_line = self.cur.line;
        let size = h.ordinate_type.number_size();
        let uneven = matches!(spacing, Spacing::Uneven);
        let per = values_per_point(h.ordinate_type, uneven);
        let path = self.path;
        let boff = |off: usize, m: String| {
            FrfError::File(FileError::Parse {
                path: path.to_path_buf(),
                line: off,
                message: format!("byte offset {off}: {label}: {m}"),
            })
        };
        let expected = n.checked_mul(per).and_then(|v| v.checked_mul(size));
        // pyuff declares 8 bytes per abscissa point whatever the data holds; its reader ignores
        // the count. Trust record 7 instead when the closing `-1` is exactly where it says the
        // data ends.
        let mut n_bytes = info.n_bytes;
        if let Some(e) = expected
            && e != n_bytes
            && self.cur.closes_at(start.saturating_add(e))
        {
            self.notes.push(format!(
                "{label}: the `58b` line declares {n_bytes} bytes of data, but record 7 needs {e} bytes and the \
                 closing `-1` confirms them (pyuff writes such files); read {e} bytes"
            ));
            n_bytes = e;
        }
        if expected != Some(n_bytes) {
            return Err(boff(
                start,
                format!(
                    "the `58b` line declares {} bytes of data, but record 7's {n} values of type {} with {} spacing \
                     need {}",
                    info.n_bytes,
                    h.ordinate_type,
                    if uneven { "uneven" } else { "even" },
                    expected.map_or_else(|| "more than can be addressed".to_string(), |e| format!("{e} bytes")),
                ),
            ));
        }
        let Some(data) = self.cur.take(n_bytes) else {
            return Err(boff(
                start,
                format!(
                    "the binary data should hold {n_bytes} bytes (the `58b` line says so), the file has {} left; \
                     is it truncated?",
                    self.cur.remaining()
                ),
            ));
        };
        let mut values = Vec::with_capacity(data.len() / size);
        for chunk in data.chunks_exact(size) {
            let x = if size == 4 {
                let mut b = [0u8; 4];
                b.copy_from_slice(chunk);
                f64::from(if info.big_endian { f32::from_be_bytes(b) } else { f32::from_le_bytes(b) })
            } else {
                let mut b = [0u8; 8];
                b.copy_from_slice(chunk);
                if info.big_endian { f64::from_be_bytes(b) } else { f64::from_le_bytes(b) }
            };
            values.push(x);
        }
        let end = self.cur.pos;
        match self.cur.next_nonblank_line() {
            Some(l) if l.text.trim_ascii() == b"-1" => {}
            Some(l) => {
                return Err(boff(
                    l.offset,
                    format!(
                        "expected `    -1` after the {n_bytes} bytes of binary data, found `{}`; \
                         does the byte count of the `58b` line match the data?",
                        show(l.text.get(..40).unwrap_or(l.text))
                    ),
                ));
            }
            None => {
                return Err(boff(end, "the file ends after the binary data; expected the closing `    -1`".into()));
            }
        }
        Ok(Numbers { values, first_line: data_line, end_line: data_line })
    }
}

#[derive(Clone, Copy)]
struct BinaryInfo {
    big_endian: bool,
    n_bytes: usize,
}

#[derive(Clone, Copy, Debug)]
enum Spacing {
    Even { min: f64, step: f64 },
    Uneven,
}

struct Numbers {
    values: Vec<f64>,
    first_line: usize,
    end_line: usize,
}

fn numbers_line(head: usize, lines: &[Line<'_>]) -> usize {
    lines.last().map_or(head, |l| l.no + 1)
}

/// Numbers per abscissa point: 1 or 2 ordinates, plus the abscissa when uneven.
pub(super) fn values_per_point(t: OrdinateType, uneven: bool) -> usize {
    (if t.is_complex() { 2 } else { 1 }) + usize::from(uneven)
}

/// Builds the function from the numbers of its data block.
fn assemble(h: Header58, n: usize, spacing: Spacing, numbers: Numbers) -> Result<Function58, String> {
    let uneven = matches!(spacing, Spacing::Uneven);
    let per = values_per_point(h.ordinate_type, uneven);
    let lines = if numbers.first_line < numbers.end_line {
        format!(" (lines {}-{})", numbers.first_line, numbers.end_line - 1)
    } else {
        String::new()
    };
    let v = numbers.values;
    if n.checked_mul(per) != Some(v.len()) {
        let layout = match (h.ordinate_type.is_complex(), uneven) {
            (false, false) => "one number per value",
            (true, false) => "real and imaginary part per value",
            (false, true) => "abscissa and ordinate per value",
            (true, true) => "abscissa, real and imaginary part per value",
        };
        return Err(format!(
            "record 7 declares {n} values of type {} with {} spacing ({layout}: {} numbers), but the data holds {} \
             numbers{lines}",
            h.ordinate_type,
            if uneven { "uneven" } else { "even" },
            n.saturating_mul(per),
            v.len()
        ));
    }
    let abscissa = match spacing {
        Spacing::Even { min, step } => Abscissa::Even { min, step },
        Spacing::Uneven => Abscissa::Uneven(v.chunks_exact(per).map(|c| c[0]).collect()),
    };
    let skip = usize::from(uneven);
    let ordinates = if h.ordinate_type.is_complex() {
        Ordinates::Complex(v.chunks_exact(per).map(|c| C64::new(c[skip], c[skip + 1])).collect())
    } else {
        Ordinates::Real(v.chunks_exact(per).map(|c| c[skip]).collect())
    };
    Ok(Function58 { header: h, abscissa, ordinates })
}

// ----------------------------------------------------------------- helpers

/// The dataset number of the line after `-1` and whether it is binary (`58b`).
fn dataset_number(text: &[u8]) -> Option<(i64, bool)> {
    let t = text.trim_ascii_start();
    let digits = t.iter().take_while(|b| b.is_ascii_digit()).count();
    let number = std::str::from_utf8(t.get(..digits)?).ok()?.parse().ok()?;
    let rest = t.get(digits..).unwrap_or_default();
    let binary = matches!(rest.first(), Some(b'b' | b'B'));
    if !binary && rest.first().is_some_and(|b| !b.is_ascii_whitespace()) {
        return None;
    }
    Some((number, binary))
}

/// Bytes `a..b` of a line, clipped to its length (fixed-column fields).
fn cols(text: &[u8], a: usize, b: usize) -> &[u8] {
    let a = a.min(text.len());
    let b = b.clamp(a, text.len());
    text.get(a..b).unwrap_or_default()
}

/// Field text: UTF-8 when valid, otherwise Latin-1 (older test systems write
/// `²` as the single byte 0xB2); trimmed.
pub(super) fn text(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.trim().to_string(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect::<String>().trim().to_string(),
    }
}

/// A short printable excerpt of a line for messages.
fn show(bytes: &[u8]) -> String {
    let t = text(bytes.get(..60).unwrap_or(bytes));
    t.chars().map(|c| if c.is_control() { '?' } else { c }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_numbers_and_binary_marker() {
        assert_eq!(dataset_number(b"    58"), Some((58, false)));
        assert_eq!(dataset_number(b"    58b     1     2          11        2000"), Some((58, true)));
        assert_eq!(dataset_number(b"   151                 "), Some((151, false)));
        assert_eq!(dataset_number(b"  2411x"), None);
        assert_eq!(dataset_number(b"  "), None);
    }

    #[test]
    fn fields_decode_latin1_when_not_utf8() {
        assert_eq!(text(b"(1/N)*(m/s\xb2)  "), "(1/N)*(m/s²)");
        assert_eq!(text("m/s²".as_bytes()), "m/s²");
        assert_eq!(cols(b"abc", 1, 99), b"bc");
        assert_eq!(cols(b"abc", 5, 9), b"");
    }
}

//! Plain-text tables for the terminal.

/// A table with a header row, printed with aligned columns.
pub(crate) struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    pub(crate) fn new(header: &[&str]) -> Self {
        Table { header: header.iter().map(|s| s.to_string()).collect(), rows: Vec::new() }
    }

    pub(crate) fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    pub(crate) fn render(&self) -> String {
        let mut layout = Layout::new(&self.header);
        for r in &self.rows {
            layout.add(r);
        }
        let mut out = layout.head(&self.header);
        for r in &self.rows {
            out.push('\n');
            out.push_str(&layout.line(r));
        }
        out
    }
}

/// Writes the table of `header` and the rows that `rows` makes, line by
/// line, each followed by a newline: the text of [`Table::render`]. `rows`
/// is called twice, once to lay the columns out and once to write them, so
/// that only one row is held at a time (a listing of 500,000 channels
/// would otherwise hold millions of cells).
pub(crate) fn write_streamed<I: Iterator<Item = Vec<String>>>(
    header: &[&str],
    rows: impl Fn() -> I,
    out: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let header: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    let mut layout = Layout::new(&header);
    for r in rows() {
        layout.add(&r);
    }
    writeln!(out, "{}", layout.head(&header))?;
    for r in rows() {
        writeln!(out, "{}", layout.line(&r))?;
    }
    Ok(())
}

/// The widths and alignment of a table's columns, found one row at a time.
struct Layout {
    width: Vec<usize>,
    /// Right-aligned: every non-empty cell below the header reads as a
    /// number (the first column never is).
    right: Vec<bool>,
}

impl Layout {
    fn new(header: &[String]) -> Self {
        Layout {
            width: header.iter().map(|c| c.chars().count()).collect(),
            right: (0..header.len()).map(|i| i > 0).collect(),
        }
    }

    fn add(&mut self, row: &[String]) {
        for (i, c) in row.iter().enumerate() {
            self.width[i] = self.width[i].max(c.chars().count());
            self.right[i] &= c.is_empty() || numeric(c);
        }
    }

    /// The header line and the rule under it.
    fn head(&self, header: &[String]) -> String {
        let mut out = self.line(header);
        out.push('\n');
        let rule: Vec<String> = self
            .width
            .iter()
            .zip(header)
            .map(|(w, h)| if h.is_empty() { String::new() } else { "-".repeat(*w) })
            .collect();
        out.push_str(rule.join("  ").trim_end());
        out
    }

    fn line(&self, r: &[String]) -> String {
        let cells: Vec<String> = r
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let w = self.width[i];
                if self.right[i] { format!("{c:>w$}") } else { format!("{c:<w$}") }
            })
            .collect();
        cells.join("  ").trim_end().to_string()
    }
}

/// Whether a cell reads as a number (digits, signs, exponents, %; units
/// after a space are not numbers).
fn numeric(c: &str) -> bool {
    let c = c.trim_end_matches(" %").trim_end_matches('%');
    c.parse::<f64>().is_ok() || c == "-" || c == "inf"
}

/// A relative uncertainty as a percentage with two significant digits.
pub(crate) fn percent(x: f64) -> String {
    let p = 100.0 * x;
    if !p.is_finite() || p >= 1e4 {
        "> 10000 %".into()
    } else if p >= 10.0 {
        format!("{p:.0} %")
    } else if p >= 1.0 {
        format!("{p:.1} %")
    } else {
        format!("{p:.2e} %")
    }
}

/// A number in a short engineering form.
pub(crate) fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() {
        format!("{v}")
    } else if (1e-3..1e5).contains(&v.abs()) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.6e}")
    }
}

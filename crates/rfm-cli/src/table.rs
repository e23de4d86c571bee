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

/// Whether a cell reads as a number (digits, signs, exponents, %, thousands
/// grouped with commas; units after a space are not numbers).
fn numeric(c: &str) -> bool {
    let c = c.trim_end_matches(" %").trim_end_matches('%').replace(',', "");
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

/// A value of a model quantity (a stiffness, a damping coefficient, a
/// frequency): six significant digits, plain notation from 1e-3 to 1e6 and
/// exponent notation outside it, trailing zeros dropped, so that `1e5`
/// and `20002.8` sit side by side in one form (`100000`, `20002.8`).
pub(crate) fn num(v: f64) -> String {
    significant(v, 6)
}

/// `v` to `digits` significant digits in the form [`num`] describes;
/// `-` for NaN, and never a negative zero.
pub(crate) fn significant(v: f64, digits: usize) -> String {
    digits_of(v, digits, true)
}

/// `v` to `digits` significant digits as [`significant`] writes them, the
/// trailing zeros kept when `trim` is false (`1.070`: a column of
/// misfits reads digit for digit).
fn digits_of(v: f64, digits: usize, trim: bool) -> String {
    if v.is_nan() {
        return "-".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    let s = if (1e-3..1e6).contains(&a) {
        let decimals = (digits as i32 - 1 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        // 999999.7 rounds up to 1e6 and reads as a number all the same
        if trim && s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    } else {
        let s = format!("{v:.prec$e}", prec = digits.saturating_sub(1));
        match s.split_once('e') {
            Some((m, e)) if trim && m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    };
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') { "0".into() } else { s }
}

/// `v` to `digits` significant digits with its trailing zeros kept
/// (`42.00`): a measured value shown to its precision.
pub(crate) fn digits(v: f64, digits: usize) -> String {
    digits_of(v, digits, false)
}

/// A misfit or a noise level: four significant digits, plain notation
/// (`1.448`, `0.004725`, `1.070`), as every output prints them.
pub(crate) fn misfit(v: f64) -> String {
    digits_of(v, 4, false)
}

/// `v` with `decimals` decimals, never a negative zero (`-0.00` of a tiny
/// negative value reads `0.00`); `signed` puts a `+` before positive values.
pub(crate) fn fixed(v: f64, decimals: usize, signed: bool) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    let s = if signed { format!("{v:+.decimals$}") } else { format!("{v:.decimals$}") };
    if s.trim_start_matches(['-', '+']).chars().all(|c| c == '0' || c == '.') {
        format!("{:.decimals$}", 0.0)
    } else {
        s
    }
}

/// A misfit as a multiple of the noise: two decimals below 10 (`0.95`,
/// `1.50`, where the line between explained and not lies), one above.
pub(crate) fn times(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v < 10.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.1}")
    }
}

/// A dBIC, as [`rfm_update::quantities::dbic_text`] writes every one.
pub(crate) fn dbic(v: f64) -> String {
    rfm_update::quantities::dbic_text(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One form for values of every size: plain between 1e-3 and 1e6,
    /// exponent outside, six digits, no trailing zeros, no negative zero.
    #[test]
    fn values_print_in_one_form() {
        assert_eq!(num(1.0e5), "100000");
        assert_eq!(num(20002.821128), "20002.8");
        assert_eq!(num(1.0e-5), "1e-5");
        assert_eq!(num(1.000790e-4), "1.00079e-4");
        assert_eq!(num(2.513274e6), "2.51327e6");
        assert_eq!(num(0.407263), "0.407263");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(f64::NAN), "-");
        assert_eq!(significant(-0.0004, 2), "-4e-4");
        assert_eq!(significant(-0.00001, 2), "-1e-5");
        assert_eq!(misfit(1.44763), "1.448");
        assert_eq!(misfit(0.00472513), "0.004725");
        assert_eq!(misfit(0.0098578), "0.009858");
        assert_eq!(misfit(1.0700), "1.070");
        assert_eq!(misfit(2.5e-5), "2.500e-5");
        assert_eq!(times(0.947), "0.95");
        assert_eq!(fixed(-0.001, 2, true), "0.00");
        assert_eq!(fixed(-0.0, 1, false), "0.0");
        assert_eq!(fixed(19.294, 2, true), "+19.29");
        assert_eq!(fixed(-2.2, 2, true), "-2.20");
        assert_eq!(times(132.19), "132.2");
    }

    /// Large dBICs are whole and grouped, small ones keep a decimal; a
    /// table aligns grouped numbers to the right as numbers.
    #[test]
    fn dbic_is_grouped_and_aligned_as_a_number() {
        assert_eq!(dbic(-56161044.7), "-56,161,045");
        assert_eq!(dbic(-12037019.2), "-12,037,019");
        assert_eq!(dbic(-1234.4), "-1,234");
        assert_eq!(dbic(-999.94), "-999.9");
        assert_eq!(dbic(6.94), "6.9");
        assert_eq!(dbic(-0.01), "0.0");
        let mut t = Table::new(&["effect", "dBIC"]);
        t.row(vec!["a".into(), dbic(-56161044.7)]);
        t.row(vec!["b".into(), dbic(-7.0)]);
        let text = t.render();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[3].ends_with(" -7.0") && lines[2].len() == lines[3].len(), "{text}");
    }
}

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

    /// True when every non-empty cell of column `i` reads as a number
    /// (digits, signs, exponents, %, units after a space are not numbers).
    fn numeric(&self, i: usize) -> bool {
        self.rows.iter().filter_map(|r| r.get(i)).filter(|c| !c.is_empty()).all(|c| {
            let c = c.trim_end_matches(" %").trim_end_matches('%');
            c.parse::<f64>().is_ok() || c == "-" || c == "inf"
        })
    }

    pub(crate) fn render(&self) -> String {
        let n = self.header.len();
        let right: Vec<bool> = (0..n).map(|i| i > 0 && self.numeric(i)).collect();
        let mut width = vec![0; n];
        for r in std::iter::once(&self.header).chain(&self.rows) {
            for (i, c) in r.iter().enumerate() {
                width[i] = width[i].max(c.chars().count());
            }
        }
        let line = |r: &Vec<String>| {
            r.iter()
                .enumerate()
                .map(
                    |(i, c)| if right[i] { format!("{c:>w$}", w = width[i]) } else { format!("{c:<w$}", w = width[i]) },
                )
                .collect::<Vec<_>>()
                .join("  ")
        };
        let mut out = line(&self.header).trim_end().to_string();
        out.push('\n');
        let rule: Vec<String> = width
            .iter()
            .zip(&self.header)
            .map(|(w, h)| if h.is_empty() { String::new() } else { "-".repeat(*w) })
            .collect();
        out.push_str(rule.join("  ").trim_end());
        for r in &self.rows {
            out.push('\n');
            out.push_str(line(r).trim_end());
        }
        out
    }
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

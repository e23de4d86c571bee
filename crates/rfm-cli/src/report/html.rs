//! A self-contained HTML report: one file with inline CSS and inline SVG
//! figures, no scripts and no external resources, so that it opens offline
//! and can be mailed or archived as it is.
//!
//! A [`Report`] is a title and a list of [`Section`]s, each a list of
//! [`Block`]s; commands build the sections they need (a later section, such
//! as a mode table, is appended without touching the others).

/// A report: title, optional subtitle, sections in order.
pub(crate) struct Report {
    /// Title (the case's title and what was done).
    pub(crate) title: String,
    /// A line under the title.
    pub(crate) subtitle: Option<String>,
    /// Sections.
    pub(crate) sections: Vec<Section>,
}

/// A titled section.
pub(crate) struct Section {
    /// Heading.
    pub(crate) heading: String,
    /// Content.
    pub(crate) blocks: Vec<Block>,
}

impl Section {
    /// An empty section.
    pub(crate) fn new(heading: impl Into<String>) -> Self {
        Section { heading: heading.into(), blocks: Vec::new() }
    }

    /// Appends a block.
    pub(crate) fn push(&mut self, block: Block) -> &mut Self {
        self.blocks.push(block);
        self
    }
}

/// Content of a section.
pub(crate) enum Block {
    /// A paragraph of plain text (escaped).
    Text(String),
    /// Label-value pairs shown as a compact list.
    Facts(Vec<(String, String)>),
    /// A table.
    Table(Table),
    /// An SVG figure with a caption.
    Figure(Figure),
    /// A paragraph folded away under a one-line summary (HTML `<details>`,
    /// which opens without scripts).
    Details {
        /// What the fold holds, always shown.
        summary: String,
        /// The folded text.
        text: String,
    },
}

/// A table cell's emphasis.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Tone {
    /// Plain.
    Plain,
    /// Highlighted as a problem (the worst entries).
    Bad,
    /// Highlighted as good.
    Good,
}

/// A table with a header; cells other than the first column are right-aligned numbers.
///
/// A long table shows its first [`Table::shown`] rows and folds the rest
/// under a `<details>` element, so that a 100-row iteration history does
/// not push the figures after it out of sight.
pub(crate) struct Table {
    /// Caption above the table.
    pub(crate) caption: Option<String>,
    /// Column headings.
    pub(crate) header: Vec<String>,
    /// Rows of (text, tone).
    pub(crate) rows: Vec<Vec<(String, Tone)>>,
    /// Rows shown before the fold, when there are more than [`FOLD_ABOVE`].
    pub(crate) shown: usize,
}

/// Tables with more rows than this are folded after their first rows.
pub(crate) const FOLD_ABOVE: usize = 15;

/// Rows a folded table shows by default.
pub(crate) const SHOWN_ROWS: usize = 10;

impl Table {
    /// A table with the given headings.
    pub(crate) fn new(header: &[&str]) -> Self {
        Table {
            caption: None,
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
            shown: SHOWN_ROWS,
        }
    }

    /// Sets the caption.
    pub(crate) fn caption(mut self, text: impl Into<String>) -> Self {
        self.caption = Some(text.into());
        self
    }

    /// Appends a row of plain cells.
    pub(crate) fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells.into_iter().map(|c| (c, Tone::Plain)).collect());
    }

    /// Appends a row with tones.
    pub(crate) fn row_toned(&mut self, cells: Vec<(String, Tone)>) {
        self.rows.push(cells);
    }

    /// The table as CSV (RFC 4180): the header, then every row, each cell
    /// as the report shows it, quoted where it holds a comma, a quote or a
    /// line break.
    pub(crate) fn to_csv(&self) -> String {
        let cell = |c: &str| {
            if c.contains([',', '"', '\n', '\r']) { format!("\"{}\"", c.replace('"', "\"\"")) } else { c.to_string() }
        };
        let mut out = self.header.iter().map(|h| cell(h)).collect::<Vec<_>>().join(",");
        out.push('\n');
        for r in &self.rows {
            out.push_str(&r.iter().map(|(c, _)| cell(c)).collect::<Vec<_>>().join(","));
            out.push('\n');
        }
        out
    }
}

/// An inline SVG figure.
pub(crate) struct Figure {
    /// The SVG document (as plotters writes it).
    pub(crate) svg: String,
    /// Caption under the figure.
    pub(crate) caption: String,
}

/// Escapes text for HTML element content and attribute values.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Makes a plotters SVG scale with the page: the fixed `width`/`height` of
/// its root element are replaced by a relative width (the `viewBox` keeps
/// the aspect ratio) that never exceeds the drawn width, so that its text is
/// never blown up past the size it was drawn at; and an accessible name is
/// added.
fn responsive(svg: &str, label: &str) -> String {
    let Some(start) = svg.find("<svg") else {
        return svg.to_string();
    };
    let end = start + svg[start..].find('>').unwrap_or(0);
    let open = &svg[start..end];
    let mut attrs = String::new();
    let mut width = None;
    let mut rest = open.trim_start_matches("<svg");
    // keep every attribute but width and height
    while let Some(eq) = rest.find("=\"") {
        let name = rest[..eq].trim();
        let after = &rest[eq + 2..];
        let Some(close) = after.find('"') else { break };
        let value = &after[..close];
        match name {
            "width" => width = value.parse::<u32>().ok(),
            "height" => {}
            _ => attrs.push_str(&format!(" {name}=\"{value}\"")),
        }
        rest = &after[close + 1..];
    }
    let style = width.map_or(String::new(), |w| format!(" style=\"max-width: {w}px\""));
    format!(
        "{}<svg{attrs}{style} role=\"img\" aria-label=\"{}\" class=\"figure\">{}",
        &svg[..start],
        escape(label),
        &svg[end + 1..]
    )
}

const CSS: &str = r#"
:root { --ink: #1d1d1f; --muted: #5f6368; --rule: #d9d9de; --zebra: #f6f6f8; --accent: #0072b2;
        --bad: #fde8e1; --bad-ink: #8a2b06; --good: #e3f4ec; --good-ink: #04593e; }
* { box-sizing: border-box; }
body { margin: 0; color: var(--ink); background: #fff;
       font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1180px; margin: 0 auto; padding: 24px 28px 64px; }
header { border-bottom: 3px solid var(--accent); margin-bottom: 20px; padding-bottom: 10px; }
h1 { font-size: 26px; margin: 0 0 4px; }
.subtitle { color: var(--muted); margin: 0; }
h2 { font-size: 20px; margin: 36px 0 10px; padding-bottom: 4px; border-bottom: 1px solid var(--rule); }
nav ol { margin: 6px 0 0; padding-left: 22px; columns: 2; }
nav a { color: var(--accent); text-decoration: none; }
dl.facts { display: grid; grid-template-columns: max-content 1fr; gap: 3px 18px; margin: 10px 0; }
dl.facts dt { color: var(--muted); }
dl.facts dd { margin: 0; font-variant-numeric: tabular-nums; }
table { border-collapse: collapse; margin: 10px 0 18px; font-size: 13.5px; font-variant-numeric: tabular-nums; }
p.table-caption { color: var(--muted); margin: 14px 0 0; font-size: 14px; }
p.table-caption + .scroll table { margin-top: 6px; }
th, td { padding: 4px 9px; border-bottom: 1px solid var(--rule); }
th { text-align: right; vertical-align: bottom; background: #eef0f4; font-weight: 600; min-width: 4.5em; }
td { text-align: right; white-space: nowrap; }
th:first-child, td:first-child, th.text, td.text { text-align: left; }
tbody tr:nth-child(even) { background: var(--zebra); }
td.bad { background: var(--bad); color: var(--bad-ink); font-weight: 600; }
td.good { background: var(--good); color: var(--good-ink); }
.scroll { overflow-x: auto; }
figure { margin: 14px 0 26px; }
svg.figure { width: 100%; height: auto; display: block; margin: 0 auto; border: 1px solid var(--rule); }
figcaption { color: var(--muted); font-size: 14px; margin-top: 6px; }
details { margin: 4px 0 18px; }
summary { color: var(--accent); cursor: pointer; font-size: 14px; }
details > p { font-size: 13.5px; color: var(--muted); }
footer { margin-top: 48px; color: var(--muted); font-size: 13px; border-top: 1px solid var(--rule); padding-top: 8px; }
@media print { main { max-width: none; padding: 0; } figure, table { break-inside: avoid; } nav { display: none; } }
"#;

impl Report {
    /// A report without sections.
    pub(crate) fn new(title: impl Into<String>) -> Self {
        Report { title: title.into(), subtitle: None, sections: Vec::new() }
    }

    /// The whole HTML document.
    pub(crate) fn render(&self) -> String {
        let mut h = String::new();
        h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        h.push_str(&format!("<title>{}</title>\n<style>{CSS}</style>\n</head>\n<body>\n<main>\n", escape(&self.title)));
        h.push_str(&format!("<header>\n<h1>{}</h1>\n", escape(&self.title)));
        if let Some(s) = &self.subtitle {
            h.push_str(&format!("<p class=\"subtitle\">{}</p>\n", escape(s)));
        }
        h.push_str("</header>\n");
        if self.sections.len() > 2 {
            h.push_str("<nav><strong>Contents</strong><ol>\n");
            for (i, s) in self.sections.iter().enumerate() {
                h.push_str(&format!("<li><a href=\"#s{}\">{}</a></li>\n", i + 1, escape(&s.heading)));
            }
            h.push_str("</ol></nav>\n");
        }
        let mut figure_no = 0;
        for (i, s) in self.sections.iter().enumerate() {
            h.push_str(&format!("<section id=\"s{}\">\n<h2>{}</h2>\n", i + 1, escape(&s.heading)));
            for b in &s.blocks {
                match b {
                    Block::Text(t) => h.push_str(&format!("<p>{}</p>\n", escape(t))),
                    Block::Facts(items) => {
                        h.push_str("<dl class=\"facts\">\n");
                        for (k, v) in items {
                            h.push_str(&format!("<dt>{}</dt><dd>{}</dd>\n", escape(k), escape(v)));
                        }
                        h.push_str("</dl>\n");
                    }
                    Block::Table(t) => render_table(&mut h, t),
                    Block::Details { summary, text } => h.push_str(&format!(
                        "<details><summary>{}</summary><p>{}</p></details>\n",
                        escape(summary),
                        escape(text)
                    )),
                    Block::Figure(f) => {
                        figure_no += 1;
                        h.push_str("<figure>\n");
                        h.push_str(&responsive(&f.svg, &f.caption));
                        h.push_str(&format!(
                            "<figcaption><strong>Figure {figure_no}.</strong> {}</figcaption>\n</figure>\n",
                            escape(&f.caption)
                        ));
                    }
                }
            }
            h.push_str("</section>\n");
        }
        h.push_str(&format!(
            "<footer>Written by rfm {} (FRF-based model updating with exponential non-viscous damping, after \
             Arora, Adhikari and Vijayan, J. Sound Vib. 2023). This file is self-contained: figures are inline \
             SVG and it loads nothing from elsewhere.</footer>\n",
            env!("CARGO_PKG_VERSION")
        ));
        h.push_str("</main>\n</body>\n</html>\n");
        h
    }
}

fn render_table(h: &mut String, t: &Table) {
    // the caption is a paragraph above the table rather than a <caption>,
    // which browsers squeeze to the width of a narrow table
    if let Some(c) = &t.caption {
        h.push_str(&format!("<p class=\"table-caption\">{}</p>\n", escape(c)));
    }
    let fold = t.rows.len() > FOLD_ABOVE;
    let (first, rest) = t.rows.split_at(if fold { t.shown.min(t.rows.len()) } else { t.rows.len() });
    render_rows(h, &t.header, first);
    if fold {
        h.push_str(&format!(
            "<details class=\"more-rows\"><summary>The other {} rows (of {})</summary>\n",
            rest.len(),
            t.rows.len()
        ));
        render_rows(h, &t.header, rest);
        h.push_str("</details>\n");
    }
}

/// Whether a cell reads as a number (or is empty or a dash): numbers are
/// right-aligned, a column of words left-aligned.
fn numeric(c: &str) -> bool {
    let c = c.trim().trim_end_matches('%').trim_end().replace(',', "");
    let c = c.split_whitespace().next().unwrap_or("");
    c.is_empty() || c == "-" || c.trim_start_matches(['+', 'x']).parse::<f64>().is_ok()
}

fn render_rows(h: &mut String, header: &[String], rows: &[Vec<(String, Tone)>]) {
    // a column whose cells are not numbers is text, aligned to the left
    let text: Vec<bool> =
        (0..header.len()).map(|k| k > 0 && rows.iter().any(|r| r.get(k).is_some_and(|(c, _)| !numeric(c)))).collect();
    h.push_str("<div class=\"scroll\"><table>\n");
    h.push_str("<thead><tr>");
    for (k, c) in header.iter().enumerate() {
        let class = if text[k] { " class=\"text\"" } else { "" };
        h.push_str(&format!("<th{class}>{}</th>", escape(c)));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        h.push_str("<tr>");
        for (k, (text_cell, tone)) in r.iter().enumerate() {
            let mut classes: Vec<&str> = Vec::new();
            match tone {
                Tone::Plain => {}
                Tone::Bad => classes.push("bad"),
                Tone::Good => classes.push("good"),
            }
            if text.get(k).copied().unwrap_or(false) {
                classes.push("text");
            }
            let class = if classes.is_empty() { String::new() } else { format!(" class=\"{}\"", classes.join(" ")) };
            h.push_str(&format!("<td{class}>{}</td>", escape(text_cell)));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table></div>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_svgs_scale_with_the_page() {
        let mut r = Report::new("a <b> & c");
        let mut s = Section::new("one");
        let mut t = Table::new(&["x", "y"]);
        t.row_toned(vec![("<1>".into(), Tone::Plain), ("2".into(), Tone::Bad)]);
        s.push(Block::Table(t));
        s.push(Block::Figure(Figure {
            svg: "<svg width=\"960\" height=\"400\" viewBox=\"0 0 960 400\" xmlns=\"http://www.w3.org/2000/svg\">\n<rect/>\n</svg>"
                .into(),
            caption: "cap \"q\"".into(),
        }));
        r.sections.push(s);
        let html = r.render();
        assert!(html.contains("<h1>a &lt;b&gt; &amp; c</h1>"));
        assert!(html.contains("<td>&lt;1&gt;</td><td class=\"bad\">2</td>"));
        assert!(html.contains(
            "<svg viewBox=\"0 0 960 400\" xmlns=\"http://www.w3.org/2000/svg\" style=\"max-width: 960px\" role=\"img\" aria-label=\"cap &quot;q&quot;\" class=\"figure\">\n<rect/>"
        ));
        assert!(!html.contains("width=\"960\""));
        assert!(!html.contains("<script"));
        // a column of words is left-aligned, one of numbers not
        let mut t = Table::new(&["k", "effect", "dBIC"]);
        t.row(vec!["1".into(), "joint at node 13".into(), "-56,161,045".into()]);
        t.row(vec!["2".into(), "mass".into(), "-".into()]);
        let mut r = Report::new("t");
        let mut s = Section::new("one");
        s.push(Block::Table(t));
        r.sections.push(s);
        let html = r.render();
        assert!(html.contains("<th class=\"text\">effect</th><th>dBIC</th>"), "{html}");
        assert!(html.contains("<td class=\"text\">joint at node 13</td><td>-56,161,045</td>"), "{html}");
    }

    /// Every row and cell, cells with commas or quotes quoted.
    #[test]
    fn tables_write_as_csv() {
        let mut t = Table::new(&["effect", "dBIC"]);
        t.row(vec!["joint at node 13, \"viscous\"".into(), "-56,161,045".into()]);
        t.row(vec!["mass".into(), "-7.0".into()]);
        assert_eq!(t.to_csv(), "effect,dBIC\n\"joint at node 13, \"\"viscous\"\"\",\"-56,161,045\"\nmass,-7.0\n");
    }

    #[test]
    fn long_tables_fold_after_their_first_rows_and_short_ones_do_not() {
        let mut long = Table::new(&["k"]);
        for k in 0..=FOLD_ABOVE {
            long.row(vec![format!("row {k}")]);
        }
        let mut short = Table::new(&["k"]);
        for k in 0..FOLD_ABOVE {
            short.row(vec![format!("row {k}")]);
        }
        let mut r = Report::new("t");
        let mut s = Section::new("one");
        s.push(Block::Table(long));
        r.sections.push(s);
        let html = r.render();
        let fold = html.find("<details").expect("the long table folds");
        assert_eq!(html[..fold].matches("<tr>").count(), 1 + SHOWN_ROWS, "the header and the first rows");
        assert_eq!(html[fold..].matches("<td>").count(), FOLD_ABOVE + 1 - SHOWN_ROWS);
        assert!(html.contains(&format!("The other {} rows (of {})", FOLD_ABOVE + 1 - SHOWN_ROWS, FOLD_ABOVE + 1)));
        let mut r = Report::new("t");
        let mut s = Section::new("one");
        s.push(Block::Table(short));
        s.push(Block::Details { summary: "200 lines".into(), text: "1, 2 & 3".into() });
        r.sections.push(s);
        let html = r.render();
        assert_eq!(html.matches("<details").count(), 1, "only the text is folded");
        assert!(html.contains("<details><summary>200 lines</summary><p>1, 2 &amp; 3</p></details>"));
    }
}

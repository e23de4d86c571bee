//! Plots and reports: SVG figures ([`plot`]), the self-contained HTML
//! report ([`html`]), the JSON form of an FRF correlation ([`json`]), the
//! report sections shared by `rfm compare` and `rfm update` (this module),
//! the update report ([`update_report`]) and the report of the loop
//! ([`fix_report`]).
//!
//! Figures are drawn to strings and written through the run's
//! [`Outputs`], all or nothing.

pub(crate) mod fix_report;
pub(crate) mod html;
pub(crate) mod json;
pub(crate) mod plot;
pub(crate) mod update_report;

use frf::correlation::Correlation;
use frf::{Channel, FrfSet};
use plotters::style::RGBColor;

use html::{Block, Figure, Section, Table, Tone};

use crate::output::Outputs;

pub(crate) type Result<T> = crate::commands::Result<T>;

impl Outputs {
    /// Writes a figure as `name.svg` and returns it as a report block.
    pub(crate) fn figure(&mut self, name: &str, svg: String, caption: impl Into<String>) -> Result<Block> {
        self.write(&format!("{name}.svg"), svg.as_bytes())?;
        Ok(Block::Figure(Figure { svg, caption: caption.into() }))
    }
}

/// One model's FRFs on the measured lines and their correlation with the
/// measurement.
pub(crate) struct ModelFrfs {
    /// Legend and table label (`initial model`, `updated model`).
    pub(crate) label: String,
    /// Colour in the figures.
    pub(crate) colour: RGBColor,
    /// FRFs on the measured lines and channels.
    pub(crate) frfs: FrfSet,
    /// Correlation with the measured FRFs.
    pub(crate) correlation: Correlation,
}

/// A file-name-safe form of a channel: `H(31:uy,2:rz)` -> `frf-31uy-2rz`.
pub(crate) fn channel_file_stem(c: Channel) -> String {
    let clean = |s: String| s.chars().filter(char::is_ascii_alphanumeric).collect::<String>();
    format!("frf-{}-{}", clean(c.response.to_string()), clean(c.reference.to_string()))
}

/// Channels to show as overlays: the driving point(s) first (at most one
/// per reference, at most `n / 2`), then the `priority` channels (e.g. the
/// worst ones), then a spread over the rest, `n` at most in all.
pub(crate) fn representative_channels(set: &FrfSet, priority: &[usize], n: usize) -> Vec<usize> {
    let channels = set.channels();
    let mut out: Vec<usize> = Vec::new();
    let mut refs_done = Vec::new();
    for (i, c) in channels.iter().enumerate() {
        if c.response == c.reference && !refs_done.contains(&c.reference) && out.len() < n.div_ceil(2) {
            refs_done.push(c.reference);
            out.push(i);
        }
    }
    for &p in priority {
        if out.len() < n && p < channels.len() && !out.contains(&p) {
            out.push(p);
        }
    }
    let rest: Vec<usize> = (0..channels.len()).filter(|i| !out.contains(i)).collect();
    let want = n.saturating_sub(out.len()).min(rest.len());
    // evenly over the remaining channels, ends included
    for j in 0..want {
        let pos = if want == 1 { rest.len() / 2 } else { j * (rest.len() - 1) / (want - 1) };
        if !out.contains(&rest[pos]) {
            out.push(rest[pos]);
        }
    }
    out
}

/// Why a channel was picked for an overlay, for its caption.
fn role(set: &FrfSet, c: usize, priority: &[usize]) -> &'static str {
    let ch = set.channels()[c];
    if ch.response == ch.reference {
        "driving point"
    } else if priority.contains(&c) {
        "among the largest errors"
    } else {
        "transfer FRF"
    }
}

/// A number with about `sig` significant digits in a short form: fixed
/// notation for moderate magnitudes, exponent notation for tiny or huge ones.
pub(crate) fn sig(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return if v.is_nan() { "-".into() } else { format!("{v}") };
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        let decimals = (sig as i32 - 1 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.prec$e}", prec = sig.saturating_sub(1))
    }
}

/// A frequency or a plain value without trailing zeros: `0.5`, `31.25`, `400`
/// (up to 4 decimals; exponent notation outside 1e-3 to 1e6).
pub(crate) fn short(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e6).contains(&v.abs()) {
        return sig(v, 4);
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// Drops trailing zeros after a decimal point (`0.500` -> `0.5`), leaving
/// exponent notation alone.
pub(crate) fn trimmed(s: String) -> String {
    if s.contains('.') && !s.contains('e') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// A signed number with an explicit `+`.
pub(crate) fn signed(v: f64, digits: usize) -> String {
    let s = sig(v, digits);
    if v > 0.0 { format!("+{s}") } else { s }
}

/// Percent with one decimal.
pub(crate) fn percent(v: f64) -> String {
    if v.is_finite() { format!("{:.1} %", 100.0 * v) } else { "-".into() }
}

/// Below this complex-log misfit (about 0.4 dB or 3 degrees RMS) a channel
/// or band is not highlighted as a problem even if it is the worst: the
/// model matches there.
pub(crate) const NOTABLE_MISFIT: f64 = 0.05;

/// The `n` worst channels of a correlation that are worth pointing at.
pub(crate) fn notable_channels(c: &Correlation, n: usize) -> Vec<usize> {
    c.worst_channels(n).into_iter().filter(|&i| c.channels[i].log_misfit >= NOTABLE_MISFIT).collect()
}

/// The `n` worst bands of a correlation that are worth pointing at.
pub(crate) fn notable_bands(c: &Correlation, n: usize) -> Vec<usize> {
    c.worst_bands(n).into_iter().filter(|&i| c.bands[i].log_misfit >= NOTABLE_MISFIT).collect()
}

/// `initial model` -> `initial`, for column headings.
fn short_label(label: &str) -> &str {
    label.split_whitespace().next().unwrap_or(label)
}

/// The FRF correlation section: totals per model, error against frequency,
/// error per channel, the band table and the channel table. Figures are
/// written through `out`; `notes` are paragraphs put first.
pub(crate) fn correlation_section(
    measured: &FrfSet,
    models: &[ModelFrfs],
    out: &mut Outputs,
    notes: Vec<String>,
) -> Result<Section> {
    let mut s = Section::new("FRF correlation");
    for n in notes {
        s.push(Block::Text(n));
    }
    let Some(last) = models.last() else {
        return Ok(s);
    };
    // totals, one column per model
    let mut header = vec!["measure"];
    header.extend(models.iter().map(|m| m.label.as_str()));
    let mut t = Table::new(&header).caption(format!(
        "Over all {} channels and {} lines ({} to {} Hz), compared as {}.",
        measured.channels().len(),
        measured.n_freq(),
        short(measured.frequencies_hz().first().copied().unwrap_or(0.0)),
        short(measured.frequencies_hz().last().copied().unwrap_or(0.0)),
        measured.kind()
    ));
    type Measure = (&'static str, fn(&frf::correlation::Totals) -> String);
    let rows: [Measure; 7] = [
        ("RMS magnitude error (dB)", |t| sig(t.rms_db, 3)),
        ("mean magnitude error (dB)", |t| signed(t.mean_db, 3)),
        ("RMS phase error (deg)", |t| sig(t.rms_phase_deg, 3)),
        ("mean FRAC", |t| format!("{:.4}", t.mean_frac)),
        ("lowest FRAC", |t| format!("{:.4}", t.min_frac)),
        ("complex-log misfit", |t| sig(t.log_misfit, 3)),
        ("relative residual |A - X| / |X|", |t| sig(t.relative_residual, 3)),
    ];
    for (name, f) in rows {
        let mut row = vec![name.to_string()];
        row.extend(models.iter().map(|m| f(&m.correlation.total)));
        t.row(row);
    }
    let excluded: usize = models.iter().map(|m| m.correlation.total.lines_excluded).sum();
    s.push(Block::Table(t));
    if excluded > 0 {
        s.push(Block::Text(format!(
            "{excluded} (channel, line) values were left out because a value was zero or not finite."
        )));
    }

    let bands: Vec<frf::correlation::Band> = last.correlation.bands.iter().map(|b| b.band.clone()).collect();
    let curves: Vec<plot::ErrorCurve<'_>> = models
        .iter()
        .map(|m| plot::ErrorCurve { label: m.label.clone(), colour: m.colour, lines: &m.correlation.lines })
        .collect();
    let svg = plot::error_vs_frequency("Error against frequency (RMS over channels)", &curves, &bands)?;
    s.push(out.figure(
        "error-vs-frequency",
        svg,
        "RMS over all channels of the magnitude error 20 log10(|model| / |measured|) and of the wrapped phase \
         error at each line. Peaks near resonances mean a frequency shift (stiffness or mass) or a wrong peak \
         height (damping); a raised level across a whole band points at a gain or a broad stiffness error. \
         Shaded bands are numbered as in the band table.",
    )?);

    let names: Vec<String> = measured.channels().iter().map(|c| c.response.to_string()).collect();
    let series: Vec<plot::ChannelSeries> = models
        .iter()
        .map(|m| plot::ChannelSeries {
            label: m.label.clone(),
            colour: m.colour,
            rms_db: m.correlation.channels.iter().map(|c| c.rms_db).collect(),
            frac: m.correlation.channels.iter().map(|c| c.frac).collect(),
        })
        .collect();
    let svg = plot::channel_errors("Error per channel", &names, &series)?;
    s.push(out.figure(
        "channel-errors",
        svg,
        "RMS magnitude error and FRAC per measured channel (labelled by response DOF). A single bad channel \
         suggests a sensor problem (position, direction, calibration) or a local model error near it; FRAC near \
         1 with a large dB error means the right shape at the wrong level.",
    )?);

    // bands
    let worst_bands = notable_bands(&last.correlation, 3);
    let mut header: Vec<String> = vec!["band".into(), "range".into(), "lines".into()];
    for m in models {
        for what in ["RMS dB", "mean dB", "RMS phase (deg)", "share"] {
            header.push(if models.len() > 1 {
                format!("{what} ({})", short_label(&m.label))
            } else {
                what.to_string()
            });
        }
    }
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(&header_refs).caption(format!(
        "Errors per frequency band over all channels; share is the band's part of the total squared \
         complex-log error. Highlighted: the worst bands of the {} (at most three, only where the misfit \
         exceeds {NOTABLE_MISFIT}).",
        last.label
    ));
    for (i, b) in last.correlation.bands.iter().enumerate() {
        let name = match b.band.resonance_hz {
            Some(f) => format!("{}: peak at {} Hz", i + 1, trimmed(sig(f, 4))),
            None => format!("{}", i + 1),
        };
        let mut row = vec![
            (name, Tone::Plain),
            (format!("{}-{} Hz", trimmed(sig(b.band.lo_hz, 3)), trimmed(sig(b.band.hi_hz, 3))), Tone::Plain),
            (b.lines.to_string(), Tone::Plain),
        ];
        for m in models {
            let mb = &m.correlation.bands[i];
            let tone = if std::ptr::eq(m, last) && worst_bands.contains(&i) { Tone::Bad } else { Tone::Plain };
            row.push((sig(mb.rms_db, 3), tone));
            row.push((signed(mb.mean_db, 3), Tone::Plain));
            row.push((sig(mb.rms_phase_deg, 3), Tone::Plain));
            row.push((percent(mb.share), Tone::Plain));
        }
        t.row_toned(row);
    }
    s.push(Block::Table(t));

    // channels
    let worst = notable_channels(&last.correlation, 3);
    let mut header: Vec<String> = vec!["channel".into()];
    for m in models {
        for what in ["RMS dB", "mean dB", "RMS phase (deg)", "FRAC", "share"] {
            header.push(if models.len() > 1 {
                format!("{what} ({})", short_label(&m.label))
            } else {
                what.to_string()
            });
        }
    }
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(&header_refs).caption(format!(
        "Errors per channel over all lines. Highlighted: the worst channels of the {} by complex-log \
         misfit (at most three, only where it exceeds {NOTABLE_MISFIT}).",
        last.label
    ));
    for (c, ch) in measured.channels().iter().enumerate() {
        let mut row = vec![(ch.to_string(), Tone::Plain)];
        for m in models {
            let mc = &m.correlation.channels[c];
            let tone = if std::ptr::eq(m, last) && worst.contains(&c) { Tone::Bad } else { Tone::Plain };
            row.push((sig(mc.rms_db, 3), tone));
            row.push((signed(mc.mean_db, 3), Tone::Plain));
            row.push((sig(mc.rms_phase_deg, 3), Tone::Plain));
            row.push((format!("{:.4}", mc.frac), Tone::Plain));
            row.push((percent(mc.share), Tone::Plain));
        }
        t.row_toned(row);
    }
    s.push(Block::Table(t));
    Ok(s)
}

/// The overlay section: one figure per chosen channel with the measured FRF
/// and every model's, updating lines marked when given.
pub(crate) fn overlay_section(
    measured: &FrfSet,
    models: &[ModelFrfs],
    channels: &[usize],
    priority: &[usize],
    marks_hz: &[f64],
    out: &mut Outputs,
) -> Result<Section> {
    let mut s = Section::new("FRF overlays");
    s.push(Block::Text(format!(
        "Measured and model FRFs ({}) of {} representative channels: the driving point first, then the \
         channels with the largest errors and a spread over the others. Magnitude in dB (20 log10 |H|), phase \
         in degrees wrapped to one turn.{}",
        measured.kind(),
        channels.len(),
        if marks_hz.is_empty() { "" } else { " Circles mark the lines used for updating." }
    )));
    for &c in channels {
        let ch = measured.channels()[c];
        let mut curves =
            vec![plot::FrfCurve { label: "measured".into(), colour: plot::MEASURED, values: measured.channel(c) }];
        for m in models {
            let mc = m.frfs.find(ch).ok_or_else(|| format!("the model FRFs lack channel {ch}"))?;
            curves.push(plot::FrfCurve { label: m.label.clone(), colour: m.colour, values: m.frfs.channel(mc) });
        }
        let title = format!("{ch}: response {} over excitation {}", ch.response, ch.reference);
        let svg = plot::frf_overlay(&plot::Overlay {
            title,
            frequencies_hz: measured.frequencies_hz(),
            kind: measured.kind(),
            curves,
            marks_hz,
        })?;
        let stats: Vec<String> = models
            .iter()
            .map(|m| {
                let cc = &m.correlation.channels[c];
                format!(
                    "{}: RMS {} dB, {} deg, FRAC {:.3}",
                    m.label,
                    sig(cc.rms_db, 3),
                    sig(cc.rms_phase_deg, 3),
                    cc.frac
                )
            })
            .collect();
        let caption = format!("{ch} ({}). {}.", role(measured, c, priority), stats.join("; "));
        s.push(out.figure(&channel_file_stem(ch), svg, caption)?);
    }
    Ok(s)
}

/// A short section that says how to read the numbers.
pub(crate) fn definitions_section() -> Section {
    let mut s = Section::new("How to read this report");
    s.push(Block::Facts(vec![
        (
            "magnitude error".into(),
            "20 log10(|model| / |measured|) in dB, per line; positive when the model is too high. \
             A constant 2x is 6.02 dB."
                .into(),
        ),
        (
            "phase error".into(),
            "arg(model / measured) in degrees, wrapped to (-180, 180]; 90 means a quarter period late/early.".into(),
        ),
        (
            "FRAC".into(),
            "|sum conj(X) A|^2 / (sum |X|^2 sum |A|^2) per channel: 1 when the FRF shapes agree up to a \
             constant factor; falls when peaks move or change shape."
                .into(),
        ),
        (
            "complex-log misfit".into(),
            "RMS of |ln(A / X)|: magnitude (in nepers, 1 Np = 8.69 dB) and phase (in radians) errors together; \
             0.1 is about 0.9 dB or 6 deg."
                .into(),
        ),
        ("share".into(), "the part of the total squared complex-log misfit in a channel or band.".into()),
        (
            "bands".into(),
            "by default one band per measured resonance, edges halfway (geometrically) between neighbours.".into(),
        ),
        (
            "symptoms".into(),
            "a frequency shift (stiffness or mass) shows as large errors on both sides of a peak and a low FRAC; \
             a wrong peak height or width (damping) as errors confined to the peak with FRAC still high; a \
             uniform offset in one channel as a constant mean dB error (gain or calibration)."
                .into(),
        ),
    ]));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, DofRef};
    use frf::FrfKind;

    #[test]
    fn representative_channels_start_at_the_driving_point_and_spread() {
        let tip = DofRef::new(31, Dof::Uy);
        let channels: Vec<Channel> = (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let set = FrfSet::zeros(vec![1.0, 2.0], channels, FrfKind::Receptance).unwrap();
        let pick = representative_channels(&set, &[], 4);
        assert_eq!(pick[0], 29, "the driving point 31:uy comes first");
        assert_eq!(pick.len(), 4);
        assert_eq!(&pick[1..], &[0, 14, 28]);
        let pick = representative_channels(&set, &[5, 7], 4);
        assert_eq!(pick[..3], [29, 5, 7]);
        assert_eq!(channel_file_stem(set.channels()[0]), "frf-2uy-31uy");
    }

    #[test]
    fn numbers_are_short_and_keep_tiny_values_visible() {
        assert_eq!(sig(6.0206, 3), "6.02");
        assert_eq!(sig(123.456, 3), "123");
        assert_eq!(sig(2.5e-8, 3), "2.50e-8");
        assert_eq!(signed(0.5, 2), "+0.50");
        assert_eq!(sig(f64::NAN, 3), "-");
        assert_eq!(percent(0.4567), "45.7 %");
        assert_eq!(short(0.5), "0.5");
        assert_eq!(short(400.0), "400");
        assert_eq!(short(15.874), "15.874");
        assert_eq!(trimmed(sig(0.5, 3)), "0.5");
        assert_eq!(trimmed(sig(15.874, 3)), "15.9");
        assert_eq!(trimmed(sig(2.5e-8, 3)), "2.50e-8");
    }
}

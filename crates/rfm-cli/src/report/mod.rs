//! Plots and reports: SVG figures ([`plot`]), the self-contained HTML
//! report ([`html`]), the report sections shared by `rfm compare`, `rfm update` and `rfm fix`
//! (this module: the correlation, the overlays of every channel, the
//! structure, the definitions), the modal comparison ([`modes`]), the
//! update report ([`update_report`]), the report of a diagnosis
//! ([`diagnose_report`]), the report of the loop ([`fix_report`]), and
//! the data's findings and step 0 that the last two share ([`setup`]).
//!
//! Figures are drawn to strings and written through the run's
//! [`Outputs`], all or nothing.

pub(crate) mod diagnose_report;
pub(crate) mod fix_report;
pub(crate) mod html;
pub(crate) mod loop_story;
pub(crate) mod modes;
pub(crate) mod plot;
pub(crate) mod setup;
pub(crate) mod units;
pub(crate) mod update_report;

use std::path::{Path, PathBuf};

use fe_model::{DofRef, Model};
use frf::correlation::Correlation;
use frf::{Channel, FrfSet};
use plotters::style::RGBColor;
use rfm_update::gain::GainReport;
use rfm_update::quantities::MisfitReport;

use plot::axes::FrequencyScale;
use plot::structure::{Highlight, Sensors};

use html::{Block, Figure, Section, Table, Tone};
use units::DataUnits;

use crate::output::Outputs;

pub(crate) type Result<T> = crate::commands::Result<T>;

use rfm_update::quantities;

use crate::table;

impl Outputs {
    /// Writes a figure as `name.svg` and returns it as a report block.
    pub(crate) fn figure(&mut self, name: &str, svg: String, caption: impl Into<String>) -> Result<Block> {
        self.write(&format!("{name}.svg"), svg.as_bytes())?;
        Ok(Block::Figure(Figure { svg, caption: caption.into() }))
    }

    /// Writes a table as `name.csv` beside the report (for a spreadsheet)
    /// and returns it as a report block whose caption names the file.
    pub(crate) fn table(&mut self, name: &str, mut table: Table) -> Result<Block> {
        let file = format!("{name}.csv");
        self.write(&file, table.to_csv().as_bytes())?;
        let note = format!("(Also in {file}.)");
        table.caption = Some(match table.caption.take() {
            Some(c) => format!("{c} {note}"),
            None => note,
        });
        Ok(Block::Table(table))
    }
}

/// How a report draws what the command line and the case choose.
#[derive(Clone, Copy, Debug)]
pub struct ReportOptions {
    /// Scale of every frequency axis.
    pub frequency_scale: FrequencyScale,
    /// Lines of measured coherence below it are shaded in the FRF figures
    /// (the case's `[measurement] coherence_threshold`, see `ReportOptions::for_case`).
    pub coherence_threshold: f64,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            frequency_scale: FrequencyScale::default(),
            coherence_threshold: fe_model::case::DEFAULT_COHERENCE_THRESHOLD,
        }
    }
}

impl ReportOptions {
    /// These options with what `case` chooses (its coherence threshold).
    pub(crate) fn for_case(self, case: &fe_model::CaseFile) -> ReportOptions {
        let threshold = case.measurement.as_ref().map(|m| m.coherence_threshold);
        ReportOptions { coherence_threshold: threshold.unwrap_or(self.coherence_threshold), ..self }
    }
}

/// The measured FRFs a report shows, in the kind they were measured in,
/// with their unit and noise level.
pub(crate) struct Data<'a> {
    /// The FRFs as measured (accelerance per volt, say): every report of a
    /// case draws and compares this one kind.
    pub(crate) set: &'a FrfSet,
    /// What their values are in.
    pub(crate) units: DataUnits,
    /// Their noise level ([`rfm_update::quantities::NOISE`]) without line
    /// weights, as the errors the figures draw have none: for the noise
    /// floors; `None` when it is not known.
    pub(crate) noise: Option<f64>,
}

impl<'a> Data<'a> {
    /// The data `set`, per volt at the references `per_volt`, with their
    /// unweighted noise level.
    pub(crate) fn new(set: &'a FrfSet, per_volt: &[fe_model::DofRef], noise: Option<f64>) -> Data<'a> {
        Data { set, units: DataUnits::new(set.kind(), per_volt), noise }
    }

    /// The unit every channel shares (`m/s²/V`), or both.
    pub(crate) fn unit(&self) -> String {
        self.units.common(self.set.channels())
    }

    /// The data's quantity in words (`accelerance per volt`).
    pub(crate) fn quantity(&self) -> String {
        self.units.describe(self.set.channels())
    }
}

/// One model's FRFs on the measured lines and their correlation with the
/// measurement.
pub(crate) struct ModelFrfs {
    /// Legend and table label (`initial model`, `updated model`).
    pub(crate) label: String,
    /// Colour in the figures.
    pub(crate) colour: RGBColor,
    /// FRFs on the measured lines and channels, times `gains`.
    pub(crate) frfs: FrfSet,
    /// Correlation with the measured FRFs.
    pub(crate) correlation: Correlation,
    /// The gains the model's FRFs were multiplied by (empty without gains).
    pub(crate) gains: Vec<GainReport>,
    /// Its [`rfm_update::quantities::MISFIT`] and the noise, when known.
    pub(crate) misfit: Option<MisfitReport>,
}

/// The gains an update estimated, as reports show gains.
pub(crate) fn gain_reports(gains: &[rfm_update::output_error::Gain]) -> Vec<GainReport> {
    gains
        .iter()
        .map(|g| GainReport {
            key: g.key.to_string(),
            magnitude: g.magnitude,
            magnitude_db: 20.0 * g.magnitude.log10(),
            phase_deg: g.phase_deg,
        })
        .collect()
}

/// Where a mesh check is read, which decides what it means there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MeshReading {
    /// Beside a comparison, before any effect is fitted.
    Compared,
    /// Beside a ranking of candidate effects.
    Ranked,
    /// After the loop, which the mesh stopped (`true`) or not.
    Looped { stopped: bool },
}

/// The mesh check in one sentence, the same in the terminal and every
/// report, when the mesh decides part of what the model leaves
/// ([`rfm_update::diagnose::MeshCheck::visible`]): what it moves, and
/// what that means where it is read.
pub(crate) fn mesh_sentence(
    mesh: Option<&rfm_update::diagnose::MeshCheck>,
    noise: f64,
    reading: MeshReading,
) -> Option<String> {
    let m = mesh.filter(|m| m.visible(noise))?;
    let consequence = match reading {
        MeshReading::Compared => "a missing effect fitted to what the mesh decides stands for the mesh (refine it)",
        MeshReading::Ranked if m.explains(noise, rfm_update::fix::CONSISTENT) => {
            "the same model meshed finer explains the data to their noise: refine the mesh before adding any \
             effect (what the ranking proposes stands for the mesh)"
        }
        MeshReading::Looped { stopped: true } => {
            "what is left is the mesh's, and no effect is added for it (refine the mesh)"
        }
        MeshReading::Ranked | MeshReading::Looped { stopped: false } => {
            "effects found may stand in part for the mesh (refine it)"
        }
    };
    Some(format!("{}: {consequence}", m.describe(noise)))
}

/// How the loop's outcome reads its last mesh check.
pub(crate) fn mesh_reading(outcome: &rfm_update::fix::FixOutcome) -> MeshReading {
    MeshReading::Looped { stopped: outcome.stop == rfm_update::fix::FixStop::MeshTooCoarse }
}

/// [`mesh_sentence`] as a report's paragraph.
pub(crate) fn mesh_text(
    mesh: Option<&rfm_update::diagnose::MeshCheck>,
    noise: f64,
    reading: MeshReading,
) -> Option<Block> {
    let mut text = mesh_sentence(mesh, noise, reading)?;
    if let Some(first) = text.get_mut(..1) {
        first.make_ascii_uppercase();
    }
    Some(Block::Text(format!("{text}.")))
}

/// A gain in one form for every output: `5:uy: x40.26 (+32.1 dB) at -37.0 deg`.
/// The ranks folded into a row of the ranking
/// ([`rfm_update::diagnose::ShownRank::alike`]), as its note says them:
/// "ranks 3-5, 8 alike"; empty when none.
pub(crate) fn alike_text(alike: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < alike.len() {
        let mut j = i;
        while j + 1 < alike.len() && alike[j + 1] == alike[j] + 1 {
            j += 1;
        }
        parts.push(if j == i { alike[i].to_string() } else { format!("{}-{}", alike[i], alike[j]) });
        i = j + 1;
    }
    match alike.len() {
        0 => String::new(),
        1 => format!("rank {} alike", parts[0]),
        _ => format!("ranks {} alike", parts.join(", ")),
    }
}

/// What "alike" in the ranking's notes means, for its legend.
pub(crate) const ALIKE_LEGEND: &str = "ranks alike: the row's effect at its place, with the same form and \
     parameters, fitted from other starting values (a resonator's tuning) to a dBIC within 10 of its own: the data \
     do not tell them apart";

pub(crate) fn gain_text(g: &GainReport) -> String {
    format!(
        "{}: x{} ({:+.1} dB) at {:+.1} deg",
        g.key,
        crate::table::digits(g.magnitude, 4),
        g.magnitude_db,
        g.phase_deg
    )
}

/// The gains of a model in one phrase (empty without gains).
pub(crate) fn gains_text(gains: &[GainReport]) -> String {
    gains.iter().map(gain_text).collect::<Vec<_>>().join("; ")
}

/// A file-name-safe form of a channel: `H(31:uy,2:rz)` -> `frf-31uy-2rz`.
pub(crate) fn channel_file_stem(c: Channel) -> String {
    let clean = |s: String| s.chars().filter(char::is_ascii_alphanumeric).collect::<String>();
    format!("frf-{}-{}", clean(c.response.to_string()), clean(c.reference.to_string()))
}

/// The channels from the worst to the best by the complex-log misfit of
/// `c` (channels without a misfit last, in measurement order).
pub(crate) fn worst_first(c: &Correlation) -> Vec<usize> {
    let key = |i: usize| {
        let m = c.channels[i].log_misfit;
        if m.is_finite() { m } else { f64::NEG_INFINITY }
    };
    let mut order: Vec<usize> = (0..c.channels.len()).collect();
    order.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
    order
}

/// The distinct driving points of a set (response equal to reference), at
/// most `n`, in measurement order.
fn driving_points(set: &FrfSet, n: usize) -> Vec<usize> {
    let mut seen = Vec::new();
    set.channels()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.response == c.reference)
        .filter(|(_, c)| {
            let new = !seen.contains(&c.reference);
            seen.push(c.reference);
            new
        })
        .map(|(i, _)| i)
        .take(n)
        .collect()
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
    if v.is_finite() { format!("{} %", table::fixed(100.0 * v, 1, false)) } else { "-".into() }
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

/// A table header: the `first` columns, then each of `per_model` once per
/// model, named with the model where there are several.
fn per_model_header(first: &[&str], per_model: &[&str], models: &[ModelFrfs]) -> Vec<String> {
    let mut header: Vec<String> = first.iter().map(|s| s.to_string()).collect();
    for m in models {
        for what in per_model {
            header.push(if models.len() > 1 {
                format!("{what} ({})", short_label(&m.label))
            } else {
                what.to_string()
            });
        }
    }
    header
}

/// The FRF correlation section: totals per model, error against frequency,
/// error per channel, the band table and the channel table. Figures and
/// tables (as CSV) are written through `out`; `notes` are paragraphs put
/// first.
pub(crate) fn correlation_section(
    data: &Data<'_>,
    models: &[ModelFrfs],
    opts: &ReportOptions,
    out: &mut Outputs,
    notes: Vec<String>,
) -> Result<Section> {
    let measured = data.set;
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
    let with_misfit = models.iter().find_map(|m| m.misfit);
    let mut t = Table::new(&header).caption(format!(
        "The misfit over the {} lines the diagnosis reads{}; the other measures over all {} channels and {} lines \
         ({} to {} Hz), compared as {}.",
        with_misfit.map_or(quantities::MISFIT_LINES, |m| m.lines),
        if with_misfit.is_some_and(|m| m.weighted) { ", each value weighted by its coherence" } else { "" },
        measured.channels().len(),
        measured.n_freq(),
        short(measured.frequencies_hz().first().copied().unwrap_or(0.0)),
        short(measured.frequencies_hz().last().copied().unwrap_or(0.0)),
        data.quantity()
    ));
    let cell = |f: &dyn Fn(&ModelFrfs) -> String| models.iter().map(f).collect::<Vec<String>>();
    let mut rows: Vec<(String, Vec<String>)> = Vec::new();
    if with_misfit.is_some() {
        rows.push(("misfit".into(), cell(&|m| m.misfit.map_or("-".into(), |r| table::misfit(r.misfit)))));
        rows.push(("x noise".into(), cell(&|m| m.misfit.and_then(|r| r.times_noise).map_or("-".into(), table::times))));
    }
    rows.extend([
        ("RMS dB error".to_string(), cell(&|m| sig(m.correlation.total.rms_db, 3))),
        ("mean dB error".to_string(), cell(&|m| signed(m.correlation.total.mean_db, 3))),
        ("RMS phase error (deg)".to_string(), cell(&|m| sig(m.correlation.total.rms_phase_deg, 3))),
        ("mean FRAC".to_string(), cell(&|m| format!("{:.4}", m.correlation.total.mean_frac))),
        ("lowest FRAC".to_string(), cell(&|m| format!("{:.4}", m.correlation.total.min_frac))),
    ]);
    if models.iter().any(|m| !m.gains.is_empty()) {
        rows.push((
            "gain applied".into(),
            cell(&|m| if m.gains.is_empty() { "none".into() } else { gains_text(&m.gains) }),
        ));
    }
    for (name, cells) in rows {
        let mut row = vec![name];
        row.extend(cells);
        t.row(row);
    }
    let excluded: usize = models.iter().map(|m| m.correlation.total.lines_excluded).sum();
    s.push(out.table("totals", t)?);
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
    let svg = plot::error_vs_frequency(
        "Error against frequency (RMS over channels)",
        &curves,
        &bands,
        opts.frequency_scale,
        data.noise,
    )?;
    let floor = match data.noise {
        Some(n) => format!(
            " The dashed lines are the noise floor: the RMS errors the data's noise alone leaves, {1} dB and {2} \
             deg (its level {0}, read over all lines without weights, as these errors are); a model whose curve lies \
             on them is as good as the data allow.",
            table::misfit(n),
            sig(quantities::noise_floor_db(n), 2),
            sig(quantities::noise_floor_deg(n), 2)
        ),
        None => String::new(),
    };
    s.push(out.figure(
        "error-vs-frequency",
        svg,
        format!(
            "RMS over all channels of the dB error 20 log10(|model| / |measured|) and of the phase error at each \
             line. Peaks near resonances mean a frequency shift (stiffness or mass) or a wrong peak height \
             (damping); a raised level across a whole band points at a gain or a broad stiffness error. Shaded \
             bands are numbered as in the band table.{floor}"
        ),
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
        "RMS dB error (bars) and FRAC (dots) per measured channel, labelled by response DOF, one colour per \
         model. A single bad channel suggests a sensor problem (position, direction, calibration) or a local \
         model error near it; FRAC near 1 with a large dB error means the right shape at the wrong level.",
    )?);

    // bands
    let worst_bands = notable_bands(&last.correlation, 3);
    let header = per_model_header(
        &["band", "range", "lines"],
        &["RMS dB error", "mean dB error", "RMS phase error (deg)", "misfit", "share"],
        models,
    );
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(&header_refs).caption(format!(
        "Errors per frequency band over all channels and the band's lines; share is the band's part of the \
         squared misfit of all lines. Highlighted: the worst bands of the {} (at most three, only where the \
         misfit exceeds {NOTABLE_MISFIT}).",
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
            row.push((table::misfit(mb.log_misfit), Tone::Plain));
            row.push((percent(mb.share), Tone::Plain));
        }
        t.row_toned(row);
    }
    s.push(out.table("bands", t)?);

    // channels
    let worst = notable_channels(&last.correlation, 3);
    let header = per_model_header(
        &["channel"],
        &["RMS dB error", "mean dB error", "RMS phase error (deg)", "FRAC", "misfit", "share"],
        models,
    );
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(&header_refs).caption(format!(
        "Errors per channel over all its lines. Highlighted: the worst channels of the {} by misfit (at most \
         three, only where it exceeds {NOTABLE_MISFIT}).",
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
            row.push((table::misfit(mc.log_misfit), Tone::Plain));
            row.push((percent(mc.share), Tone::Plain));
        }
        t.row_toned(row);
    }
    s.push(out.table("channels", t)?);
    Ok(s)
}

/// Driving points drawn large, besides the small multiples of every channel.
const LARGE_OVERLAYS: usize = 2;

/// The overlay section: the driving points large, then every channel as
/// small multiples from the worst to the best (by the last model's
/// misfit), the updating lines as ticks on the frequency axis when given.
pub(crate) fn overlay_section(
    data: &Data<'_>,
    models: &[ModelFrfs],
    ticks_hz: &[f64],
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<Section> {
    let measured = data.set;
    let mut s = Section::new("FRF overlays");
    let n = measured.channels().len();
    let gains: Vec<String> = models
        .iter()
        .filter(|m| !m.gains.is_empty())
        .map(|m| format!("the {} by {}", m.label, gains_text(&m.gains)))
        .collect();
    s.push(Block::Text(format!(
        "Measured and model FRFs ({}) of all {n} channels, the driving point{} large first. Magnitude in dB \
         (20 log10 |H|, re 1 {}), phase in degrees drawn continuous: each model's phase at the turn nearest the \
         measured one, so that the gap between the curves is the phase error. The measurement is the wide grey \
         line; a model that matches it runs along its middle.{}{}{}{}",
        data.quantity(),
        if driving_points(measured, LARGE_OVERLAYS).len() > 1 { "s" } else { "" },
        data.unit(),
        if gains.is_empty() {
            String::new()
        } else {
            format!(" The model FRFs are multiplied by their fitted gains: {}.", gains.join("; "))
        },
        if data.noise.is_some() && !models.is_empty() {
            format!(
                " The thin line under the curves is the residual |model - measured| of the {}, the dashed one \
                 the noise floor (the data's noise level over all lines, {}, times |measured|): where the residual \
                 lies on the floor the model is as good as the data allow.",
                models.last().map_or("model", |m| m.label.as_str()),
                data.noise.map_or("-".into(), table::misfit)
            )
        } else {
            String::new()
        },
        if (0..n).any(|c| measured.coherence(c).is_some()) {
            format!(
                " Under the phase, the measured coherence, with the case's threshold ({}) dashed; lines below \
                 it are shaded in every panel.",
                opts.coherence_threshold
            )
        } else {
            String::new()
        },
        if ticks_hz.is_empty() { "" } else { " Ticks on the frequency axis mark the lines used for updating." }
    )));
    // every model's FRFs in the measured channels' order
    let mut columns: Vec<Vec<usize>> = Vec::new();
    for m in models {
        let idx = m.frfs.channel_indices();
        let col = measured
            .channels()
            .iter()
            .map(|ch| idx.get(ch).copied().ok_or_else(|| format!("the model FRFs lack channel {ch}")))
            .collect::<std::result::Result<Vec<usize>, String>>()?;
        columns.push(col);
    }
    let panel = |c: usize, title: String| plot::frf::FrfPanel {
        title,
        curves: std::iter::once(plot::frf::FrfCurve {
            label: "measured".into(),
            colour: plot::MEASURED_FRF,
            values: measured.channel(c),
        })
        .chain(models.iter().zip(&columns).map(|(m, col)| plot::frf::FrfCurve {
            label: m.label.clone(),
            colour: m.colour,
            values: m.frfs.channel(col[c]),
        }))
        .collect(),
        coherence: measured.coherence(c),
    };
    let stats = |c: usize| -> String {
        models
            .iter()
            .map(|m| {
                let cc = &m.correlation.channels[c];
                format!(
                    "{}: RMS dB error {}, RMS phase error {} deg, FRAC {:.3}",
                    m.label,
                    sig(cc.rms_db, 3),
                    sig(cc.rms_phase_deg, 3),
                    cc.frac
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let figure = |panels, title: String, unit: String| plot::frf::FrfFigure {
        title,
        frequencies_hz: measured.frequencies_hz(),
        unit,
        panels,
        ticks_hz,
        coherence_threshold: opts.coherence_threshold,
        scale: opts.frequency_scale,
        noise: data.noise,
    };

    for c in driving_points(measured, LARGE_OVERLAYS) {
        let ch = measured.channels()[c];
        let title = format!("{ch}: response {} over excitation {}", ch.response, ch.reference);
        let svg = plot::frf::frf_overlay(&figure(vec![panel(c, String::new())], title, data.units.of(&ch)))?;
        let caption = format!("{ch} (driving point), {}. {}.", data.units.describe(&[ch]), stats(c));
        s.push(out.figure(&channel_file_stem(ch), svg, caption)?);
    }

    let order = models.last().map_or_else(|| (0..n).collect(), |m| worst_first(&m.correlation));
    let chunks: Vec<&[usize]> = order.chunks(plot::frf::PANELS_PER_FIGURE).collect();
    for (k, chunk) in chunks.iter().enumerate() {
        let panels = chunk
            .iter()
            .enumerate()
            .map(|(j, &c)| {
                let rank = k * plot::frf::PANELS_PER_FIGURE + j + 1;
                let ch = measured.channels()[c];
                let worst = models.last().map_or(String::new(), |m| {
                    let cc = &m.correlation.channels[c];
                    format!(": {} dB, FRAC {:.3}", sig(cc.rms_db, 2), cc.frac)
                });
                panel(c, format!("{rank}. {ch}{worst}"))
            })
            .collect();
        let (name, title) = if chunks.len() == 1 {
            ("frf-channels".to_string(), format!("Every channel ({n}), worst first"))
        } else {
            (
                format!("frf-channels-{}", k + 1),
                format!(
                    "Channels {} to {} of {n}, worst first",
                    k * plot::frf::PANELS_PER_FIGURE + 1,
                    k * plot::frf::PANELS_PER_FIGURE + chunk.len()
                ),
            )
        };
        let shown: Vec<Channel> = chunk.iter().map(|&c| measured.channels()[c]).collect();
        let svg = plot::frf::frf_multiples(&figure(panels, title, data.units.common(&shown)))?;
        let last = models.last().map_or("model".into(), |m| m.label.clone());
        let caption = format!(
            "Measured (wide grey) and model FRFs of {} channels, magnitude in dB re 1 {}, ordered by the misfit \
             of the {last}, the worst first; each panel's title gives its RMS dB error and FRAC. Every panel has \
             its own magnitude scale.{}",
            chunk.len(),
            data.units.common(&shown),
            if chunk.iter().any(|&c| measured.coherence(c).is_some()) {
                " Shading marks lines where the measured coherence is below the case's threshold, and the \
                 coherence itself is drawn under the phase: the data are less certain there."
            } else {
                ""
            }
        );
        s.push(out.figure(&name, svg, caption)?);
    }
    Ok(s)
}

/// The natural frequencies and damping ratios of each model's complex
/// modes in the band `band_hz`, side by side (the k-th mode of each model
/// in frequency order on row k), after those the modal estimate found in
/// the data when given; a model too large for the dense modal analysis
/// has its column say so.
pub(crate) fn natural_frequency_table(
    models: &[(String, &damping::DampedSystem)],
    band_hz: (f64, f64),
    measured: Option<&frf::ModalComparison>,
) -> Table {
    /// A column's modes, `(Hz, damping ratio)` in frequency order; `None`
    /// where the modal analysis could not be made.
    type Modes = Option<Vec<(f64, f64)>>;
    let in_band = |f: f64| band_hz.0 <= f && f <= band_hz.1;
    let mut columns: Vec<(String, Modes)> = Vec::new();
    if let Some(c) = measured {
        let mut m: Vec<(f64, f64)> = c.measured.iter().map(|m| (m.frequency_hz, m.damping_ratio)).collect();
        m.sort_by(|a, b| a.0.total_cmp(&b.0));
        columns.push(("measured".into(), Some(m)));
    }
    for (label, sys) in models {
        let modes = damping::complex_modes(sys).ok().map(|m| {
            let mut v: Vec<(f64, f64)> = m
                .oscillatory
                .iter()
                .filter(|m| in_band(m.frequency_hz))
                .map(|m| (m.frequency_hz, m.damping_ratio))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            v
        });
        columns.push((label.clone(), modes));
    }
    let mut header = vec!["mode".to_string()];
    for (label, _) in &columns {
        header.push(format!("{label} Hz"));
        header.push(format!("{label} zeta %"));
    }
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let rows = columns.iter().filter_map(|(_, m)| m.as_ref().map(Vec::len)).max().unwrap_or(0);
    let too_large: Vec<&str> = columns.iter().filter(|(_, m)| m.is_none()).map(|(l, _)| l.as_str()).collect();
    let mut t = Table::new(&header_refs).caption(format!(
        "Natural frequencies and damping ratios of the complex modes in the band {} to {} Hz{}, each column in \
         frequency order (row k: the k-th mode of each){}.",
        short(band_hz.0),
        short(band_hz.1),
        if measured.is_some() { ", and the modes the modal estimate (LSCF) found in the data" } else { "" },
        if too_large.is_empty() {
            String::new()
        } else {
            format!("; not computed for {} (too large for the dense modal analysis)", too_large.join(", "))
        }
    ));
    for k in 0..rows {
        let mut row = vec![format!("{}", k + 1)];
        for (_, m) in &columns {
            match m.as_ref().and_then(|m| m.get(k)) {
                Some(&(f, z)) => {
                    row.push(format!("{f:.2}"));
                    row.push(format!("{:.3}", 100.0 * z));
                }
                None => row.extend(["-".to_string(), "-".to_string()]),
            }
        }
        t.row(row);
    }
    t
}

/// The distinct responses and references of a set's channels.
fn sensor_dofs(set: &FrfSet) -> (Vec<DofRef>, Vec<DofRef>) {
    let mut responses: Vec<DofRef> = Vec::new();
    let mut references: Vec<DofRef> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for c in set.channels() {
        if seen.insert((0, c.response)) {
            responses.push(c.response);
        }
        if seen.insert((1, c.reference)) {
            references.push(c.reference);
        }
    }
    (responses, references)
}

/// `path` for reading: `name/..` pairs taken out (`fix/../../data.csv` is
/// `../data.csv`). Only for display: through a symbolic link the two can
/// name different files, so files are opened by the path as given.
pub(crate) fn shown_path(path: &Path) -> String {
    use std::path::Component;
    let mut parts: Vec<Component<'_>> = Vec::new();
    for c in path.components() {
        match (c, parts.last()) {
            (Component::CurDir, _) if !parts.is_empty() => {}
            (Component::ParentDir, Some(Component::Normal(_))) => {
                parts.pop();
            }
            (Component::ParentDir, Some(Component::RootDir)) => {}
            _ => parts.push(c),
        }
    }
    if parts.is_empty() { ".".to_string() } else { parts.iter().collect::<PathBuf>().display().to_string() }
}

/// A drawing of the structure with the measured DOFs of `measured` and the
/// `highlights`, as a report block.
pub(crate) fn structure_figure(
    model: &Model,
    measured: &FrfSet,
    highlights: &[Highlight],
    caption: &str,
    out: &mut Outputs,
) -> Result<Block> {
    let (responses, references) = sensor_dofs(measured);
    let title =
        if highlights.is_empty() { "The structure and its measured DOFs" } else { "The structure and what was added" };
    let svg = plot::structure::structure(
        title,
        model,
        &Sensors { responses: &responses, references: &references },
        highlights,
    )?;
    let text = format!(
        "{caption} The structure to scale ({} nodes, {} beams): supports hatched, joints as hinges, springs as \
         zigzags, masses as squares, a resonator as a square on a zigzag beside its node; green arrows at the {} measured responses in their direction, orange arrows at \
         the {} excitation point{}; node numbers where something is measured, supported or added.",
        model.nodes().len(),
        model.beams().len(),
        responses.len(),
        references.len(),
        if references.len() == 1 { "" } else { "s" }
    );
    out.figure("structure", svg, text)
}

/// Heading of the glossary every report ends with.
pub(crate) const GLOSSARY: &str = "How to read this report";

/// The glossary every report ends with: each reported quantity under the
/// name every output gives it, as [`rfm_update::quantities`] defines it,
/// then the words the report's tables use.
pub(crate) fn definitions_section() -> Section {
    let mut s = Section::new(GLOSSARY);
    s.push(Block::Text(
        "Each number in this report, in the terminal, in the JSON files and in the documentation goes by one of \
         these names and means the same in each."
            .into(),
    ));
    let mut items: Vec<(String, String)> = rfm_update::quantities::GLOSSARY
        .iter()
        .map(|q| {
            let name = if q.unit.is_empty() { q.name.to_string() } else { format!("{} ({})", q.name, q.unit) };
            (name, q.definition.to_string())
        })
        .collect();
    items.extend([
        ("share".into(), "the part of the total squared misfit of all lines that a channel or band holds.".into()),
        (
            "bands".into(),
            "by default one band per measured resonance, edges halfway (geometrically) between neighbours.".into(),
        ),
        (
            "gain".into(),
            "data referenced to a voltage (per volt) or from an uncalibrated sensor carry an unknown complex \
             factor: the model's FRFs are multiplied by the gain that fits them best before any comparison, and \
             the report says where."
                .into(),
        ),
        (
            "LSCF".into(),
            "the least-squares complex frequency method: the measured modes are the poles of rational fits of the \
             FRFs at increasing model orders that stay put from one order to the next (the stabilisation diagram)."
                .into(),
        ),
        (
            "symptoms".into(),
            "a frequency shift (stiffness or mass) shows as large errors on both sides of a peak and a low FRAC; \
             a wrong peak height or width (damping) as errors confined to the peak with FRAC still high; a \
             uniform offset in one channel as a constant mean dB error (gain or calibration)."
                .into(),
        ),
    ]);
    s.push(Block::Facts(items));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, DofRef};
    use frf::FrfKind;

    /// Runs of ranks are written as ranges, the rest one by one.
    #[test]
    fn ranks_alike_are_said_as_ranges() {
        assert_eq!(alike_text(&[]), "");
        assert_eq!(alike_text(&[3]), "rank 3 alike");
        assert_eq!(alike_text(&[3, 4, 5, 8, 10, 11]), "ranks 3-5, 8, 10-11 alike");
    }

    /// A folder and the `..` after it cancel; leading `..`, a root and the
    /// file name stay.
    #[test]
    fn shown_paths_drop_a_folder_and_the_dotdot_after_it() {
        for (given, shown) in [
            ("fix/../../../work/main/m.csv", "../../work/main/m.csv"),
            ("a/./b/../c.csv", "a/c.csv"),
            ("../x.uff", "../x.uff"),
            ("/tmp/a/../b.uff", "/tmp/b.uff"),
            ("/../b.uff", "/b.uff"),
            ("a/..", "."),
        ] {
            assert_eq!(shown_path(Path::new(given)), shown, "{given}");
        }
    }

    #[test]
    fn driving_points_come_once_per_reference() {
        let tip = DofRef::new(31, Dof::Uy);
        let mid = DofRef::new(15, Dof::Uy);
        let mut channels: Vec<Channel> = (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        channels.push(Channel::new(mid, mid));
        let set = FrfSet::zeros(vec![1.0, 2.0], channels, FrfKind::Receptance).unwrap();
        assert_eq!(driving_points(&set, 2), vec![29, 30]);
        assert_eq!(driving_points(&set, 1), vec![29]);
        assert_eq!(channel_file_stem(set.channels()[0]), "frf-2uy-31uy");
        let (responses, references) = sensor_dofs(&set);
        assert_eq!((responses.len(), references), (30, vec![tip, mid]));
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

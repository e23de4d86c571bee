//! FRF overlays: measured and model FRFs of a channel, magnitude (dB) above
//! and phase below. [`frf_overlay`] draws one channel large;
//! [`frf_multiples`] draws many channels as small multiples with one legend
//! for all, so that every channel can be seen at once.
//!
//! The measurement is drawn first and thick, the models thin on top of it,
//! so that a model that matches shows as a coloured line inside the black
//! one. The lines used for updating are ticks on the frequency axis (marks
//! on the curve would bury it), lines of poor coherence are shaded and the
//! coherence itself drawn as a trace under the phase, the last model's
//! residual `|model - measured|` is drawn beside the noise floor (the
//! data's noise level times the measured magnitude), and the phase is
//! drawn continuous ([`super::axes::phases`]). Curves and shades of more
//! lines than pixel columns are thinned to what draws them
//! ([`super::decimate`]).

use frf::C64;
use plotters::prelude::*;

use super::axes::{FreqAxis, FrequencyScale, PhaseAxis, phases};
use super::decimate::{per_pixel_column, spans_per_pixel};
use super::{
    Area, Dash, DrawResult, FONT, HouseStyle, LegendEntry, Look, MEASURED, Mark, PlotError, draw_line, frame, range,
    segments, svg, tick,
};

/// Shade of lines whose coherence is below the case's threshold
/// ([`FrfFigure::coherence_threshold`]).
const COHERENCE_SHADE: RGBColor = RGBColor(253, 228, 214);
/// Shade of lines whose coherence is below [`COHERENCE_POOR`].
const COHERENCE_DARK: RGBColor = RGBColor(246, 190, 160);
/// Below this coherence a line is shaded darker (and below the case's
/// threshold, when that is lower).
pub(crate) const COHERENCE_POOR: f64 = 0.5;

/// Colour of the coherence trace and its threshold.
const COHERENCE_TRACE: RGBColor = RGBColor(190, 80, 20);
/// Colour of the last model's residual `|model - measured|`.
const RESIDUAL: RGBColor = RGBColor(136, 34, 85);
/// Colour of the noise floor (the noise level times the measured magnitude).
const NOISE_FLOOR: RGBColor = RGBColor(0, 128, 64);

/// Panels of [`frf_multiples`] per row.
pub(crate) const COLUMNS: usize = 2;
/// Height of one panel of [`frf_multiples`] (px).
const PANEL_HEIGHT: u32 = 290;

/// One FRF curve of an overlay.
pub(crate) struct FrfCurve<'a> {
    /// Legend label.
    pub(crate) label: String,
    /// Colour.
    pub(crate) colour: RGBColor,
    /// Values on the figure's lines.
    pub(crate) values: &'a [C64],
}

/// One channel: its curves (the first is the measurement) and coherence.
pub(crate) struct FrfPanel<'a> {
    /// Panel title (small multiples only; a single overlay uses the figure's).
    pub(crate) title: String,
    /// Curves; the first is drawn thickest (the measurement).
    pub(crate) curves: Vec<FrfCurve<'a>>,
    /// Coherence of the measurement per line, when the data carry it.
    pub(crate) coherence: Option<&'a [f64]>,
}

/// FRFs of one or more channels on common lines.
pub(crate) struct FrfFigure<'a> {
    /// Figure title.
    pub(crate) title: String,
    /// Lines (Hz).
    pub(crate) frequencies_hz: &'a [f64],
    /// The unit of the values (`m/s²/V`): the magnitude is in dB re 1 of it.
    pub(crate) unit: String,
    /// One panel per channel; every panel has the same curve labels.
    pub(crate) panels: Vec<FrfPanel<'a>>,
    /// Lines to tick on the frequency axis (the updating lines), Hz.
    pub(crate) ticks_hz: &'a [f64],
    /// Lines whose coherence is below it are shaded (the case's
    /// `[measurement] coherence_threshold`).
    pub(crate) coherence_threshold: f64,
    /// Frequency axis scale.
    pub(crate) scale: FrequencyScale,
    /// The data's noise level (relative, RMS per value): with it, each
    /// panel with a model draws the last model's residual `|model -
    /// measured|` and the noise floor `noise |measured|` under the curves.
    pub(crate) noise: Option<f64>,
}

/// The first curve (the measurement) is drawn wide and pale, under the
/// others, so that a model that matches it shows as a coloured line along
/// its middle instead of vanishing into it.
fn width_of(i: usize, compact: bool) -> u32 {
    match (i, compact) {
        (0, false) => 5,
        (0, true) => 4,
        (_, false) => 2,
        (_, true) => 1,
    }
}

/// The residual of the last model against the measurement and the noise
/// floor, in dB (NaN where either is zero or not finite); `None` without a
/// model or a noise level.
fn residual_and_floor(panel: &FrfPanel<'_>, noise: Option<f64>) -> Option<(Vec<f64>, Vec<f64>)> {
    let noise = noise.filter(|n| *n > 0.0)?;
    let (measured, last) = (panel.curves.first()?, panel.curves.get(1..)?.last()?);
    let db = |v: f64| if v > 0.0 && v.is_finite() { 20.0 * v.log10() } else { f64::NAN };
    let residual = measured.values.iter().zip(last.values).map(|(x, a)| db((a - x).norm())).collect();
    let floor = measured.values.iter().map(|x| db(noise * x.norm())).collect();
    Some((residual, floor))
}

/// Coherence level of a line: 0 fair, 1 below the case's `threshold`, 2
/// below [`COHERENCE_POOR`] (or the threshold, when that is lower).
fn coherence_level(c: f64, threshold: f64) -> u8 {
    if !c.is_finite() {
        0
    } else if c < COHERENCE_POOR.min(threshold) {
        2
    } else if c < threshold {
        1
    } else {
        0
    }
}

/// Runs of lines with poor coherence as `(from Hz, to Hz, level)`, each
/// line covering the span to halfway (geometrically on a log axis) to its
/// neighbours.
fn coherence_spans(f: &[f64], coherence: &[f64], threshold: f64, axis: &FreqAxis) -> Vec<(f64, f64, u8)> {
    let mid = |a: f64, b: f64| if axis.is_log() && a > 0.0 { (a * b).sqrt() } else { 0.5 * (a + b) };
    let (lo, hi) = axis.ends();
    let mut out: Vec<(f64, f64, u8)> = Vec::new();
    for (k, (&fk, &c)) in f.iter().zip(coherence).enumerate() {
        let level = coherence_level(c, threshold);
        if level == 0 || !axis.shows(fk) {
            continue;
        }
        let left = if k == 0 { fk } else { mid(f[k - 1], fk) }.max(lo);
        let right = if k + 1 == f.len() { fk } else { mid(fk, f[k + 1]) }.min(hi);
        match out.last_mut() {
            Some(last) if last.2 == level && (last.1 - left).abs() <= 1e-9 * left.abs().max(1.0) => last.1 = right,
            _ => out.push((left, right, level)),
        }
    }
    out
}

/// The legend shared by every panel: the curves of the first panel, then
/// the ticks and the coherence shades when they appear.
fn legend(fig: &FrfFigure<'_>, axis: &FreqAxis, compact: bool) -> Vec<LegendEntry> {
    let mut legend: Vec<LegendEntry> = fig.panels.first().map_or_else(Vec::new, |p| {
        p.curves
            .iter()
            .enumerate()
            .map(|(i, c)| LegendEntry::new(c.label.clone(), c.colour, Mark::Line(width_of(i, compact))))
            .collect()
    });
    if fig.panels.iter().any(|p| residual_and_floor(p, fig.noise).is_some()) {
        let last = fig.panels.first().and_then(|p| p.curves.last()).map_or(String::new(), |c| c.label.clone());
        legend.push(LegendEntry::new(format!("residual |model - measured| ({last})"), RESIDUAL, Mark::Line(1)));
        legend.push(LegendEntry::new("noise floor (noise x |measured|)", NOISE_FLOOR, Mark::Styled(1, Dash::Dashed)));
    }
    if fig.ticks_hz.iter().any(|&t| axis.shows(t)) {
        legend.push(LegendEntry::new("updating lines (ticks on the axis)", MEASURED, Mark::Tick));
    }
    if fig.panels.iter().any(|p| p.coherence.is_some()) {
        legend.push(LegendEntry::new("coherence (panel below the phase)", COHERENCE_TRACE, Mark::Line(1)));
    }
    let threshold = fig.coherence_threshold;
    let levels: Vec<u8> = fig
        .panels
        .iter()
        .filter_map(|p| p.coherence)
        .flat_map(|c| c.iter().map(|&v| coherence_level(v, threshold)))
        .collect();
    if levels.contains(&1) {
        legend.push(LegendEntry::new(format!("coherence below {threshold}"), COHERENCE_SHADE, Mark::Shade));
    }
    if levels.contains(&2) {
        let poor = COHERENCE_POOR.min(threshold);
        legend.push(LegendEntry::new(format!("coherence below {poor}"), COHERENCE_DARK, Mark::Shade));
    }
    legend
}

/// Sizes of one panel's text and axes.
struct Style {
    compact: bool,
    label: u32,
    desc: u32,
    y_area: u32,
    x_labels: usize,
}

const LARGE: Style = Style { compact: false, label: 13, desc: 15, y_area: 72, x_labels: 12 };
const SMALL: Style = Style { compact: true, label: 11, desc: 12, y_area: 54, x_labels: 7 };

/// Draws one channel's magnitude into `top`, its phase into `bottom` and,
/// when given an area and the data carry it, its coherence into
/// `coherence` (which then carries the frequency labels).
fn draw_channel(
    top: &Area<'_>,
    bottom: &Area<'_>,
    coherence: Option<&Area<'_>>,
    fig: &FrfFigure<'_>,
    panel: &FrfPanel<'_>,
    axis: FreqAxis,
    style: &Style,
) -> DrawResult {
    let f = fig.frequencies_hz;
    let shown: Vec<f64> = f.iter().map(|&x| if axis.shows(x) { x } else { f64::NAN }).collect();
    let db: Vec<Vec<f64>> =
        panel.curves.iter().map(|c| c.values.iter().map(|v| 20.0 * v.norm().log10()).collect()).collect();
    let (reference, others) = match panel.curves.split_first() {
        Some((first, rest)) => {
            let rest: Vec<&[C64]> = rest.iter().map(|c| c.values).collect();
            let (r, o) = phases(first.values, &rest);
            (vec![r], o)
        }
        None => (Vec::new(), Vec::new()),
    };
    let phase: Vec<Vec<f64>> = reference.into_iter().chain(others).collect();
    let visible =
        |v: &[f64]| -> Vec<f64> { v.iter().zip(&shown).filter(|(_, x)| x.is_finite()).map(|(y, _)| *y).collect() };
    let floors = residual_and_floor(panel, fig.noise);
    let (y0, y1) = range(
        db.iter()
            .flat_map(|c| visible(c))
            .chain(floors.iter().flat_map(|(r, n)| visible(r).into_iter().chain(visible(n)))),
        (-100.0, 0.0),
    );
    let (y0, y1) = ((y0 / 10.0).floor() * 10.0, (y1 / 10.0).ceil() * 10.0);
    let phase_axis = PhaseAxis::over(phase.iter().flat_map(|c| visible(c)));
    let spans = panel.coherence.map(|c| coherence_spans(f, c, fig.coherence_threshold, &axis)).unwrap_or_default();
    let shade = |level: u8| if level == 2 { COHERENCE_DARK } else { COHERENCE_SHADE };
    let x_label = |v: &f64| axis.label(v);
    let y_desc = if style.compact { "dB".to_string() } else { format!("Magnitude (dB re 1 {})", fig.unit) };

    let mut chart = ChartBuilder::on(top)
        .margin_left(if style.compact { 6 } else { 12 })
        .margin_right(if style.compact { 12 } else { 24 })
        .margin_top(6)
        .x_label_area_size(if style.compact { 4 } else { 26 })
        .y_label_area_size(style.y_area)
        .build_cartesian_2d(axis, y0..y1)?;
    // the shading first, so that the grid and the curves stay on top
    let drawn = spans_per_pixel(&spans, |x| chart.backend_coord(&(x, y0)).0);
    chart.draw_series(drawn.iter().map(|&(a, b, l)| Rectangle::new([(a, y0), (b, y1)], shade(l).filled())))?;
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(y_desc)
        .x_label_formatter(&x_label)
        .y_label_formatter(&tick)
        .house_style(style.label, style.desc)
        .x_labels(style.x_labels)
        .y_labels(if style.compact { 5 } else { 8 });
    let blank = |_: &f64| String::new();
    if style.compact {
        // the phase panel below carries the frequency labels
        mesh.x_label_formatter(&blank);
    }
    mesh.draw()?;
    // the residual and the noise floor under the curves: where the residual
    // sits on the floor, the model is as good as the data allow
    if let Some((residual, floor)) = &floors {
        for seg in segments(&shown, residual, None) {
            let seg = per_pixel_column(&seg, |p| chart.backend_coord(p));
            chart.draw_series(LineSeries::new(seg, RESIDUAL.stroke_width(1)))?;
        }
        for seg in segments(&shown, floor, None) {
            let seg = per_pixel_column(&seg, |p| chart.backend_coord(p));
            draw_line(&mut chart, seg, Look { colour: NOISE_FLOOR, dash: Dash::Dashed }, 1)?;
        }
    }
    for (i, c) in panel.curves.iter().enumerate() {
        let line = c.colour.stroke_width(width_of(i, style.compact));
        for seg in segments(&shown, &db[i], None) {
            let seg = per_pixel_column(&seg, |p| chart.backend_coord(p));
            chart.draw_series(LineSeries::new(seg, line))?;
        }
    }
    let tick_height = 0.06 * (y1 - y0);
    // one tick per pixel column: thousands of updating lines would each
    // draw the same pixels, and bloat the file
    let mut columns = std::collections::HashSet::new();
    let ticks: Vec<f64> = fig
        .ticks_hz
        .iter()
        .copied()
        .filter(|&t| axis.shows(t) && columns.insert(chart.backend_coord(&(t, y0)).0))
        .collect();
    chart.draw_series(
        ticks.iter().map(|&t| PathElement::new(vec![(t, y0), (t, y0 + tick_height)], MEASURED.stroke_width(1))),
    )?;

    // the panel at the bottom carries the frequency labels
    let trace = coherence.zip(panel.coherence);
    let labelled = if style.compact { 34 } else { 44 };
    let mut chart = ChartBuilder::on(bottom)
        .margin_left(if style.compact { 6 } else { 12 })
        .margin_right(if style.compact { 12 } else { 24 })
        .margin_top(if style.compact { 4 } else { 8 })
        .x_label_area_size(if trace.is_some() { 4 } else { labelled })
        .y_label_area_size(style.y_area)
        .build_cartesian_2d(axis, phase_axis)?;
    let drawn = spans_per_pixel(&spans, |x| chart.backend_coord(&(x, phase_axis.lo)).0);
    chart.draw_series(
        drawn.iter().map(|&(a, b, l)| Rectangle::new([(a, phase_axis.lo), (b, phase_axis.hi)], shade(l).filled())),
    )?;
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(if style.compact { "deg" } else { "Phase (deg)" })
        .x_label_formatter(&x_label)
        .y_label_formatter(&tick)
        .house_style(style.label, style.desc)
        .x_labels(style.x_labels)
        .y_labels(if style.compact { 4 } else { 9 });
    if trace.is_some() {
        mesh.x_label_formatter(&blank);
    } else {
        mesh.x_desc(axis.describe());
    }
    mesh.draw()?;
    for (i, c) in panel.curves.iter().enumerate() {
        let line = c.colour.stroke_width(width_of(i, style.compact));
        // a jump of more than half a turn is a model crossing the measured
        // phase's opposite: split there rather than draw a vertical line
        for seg in segments(&shown, &phase[i], Some(360.0)) {
            let seg = per_pixel_column(&seg, |p| chart.backend_coord(p));
            chart.draw_series(LineSeries::new(seg, line))?;
        }
    }
    if let Some((area, values)) = trace {
        draw_coherence(area, fig, values, &spans, axis, style)?;
    }
    Ok(())
}

/// The coherence of one channel from 0 to 1 against frequency, the case's
/// threshold dashed, the poor lines shaded as in the panels above.
fn draw_coherence(
    area: &Area<'_>,
    fig: &FrfFigure<'_>,
    values: &[f64],
    spans: &[(f64, f64, u8)],
    axis: FreqAxis,
    style: &Style,
) -> DrawResult {
    let shown: Vec<f64> = fig.frequencies_hz.iter().map(|&x| if axis.shows(x) { x } else { f64::NAN }).collect();
    let x_label = |v: &f64| axis.label(v);
    let mut chart = ChartBuilder::on(area)
        .margin_left(if style.compact { 6 } else { 12 })
        .margin_right(if style.compact { 12 } else { 24 })
        .margin_top(4)
        .x_label_area_size(if style.compact { 34 } else { 44 })
        .y_label_area_size(style.y_area)
        .build_cartesian_2d(axis, 0.0..1.05)?;
    let drawn = spans_per_pixel(spans, |x| chart.backend_coord(&(x, 0.0)).0);
    let shade = |level: u8| if level == 2 { COHERENCE_DARK } else { COHERENCE_SHADE };
    chart.draw_series(drawn.iter().map(|&(a, b, l)| Rectangle::new([(a, 0.0), (b, 1.05)], shade(l).filled())))?;
    chart
        .configure_mesh()
        .x_desc(axis.describe())
        .y_desc(if style.compact { "coh." } else { "Coherence" })
        .x_label_formatter(&x_label)
        .y_label_formatter(&tick)
        .house_style(style.label, style.desc)
        .x_labels(style.x_labels)
        .y_labels(3)
        .draw()?;
    let (f0, f1) = axis.ends();
    let t = fig.coherence_threshold;
    draw_line(&mut chart, vec![(f0, t), (f1, t)], Look { colour: COHERENCE_TRACE, dash: Dash::Dashed }, 1)?;
    for seg in segments(&shown, values, None) {
        let seg = per_pixel_column(&seg, |p| chart.backend_coord(p));
        chart.draw_series(LineSeries::new(seg, COHERENCE_TRACE.stroke_width(1)))?;
    }
    Ok(())
}

/// Draws the first panel of `fig` large: magnitude above, phase below.
pub(crate) fn frf_overlay(fig: &FrfFigure<'_>) -> Result<String, PlotError> {
    let axis = FreqAxis::new(fig.frequencies_hz, fig.scale);
    let legend = legend(fig, &axis, false);
    let height = if fig.panels.first().is_some_and(|p| p.coherence.is_some()) { 800 } else { 660 };
    svg(&fig.title, height, |root| {
        let body = frame(root, &fig.title, &legend)?;
        let Some(panel) = fig.panels.first() else {
            return Ok(());
        };
        let h = body.dim_in_pixel().1;
        if panel.coherence.is_some() {
            let (top, rest) = body.split_vertically(h * 52 / 100);
            let (bottom, trace) = rest.split_vertically(h * 29 / 100);
            draw_channel(&top, &bottom, Some(&trace), fig, panel, axis, &LARGE)
        } else {
            let (top, bottom) = body.split_vertically(h * 62 / 100);
            draw_channel(&top, &bottom, None, fig, panel, axis, &LARGE)
        }
    })
}

/// Draws every panel of `fig` as small multiples, [`COLUMNS`] to a row,
/// under one legend.
pub(crate) fn frf_multiples(fig: &FrfFigure<'_>) -> Result<String, PlotError> {
    let axis = FreqAxis::new(fig.frequencies_hz, fig.scale);
    let legend = legend(fig, &axis, true);
    let rows = fig.panels.len().div_ceil(COLUMNS).max(1);
    let coherent = fig.panels.iter().any(|p| p.coherence.is_some());
    let panel_height = if coherent { PANEL_HEIGHT + PANEL_HEIGHT / 4 } else { PANEL_HEIGHT };
    let height = 44 + super::legend_height(&legend) + rows as u32 * panel_height;
    svg(&fig.title, height, |root| {
        let body = frame(root, &fig.title, &legend)?;
        let cells = body.split_evenly((rows, COLUMNS));
        for (panel, cell) in fig.panels.iter().zip(&cells) {
            let (w, _) = cell.dim_in_pixel();
            // the title left-aligned over the panel, cut to what fits
            let max_chars = ((w as f64 - 16.0) / 7.0) as usize;
            let title: String = if panel.title.chars().count() > max_chars {
                panel.title.chars().take(max_chars.saturating_sub(1)).chain(['\u{2026}']).collect()
            } else {
                panel.title.clone()
            };
            cell.draw(&Text::new(title, (12, 6), (FONT, 13).into_font().style(FontStyle::Bold).color(&BLACK)))?;
            let (_, rest) = cell.split_vertically(24);
            let h = rest.dim_in_pixel().1;
            if panel.coherence.is_some() {
                let (top, rest) = rest.split_vertically(h * 47 / 100);
                let (bottom, trace) = rest.split_vertically(h * 28 / 100);
                draw_channel(&top, &bottom, Some(&trace), fig, panel, axis, &SMALL)?;
            } else {
                let (top, bottom) = rest.split_vertically(h * 58 / 100);
                draw_channel(&top, &bottom, None, fig, panel, axis, &SMALL)?;
            }
        }
        Ok(())
    })
}

/// Panels of [`frf_multiples`] that fit the page width in one figure of
/// reasonable height; more channels make more figures.
pub(crate) const PANELS_PER_FIGURE: usize = 12;

#[cfg(test)]
mod tests {
    use super::super::decimate::{most_per_column, polylines};
    use super::*;

    fn curves<'a>(x: &'a [C64], a: &'a [C64]) -> Vec<FrfCurve<'a>> {
        vec![
            FrfCurve { label: "measured".into(), colour: MEASURED, values: x },
            FrfCurve { label: "model".into(), colour: super::super::UPDATED, values: a },
        ]
    }

    #[test]
    fn an_overlay_has_both_panels_labels_and_ticks_not_circles() {
        let f = [1.0, 2.0, 3.0, 4.0];
        let x: Vec<C64> = f.iter().map(|&v| C64::new(1.0 / v, 0.1)).collect();
        let a: Vec<C64> = f.iter().map(|&v| C64::new(-1.0 / v, 0.2)).collect();
        let svg = frf_overlay(&FrfFigure {
            title: "H(3:uy,3:uy) <driving point>".into(),
            frequencies_hz: &f,
            unit: "m/s\u{b2}/N".into(),
            panels: vec![FrfPanel { title: String::new(), curves: curves(&x, &a), coherence: None }],
            ticks_hz: &[2.0],
            coherence_threshold: 0.8,
            scale: FrequencyScale::Linear,
            noise: None,
        })
        .unwrap();
        assert!(svg.starts_with("<svg"));
        for text in ["Frequency (Hz)", "Phase (deg)", "dB re 1 m/s\u{b2}/N", "updating lines", "&lt;driving point&gt;"]
        {
            assert!(svg.contains(text), "missing {text}");
        }
        assert!(svg.matches("<polyline").count() >= 4);
        assert!(!svg.contains("<circle"), "updating lines are ticks, not circles on the curve");
    }

    #[test]
    fn a_hundred_thousand_updating_lines_draw_one_tick_per_pixel_column() {
        let f: Vec<f64> = (1..=1000).map(f64::from).collect();
        let x: Vec<C64> = f.iter().map(|&v| C64::new(1.0 / v, 0.1)).collect();
        let ticks: Vec<f64> = (0..100_000).map(|k| 1.0 + 999.0 * f64::from(k) / 99_999.0).collect();
        let figure = |ticks: &[f64]| {
            frf_overlay(&FrfFigure {
                title: "H(3:uy,3:uy)".into(),
                frequencies_hz: &f,
                unit: "m/N".into(),
                panels: vec![FrfPanel { title: String::new(), curves: curves(&x, &x), coherence: None }],
                ticks_hz: ticks,
                coherence_threshold: 0.8,
                scale: FrequencyScale::Linear,
                noise: None,
            })
            .unwrap()
        };
        let without = figure(&[]).matches("<polyline").count();
        let ticks_drawn = figure(&ticks).matches("<polyline").count() - without;
        // the plot is some hundreds of pixels wide: one tick in each column
        assert!((100..2_000).contains(&ticks_drawn), "{ticks_drawn} ticks drawn for 100,000 lines");
    }

    #[test]
    fn small_multiples_draw_every_panel_under_one_legend_and_shade_poor_coherence() {
        let f: Vec<f64> = (1..=100).map(f64::from).collect();
        let x: Vec<C64> = f.iter().map(|&v| C64::new(1.0 / v, 0.1)).collect();
        let a: Vec<C64> = f.iter().map(|&v| C64::new(1.1 / v, 0.1)).collect();
        let coherence: Vec<f64> = f.iter().map(|&v| if (40.0..50.0).contains(&v) { 0.3 } else { 0.99 }).collect();
        let panels: Vec<FrfPanel<'_>> = (0..5)
            .map(|k| FrfPanel {
                title: format!("panel {k}"),
                curves: curves(&x, &a),
                coherence: (k == 0).then_some(coherence.as_slice()),
            })
            .collect();
        let svg = frf_multiples(&FrfFigure {
            title: "every channel".into(),
            frequencies_hz: &f,
            unit: "m/N".into(),
            panels,
            ticks_hz: &[],
            coherence_threshold: 0.8,
            scale: FrequencyScale::Auto,
            noise: None,
        })
        .unwrap();
        for k in 0..5 {
            assert!(super::super::has_text(&svg, &format!("panel {k}")), "panel {k} missing");
        }
        // one legend: each label once
        assert_eq!(svg.matches(">\nmeasured\n<").count(), 1);
        assert_eq!(svg.matches(">\nmodel\n<").count(), 1);
        assert!(svg.contains("coherence below 0.5") && !svg.contains("coherence below 0.9"));
        assert!(svg.contains("Frequency (Hz, logarithmic)"));
        // two curves in two panels each, in five channels
        assert!(svg.matches("<polyline").count() >= 20);
    }

    #[test]
    fn a_million_lines_draw_at_most_four_points_per_pixel_column_with_the_peak_in_place() {
        let n = 1_000_000;
        let f: Vec<f64> = (0..n).map(|k| 1.0 + 399.0 * k as f64 / (n - 1) as f64).collect();
        // a resonance at 143 Hz with a ripple of 5 % from line to line, as noise makes
        let x: Vec<C64> = f
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let r = v / 143.0;
                let ripple = if k % 2 == 0 { 1.05 } else { 0.95 };
                C64::new(1e-6 * ripple, 0.0) / C64::new(1.0 - r * r, 0.02 * r)
            })
            .collect();
        let figure = |f: &[f64], x: &[C64]| {
            frf_overlay(&FrfFigure {
                title: "H(2:uy,11:uy)".into(),
                frequencies_hz: f,
                unit: "m/N".into(),
                panels: vec![FrfPanel {
                    title: String::new(),
                    curves: vec![FrfCurve { label: "measured".into(), colour: MEASURED, values: x }],
                    coherence: None,
                }],
                ticks_hz: &[],
                coherence_threshold: 0.8,
                scale: FrequencyScale::Linear,
                noise: None,
            })
            .unwrap()
        };
        // the measurement is drawn 5 px wide: its magnitude, then its phase
        let drawn = polylines(&figure(&f, &x), "stroke-width=\"5\"");
        assert_eq!(drawn.len(), 2);
        for line in &drawn {
            assert!(most_per_column(line) <= 4, "{} points in a pixel column", most_per_column(line));
        }
        // the same curve at a few hundred of its lines, among them the first,
        // the last, the peak and the lowest: a figure with the same axes,
        // whose curve has fewer points than pixel columns and is drawn point
        // for point
        let by_norm = |a: &(usize, &C64), b: &(usize, &C64)| a.1.norm().total_cmp(&b.1.norm());
        let peak = x.iter().enumerate().max_by(by_norm).unwrap().0;
        let low = x.iter().enumerate().min_by(by_norm).unwrap().0;
        let mut keep: Vec<usize> = (0..n).step_by(4001).chain([peak, low, n - 1]).collect();
        keep.sort_unstable();
        keep.dedup();
        let (fs, xs): (Vec<f64>, Vec<C64>) = keep.iter().map(|&k| (f[k], x[k])).unzip();
        let sparse = polylines(&figure(&fs, &xs), "stroke-width=\"5\"");
        assert_eq!(sparse[0].len(), keep.len());
        // drawn y grows downwards: the peak is the least y, the lowest point the greatest
        let highest = |l: &[(i32, i32)]| l.iter().map(|p| p.1).min();
        let lowest = |l: &[(i32, i32)]| l.iter().map(|p| p.1).max();
        assert_eq!(highest(&drawn[0]), highest(&sparse[0]));
        assert_eq!(lowest(&drawn[0]), lowest(&sparse[0]));
    }

    #[test]
    fn coherence_changing_at_every_one_of_a_million_lines_is_shaded_with_at_most_a_shade_per_pixel_column() {
        let f: Vec<f64> = (0..1_000_000).map(|k| 1.0 + f64::from(k) * 1e-4).collect();
        let x: Vec<C64> = f.iter().map(|&v| C64::new(1.0 / v, 0.1)).collect();
        let coherence: Vec<f64> = (0..f.len()).map(|k| [0.99, 0.7, 0.3][k % 3]).collect();
        let svg = frf_overlay(&FrfFigure {
            title: "H(3:uy,3:uy)".into(),
            frequencies_hz: &f,
            unit: "m/N".into(),
            panels: vec![FrfPanel {
                title: String::new(),
                curves: vec![FrfCurve { label: "measured".into(), colour: MEASURED, values: &x }],
                coherence: Some(&coherence),
            }],
            ticks_hz: &[],
            coherence_threshold: 0.8,
            scale: FrequencyScale::Linear,
            noise: None,
        })
        .unwrap();
        let fill = |c: RGBColor| format!("fill=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
        let shades = svg.matches(&fill(COHERENCE_SHADE)).count() + svg.matches(&fill(COHERENCE_DARK)).count();
        // both panels, at most one shade per pixel column of the figure, and the legend's two
        assert!(shades >= 2 && shades <= 2 * super::super::WIDTH as usize + 2, "{shades} shades");
    }

    #[test]
    fn poor_coherence_runs_merge_into_spans() {
        let f = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let c = [0.95, 0.7, 0.6, 0.2, 0.95, 0.1];
        let axis = FreqAxis::new(&f, FrequencyScale::Linear);
        assert_eq!(coherence_spans(&f, &c, 0.9, &axis), vec![(1.5, 3.5, 1), (3.5, 4.5, 2), (5.5, 6.0, 2)]);
        // the case's threshold decides what is shaded: at 0.65 the line of
        // 0.7 is fair; at 0.3 only the two lines below it are shaded, darkest
        assert_eq!(coherence_spans(&f, &c, 0.65, &axis), vec![(2.5, 3.5, 1), (3.5, 4.5, 2), (5.5, 6.0, 2)]);
        assert_eq!(coherence_spans(&f, &c, 0.3, &axis), vec![(3.5, 4.5, 2), (5.5, 6.0, 2)]);
    }
}

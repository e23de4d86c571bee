//! SVG figures drawn with plotters into strings. This file holds what every
//! figure shares (the frame, the legend, axes and colours) and the figures
//! of the correlation and the iteration: error versus frequency, error per
//! channel, misfit and parameter values per iteration. The FRF overlays are
//! in [`frf`], the frequency and phase axes in [`axes`], the structure and
//! its mode shapes in [`structure`], the MAC matrix and the stabilisation
//! diagram in [`modes`], the misfit of each step of the loop in [`steps`].
//!
//! Text is emitted as SVG `<text>` elements in a generic `sans-serif` family
//! (plotters is built without its font features), so the figures need no
//! font files and the browser's own font renders them. Legends are drawn as
//! a row under the title rather than inside the axes, where they would hide
//! curves.

use std::fmt;

// `::frf` is the crate; `frf` alone is the overlay module below
use ::frf::C64;
use ::frf::FrfKind;
use ::frf::correlation::{Band, LineError};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(crate) mod axes;
pub(crate) mod frf;
pub(crate) mod modes;
mod projection;
mod steps;
pub(crate) mod structure;
pub(crate) use steps::misfit_steps;

use axes::FreqAxis;

/// Colour of measured data.
pub(crate) const MEASURED: RGBColor = RGBColor(0, 0, 0);
/// Colour of the initial model.
pub(crate) const INITIAL: RGBColor = RGBColor(213, 94, 0);
/// Colour of the updated model.
pub(crate) const UPDATED: RGBColor = RGBColor(0, 114, 178);
/// Colours for several series: Okabe-Ito without yellow (too pale on
/// white), then three of Paul Tol's muted scheme, all distinguishable with
/// the common colour-vision deficiencies. With the three [`Dash`] styles
/// they give 30 different looks before one repeats ([`look`]).
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(90, 90, 90),
    RGBColor(136, 34, 85),
    RGBColor(51, 34, 136),
    RGBColor(153, 153, 51),
];

/// How a series' line is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Dash {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Dots.
    Dotted,
}

/// Colour and line style of one series of many (a parameter, a step).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Look {
    /// Colour.
    pub(crate) colour: RGBColor,
    /// Line style.
    pub(crate) dash: Dash,
}

/// The look of series `i`: every colour solid first, then dashed, then dotted.
pub(crate) fn look(i: usize) -> Look {
    let dash = [Dash::Solid, Dash::Dashed, Dash::Dotted][(i / PALETTE.len()) % 3];
    Look { colour: PALETTE[i % PALETTE.len()], dash }
}

/// Dash and gap lengths (px) of a line style, `None` for a solid line.
fn dash_pattern(dash: Dash) -> Option<(i32, i32)> {
    match dash {
        Dash::Solid => None,
        Dash::Dashed => Some((9, 5)),
        Dash::Dotted => Some((2, 4)),
    }
}

/// Draws `points` as a line of the given look and width on a chart.
fn draw_line<DB, CT>(
    chart: &mut ChartContext<'_, DB, CT>,
    points: Vec<(f64, f64)>,
    look: Look,
    width: u32,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    CT: CoordTranslate<From = (f64, f64)>,
{
    let style = look.colour.stroke_width(width);
    match dash_pattern(look.dash) {
        None => {
            chart.draw_series(LineSeries::new(points, style))?;
        }
        Some((on, off)) => {
            chart.draw_series(DashedLineSeries::new(points, on, off, style))?;
        }
    }
    Ok(())
}

const FONT: &str = "sans-serif";
const WIDTH: u32 = 960;
const GRID_LIGHT: RGBColor = RGBColor(238, 238, 238);
const GRID_BOLD: RGBColor = RGBColor(205, 205, 205);
const BAND_SHADE: RGBColor = RGBColor(244, 244, 248);
const AXIS: RGBColor = RGBColor(60, 60, 60);

/// A figure could not be drawn.
#[derive(Debug)]
pub(crate) struct PlotError {
    figure: String,
    message: String,
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot draw the figure `{}`: {}", self.figure, self.message)
    }
}

impl std::error::Error for PlotError {}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// Draws into an SVG string of the given height.
fn svg(figure: &str, height: u32, draw: impl FnOnce(&Area<'_>) -> DrawResult) -> Result<String, PlotError> {
    let mut buf = String::new();
    let result = {
        let root = SVGBackend::with_string(&mut buf, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| e.to_string())
            .and_then(|()| draw(&root).map_err(|e| e.to_string()))
            .and_then(|()| root.present().map_err(|e| e.to_string()))
    };
    result.map_err(|message| PlotError { figure: figure.to_string(), message })?;
    Ok(buf)
}

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
pub(crate) enum Mark {
    /// A line segment of the given width.
    Line(u32),
    /// A line segment of the given width and style.
    Styled(u32, Dash),
    /// A filled circle.
    Dot,
    /// A filled bar.
    Bar,
    /// A short vertical tick, as on an axis.
    Tick,
    /// A pale band.
    Shade,
}

/// One legend entry.
pub(crate) struct LegendEntry {
    label: String,
    colour: RGBColor,
    mark: Mark,
}

impl LegendEntry {
    /// An entry.
    pub(crate) fn new(label: impl Into<String>, colour: RGBColor, mark: Mark) -> Self {
        LegendEntry { label: label.into(), colour, mark }
    }
}

const LEGEND_ROW: u32 = 22;

/// Rows of legend entries that fit the width (text estimated at 7.6 px per
/// character of the 14 px legend font).
fn legend_layout(entries: &[LegendEntry]) -> Vec<Vec<(usize, i32)>> {
    let mut rows: Vec<Vec<(usize, i32)>> = vec![Vec::new()];
    let mut x = 0;
    for (i, e) in entries.iter().enumerate() {
        let w = 34 + (e.label.chars().count() as f64 * 7.6) as i32 + 22;
        if x + w > WIDTH as i32 - 80 && x > 0 {
            rows.push(Vec::new());
            x = 0;
        }
        rows.last_mut().unwrap().push((i, x));
        x += w;
    }
    rows
}

fn legend_height(entries: &[LegendEntry]) -> u32 {
    if entries.is_empty() { 0 } else { legend_layout(entries).len() as u32 * LEGEND_ROW + 6 }
}

/// Draws the legend rows centred in `area` (which has [`legend_height`]).
fn draw_legend(area: &Area<'_>, entries: &[LegendEntry]) -> DrawResult {
    let style = (FONT, 14).into_font().color(&AXIS);
    for (r, row) in legend_layout(entries).iter().enumerate() {
        let width = row.last().map_or(0, |&(i, x)| x + 34 + (entries[i].label.chars().count() as f64 * 7.6) as i32);
        let x0 = (WIDTH as i32 - width) / 2;
        let y = r as i32 * LEGEND_ROW as i32 + LEGEND_ROW as i32 / 2 + 2;
        for &(i, x) in row {
            let e = &entries[i];
            let x = x0 + x;
            match e.mark {
                Mark::Line(w) => {
                    area.draw(&PathElement::new(vec![(x, y), (x + 26, y)], e.colour.stroke_width(w + 1)))?;
                }
                Mark::Styled(w, dash) => match dash_pattern(dash) {
                    None => area.draw(&PathElement::new(vec![(x, y), (x + 26, y)], e.colour.stroke_width(w + 1)))?,
                    Some((on, off)) => {
                        let mut a = x;
                        while a < x + 26 {
                            let b = (a + on).min(x + 26);
                            area.draw(&PathElement::new(vec![(a, y), (b, y)], e.colour.stroke_width(w + 1)))?;
                            a = b + off;
                        }
                    }
                },
                Mark::Dot => area.draw(&Circle::new((x + 13, y), 5, e.colour.filled()))?,
                Mark::Bar => area.draw(&Rectangle::new([(x + 6, y - 7), (x + 20, y + 7)], e.colour.filled()))?,
                Mark::Tick => {
                    area.draw(&PathElement::new(vec![(x + 8, y + 6), (x + 8, y - 6)], e.colour.stroke_width(1)))?;
                    area.draw(&PathElement::new(vec![(x + 13, y + 6), (x + 13, y - 6)], e.colour.stroke_width(1)))?;
                    area.draw(&PathElement::new(vec![(x + 18, y + 6), (x + 18, y - 6)], e.colour.stroke_width(1)))?;
                }
                Mark::Shade => {
                    area.draw(&Rectangle::new([(x, y - 7), (x + 26, y + 7)], e.colour.filled()))?;
                    area.draw(&Rectangle::new([(x, y - 7), (x + 26, y + 7)], GRID_BOLD.stroke_width(1)))?;
                }
            }
            area.draw(&Text::new(e.label.clone(), (x + 34, y - 8), style.clone()))?;
        }
    }
    Ok(())
}

/// Title, legend strip and the rest of the figure.
fn frame<'a>(root: &Area<'a>, title: &str, legend: &[LegendEntry]) -> Result<Area<'a>, Box<dyn std::error::Error>> {
    let body = root.titled(title, (FONT, 20).into_font().color(&BLACK))?;
    let h = legend_height(legend);
    if h == 0 {
        return Ok(body);
    }
    let (strip, rest) = body.split_vertically(h);
    draw_legend(&strip, legend)?;
    Ok(rest)
}

/// Whether an SVG written by plotters has a text element reading `t`
/// (plotters puts the text on a line of its own; the compact layout is
/// accepted too, should a version of plotters write it).
#[cfg(test)]
pub(crate) fn has_text(svg: &str, t: &str) -> bool {
    svg.contains(&format!(">\n{t}\n</text>")) || svg.contains(&format!(">{t}</text>"))
}

/// Padded range of finite values, or `fallback` when there are none.
fn range(values: impl Iterator<Item = f64>, fallback: (f64, f64)) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return fallback;
    }
    let pad = ((hi - lo) * 0.05).max(1e-9 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

/// A range for a logarithmic axis: from the 1-2-5 step at or below the
/// smallest positive value to the one at or above the largest.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    let steps = |v: f64| {
        let d = 10f64.powf(v.log10().floor());
        [d, 2.0 * d, 5.0 * d, 10.0 * d]
    };
    let lo = steps(lo).into_iter().rev().find(|&s| s <= lo * (1.0 + 1e-9)).unwrap_or(lo);
    let hi = steps(hi).into_iter().find(|&s| s >= hi * (1.0 - 1e-9)).unwrap_or(hi);
    if hi <= lo { (lo / 2.0, hi * 2.0) } else { (lo, hi) }
}

/// Tick labels of a logarithmic axis: `1e-5`, `0.01`, `0.2`, `5`, `100`;
/// whole mantissas only (which ticks exist is up to [`LogAxis`]).
fn log_tick(v: &f64) -> String {
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    let Some(m) = (1..=10).map(f64::from).find(|x| (m - x).abs() < 1e-6 * x) else {
        return String::new();
    };
    let (m, e) = if m == 10.0 { (1.0, e as i32 + 1) } else { (m, e as i32) };
    match e {
        -2..=3 => crate::table::num(m * 10f64.powi(e)),
        _ if m == 1.0 => format!("1e{e}"),
        _ => format!("{m}e{e}"),
    }
}

/// Tick labels of a linear axis without a trailing `.0`.
fn tick(v: &f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// Splits a curve where it is not finite or where a wrapped phase jumps by
/// more than half a turn, so that no line is drawn across the gap.
fn segments(x: &[f64], y: &[f64], wrap: Option<f64>) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for (&a, &b) in x.iter().zip(y) {
        if !b.is_finite() {
            if !current.is_empty() {
                out.push(std::mem::take(&mut current));
            }
            continue;
        }
        if let (Some(turn), Some(&(_, prev))) = (wrap, current.last())
            && (b - prev).abs() > turn / 2.0
        {
            out.push(std::mem::take(&mut current));
        }
        current.push((a, b));
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

pub(crate) fn unit(kind: FrfKind) -> &'static str {
    match kind {
        FrfKind::Receptance => "m/N",
        FrfKind::Mobility => "m/s/N",
        FrfKind::Accelerance => "m/s\u{b2}/N",
    }
}

/// A logarithmic axis with ticks on whole decades for wide ranges and on
/// the 1-2-5 steps for narrow ones (plotters' own logarithmic axis leaves
/// narrow ranges with one or two labels).
struct LogAxis {
    lo: f64,
    hi: f64,
}

impl Ranged for LogAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10());
        limit.0 + (f64::from(limit.1 - limit.0) * t).round() as i32
    }

    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let decades = (self.hi / self.lo).log10();
        let light = hint.weight().allow_light_points();
        let all = &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
        let mantissas: &[f64] = if decades <= 0.5 || (light && decades <= 3.0) {
            all
        } else if decades <= 1.2 {
            &[1.0, 2.0, 3.0, 5.0]
        } else if decades <= 2.5 {
            &[1.0, 2.0, 5.0]
        } else {
            &[1.0]
        };
        let max = hint.max_num_points().max(2);
        let step = if mantissas.len() == 1 { (decades / max as f64).ceil().max(1.0) as i32 } else { 1 };
        let (e0, e1) = (self.lo.log10().floor() as i32, self.hi.log10().ceil() as i32);
        let inside = |v: &f64| *v >= self.lo * (1.0 - 1e-9) && *v <= self.hi * (1.0 + 1e-9);
        (e0..=e1)
            .filter(|e| (e - e0) % step == 0)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(inside)
            .collect()
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// One model's error per line, for [`error_vs_frequency`].
pub(crate) struct ErrorCurve<'a> {
    /// Legend label.
    pub(crate) label: String,
    /// Colour.
    pub(crate) colour: RGBColor,
    /// Per-line errors over all channels.
    pub(crate) lines: &'a [LineError],
}

/// RMS (over channels) dB and phase errors against frequency, one curve
/// per model, bands shaded alternately and numbered as in the band table.
pub(crate) fn error_vs_frequency(
    title: &str,
    curves: &[ErrorCurve<'_>],
    bands: &[Band],
    scale: axes::FrequencyScale,
) -> Result<String, PlotError> {
    let f: Vec<f64> = curves.first().map(|c| c.lines.iter().map(|l| l.frequency_hz).collect()).unwrap_or_default();
    let axis = FreqAxis::new(&f, scale);
    let (f0, f1) = axis.ends();
    // lines a logarithmic axis cannot show (0 Hz) are left out of the curves
    let f: Vec<f64> = f.iter().map(|&x| if axis.shows(x) { x } else { f64::NAN }).collect();
    let db_max = range(curves.iter().flat_map(|c| c.lines.iter().map(|l| l.rms_db)), (0.0, 1.0)).1.max(1e-3);
    let ph_max = range(curves.iter().flat_map(|c| c.lines.iter().map(|l| l.rms_phase_deg)), (0.0, 1.0)).1.max(1e-3);
    let mut legend: Vec<LegendEntry> =
        curves.iter().map(|c| LegendEntry::new(c.label.clone(), c.colour, Mark::Line(2))).collect();
    if bands.len() > 1 {
        legend.push(LegendEntry::new("bands (numbered as in the table)", BAND_SHADE, Mark::Shade));
    }
    let x_label = |v: &f64| axis.label(v);
    svg(title, 600, |root| {
        let body = frame(root, title, &legend)?;
        let h = body.dim_in_pixel().1;
        let (top, bottom) = body.split_vertically(h / 2);
        for (panel, area) in [(0, &top), (1, &bottom)] {
            let ymax = if panel == 0 { db_max } else { ph_max };
            let mut chart = ChartBuilder::on(area)
                .margin_left(12)
                .margin_right(24)
                .margin_top(8)
                .x_label_area_size(if panel == 0 { 30 } else { 44 })
                .y_label_area_size(72)
                .build_cartesian_2d(axis, 0.0..ymax)?;
            // shading first, so that the grid and the curves stay on top
            if bands.len() > 1 {
                for (i, b) in bands.iter().enumerate() {
                    if i % 2 == 0 {
                        let (lo, hi) = (b.lo_hz.max(f0), b.hi_hz.min(f1));
                        chart.draw_series(std::iter::once(Rectangle::new(
                            [(lo, 0.0), (hi, ymax)],
                            BAND_SHADE.filled(),
                        )))?;
                    }
                }
            }
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(if panel == 0 { "RMS magnitude error (dB)" } else { "RMS phase error (deg)" })
                .light_line_style(GRID_LIGHT)
                .bold_line_style(GRID_BOLD)
                .axis_style(AXIS)
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 15))
                .x_labels(12)
                .x_label_formatter(&x_label)
                .y_labels(6)
                .y_label_formatter(&tick);
            if panel == 1 {
                mesh.x_desc(axis.describe());
            }
            mesh.draw()?;
            if panel == 0 && bands.len() > 1 {
                let style = (FONT, 12).into_font().color(&RGBColor(120, 120, 140));
                for (i, b) in bands.iter().enumerate() {
                    let (lo, hi) = (b.lo_hz.max(f0), b.hi_hz.min(f1));
                    let (px0, _) = chart.backend_coord(&(lo, ymax));
                    let (px1, _) = chart.backend_coord(&(hi, ymax));
                    if px1 - px0 >= 18 {
                        let mid = if axis.is_log() { (lo * hi).sqrt() } else { 0.5 * (lo + hi) };
                        chart.draw_series(std::iter::once(Text::new(
                            format!("{}", i + 1),
                            (mid, ymax * 0.97),
                            style.clone().pos(plotters::style::text_anchor::Pos::new(
                                plotters::style::text_anchor::HPos::Center,
                                plotters::style::text_anchor::VPos::Top,
                            )),
                        )))?;
                    }
                }
            }
            for c in curves.iter().rev() {
                let y: Vec<f64> = c.lines.iter().map(|l| if panel == 0 { l.rms_db } else { l.rms_phase_deg }).collect();
                for seg in segments(&f, &y, None) {
                    chart.draw_series(LineSeries::new(seg, c.colour.stroke_width(2)))?;
                }
            }
        }
        Ok(())
    })
}

/// One model's per-channel errors, for [`channel_errors`].
pub(crate) struct ChannelSeries {
    /// Legend label.
    pub(crate) label: String,
    /// Colour.
    pub(crate) colour: RGBColor,
    /// RMS dB error per channel.
    pub(crate) rms_db: Vec<f64>,
    /// FRAC per channel.
    pub(crate) frac: Vec<f64>,
}

/// RMS dB error (bars) and FRAC (dots) per channel (measurement point),
/// one series per model side by side. Channels are categories: nothing
/// joins one to the next.
pub(crate) fn channel_errors(title: &str, names: &[String], series: &[ChannelSeries]) -> Result<String, PlotError> {
    let n = names.len().max(1);
    let db_max = range(series.iter().flat_map(|s| s.rms_db.iter().copied()), (0.0, 1.0)).1.max(1e-3);
    let legend: Vec<LegendEntry> =
        series.iter().map(|s| LegendEntry::new(s.label.clone(), s.colour, Mark::Bar)).collect();
    let label = |v: &f64| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
            names[i as usize].clone()
        } else {
            String::new()
        }
    };
    let frac_min = series
        .iter()
        .flat_map(|s| s.frac.iter().copied())
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::min)
        .clamp(0.0, 0.9);
    let frac_lo = (frac_min * 10.0).floor() / 10.0;
    // each channel's slot holds one bar per model, side by side
    let slot = 0.8 / series.len().max(1) as f64;
    let offset = |k: usize| -0.4 + slot * (k as f64 + 0.5);
    svg(title, 560, |root| {
        let body = frame(root, title, &legend)?;
        let h = body.dim_in_pixel().1;
        let (top, bottom) = body.split_vertically(h / 2);
        for (panel, area) in [(0, &top), (1, &bottom)] {
            let (y0, y1) = if panel == 0 { (0.0, db_max) } else { (frac_lo, 1.0) };
            let mut chart = ChartBuilder::on(area)
                .margin_left(12)
                .margin_right(24)
                .margin_top(8)
                .x_label_area_size(if panel == 0 { 30 } else { 48 })
                .y_label_area_size(72)
                .build_cartesian_2d(-0.5..(n as f64 - 0.5), y0..y1)?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(if panel == 0 { "RMS magnitude error (dB)" } else { "FRAC" })
                .light_line_style(GRID_LIGHT)
                .bold_line_style(GRID_BOLD)
                .axis_style(AXIS)
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 15))
                .disable_x_mesh()
                .x_labels(n.min(16))
                .x_label_formatter(&label)
                .y_labels(6)
                .y_label_formatter(&tick);
            if panel == 1 {
                mesh.x_desc("Channel (response DOF)");
            }
            mesh.draw()?;
            for (k, s) in series.iter().enumerate() {
                let y = if panel == 0 { &s.rms_db } else { &s.frac };
                let points =
                    y.iter().enumerate().filter(|(_, v)| v.is_finite()).map(|(i, &v)| (i as f64 + offset(k), v));
                if panel == 0 {
                    chart.draw_series(points.map(|(x, v)| {
                        Rectangle::new([(x - 0.45 * slot, 0.0), (x + 0.45 * slot, v)], s.colour.filled())
                    }))?;
                } else {
                    chart.draw_series(points.map(|p| Circle::new(p, 4, s.colour.filled())))?;
                }
            }
        }
        Ok(())
    })
}

/// Misfit per iteration: the updating method's residual at its lines and,
/// when given, the RMS dB error over all measured lines; logarithmic axes.
pub(crate) fn convergence(
    residual_label: &str,
    residual: &[f64],
    all_lines_db: Option<&[f64]>,
) -> Result<String, PlotError> {
    let title = "Misfit per iteration";
    let mut legend = vec![LegendEntry::new(format!("{residual_label} at the updating lines"), UPDATED, Mark::Line(2))];
    if all_lines_db.is_some() {
        legend.push(LegendEntry::new("RMS magnitude error over the measured band", INITIAL, Mark::Line(2)));
    }
    let n = residual.len().max(all_lines_db.map_or(0, <[f64]>::len)).max(2);
    let panels: Vec<(&str, RGBColor, &[f64])> = std::iter::once((residual_label, UPDATED, residual))
        .chain(all_lines_db.map(|d| ("RMS error over the band (dB)", INITIAL, d)))
        .collect();
    let height = if panels.len() == 2 { 600 } else { 380 };
    svg(title, height, |root| {
        let body = frame(root, title, &legend)?;
        let areas = body.split_evenly((panels.len(), 1));
        for (p, ((ydesc, colour, values), area)) in panels.iter().zip(&areas).enumerate() {
            let (y0, y1) = log_range(values.iter().copied());
            let last = p + 1 == panels.len();
            let mut chart = ChartBuilder::on(area)
                .margin_left(12)
                .margin_right(24)
                .margin_top(8)
                .x_label_area_size(if last { 44 } else { 30 })
                .y_label_area_size(72)
                .build_cartesian_2d(-0.3..(n as f64 - 0.7), LogAxis { lo: y0, hi: y1 })?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(*ydesc)
                .light_line_style(GRID_LIGHT)
                .bold_line_style(GRID_BOLD)
                .axis_style(AXIS)
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 15))
                .x_labels(n.min(12))
                .x_label_formatter(&|v| {
                    if (v - v.round()).abs() < 1e-6 && *v >= 0.0 {
                        format!("{}", v.round() as i64)
                    } else {
                        String::new()
                    }
                })
                .y_label_formatter(&log_tick);
            if last {
                mesh.x_desc("Iteration");
            }
            mesh.draw()?;
            let pts: Vec<(f64, f64)> = values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite() && **v > 0.0)
                .map(|(i, &v)| (i as f64, v))
                .collect();
            chart.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?;
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))?;
        }
        Ok(())
    })
}

/// A parameter's history for [`parameter_history`].
pub(crate) struct ParameterTrace {
    /// Dotted name.
    pub(crate) name: String,
    /// Value / initial value, per iteration.
    pub(crate) ratios: Vec<f64>,
    /// Truth / initial value, when known.
    pub(crate) truth_ratio: Option<f64>,
}

/// Parameter values relative to their initial values, per iteration
/// (logarithmic axis), each parameter in its own [`look`]; its truth, when
/// known, as a thin dotted line in the same colour, labelled at the right.
pub(crate) fn parameter_history(traces: &[ParameterTrace]) -> Result<String, PlotError> {
    let title = "Parameter values relative to initial";
    let mut legend: Vec<LegendEntry> = traces
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let l = look(i);
            LegendEntry::new(t.name.clone(), l.colour, Mark::Styled(2, l.dash))
        })
        .collect();
    if traces.iter().any(|t| t.truth_ratio.is_some()) {
        legend.push(LegendEntry::new(
            "truth (thin dotted line in the parameter's colour)",
            AXIS,
            Mark::Styled(1, Dash::Dotted),
        ));
    }
    let n = traces.iter().map(|t| t.ratios.len()).max().unwrap_or(0).max(2);
    let (y0, y1) =
        log_range(traces.iter().flat_map(|t| t.ratios.iter().copied().chain(t.truth_ratio)).chain([0.9, 1.1]));
    let x1 = n as f64 - 0.7;
    svg(title, 500, |root| {
        let body = frame(root, title, &legend)?;
        let mut chart = ChartBuilder::on(&body)
            .margin_left(12)
            .margin_right(24)
            .margin_top(8)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(-0.3..x1, LogAxis { lo: y0, hi: y1 })?;
        chart
            .configure_mesh()
            .x_desc("Iteration")
            .y_desc("Value / initial value")
            .light_line_style(GRID_LIGHT)
            .bold_line_style(GRID_BOLD)
            .axis_style(AXIS)
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .x_labels(n.min(12))
            .x_label_formatter(&|v| {
                if (v - v.round()).abs() < 1e-6 && *v >= 0.0 { format!("{}", v.round() as i64) } else { String::new() }
            })
            .y_label_formatter(&log_tick)
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(vec![(-0.3, 1.0), (x1, 1.0)], AXIS.stroke_width(1))))?;
        for (i, t) in traces.iter().enumerate() {
            let l = look(i);
            if let Some(r) = t.truth_ratio.filter(|r| r.is_finite() && *r > 0.0) {
                draw_line(&mut chart, vec![(-0.3, r), (x1, r)], Look { colour: l.colour, dash: Dash::Dotted }, 1)?;
            }
            let pts: Vec<(f64, f64)> = t
                .ratios
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite() && **v > 0.0)
                .map(|(k, &v)| (k as f64, v))
                .collect();
            draw_line(&mut chart, pts.clone(), l, 2)?;
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, l.colour.filled())))?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapped_phase_and_gaps_split_the_curve() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let y = [170.0, 178.0, -178.0, -170.0, f64::NAN, -160.0];
        let s = segments(&x, &y, Some(360.0));
        assert_eq!(s.iter().map(Vec::len).collect::<Vec<_>>(), vec![2, 2, 1]);
        // without wrapping, only the gap splits
        assert_eq!(segments(&x, &y, None).len(), 2);
    }

    #[test]
    fn thirty_series_look_different_and_each_truth_takes_its_parameter_colour() {
        let looks: std::collections::HashSet<Look> = (0..3 * PALETTE.len()).map(look).collect();
        assert_eq!(looks.len(), 30);
        let colours: std::collections::HashSet<RGBColor> = PALETTE.iter().copied().collect();
        assert_eq!(colours.len(), PALETTE.len());
        // nine parameters, as the F-frame updates: nine colours, each with its truth
        let traces: Vec<ParameterTrace> = (0..9)
            .map(|i| ParameterTrace {
                name: format!("p{i}"),
                ratios: vec![1.0, 1.5, 2.0 + f64::from(i)],
                truth_ratio: Some(2.0 + f64::from(i)),
            })
            .collect();
        let svg = parameter_history(&traces).unwrap();
        for i in 0..9 {
            let c = look(i).colour;
            let stroke = format!("stroke=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
            // the trace (one polyline) and its dotted truth (many short ones)
            assert!(svg.matches(&stroke).count() >= 3, "parameter {i}");
        }
        assert!(svg.contains("truth (thin dotted line in the parameter"));
    }

    #[test]
    fn channel_errors_are_bars_and_dots_not_lines() {
        let names: Vec<String> = (1..=4).map(|k| format!("{k}:uy")).collect();
        let series = vec![
            ChannelSeries { label: "a".into(), colour: INITIAL, rms_db: vec![1.0, 2.0, 0.5, 3.0], frac: vec![0.9; 4] },
            ChannelSeries {
                label: "b".into(),
                colour: UPDATED,
                rms_db: vec![0.1, 0.2, 0.05, 0.3],
                frac: vec![0.99; 4],
            },
        ];
        let svg = channel_errors("per channel", &names, &series).unwrap();
        let fill = |c: RGBColor| format!("fill=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
        // four bars, four dots and the legend's bar, per model
        for c in [INITIAL, UPDATED] {
            assert_eq!(svg.matches(&fill(c)).count(), 4 + 4 + 1);
        }
        assert_eq!(svg.matches("<circle").count(), 8);
    }

    #[test]
    fn log_axes_span_1_2_5_steps_and_label_them() {
        assert_eq!(log_range([3e-9, 0.0015, 0.0, f64::NAN].into_iter()), (2e-9, 0.002));
        assert_eq!(log_range([0.4, 3.3].into_iter()), (0.2, 5.0));
        assert_eq!(log_tick(&1e-5), "1e-5");
        assert_eq!(log_tick(&5e-7), "5e-7");
        assert_eq!(log_tick(&100.0), "100");
        assert_eq!(log_tick(&0.2), "0.2");
        assert_eq!(log_tick(&3.0), "3");
        assert_eq!(log_tick(&3.5), "");
        assert_eq!(tick(&50.0), "50");
        assert_eq!(tick(&-0.0), "0");
        assert_eq!(tick(&0.25), "0.25");
    }
}

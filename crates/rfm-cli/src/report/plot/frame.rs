//! The frame of a figure: the SVG string backend, the title, the legend
//! strip under it, and the error a figure that cannot be drawn gives.

use std::fmt;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{AXIS, Dash, FONT, GRID_BOLD, WIDTH, dash_pattern};

/// A figure could not be drawn.
#[derive(Debug)]
pub(crate) struct PlotError {
    pub(super) figure: String,
    pub(super) message: String,
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot draw the figure `{}`: {}", self.figure, self.message)
    }
}

impl std::error::Error for PlotError {}

pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
pub(super) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// Draws into an SVG string of the given height.
pub(super) fn svg(figure: &str, height: u32, draw: impl FnOnce(&Area<'_>) -> DrawResult) -> Result<String, PlotError> {
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
    pub(super) label: String,
    pub(super) colour: RGBColor,
    pub(super) mark: Mark,
}

impl LegendEntry {
    /// An entry.
    pub(crate) fn new(label: impl Into<String>, colour: RGBColor, mark: Mark) -> Self {
        LegendEntry { label: label.into(), colour, mark }
    }
}

pub(super) const LEGEND_ROW: u32 = 22;

/// Rows of legend entries that fit the width (text estimated at 7.6 px per
/// character of the 14 px legend font).
pub(super) fn legend_layout(entries: &[LegendEntry]) -> Vec<Vec<(usize, i32)>> {
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

pub(super) fn legend_height(entries: &[LegendEntry]) -> u32 {
    if entries.is_empty() { 0 } else { legend_layout(entries).len() as u32 * LEGEND_ROW + 6 }
}

/// Draws the legend rows centred in `area` (which has [`legend_height`]).
pub(super) fn draw_legend(area: &Area<'_>, entries: &[LegendEntry]) -> DrawResult {
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
pub(super) fn frame<'a>(
    root: &Area<'a>,
    title: &str,
    legend: &[LegendEntry],
) -> Result<Area<'a>, Box<dyn std::error::Error>> {
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

//! The look every figure shares: the colour scheme (measured black,
//! initial orange, updated blue), `look(i)` for many series (ten colours
//! times three line styles), the font and the grid colours.

use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::Ranged;
use plotters::prelude::*;

use super::DrawResult;

/// Colour of measured data.
pub(crate) const MEASURED: RGBColor = RGBColor(0, 0, 0);
/// Colour of a measured FRF in an overlay: drawn wide and pale under the
/// models, so that a model that matches runs visibly along its middle.
pub(crate) const MEASURED_FRF: RGBColor = RGBColor(160, 160, 160);
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
pub(super) fn dash_pattern(dash: Dash) -> Option<(i32, i32)> {
    match dash {
        Dash::Solid => None,
        Dash::Dashed => Some((9, 5)),
        Dash::Dotted => Some((2, 4)),
    }
}

/// Draws `points` as a line of the given look and width on a chart.
pub(super) fn draw_line<DB, CT>(
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

pub(super) const FONT: &str = "sans-serif";
pub(super) const WIDTH: u32 = 960;
pub(super) const GRID_LIGHT: RGBColor = RGBColor(238, 238, 238);
pub(super) const GRID_BOLD: RGBColor = RGBColor(205, 205, 205);
pub(super) const BAND_SHADE: RGBColor = RGBColor(244, 244, 248);
pub(super) const AXIS: RGBColor = RGBColor(60, 60, 60);

/// The grid and labels every chart shares: light and bold grid lines, the
/// axis colour, and labels and axis descriptions in [`FONT`] at the given
/// sizes (px).
pub(super) trait HouseStyle {
    /// Sets the shared grid and label style.
    fn house_style(&mut self, label: u32, desc: u32) -> &mut Self;
}

impl<X: Ranged, Y: Ranged, DB: DrawingBackend> HouseStyle for MeshStyle<'_, '_, X, Y, DB> {
    fn house_style(&mut self, label: u32, desc: u32) -> &mut Self {
        self.light_line_style(GRID_LIGHT)
            .bold_line_style(GRID_BOLD)
            .axis_style(AXIS)
            .label_style((FONT, label))
            .axis_desc_style((FONT, desc))
    }
}

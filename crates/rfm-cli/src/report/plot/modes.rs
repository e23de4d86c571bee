//! Figures of the modal comparison: the MAC matrix of measured against
//! model modes with the pairing outlined, and the stabilisation diagram of
//! the modal estimate.

use frf::PoleStatus;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axes::{FreqAxis, FrequencyScale};
use super::{
    AXIS, Dash, FONT, GRID_BOLD, HouseStyle, LegendEntry, MEASURED, Mark, PlotError, UPDATED, WIDTH, frame, svg,
};

/// Colour of a MAC value from 0 (white) to 1 (the updated model's blue).
pub(crate) fn mac_colour(v: f64) -> RGBColor {
    let t = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
    let mix = |a: u8, b: u8| (f64::from(a) + t * (f64::from(b) - f64::from(a))).round() as u8;
    RGBColor(mix(255, 8), mix(255, 48), mix(255, 107))
}

/// The MAC matrix as a heat map: measured modes down, model modes across,
/// each cell's value printed in it, the paired cells outlined.
pub(crate) fn mac_matrix(
    title: &str,
    measured_hz: &[f64],
    model_hz: &[f64],
    mac: &[Vec<f64>],
    pairs: &[(usize, usize)],
) -> Result<String, PlotError> {
    let (rows, cols) = (measured_hz.len().max(1), model_hz.len().max(1));
    let legend = vec![LegendEntry::new("paired (one-to-one, by MAC)", MEASURED, Mark::Styled(2, Dash::Solid))];
    let left = 150;
    let right = 90;
    let cell_w = ((f64::from(WIDTH) - f64::from(left + right)) / cols as f64).min(90.0);
    let cell_h = cell_w.clamp(22.0, 46.0);
    let grid_h = (cell_h * rows as f64) as u32;
    let height = 40 + super::legend_height(&legend) + grid_h + 88;
    let numbers = cell_w >= 34.0;
    svg(title, height, |root| {
        let body = frame(root, title, &legend)?;
        let x0 = f64::from(left) + (f64::from(WIDTH - left - right) - cell_w * cols as f64) / 2.0;
        let y0 = 30.0;
        let cell = |i: usize, j: usize| {
            let (a, b) = (x0 + cell_w * j as f64, y0 + cell_h * i as f64);
            ((a.round() as i32, b.round() as i32), ((a + cell_w).round() as i32, (b + cell_h).round() as i32))
        };
        let small = (FONT, 12).into_font();
        for (i, row) in mac.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                let (a, b) = cell(i, j);
                body.draw(&Rectangle::new([a, b], mac_colour(v).filled()))?;
                body.draw(&Rectangle::new([a, b], GRID_BOLD.stroke_width(1)))?;
                if numbers {
                    let ink = if v > 0.55 { WHITE } else { BLACK };
                    let style = small.clone().color(&ink).pos(Pos::new(HPos::Center, VPos::Center));
                    body.draw(&Text::new(format!("{v:.2}"), ((a.0 + b.0) / 2, (a.1 + b.1) / 2), style))?;
                }
            }
        }
        // outlines as closed paths: plotters writes no stroke width for a rectangle
        for &(i, j) in pairs {
            let (a, b) = cell(i, j);
            let (a, b) = ((a.0 + 2, a.1 + 2), (b.0 - 2, b.1 - 2));
            body.draw(&PathElement::new(vec![a, (b.0, a.1), b, (a.0, b.1), a], MEASURED.stroke_width(3)))?;
        }
        let label = (FONT, 13).into_font().color(&AXIS);
        for (i, f) in measured_hz.iter().enumerate() {
            let (a, b) = cell(i, 0);
            let style = label.clone().pos(Pos::new(HPos::Right, VPos::Center));
            body.draw(&Text::new(format!("{}: {f:.1} Hz", i + 1), (a.0 - 8, (a.1 + b.1) / 2), style))?;
        }
        let bottom = cell(rows - 1, 0).1.1;
        for (j, f) in model_hz.iter().enumerate() {
            let (a, b) = cell(0, j);
            let x = (a.0 + b.0) / 2;
            let style = label.clone().pos(Pos::new(HPos::Center, VPos::Top));
            body.draw(&Text::new(format!("{}", j + 1), (x, bottom + 6), style.clone()))?;
            if cell_w >= 56.0 {
                body.draw(&Text::new(format!("{f:.1} Hz"), (x, bottom + 22), style))?;
            }
        }
        let desc = (FONT, 15).into_font().color(&AXIS);
        body.draw(&Text::new(
            "model modes",
            (((x0 + cell_w * cols as f64 / 2.0) as i32), bottom + 42),
            desc.clone().pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
        body.draw(&Text::new(
            "measured modes",
            (x0 as i32 - 8, y0 as i32 - 8),
            desc.pos(Pos::new(HPos::Right, VPos::Bottom)),
        ))?;
        // the colour scale
        let (sx, top) = ((x0 + cell_w * cols as f64) as i32 + 28, y0 as i32);
        let span = (grid_h as i32).max(60);
        for k in 0..span {
            let v = 1.0 - f64::from(k) / f64::from(span - 1);
            body.draw(&Rectangle::new([(sx, top + k), (sx + 14, top + k + 1)], mac_colour(v).filled()))?;
        }
        body.draw(&Rectangle::new([(sx, top), (sx + 14, top + span)], GRID_BOLD.stroke_width(1)))?;
        for (v, y) in [(1.0, top), (0.5, top + span / 2), (0.0, top + span)] {
            let style = small.clone().color(&AXIS).pos(Pos::new(HPos::Left, VPos::Center));
            body.draw(&Text::new(format!("{v}"), (sx + 20, y), style))?;
        }
        Ok(())
    })
}

/// One pole of one model order, for [`stabilisation`].
pub(crate) struct StabilisationPoint {
    /// Frequency (Hz).
    pub(crate) frequency_hz: f64,
    /// Model order.
    pub(crate) order: usize,
    /// How it compares with the previous order.
    pub(crate) status: PoleStatus,
}

/// Colour, radius and fill of a pole's mark by its status.
fn status_mark(s: PoleStatus) -> (RGBColor, i32, bool) {
    match s {
        PoleStatus::New => (RGBColor(175, 175, 175), 2, true),
        PoleStatus::Frequency => (RGBColor(230, 159, 0), 3, false),
        PoleStatus::Damping => (RGBColor(86, 180, 233), 3, false),
        PoleStatus::Stable => (UPDATED, 4, true),
    }
}

/// The stabilisation diagram: every order's poles by frequency, marked by
/// how they compare with the previous order, the identified modes as
/// dashed lines, and the measured FRFs' summed magnitude behind them (on
/// its own logarithmic scale, for where the peaks are).
pub(crate) fn stabilisation(
    points: &[StabilisationPoint],
    modes_hz: &[f64],
    lines_hz: &[f64],
    magnitude: &[f64],
    scale: FrequencyScale,
) -> Result<String, PlotError> {
    let title = "Stabilisation diagram of the modal estimate";
    let mut legend = vec![
        LegendEntry::new("new pole", status_mark(PoleStatus::New).0, Mark::Dot),
        LegendEntry::new("stable in frequency", status_mark(PoleStatus::Frequency).0, Mark::Dot),
        LegendEntry::new("and in damping", status_mark(PoleStatus::Damping).0, Mark::Dot),
        LegendEntry::new("stable (and participation)", status_mark(PoleStatus::Stable).0, Mark::Dot),
        LegendEntry::new("identified mode", MEASURED, Mark::Styled(1, Dash::Dashed)),
    ];
    if !magnitude.is_empty() {
        legend.push(LegendEntry::new("sum of |H| over channels (log scale)", GRID_BOLD, Mark::Line(2)));
    }
    let axis = FreqAxis::new(lines_hz, scale);
    let max_order = points.iter().map(|p| p.order).max().unwrap_or(1) + 2;
    let y_top = max_order as f64;
    svg(title, 520, |root| {
        let body = frame(root, title, &legend)?;
        let mut chart = ChartBuilder::on(&body)
            .margin_left(12)
            .margin_right(24)
            .margin_top(18)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(axis, 0.0..y_top)?;
        let x_label = |v: &f64| axis.label(v);
        chart
            .configure_mesh()
            .x_desc(axis.describe())
            .y_desc("Model order")
            .x_label_formatter(&x_label)
            .y_label_formatter(&super::tick)
            .house_style(13, 15)
            .x_labels(12)
            .y_labels(10)
            .draw()?;
        // the summed magnitude, mapped onto the order axis
        let db: Vec<f64> = magnitude.iter().map(|m| if *m > 0.0 { 20.0 * m.log10() } else { f64::NAN }).collect();
        let (lo, hi) = db
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        if lo.is_finite() && hi > lo {
            let pts: Vec<(f64, f64)> = lines_hz
                .iter()
                .zip(&db)
                .filter(|(f, v)| axis.shows(**f) && v.is_finite())
                .map(|(&f, &v)| (f, 0.5 + (y_top - 1.0) * (v - lo) / (hi - lo)))
                .collect();
            let pts = super::decimate::per_pixel_column(&pts, |p| chart.backend_coord(p));
            chart.draw_series(LineSeries::new(pts, GRID_BOLD.stroke_width(2)))?;
        }
        for &f in modes_hz.iter().filter(|f| axis.shows(**f)) {
            chart.draw_series(DashedLineSeries::new(vec![(f, 0.0), (f, y_top)], 6, 4, MEASURED.stroke_width(1)))?;
        }
        // weakest first, so that the stable poles are drawn on top
        let mut sorted: Vec<&StabilisationPoint> = points.iter().filter(|p| axis.shows(p.frequency_hz)).collect();
        sorted.sort_by_key(|p| p.status);
        chart.draw_series(sorted.into_iter().map(|p| {
            let (colour, r, filled) = status_mark(p.status);
            let style = if filled { colour.filled() } else { colour.stroke_width(1) };
            Circle::new((p.frequency_hz, p.order as f64), r, style)
        }))?;
        // the mode numbers along the top, each in the first row where it
        // clears the labels already placed: close modes get staggered rows
        // instead of numbers printed over each other
        let style = (FONT, 12).into_font().color(&MEASURED).pos(Pos::new(HPos::Center, VPos::Top));
        let (_, top_px) = chart.backend_coord(&(axis.ends().0, y_top));
        let (_, bottom_px) = chart.backend_coord(&(axis.ends().0, 0.0));
        let per_px = y_top / f64::from((bottom_px - top_px).max(1));
        let placed =
            label_rows(modes_hz.iter().map(|&f| axis.shows(f).then(|| chart.backend_coord(&(f, y_top)).0)).collect());
        for (k, (&f, row)) in modes_hz.iter().zip(placed).enumerate() {
            let Some(row) = row else { continue };
            let y = y_top - per_px * (6.0 + f64::from(LABEL_ROW_PX) * row as f64);
            chart.draw_series(std::iter::once(Text::new(format!("{}", k + 1), (f, y), style.clone())))?;
        }
        Ok(())
    })
}

/// Height of a row of mode numbers (px).
const LABEL_ROW_PX: i32 = 14;

/// Width a mode number needs clear on each side of its place (px).
const LABEL_HALF_WIDTH: i32 = 9;

/// The row of each mode number drawn at pixel column `x` (`None`: not
/// shown): the first row in which it clears every number already placed in
/// that row, in order.
fn label_rows(x: Vec<Option<i32>>) -> Vec<Option<usize>> {
    let mut last_in_row: Vec<i32> = Vec::new();
    x.into_iter()
        .map(|x| {
            let x = x?;
            let row = last_in_row.iter().position(|&l| x - l >= 2 * LABEL_HALF_WIDTH).unwrap_or(last_in_row.len());
            if row == last_in_row.len() {
                last_in_row.push(x);
            } else {
                last_in_row[row] = x;
            }
            Some(row)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    /// Numbers far apart share the first row; close ones step down a row
    /// each, and a later one returns to the first row once it is clear.
    #[test]
    fn close_mode_numbers_are_staggered_and_never_overlap() {
        let rows = label_rows(vec![Some(100), Some(104), Some(110), None, Some(160), Some(300)]);
        assert_eq!(rows, vec![Some(0), Some(1), Some(2), None, Some(0), Some(0)]);
        // every pair in one row is at least a label apart
        let x = [100, 104, 110, 160, 300];
        let r: Vec<usize> = rows.into_iter().flatten().collect();
        for i in 0..x.len() {
            for j in 0..i {
                if r[i] == r[j] {
                    assert!(x[i] - x[j] >= 2 * LABEL_HALF_WIDTH, "{} and {}", x[j], x[i]);
                }
            }
        }
    }

    use super::*;

    #[test]
    fn the_mac_matrix_prints_every_value_and_outlines_each_pair() {
        let mac = vec![vec![0.99, 0.02, 0.1], vec![0.01, 0.95, 0.3]];
        let svg = mac_matrix("MAC", &[17.9, 43.8], &[18.2, 52.3, 240.0], &mac, &[(0, 0), (1, 1)]).unwrap();
        for v in ["0.99", "0.02", "0.10", "0.01", "0.95", "0.30", "1: 17.9 Hz", "2: 43.8 Hz", "52.3 Hz"] {
            assert!(super::super::has_text(&svg, v), "missing {v}");
        }
        // two pair outlines in black, three px wide, and the legend's
        assert_eq!(svg.matches("stroke=\"#000000\" stroke-width=\"3\"").count(), 2 + 1);
        assert_eq!(mac_colour(0.0), RGBColor(255, 255, 255));
        assert_eq!(mac_colour(1.0), RGBColor(8, 48, 107));
    }

    #[test]
    fn the_summed_magnitude_of_a_million_lines_draws_at_most_four_points_per_pixel_column() {
        let f: Vec<f64> = (0..1_000_000).map(|k| 1.0 + f64::from(k) * 1e-4).collect();
        let m: Vec<f64> = f.iter().map(|&x| 1.0 / (1.0 + (x - 20.0).powi(2))).collect();
        let points = [StabilisationPoint { frequency_hz: 20.0, order: 4, status: PoleStatus::Stable }];
        let svg = stabilisation(&points, &[20.0], &f, &m, FrequencyScale::Linear).unwrap();
        let drawn = super::super::decimate::polylines(&svg, "stroke-width=\"2\"");
        let curve = drawn.iter().max_by_key(|l| l.len()).unwrap();
        assert!(curve.len() > 100, "{} points", curve.len());
        let most = super::super::decimate::most_per_column(curve);
        assert!(most <= 4, "{most} points in a pixel column");
    }

    #[test]
    fn the_stabilisation_diagram_marks_each_status_and_mode() {
        let points: Vec<StabilisationPoint> = (4..=10)
            .flat_map(|order| {
                [
                    StabilisationPoint { frequency_hz: 20.0, order, status: PoleStatus::Stable },
                    StabilisationPoint { frequency_hz: 33.0 + order as f64, order, status: PoleStatus::New },
                ]
            })
            .collect();
        let f: Vec<f64> = (1..=100).map(f64::from).collect();
        let m: Vec<f64> = f.iter().map(|&x| 1.0 / (1.0 + (x - 20.0).powi(2))).collect();
        let svg = stabilisation(&points, &[20.0], &f, &m, FrequencyScale::Linear).unwrap();
        let blue = format!("fill=\"#{:02X}{:02X}{:02X}\"", UPDATED.0, UPDATED.1, UPDATED.2);
        assert!(svg.matches(&blue).count() >= 7, "seven stable poles");
        for text in ["Model order", "identified mode", "stable (and participation)"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }
}

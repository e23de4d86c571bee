//! The figures of a correlation: error against frequency (dB and phase,
//! bands shaded) and the error of every channel as bars and dots.

use ::frf::correlation::{Band, LineError};
use plotters::prelude::*;

use super::axes::{self, FreqAxis};
use super::{
    BAND_SHADE, Dash, FONT, HouseStyle, LegendEntry, Look, Mark, PlotError, draw_line, frame, range, segments, svg,
    tick,
};

/// Colour of the noise floor.
const NOISE_FLOOR: RGBColor = RGBColor(0, 128, 64);

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
/// per model, bands shaded alternately and numbered as in the band table;
/// with the data's noise level, the RMS errors that noise alone leaves
/// (the noise floor, [`rfm_update::quantities::noise_floor_db`]) as dashed
/// lines: a model whose curve lies on them is as good as the data allow.
pub(crate) fn error_vs_frequency(
    title: &str,
    curves: &[ErrorCurve<'_>],
    bands: &[Band],
    scale: axes::FrequencyScale,
    noise: Option<f64>,
) -> Result<String, PlotError> {
    let f: Vec<f64> = curves.first().map(|c| c.lines.iter().map(|l| l.frequency_hz).collect()).unwrap_or_default();
    let axis = FreqAxis::new(&f, scale);
    let (f0, f1) = axis.ends();
    // lines a logarithmic axis cannot show (0 Hz) are left out of the curves
    let f: Vec<f64> = f.iter().map(|&x| if axis.shows(x) { x } else { f64::NAN }).collect();
    let floor = noise
        .filter(|n| *n > 0.0)
        .map(|n| (rfm_update::quantities::noise_floor_db(n), rfm_update::quantities::noise_floor_deg(n)));
    let db_max =
        range(curves.iter().flat_map(|c| c.lines.iter().map(|l| l.rms_db)).chain(floor.map(|f| 2.0 * f.0)), (0.0, 1.0))
            .1
            .max(1e-3);
    let ph_max = range(
        curves.iter().flat_map(|c| c.lines.iter().map(|l| l.rms_phase_deg)).chain(floor.map(|f| 2.0 * f.1)),
        (0.0, 1.0),
    )
    .1
    .max(1e-3);
    let mut legend: Vec<LegendEntry> =
        curves.iter().map(|c| LegendEntry::new(c.label.clone(), c.colour, Mark::Line(2))).collect();
    if floor.is_some() {
        legend.push(LegendEntry::new(
            "noise floor (what the noise alone leaves)",
            NOISE_FLOOR,
            Mark::Styled(1, Dash::Dashed),
        ));
    }
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
            mesh.y_desc(if panel == 0 { "RMS dB error" } else { "RMS phase error (deg)" })
                .house_style(13, 15)
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
            if let Some((db, deg)) = floor {
                let y = if panel == 0 { db } else { deg };
                draw_line(&mut chart, vec![(f0, y), (f1, y)], Look { colour: NOISE_FLOOR, dash: Dash::Dashed }, 1)?;
            }
            for c in curves.iter().rev() {
                let y: Vec<f64> = c.lines.iter().map(|l| if panel == 0 { l.rms_db } else { l.rms_phase_deg }).collect();
                for seg in segments(&f, &y, None) {
                    let seg = super::decimate::per_pixel_column(&seg, |p| chart.backend_coord(p));
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
                .house_style(13, 15)
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

#[cfg(test)]
mod tests {
    use super::super::decimate::{most_per_column, polylines};
    use super::super::{INITIAL, UPDATED};
    use super::*;

    #[test]
    fn errors_at_a_million_lines_draw_at_most_four_points_per_pixel_column() {
        let n = 1_000_000;
        let lines: Vec<LineError> = (0..n)
            .map(|k| {
                let f = 1.0 + 399.0 * k as f64 / (n - 1) as f64;
                let ripple = if k % 2 == 0 { 1.0 } else { -1.0 };
                LineError { frequency_hz: f, rms_db: 3.0 + ripple, rms_phase_deg: 10.0 + ripple, log_misfit: 0.1 }
            })
            .collect();
        let curves = [ErrorCurve { label: "model".into(), colour: UPDATED, lines: &lines }];
        let svg = error_vs_frequency("errors", &curves, &[], axes::FrequencyScale::Linear, None).unwrap();
        let drawn = polylines(&svg, "stroke-width=\"2\"");
        // dB and phase
        assert_eq!(drawn.iter().filter(|l| l.len() > 2).count(), 2);
        for line in &drawn {
            assert!(most_per_column(line) <= 4, "{} points in a pixel column", most_per_column(line));
        }
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
}

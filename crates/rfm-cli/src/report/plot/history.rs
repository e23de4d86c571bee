//! The figures of an iteration: the misfit per iteration and the value of
//! every parameter per iteration.

use plotters::prelude::*;

use super::{
    AXIS, Area, Dash, HouseStyle, INITIAL, LegendEntry, LogAxis, Look, Mark, PlotError, UPDATED, draw_line, frame,
    log_range, log_tick, look, svg,
};

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
        legend.push(LegendEntry::new("RMS dB error over the measured band", INITIAL, Mark::Line(2)));
    }
    let n = residual.len().max(all_lines_db.map_or(0, <[f64]>::len)).max(2);
    let panels: Vec<(&str, RGBColor, &[f64])> = std::iter::once((residual_label, UPDATED, residual))
        .chain(all_lines_db.map(|d| ("RMS dB error over the band", INITIAL, d)))
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
                .house_style(13, 15)
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
            let pts = per_iteration(values);
            chart.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?;
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))?;
        }
        Ok(())
    })
}

/// A full-width chart against the iteration (or step) number, with the
/// margins and label areas the iteration figures share.
pub(super) fn iteration_chart<'a, 'b, 'c>(area: &'a Area<'c>) -> ChartBuilder<'a, 'b, SVGBackend<'c>> {
    let mut builder = ChartBuilder::on(area);
    builder.margin_left(12).margin_right(24).margin_top(8).x_label_area_size(44).y_label_area_size(72);
    builder
}

/// The finite positive values of a series as `(iteration, value)`, for a
/// logarithmic axis: a value that is not is left out, not drawn at zero.
pub(super) fn per_iteration(values: &[f64]) -> Vec<(f64, f64)> {
    values.iter().enumerate().filter(|(_, v)| v.is_finite() && **v > 0.0).map(|(i, &v)| (i as f64, v)).collect()
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
        let mut chart = iteration_chart(&body).build_cartesian_2d(-0.3..x1, LogAxis { lo: y0, hi: y1 })?;
        chart
            .configure_mesh()
            .x_desc("Iteration")
            .y_desc("Value / initial value")
            .house_style(13, 15)
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
    use super::super::{PALETTE, look};
    use super::*;

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
}

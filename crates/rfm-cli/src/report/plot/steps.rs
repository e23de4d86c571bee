//! The misfit after each step of the loop (`rfm fix`) against the noise.

use plotters::prelude::*;

use super::{HouseStyle, LegendEntry, LogAxis, Mark, PlotError, UPDATED, frame, log_range, log_tick, svg};

/// Shade of the band where a misfit is consistent with the noise.
const NOISE_SHADE: RGBColor = RGBColor(226, 240, 226);
/// Colour of the noise level.
const NOISE: RGBColor = RGBColor(0, 128, 64);

/// The misfit of each stage (`labels[i]`, `misfits[i]`; short labels on the
/// axis, the caption says what they are), as dots joined in order on a
/// logarithmic axis, over the band from the noise level to `consistent`
/// times it.
pub(crate) fn misfit_steps(
    labels: &[String],
    misfits: &[f64],
    noise: f64,
    consistent: f64,
) -> Result<String, PlotError> {
    let title = "Misfit after each step";
    let legend = vec![
        LegendEntry {
            label: "misfit (RMS of |ln(model/measured)| per complex value)".into(),
            colour: UPDATED,
            mark: Mark::Line(2),
        },
        LegendEntry { label: format!("noise level to {consistent} times it"), colour: NOISE_SHADE, mark: Mark::Shade },
    ];
    let n = misfits.len().max(2);
    let (y0, y1) = log_range(misfits.iter().copied().chain([noise, consistent * noise]));
    svg(title, 420, |root| {
        let body = frame(root, title, &legend)?;
        let mut chart = super::history::iteration_chart(&body)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), LogAxis { lo: y0, hi: y1 })?;
        chart
            .configure_mesh()
            .y_desc("misfit")
            .x_desc("step")
            .house_style(13, 15)
            .x_labels(n)
            .x_label_formatter(&|v| {
                let i = v.round();
                if (v - i).abs() < 1e-6 && i >= 0.0 {
                    labels.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&log_tick)
            .draw()?;
        if noise > 0.0 {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(-0.5, noise.max(y0)), (n as f64 - 0.5, (consistent * noise).min(y1))],
                NOISE_SHADE.filled(),
            )))?;
            chart.draw_series(LineSeries::new([(-0.5, noise), (n as f64 - 0.5, noise)], NOISE.stroke_width(1)))?;
        }
        let pts = super::history::per_iteration(misfits);
        chart.draw_series(LineSeries::new(pts.clone(), UPDATED.stroke_width(1)))?;
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 5, UPDATED.filled())))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_step_figure_is_valid_svg_with_every_label() {
        let labels: Vec<String> = ["nominal", "+1", "updated 1"].iter().map(|s| s.to_string()).collect();
        let svg = misfit_steps(&labels, &[1.4, 0.0101, 0.00998], 0.011, 1.5).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for l in &labels {
            assert!(super::super::has_text(&svg, l), "label {l} missing");
        }
    }
}

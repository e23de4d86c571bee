//! The updating lines of a study: the case's choice of measured lines, or
//! the method's default.

use fe_model::case::FrequencyChoice;

use super::{Method, Study};
use crate::error::UpdateError;
use crate::freqsel;

impl Study {
    /// Updating lines for a method: the case's choice, else the method's
    /// default (RFM: points away from resonances, two per parameter and at
    /// least ten; output-error: 200 lines spread over the band).
    pub fn lines_for(&self, method: Method) -> Result<Vec<f64>, UpdateError> {
        let given = self.case.update.as_ref().and_then(|u| u.frequencies.clone());
        let choice = given.unwrap_or(match method {
            Method::Rfm => FrequencyChoice::Auto(2 * self.parameters.len().max(5)),
            Method::OutputError => FrequencyChoice::Lines(200),
        });
        let lines = self.choose_lines(&choice)?;
        if lines.is_empty() {
            return Err(UpdateError::Lines(format!(
                "no measured line to fit: the [update] frequencies designate none of the {} measured lines",
                self.measured.n_freq()
            )));
        }
        Ok(lines)
    }

    /// `lines` without those where the initial model's dynamic stiffness is
    /// singular (a lightly damped or undamped model evaluated on its own
    /// resonance: no receptance exists there to compare with), and a note
    /// that says which were left out and why; refused when every line is.
    pub fn regular_lines(&self, lines: Vec<f64>) -> Result<(Vec<f64>, Option<String>), UpdateError> {
        let channels = self.measured.channels();
        let (_, singular) = frf::synthesize_regular(&self.system, &channels[..channels.len().min(1)], &lines)?;
        if singular.is_empty() {
            return Ok((lines, None));
        }
        let kept: Vec<f64> = lines.iter().copied().filter(|f| !singular.contains(f)).collect();
        let list = singular.iter().map(|f| format!("{f} Hz")).collect::<Vec<_>>().join(", ");
        if kept.is_empty() {
            return Err(UpdateError::Numerics(format!(
                "the initial model's dynamic stiffness is singular at every updating line ({list})"
            )));
        }
        Ok((
            kept,
            Some(format!(
                "{} updating line(s) left out, where the initial model's dynamic stiffness is singular (an undamped \
                 mode on the line): {list}",
                singular.len()
            )),
        ))
    }

    /// The measured lines a frequency choice designates.
    pub fn choose_lines(&self, choice: &FrequencyChoice) -> Result<Vec<f64>, UpdateError> {
        let lines = self.measured.frequencies_hz();
        Ok(match choice {
            FrequencyChoice::All => lines.to_vec(),
            FrequencyChoice::Lines(n) => {
                let n = (*n).min(lines.len());
                if n == lines.len() {
                    lines.to_vec()
                } else {
                    // evenly spread, first and last included
                    let mut idx: Vec<usize> = (0..n)
                        .map(|i| (i as f64 * (lines.len() - 1) as f64 / (n - 1).max(1) as f64).round() as usize)
                        .collect();
                    idx.dedup();
                    idx.iter().map(|&k| lines[k]).collect()
                }
            }
            FrequencyChoice::List(points) => {
                for &p in points {
                    if self.measured.line_of(p).is_none() {
                        return Err(UpdateError::Lines(format!(
                            "updating point {p} Hz is not a line of the measured data"
                        )));
                    }
                }
                points.clone()
            }
            FrequencyChoice::Auto(n) => {
                let model = frf::synthesize(&self.system, self.measured.channels(), lines)?;
                let mut avoid = freqsel::features(&model);
                avoid.extend(freqsel::features(&self.measured));
                freqsel::choose(lines, &avoid, *n)
            }
        })
    }
}

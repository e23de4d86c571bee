//! The JSON form of a correlation (feature `serde`), the one `rfm compare
//! --json` prints and `compare.json` holds.
//!
//! The result types keep what the numerics need (a [`crate::Channel`], the
//! largest error with its line as a pair, a [`super::Band`]); the JSON names
//! what a reader looks for: the channel as text with its response and
//! reference, the largest error and its line as two numbers, the band's
//! label beside its edges, the worst channels and bands by name. The
//! private views below hold that form, so that the shape is written down
//! once, here. [`Totals`] and [`super::LineError`] derive theirs (their
//! fields are the JSON's).

use serde::{Serialize, Serializer};

use super::{BandCorrelation, ChannelCorrelation, Correlation, Totals};

/// Channels listed as the worst, by name.
const WORST_CHANNELS: usize = 5;
/// Bands listed as the worst, by label.
const WORST_BANDS: usize = 3;

#[derive(Serialize)]
struct CorrelationView<'a> {
    kind: String,
    lines: usize,
    frequency_range_hz: [f64; 2],
    total: &'a Totals,
    channels: &'a [ChannelCorrelation],
    bands: &'a [BandCorrelation],
    worst_channels: Vec<String>,
    worst_bands: Vec<String>,
}

impl Serialize for Correlation {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let f = self.frequencies_hz();
        CorrelationView {
            kind: self.kind().to_string(),
            lines: f.len(),
            frequency_range_hz: [f.first().copied().unwrap_or(f64::NAN), f.last().copied().unwrap_or(f64::NAN)],
            total: &self.total,
            channels: &self.channels,
            bands: &self.bands,
            worst_channels: self
                .worst_channels(WORST_CHANNELS)
                .into_iter()
                .map(|i| self.channels[i].channel.to_string())
                .collect(),
            worst_bands: self.worst_bands(WORST_BANDS).into_iter().map(|i| self.bands[i].band.label()).collect(),
        }
        .serialize(s)
    }
}

#[derive(Serialize)]
struct ChannelView {
    channel: String,
    response: String,
    reference: String,
    rms_db: f64,
    mean_db: f64,
    max_abs_db: f64,
    max_abs_db_at_hz: f64,
    rms_phase_deg: f64,
    frac: f64,
    log_misfit: f64,
    share: f64,
    lines_used: usize,
}

impl Serialize for ChannelCorrelation {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        ChannelView {
            channel: self.channel.to_string(),
            response: self.channel.response.to_string(),
            reference: self.channel.reference.to_string(),
            rms_db: self.rms_db,
            mean_db: self.mean_db,
            max_abs_db: self.max_abs_db.0,
            max_abs_db_at_hz: self.max_abs_db.1,
            rms_phase_deg: self.rms_phase_deg,
            frac: self.frac,
            log_misfit: self.log_misfit,
            share: self.share,
            lines_used: self.lines_used,
        }
        .serialize(s)
    }
}

#[derive(Serialize)]
struct BandView {
    label: String,
    lo_hz: f64,
    hi_hz: f64,
    resonance_hz: Option<f64>,
    lines: usize,
    rms_db: f64,
    mean_db: f64,
    rms_phase_deg: f64,
    log_misfit: f64,
    share: f64,
}

impl Serialize for BandCorrelation {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        BandView {
            label: self.band.label(),
            lo_hz: self.band.lo_hz,
            hi_hz: self.band.hi_hz,
            resonance_hz: self.band.resonance_hz,
            lines: self.lines,
            rms_db: self.rms_db,
            mean_db: self.mean_db,
            rms_phase_deg: self.rms_phase_deg,
            log_misfit: self.log_misfit,
            share: self.share,
        }
        .serialize(s)
    }
}

#[cfg(test)]
mod tests {
    use num_complex::Complex64 as C64;
    use serde_json::{Value, json};

    use super::super::tests::{measured, scaled};
    use super::super::{BandSpec, correlate};

    /// The keys of a JSON object in the order written (`serde_json`'s
    /// `Value` sorts them, so the text is read instead).
    fn keys<T: serde::Serialize>(value: &T) -> Vec<String> {
        let text = serde_json::to_string(value).unwrap();
        let (mut depth, mut in_string, mut escaped, mut start) = (0, false, false, 0);
        let mut keys = Vec::new();
        for (i, c) in text.char_indices() {
            if in_string {
                match c {
                    _ if escaped => escaped = false,
                    '\\' => escaped = true,
                    '"' => {
                        in_string = false;
                        if depth == 1 && text[i + 1..].starts_with(':') {
                            keys.push(text[start..i].to_string());
                        }
                    }
                    _ => {}
                }
                continue;
            }
            match c {
                '"' => (in_string, start) = (true, i + 1),
                '{' | '[' => depth += 1,
                '}' | ']' => depth -= 1,
                _ => {}
            }
        }
        keys
    }

    #[test]
    fn the_json_keeps_the_keys_and_order_of_compare_json() {
        // the model is 2x too high below 50 Hz and exact above
        let x = measured();
        let mut a = x.clone();
        for c in 0..x.channels().len() {
            for k in 0..x.n_freq() {
                if x.frequencies_hz()[k] < 50.0 {
                    a.set(c, k, x.get(c, k) * 2.0);
                }
            }
        }
        let r = correlate(&x, &a, &BandSpec::Edges(vec![0.0, 50.0, 100.0])).unwrap();
        assert_eq!(
            keys(&r),
            ["kind", "lines", "frequency_range_hz", "total", "channels", "bands", "worst_channels", "worst_bands"]
        );
        assert_eq!(
            keys(&r.total),
            [
                "rms_db",
                "mean_db",
                "rms_phase_deg",
                "log_misfit",
                "relative_residual",
                "mean_frac",
                "min_frac",
                "values_used",
                "values_excluded"
            ]
        );
        assert_eq!(
            keys(&r.channels[0]),
            [
                "channel",
                "response",
                "reference",
                "rms_db",
                "mean_db",
                "max_abs_db",
                "max_abs_db_at_hz",
                "rms_phase_deg",
                "frac",
                "log_misfit",
                "share",
                "lines_used"
            ]
        );
        assert_eq!(
            keys(&r.bands[0]),
            [
                "label",
                "lo_hz",
                "hi_hz",
                "resonance_hz",
                "lines",
                "rms_db",
                "mean_db",
                "rms_phase_deg",
                "log_misfit",
                "share"
            ]
        );

        let v = serde_json::to_value(&r).unwrap();
        assert_eq!(v["kind"], "receptance");
        assert_eq!(v["lines"], 40);
        assert_eq!(v["frequency_range_hz"], json!([2.5, 100.0]));
        assert_eq!(v["total"]["rms_db"], r.total.rms_db);
        assert_eq!(v["total"]["values_excluded"], 0);
        let c = &r.channels[1];
        assert_eq!(v["channels"][1]["channel"], c.channel.to_string());
        assert_eq!(v["channels"][1]["response"], c.channel.response.to_string());
        assert_eq!(v["channels"][1]["reference"], c.channel.reference.to_string());
        assert_eq!(v["channels"][1]["max_abs_db"], c.max_abs_db.0);
        assert_eq!(v["channels"][1]["max_abs_db_at_hz"], c.max_abs_db.1);
        assert_eq!(v["bands"][0]["label"], "0-50 Hz");
        assert_eq!(v["bands"][0]["resonance_hz"], Value::Null);
        assert_eq!(v["bands"][1]["lines"], 21);
        let worst: Vec<String> = r.worst_channels(5).iter().map(|&i| r.channels[i].channel.to_string()).collect();
        assert_eq!(v["worst_channels"], json!(worst));
        assert_eq!(v["worst_bands"], json!(["0-50 Hz", "50-100 Hz"]));
    }

    #[test]
    fn a_measure_over_no_lines_is_null() {
        // a model that is zero on channel 0 leaves that channel no line
        let x = measured();
        let mut a = scaled(&x, C64::new(2.0, 0.0));
        for v in a.channel_mut(0) {
            *v = C64::new(0.0, 0.0);
        }
        let r = correlate(&x, &a, &BandSpec::Auto).unwrap();
        assert!(r.channels[0].rms_db.is_nan() && r.channels[0].log_misfit.is_nan());
        let v = serde_json::to_value(&r).unwrap();
        let c = &v["channels"][0];
        assert_eq!(c["lines_used"], 0);
        for key in ["rms_db", "mean_db", "rms_phase_deg", "log_misfit"] {
            assert_eq!(c[key], Value::Null, "{key}");
        }
        assert_eq!(v["total"]["values_excluded"], 40);
        // a channel without a misfit is never among the worst
        assert!(!v["worst_channels"].as_array().unwrap().contains(&json!(r.channels[0].channel.to_string())));
    }
}

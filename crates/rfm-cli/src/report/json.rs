//! The JSON form of an FRF correlation (for `--json` and `compare.json`):
//! the same numbers as [`frf::correlation::Correlation`], NaN written as `null`.

use frf::correlation::Correlation;
use serde::Serialize;

/// Totals over all channels and lines.
#[derive(Serialize)]
pub(crate) struct TotalsJson {
    rms_db: f64,
    mean_db: f64,
    rms_phase_deg: f64,
    log_misfit: f64,
    relative_residual: f64,
    mean_frac: f64,
    min_frac: f64,
    values_used: usize,
    values_excluded: usize,
}

/// One channel.
#[derive(Serialize)]
pub(crate) struct ChannelJson {
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

/// One band.
#[derive(Serialize)]
pub(crate) struct BandJson {
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

/// A whole correlation.
#[derive(Serialize)]
pub(crate) struct CorrelationJson {
    kind: String,
    lines: usize,
    frequency_range_hz: [f64; 2],
    total: TotalsJson,
    channels: Vec<ChannelJson>,
    bands: Vec<BandJson>,
    /// Channel names, worst first (at most 5).
    worst_channels: Vec<String>,
    /// Band labels, worst first (at most 3).
    worst_bands: Vec<String>,
}

impl From<&Correlation> for CorrelationJson {
    fn from(c: &Correlation) -> Self {
        let t = &c.total;
        let f = c.frequencies_hz();
        CorrelationJson {
            kind: c.kind().to_string(),
            lines: f.len(),
            frequency_range_hz: [f.first().copied().unwrap_or(f64::NAN), f.last().copied().unwrap_or(f64::NAN)],
            total: TotalsJson {
                rms_db: t.rms_db,
                mean_db: t.mean_db,
                rms_phase_deg: t.rms_phase_deg,
                log_misfit: t.log_misfit,
                relative_residual: t.relative_residual,
                mean_frac: t.mean_frac,
                min_frac: t.min_frac,
                values_used: t.values_used,
                values_excluded: t.lines_excluded,
            },
            channels: c
                .channels
                .iter()
                .map(|ch| ChannelJson {
                    channel: ch.channel.to_string(),
                    response: ch.channel.response.to_string(),
                    reference: ch.channel.reference.to_string(),
                    rms_db: ch.rms_db,
                    mean_db: ch.mean_db,
                    max_abs_db: ch.max_abs_db.0,
                    max_abs_db_at_hz: ch.max_abs_db.1,
                    rms_phase_deg: ch.rms_phase_deg,
                    frac: ch.frac,
                    log_misfit: ch.log_misfit,
                    share: ch.share,
                    lines_used: ch.lines_used,
                })
                .collect(),
            bands: c
                .bands
                .iter()
                .map(|b| BandJson {
                    label: b.band.label(),
                    lo_hz: b.band.lo_hz,
                    hi_hz: b.band.hi_hz,
                    resonance_hz: b.band.resonance_hz,
                    lines: b.lines,
                    rms_db: b.rms_db,
                    mean_db: b.mean_db,
                    rms_phase_deg: b.rms_phase_deg,
                    log_misfit: b.log_misfit,
                    share: b.share,
                })
                .collect(),
            worst_channels: c.worst_channels(5).into_iter().map(|i| c.channels[i].channel.to_string()).collect(),
            worst_bands: c.worst_bands(3).into_iter().map(|i| c.bands[i].band.label()).collect(),
        }
    }
}

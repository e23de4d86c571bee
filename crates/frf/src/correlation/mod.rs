//! FRF-level correlation of a model with measurements: where, and by how
//! much, the model's FRFs miss the measured ones.
//!
//! [`correlate`] takes a measured and a model [`FrfSet`] on the same lines
//! and channels and returns a [`Correlation`]: per-channel, per-line and
//! per-band error measures, the worst channels and bands, and totals. The
//! model set is matched to the measured one by channel (any order) and
//! converted to the measured set's [`FrfKind`] first, so that every number
//! refers to what was measured.
//!
//! # Formulas
//!
//! For channel `c` at line `k`, with measured value `X = X_c(f_k)` and model
//! value `A = A_c(f_k)`:
//!
//! ```text
//! log-magnitude error   e_dB  = 20 log10(|A| / |X|)                        (dB)
//! phase error           e_ph  = arg(A conj(X))  in (-180, 180]             (degrees)
//! complex-log error     e_ln  = ln(A / X) = ln(|A|/|X|) + j e_ph(rad)
//! ```
//!
//! `e_ph` is the phase difference wrapped to one turn, so that a model at
//! `-170` degrees and a measurement at `170` degrees differ by `20` degrees,
//! not `-340`. `|e_ln|^2 = (e_dB ln(10)/20)^2 + e_ph(rad)^2` combines the
//! magnitude error (in nepers: 1 Np = 8.686 dB) and the phase error (in
//! radians: 1 rad = 57.3 degrees) into one dimensionless number that is the
//! same for a factor `q` too high or too low, and does not let the largest
//! peaks dominate as a linear difference would.
//!
//! Over a set of lines `K` (a channel's lines, a band, all lines):
//!
//! ```text
//! RMS dB error        sqrt( mean_K e_dB^2 )
//! mean dB error       mean_K e_dB          (a uniform gain error shows here)
//! RMS phase error     sqrt( mean_K e_ph^2 )
//! log misfit          sqrt( mean_K |e_ln|^2 )
//! share               sum_K |e_ln|^2 / sum_all |e_ln|^2
//! ```
//!
//! Per channel, the frequency response assurance criterion
//!
//! ```text
//! FRAC_c = |sum_k conj(X_k) A_k|^2 / ( sum_k |X_k|^2  sum_k |A_k|^2 )
//! ```
//!
//! lies in `[0, 1]`; it is `1` when the model's FRF is the measured one times
//! any complex constant (shape agrees, level may not) and falls when peaks
//! are shifted or reshaped. Being a sum of products, it is dominated by the
//! lines of largest response (the resonances) and depends on the FRF kind.
//!
//! The total relative residual `sqrt( sum |A - X|^2 / sum |X|^2 )` over all
//! channels and lines is the measure the response function method's
//! iteration reports, given here so that both can be compared.
//!
//! Lines where either value is zero or not finite have no logarithm; they
//! are left out of every measure (their per-line errors are NaN) and counted
//! in [`Totals::lines_excluded`].
//!
//! # Bands
//!
//! [`BandSpec`] chooses the bands: given edges, fractional-octave bands
//! (base-2, centred on 1 kHz, as in acoustics), or one band around each
//! resonance of the measured data ([`resonances`]: peaks of the summed
//! magnitude), with edges at the geometric means between neighbouring
//! resonances, so that each band holds one mode and the misfit can be read
//! per mode region. A line belongs to the band `[lo, hi)` (the last band
//! includes its upper edge).
//!
//! The measures of one value or one FRF are in `measure.rs`, the bands in
//! `band.rs`; this file holds the result types and [`correlate`].
//!
//! # JSON
//!
//! With the `serde` feature, [`Correlation`] and its parts implement
//! `Serialize` (`json.rs`): the kind, the number of lines and their range,
//! the totals, every channel and band with its label, and the worst five
//! channels and three bands by name; not the per-line errors. A number
//! that is not finite (a measure over no lines) is written by `serde_json`
//! as `null`.

use num_complex::Complex64 as C64;

use crate::error::{FrfError, MismatchError};
use crate::set::{Channel, FrfKind, FrfSet};

mod band;
#[cfg(feature = "serde")]
mod json;
mod measure;

pub use band::{Band, BandSpec, bands, resonances};
pub use measure::{db_error, frac, phase_error_deg};

/// Error measures of one channel over all lines (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelCorrelation {
    /// The channel.
    pub channel: Channel,
    /// RMS log-magnitude error (dB).
    pub rms_db: f64,
    /// Mean log-magnitude error (dB): positive when the model is too high.
    pub mean_db: f64,
    /// Largest absolute log-magnitude error (dB) and the line where it occurs (Hz).
    pub max_abs_db: (f64, f64),
    /// RMS wrapped phase error (degrees).
    pub rms_phase_deg: f64,
    /// Frequency response assurance criterion, in `[0, 1]`.
    pub frac: f64,
    /// RMS complex-log error (dimensionless).
    pub log_misfit: f64,
    /// This channel's fraction of the total squared complex-log error.
    pub share: f64,
    /// Lines used (finite, non-zero values in both sets).
    pub lines_used: usize,
}

/// Error measures of one band over all channels.
#[derive(Clone, Debug, PartialEq)]
pub struct BandCorrelation {
    /// The band.
    pub band: Band,
    /// Lines of the data inside the band.
    pub lines: usize,
    /// RMS log-magnitude error (dB).
    pub rms_db: f64,
    /// Mean log-magnitude error (dB).
    pub mean_db: f64,
    /// RMS wrapped phase error (degrees).
    pub rms_phase_deg: f64,
    /// RMS complex-log error.
    pub log_misfit: f64,
    /// The band's fraction of the total squared complex-log error.
    pub share: f64,
}

/// Error measures at one line over all channels (for error-versus-frequency plots).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LineError {
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// RMS over channels of the log-magnitude error (dB).
    pub rms_db: f64,
    /// RMS over channels of the wrapped phase error (degrees).
    pub rms_phase_deg: f64,
    /// RMS over channels of the complex-log error.
    pub log_misfit: f64,
}

/// Error measures over all channels and lines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Totals {
    /// RMS log-magnitude error (dB).
    pub rms_db: f64,
    /// Mean log-magnitude error (dB).
    pub mean_db: f64,
    /// RMS wrapped phase error (degrees).
    pub rms_phase_deg: f64,
    /// RMS complex-log error: the total misfit.
    pub log_misfit: f64,
    /// `sqrt(sum |A - X|^2 / sum |X|^2)`, the response function method's residual.
    pub relative_residual: f64,
    /// Mean FRAC over channels.
    pub mean_frac: f64,
    /// Smallest FRAC over channels.
    pub min_frac: f64,
    /// (channel, line) pairs used.
    pub values_used: usize,
    /// (channel, line) pairs left out (zero or non-finite values).
    #[cfg_attr(feature = "serde", serde(rename = "values_excluded"))]
    pub lines_excluded: usize,
}

/// The correlation of a model's FRFs with measured ones (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Correlation {
    frequencies_hz: Vec<f64>,
    kind: FrfKind,
    /// Per channel, in the measured set's channel order.
    pub channels: Vec<ChannelCorrelation>,
    /// Per line, over all channels.
    pub lines: Vec<LineError>,
    /// Per band, over all channels, in frequency order.
    pub bands: Vec<BandCorrelation>,
    /// Over everything.
    pub total: Totals,
    /// Channel-major `e_dB`, NaN where left out.
    db_error: Vec<f64>,
    /// Channel-major `e_ph` (degrees), NaN where left out.
    phase_error_deg: Vec<f64>,
}

impl Correlation {
    /// Frequency lines (Hz).
    pub fn frequencies_hz(&self) -> &[f64] {
        &self.frequencies_hz
    }

    /// The FRF kind both sets were compared in (the measured set's).
    pub fn kind(&self) -> FrfKind {
        self.kind
    }

    /// Log-magnitude error `e_dB` of channel `c` per line (NaN where left out).
    pub fn db_error(&self, c: usize) -> &[f64] {
        let nf = self.frequencies_hz.len();
        &self.db_error[c * nf..(c + 1) * nf]
    }

    /// Wrapped phase error `e_ph` (degrees) of channel `c` per line (NaN where left out).
    pub fn phase_error_deg(&self, c: usize) -> &[f64] {
        let nf = self.frequencies_hz.len();
        &self.phase_error_deg[c * nf..(c + 1) * nf]
    }

    /// Indices of the `n` channels with the largest log misfit, worst first.
    pub fn worst_channels(&self, n: usize) -> Vec<usize> {
        worst(self.channels.iter().map(|c| c.log_misfit), n)
    }

    /// Indices of the `n` bands with the largest log misfit, worst first
    /// (bands without lines are never listed).
    pub fn worst_bands(&self, n: usize) -> Vec<usize> {
        worst(self.bands.iter().map(|b| if b.lines == 0 { f64::NAN } else { b.log_misfit }), n)
    }
}

fn worst(values: impl Iterator<Item = f64>, n: usize) -> Vec<usize> {
    let mut idx: Vec<(usize, f64)> = values.enumerate().filter(|(_, v)| v.is_finite()).collect();
    idx.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    idx.into_iter().take(n).map(|(i, _)| i).collect()
}

/// Sums of squares over a set of (channel, line) values.
#[derive(Clone, Copy, Default)]
struct Acc {
    n: usize,
    db: f64,
    db2: f64,
    ph2: f64,
    ln2: f64,
}

impl Acc {
    fn add(&mut self, e_db: f64, e_ph_deg: f64) {
        let ln_mag = e_db * std::f64::consts::LN_10 / 20.0;
        let ph = e_ph_deg.to_radians();
        self.n += 1;
        self.db += e_db;
        self.db2 += e_db * e_db;
        self.ph2 += e_ph_deg * e_ph_deg;
        self.ln2 += ln_mag * ln_mag + ph * ph;
    }

    fn rms(sum: f64, n: usize) -> f64 {
        if n == 0 { f64::NAN } else { (sum / n as f64).sqrt() }
    }

    fn rms_db(&self) -> f64 {
        Self::rms(self.db2, self.n)
    }

    fn mean_db(&self) -> f64 {
        if self.n == 0 { f64::NAN } else { self.db / self.n as f64 }
    }

    fn rms_phase(&self) -> f64 {
        Self::rms(self.ph2, self.n)
    }

    fn log_misfit(&self) -> f64 {
        Self::rms(self.ln2, self.n)
    }
}

/// Correlates a model's FRFs with measured ones (see the module docs).
///
/// The model set must hold every measured channel (in any order; extra
/// channels are ignored) on the same lines (to 1e-6 relative); it is
/// converted to the measured set's kind.
pub fn correlate(measured: &FrfSet, model: &FrfSet, spec: &BandSpec) -> Result<Correlation, FrfError> {
    let f = measured.frequencies_hz();
    let nf = f.len();
    if model.n_freq() != nf
        || model.frequencies_hz().iter().zip(f).any(|(a, b)| (a - b).abs() > 1e-6 * b.abs().max(1e-12))
    {
        return Err(MismatchError::LinesDiffer { model: model.n_freq(), measured: nf }.into());
    }
    let model = if model.kind() == measured.kind() { model.clone() } else { model.converted(measured.kind()) };
    let index = model.channel_indices();
    let idx: Vec<usize> = measured
        .channels()
        .iter()
        .map(|c| index.get(c).copied().ok_or(FrfError::Mismatch(MismatchError::MissingChannel { channel: *c })))
        .collect::<Result<_, _>>()?;
    let bands = bands(spec, measured)?;
    let n_ch = measured.channels().len();

    let mut db_err = vec![f64::NAN; n_ch * nf];
    let mut ph_err = vec![f64::NAN; n_ch * nf];
    let mut per_channel = vec![Acc::default(); n_ch];
    let mut per_line = vec![Acc::default(); nf];
    let mut total = Acc::default();
    let (mut diff2, mut meas2) = (0.0, 0.0);
    let mut fracs = Vec::with_capacity(n_ch);
    let mut max_abs = vec![(0.0f64, f64::NAN); n_ch];
    for (c, &mc) in idx.iter().enumerate() {
        let x = measured.channel(c);
        let a = model.channel(mc);
        let mut used_x = Vec::with_capacity(nf);
        let mut used_a = Vec::with_capacity(nf);
        for k in 0..nf {
            let ok = |v: C64| v.re.is_finite() && v.im.is_finite() && v.norm() > 0.0;
            if !(ok(x[k]) && ok(a[k])) {
                continue;
            }
            let e_db = db_error(a[k], x[k]);
            let e_ph = phase_error_deg(a[k], x[k]);
            db_err[c * nf + k] = e_db;
            ph_err[c * nf + k] = e_ph;
            per_channel[c].add(e_db, e_ph);
            per_line[k].add(e_db, e_ph);
            total.add(e_db, e_ph);
            if e_db.abs() > max_abs[c].0 || max_abs[c].1.is_nan() {
                max_abs[c] = (e_db.abs(), f[k]);
            }
            diff2 += (a[k] - x[k]).norm_sqr();
            meas2 += x[k].norm_sqr();
            used_x.push(x[k]);
            used_a.push(a[k]);
        }
        fracs.push(frac(&used_x, &used_a));
    }
    let share = |ln2: f64| if total.ln2 > 0.0 { ln2 / total.ln2 } else { 0.0 };

    let channels = (0..n_ch)
        .map(|c| {
            let acc = &per_channel[c];
            ChannelCorrelation {
                channel: measured.channels()[c],
                rms_db: acc.rms_db(),
                mean_db: acc.mean_db(),
                max_abs_db: max_abs[c],
                rms_phase_deg: acc.rms_phase(),
                frac: fracs[c],
                log_misfit: acc.log_misfit(),
                share: share(acc.ln2),
                lines_used: acc.n,
            }
        })
        .collect();
    let lines = (0..nf)
        .map(|k| LineError {
            frequency_hz: f[k],
            rms_db: per_line[k].rms_db(),
            rms_phase_deg: per_line[k].rms_phase(),
            log_misfit: per_line[k].log_misfit(),
        })
        .collect();
    let last = bands.len().saturating_sub(1);
    let bands = bands
        .into_iter()
        .enumerate()
        .map(|(i, band)| {
            let mut acc = Acc::default();
            let mut lines = 0;
            for k in 0..nf {
                let inside = f[k] >= band.lo_hz && (f[k] < band.hi_hz || (i == last && f[k] <= band.hi_hz));
                if !inside {
                    continue;
                }
                lines += 1;
                for c in 0..n_ch {
                    let e_db = db_err[c * nf + k];
                    if e_db.is_finite() {
                        acc.add(e_db, ph_err[c * nf + k]);
                    }
                }
            }
            BandCorrelation {
                band,
                lines,
                rms_db: acc.rms_db(),
                mean_db: acc.mean_db(),
                rms_phase_deg: acc.rms_phase(),
                log_misfit: acc.log_misfit(),
                share: share(acc.ln2),
            }
        })
        .collect();
    let finite_fracs: Vec<f64> = fracs.iter().copied().filter(|v| v.is_finite()).collect();
    let totals = Totals {
        rms_db: total.rms_db(),
        mean_db: total.mean_db(),
        rms_phase_deg: total.rms_phase(),
        log_misfit: total.log_misfit(),
        relative_residual: if meas2 > 0.0 { (diff2 / meas2).sqrt() } else { f64::NAN },
        mean_frac: if finite_fracs.is_empty() {
            f64::NAN
        } else {
            finite_fracs.iter().sum::<f64>() / finite_fracs.len() as f64
        },
        min_frac: finite_fracs.iter().copied().fold(f64::NAN, f64::min),
        values_used: total.n,
        lines_excluded: n_ch * nf - total.n,
    };
    Ok(Correlation {
        frequencies_hz: f.to_vec(),
        kind: measured.kind(),
        channels,
        lines,
        bands,
        total: totals,
        db_error: db_err,
        phase_error_deg: ph_err,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, DofRef};

    pub(super) fn set(freqs: &[f64], channels: &[Channel], values: impl Fn(usize, usize) -> C64) -> FrfSet {
        let mut s = FrfSet::zeros(freqs.to_vec(), channels.to_vec(), FrfKind::Receptance).unwrap();
        for c in 0..channels.len() {
            for k in 0..freqs.len() {
                s.set(c, k, values(c, k));
            }
        }
        s
    }

    pub(super) fn ch(n: u32) -> Channel {
        Channel::new(DofRef::new(n, Dof::Uy), DofRef::new(5, Dof::Uy))
    }

    /// A measured set with varied magnitudes and phases, so that a constant
    /// ratio is not trivially satisfied by constant data.
    pub(super) fn measured() -> FrfSet {
        let f: Vec<f64> = (1..=40).map(|k| 2.5 * k as f64).collect();
        set(&f, &[ch(2), ch(3), ch(5)], |c, k| C64::from_polar(1e-4 / (1.0 + k as f64 + c as f64), 0.3 * k as f64))
    }

    pub(super) fn scaled(x: &FrfSet, q: C64) -> FrfSet {
        let mut a = x.clone();
        for c in 0..x.channels().len() {
            for v in a.channel_mut(c) {
                *v *= q;
            }
        }
        a
    }

    #[test]
    fn twice_the_magnitude_is_6_0206_db_with_no_phase_error() {
        let x = measured();
        let r = correlate(&x, &scaled(&x, C64::new(2.0, 0.0)), &BandSpec::Auto).unwrap();
        for c in &r.channels {
            assert!((c.rms_db - 6.0206).abs() < 1e-4, "{}", c.rms_db);
            assert!((c.mean_db - 6.0206).abs() < 1e-4);
            assert!(c.rms_phase_deg < 1e-9);
            assert!((c.frac - 1.0).abs() < 1e-12);
            assert!((c.log_misfit - 2f64.ln()).abs() < 1e-12);
        }
        assert!((r.total.relative_residual - 1.0).abs() < 1e-12);
        assert!((r.total.rms_db - 6.0206).abs() < 1e-4);
        // half the magnitude is the same error with the opposite sign
        let r = correlate(&x, &scaled(&x, C64::new(0.5, 0.0)), &BandSpec::Auto).unwrap();
        assert!((r.total.mean_db + 6.0206).abs() < 1e-4);
        assert!((r.total.log_misfit - 2f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn a_quarter_turn_is_90_degrees_with_no_magnitude_error() {
        let x = measured();
        let r = correlate(&x, &scaled(&x, C64::new(0.0, 1.0)), &BandSpec::Auto).unwrap();
        assert!((r.total.rms_phase_deg - 90.0).abs() < 1e-9);
        assert!(r.total.rms_db.abs() < 1e-12);
        assert!((r.total.log_misfit - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((r.total.relative_residual - 2f64.sqrt()).abs() < 1e-12);
        assert!((r.total.min_frac - 1.0).abs() < 1e-12, "FRAC ignores a constant complex factor");
        assert!(r.phase_error_deg(1).iter().all(|&p| (p - 90.0).abs() < 1e-9));
    }

    #[test]
    fn band_errors_point_at_the_band_that_is_wrong() {
        let x = measured();
        // the model is 2x too high below 50 Hz and exact above
        let mut a = x.clone();
        for c in 0..3 {
            for k in 0..x.n_freq() {
                if x.frequencies_hz()[k] < 50.0 {
                    a.set(c, k, x.get(c, k) * 2.0);
                }
            }
        }
        let r = correlate(&x, &a, &BandSpec::Edges(vec![0.0, 50.0, 100.0])).unwrap();
        assert_eq!(r.bands.len(), 2);
        assert_eq!((r.bands[0].lines, r.bands[1].lines), (19, 21)); // 2.5..47.5 and 50..100 inclusive
        assert!((r.bands[0].rms_db - 6.0206).abs() < 1e-4);
        assert!(r.bands[1].rms_db.abs() < 1e-12);
        assert!((r.bands[0].share - 1.0).abs() < 1e-12 && r.bands[1].share.abs() < 1e-12);
        assert_eq!(r.worst_bands(5), vec![0, 1]);
        // per line: 6.02 dB below 50 Hz, 0 above
        assert!((r.lines[0].rms_db - 6.0206).abs() < 1e-4 && r.lines[30].rms_db.abs() < 1e-12);
        // the total is the line-count weighted RMS of the bands
        let expect = (19.0 * 6.0206f64.powi(2) / 40.0).sqrt();
        assert!((r.total.rms_db - expect).abs() < 1e-3);
    }

    #[test]
    fn worst_channels_are_ranked_by_misfit_and_shares_add_up() {
        let x = measured();
        let mut a = x.clone();
        for (c, q) in [(0, 1.1), (1, 3.0), (2, 1.5)] {
            for v in a.channel_mut(c) {
                *v *= q;
            }
        }
        let r = correlate(&x, &a, &BandSpec::Auto).unwrap();
        assert_eq!(r.worst_channels(2), vec![1, 2]);
        let total: f64 = r.channels.iter().map(|c| c.share).sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert!((r.channels[1].rms_db - 20.0 * 3f64.log10()).abs() < 1e-9);
    }

    #[test]
    fn channels_are_matched_by_name_and_kinds_converted() {
        let x = measured();
        let reversed = x.select_channels(&[2, 1, 0]).converted(FrfKind::Accelerance);
        let r = correlate(&x, &reversed, &BandSpec::Auto).unwrap();
        assert!(r.total.log_misfit < 1e-12, "{}", r.total.log_misfit);
        assert_eq!(r.kind(), FrfKind::Receptance);
        let mismatch = |r: Result<Correlation, FrfError>| match r {
            Err(FrfError::Mismatch(m)) => m.to_string(),
            other => panic!("expected a mismatch, got {other:?}"),
        };
        let fewer = x.select_channels(&[0, 1]);
        let m = mismatch(correlate(&x, &fewer, &BandSpec::Auto));
        assert!(m.contains(&format!("the model FRFs have no channel {}", x.channels()[2])), "{m}");
        let other = x.select_lines(&[0, 1, 2]).unwrap();
        let m = mismatch(correlate(&x, &other, &BandSpec::Auto));
        assert!(m.contains(&format!("have 3 lines, the measured {}", x.n_freq())), "{m}");
    }

    #[test]
    fn zero_values_are_left_out_and_counted() {
        let x = measured();
        let mut a = scaled(&x, C64::new(2.0, 0.0));
        a.set(1, 4, C64::new(0.0, 0.0));
        let r = correlate(&x, &a, &BandSpec::Auto).unwrap();
        assert_eq!(r.total.lines_excluded, 1);
        assert!(r.db_error(1)[4].is_nan());
        assert_eq!(r.channels[1].lines_used, 39);
        assert!((r.total.rms_db - 6.0206).abs() < 1e-4);
    }
}

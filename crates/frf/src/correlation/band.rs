//! The bands of a correlation: given edges, fractional octaves, or one band
//! per measured resonance.

use crate::error::{FrfError, MismatchError};
use crate::label::short;
use crate::set::FrfSet;

/// How to split the frequency range into bands.
#[derive(Clone, Debug, PartialEq)]
pub enum BandSpec {
    /// One band per resonance of the measured data when it shows any
    /// (see [`BandSpec::Resonances`]), otherwise octave bands.
    Auto,
    /// One band around each resonance of the measured data, with edges at the
    /// geometric means between neighbouring resonances and at the ends of the
    /// data. One band over everything when no resonance is found.
    Resonances,
    /// Base-2 fractional-octave bands (`1` = octaves, `3` = third octaves),
    /// centred on `1000 * 2^(i / fraction)` Hz, covering the data.
    Octave {
        /// Bands per octave (at least 1).
        fraction: u32,
    },
    /// Bands between consecutive edges (Hz, strictly increasing, at least
    /// two). Lines outside `[first, last]` belong to no band.
    Edges(Vec<f64>),
}

/// One frequency band of a correlation.
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    /// Lower edge (Hz).
    pub lo_hz: f64,
    /// Upper edge (Hz).
    pub hi_hz: f64,
    /// The measured resonance the band was built around, for
    /// [`BandSpec::Resonances`].
    pub resonance_hz: Option<f64>,
}

impl Band {
    /// A short label, `"12.5-25 Hz"` or `"mode at 31.7 Hz (20-60 Hz)"`.
    pub fn label(&self) -> String {
        let range = format!("{}-{} Hz", short(self.lo_hz), short(self.hi_hz));
        match self.resonance_hz {
            Some(f) => format!("peak at {} Hz ({range})", short(f)),
            None => range,
        }
    }
}

/// Resonance frequencies (Hz) seen in a set: lines where the magnitude
/// summed over channels has a local maximum at least 1.5 times the smallest
/// value on *both* sides within 5 % of its frequency (at least 3 lines).
///
/// The window is relative because a peak's width is: with damping that
/// grows with frequency, a fixed number of lines would be too narrow to see
/// the high modes stand out. Requiring the drop on both sides rejects
/// noise ripples on the flank of a peak.
pub fn resonances(set: &FrfSet) -> Vec<f64> {
    let f = set.frequencies_hz();
    let nf = f.len();
    if nf < 3 {
        return Vec::new();
    }
    let y: Vec<f64> = (0..nf)
        .map(|k| (0..set.channels().len()).map(|c| set.get(c, k).norm()).filter(|v| v.is_finite()).sum())
        .collect();
    (1..nf - 1)
        .filter(|&k| y[k] >= y[k - 1] && y[k] > y[k + 1])
        .filter(|&k| {
            let lo = f.partition_point(|&x| x < 0.95 * f[k]).min(k.saturating_sub(3));
            let hi = f.partition_point(|&x| x <= 1.05 * f[k]).max(k + 4).min(nf);
            let left = y[lo..k].iter().copied().fold(f64::INFINITY, f64::min);
            let right = y[k + 1..hi].iter().copied().fold(f64::INFINITY, f64::min);
            y[k] >= 1.5 * left.max(right)
        })
        .map(|k| f[k])
        .collect()
}

/// The bands a [`BandSpec`] gives for a measured set.
pub fn bands(spec: &BandSpec, measured: &FrfSet) -> Result<Vec<Band>, FrfError> {
    let f = measured.frequencies_hz();
    let (Some(&lo), Some(&hi)) = (f.first(), f.last()) else {
        return Ok(Vec::new());
    };
    let plain = |lo_hz, hi_hz| Band { lo_hz, hi_hz, resonance_hz: None };
    match spec {
        BandSpec::Auto => {
            if resonances(measured).is_empty() {
                bands(&BandSpec::Octave { fraction: 1 }, measured)
            } else {
                bands(&BandSpec::Resonances, measured)
            }
        }
        BandSpec::Resonances => {
            let peaks = resonances(measured);
            if peaks.is_empty() {
                return Ok(vec![plain(lo, hi)]);
            }
            let mut edges = vec![lo];
            edges.extend(peaks.windows(2).map(|w| (w[0] * w[1]).sqrt()));
            edges.push(hi);
            Ok(edges
                .windows(2)
                .zip(&peaks)
                .map(|(w, &p)| Band { lo_hz: w[0], hi_hz: w[1], resonance_hz: Some(p) })
                .collect())
        }
        BandSpec::Octave { fraction } => {
            if *fraction == 0 {
                return Err(MismatchError::NoOctaveFraction.into());
            }
            let n = f64::from(*fraction);
            let half = 2f64.powf(0.5 / n);
            // first centre whose band reaches the lowest line, last whose band reaches the highest
            let i0 = ((lo / half / 1000.0).log2() * n).floor() as i64;
            let i1 = ((hi * half / 1000.0).log2() * n).ceil() as i64;
            Ok((i0..=i1)
                .map(|i| {
                    let c = 1000.0 * 2f64.powf(i as f64 / n);
                    plain(c / half, c * half)
                })
                .filter(|b| f.iter().any(|&x| x >= b.lo_hz && x < b.hi_hz))
                .collect())
        }
        BandSpec::Edges(edges) => {
            if edges.len() < 2 {
                return Err(MismatchError::TooFewBandEdges.into());
            }
            if let Some(&x) = edges.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return Err(MismatchError::BadBandEdge { edge_hz: x }.into());
            }
            if let Some(w) = edges.windows(2).find(|w| !(w[1] > w[0])) {
                return Err(MismatchError::BandEdgesNotIncreasing { before: w[0], after: w[1] }.into());
            }
            let out: Vec<Band> = edges.windows(2).map(|w| plain(w[0], w[1])).collect();
            let last = out.len() - 1;
            for (i, b) in out.iter().enumerate() {
                if !f.iter().any(|&x| x >= b.lo_hz && (x < b.hi_hz || (i == last && x <= b.hi_hz))) {
                    return Err(MismatchError::EmptyBand {
                        lo_hz: b.lo_hz,
                        hi_hz: b.hi_hz,
                        data_lo_hz: lo,
                        data_hi_hz: hi,
                    }
                    .into());
                }
            }
            Ok(out)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{ch, measured, set};
    use super::*;
    use crate::C64;

    #[test]
    fn octave_bands_cover_the_data_and_edges_are_checked() {
        let x = measured(); // 2.5 .. 100 Hz
        let b = bands(&BandSpec::Octave { fraction: 1 }, &x).unwrap();
        assert!(b.first().unwrap().lo_hz <= 2.5 && b.last().unwrap().hi_hz > 100.0);
        // consecutive octave bands share edges and double
        for w in b.windows(2) {
            assert!((w[0].hi_hz - w[1].lo_hz).abs() < 1e-9);
            assert!((w[1].lo_hz / w[0].lo_hz - 2.0).abs() < 1e-9);
        }
        // the 1 kHz series: 62.5 Hz is the centre of an octave band
        assert!(b.iter().any(|b| ((b.lo_hz * b.hi_hz).sqrt() - 62.5).abs() < 1e-9));
        // third octaves: every band holds a line and every line is in a band
        let third = bands(&BandSpec::Octave { fraction: 3 }, &x).unwrap();
        let inside = |b: &Band, f: f64| f >= b.lo_hz && f < b.hi_hz;
        assert!(third.iter().all(|b| x.frequencies_hz().iter().any(|&f| inside(b, f))));
        assert!(x.frequencies_hz().iter().all(|&f| third.iter().filter(|b| inside(b, f)).count() == 1));
        assert!((third[1].lo_hz / third[0].lo_hz).log2() * 3.0 >= 1.0 - 1e-9);
        let mismatch = |spec: BandSpec| match bands(&spec, &x) {
            Err(FrfError::Mismatch(m)) => m.to_string(),
            other => panic!("{spec:?}: expected a mismatch, got {other:?}"),
        };
        assert!(mismatch(BandSpec::Edges(vec![10.0])).contains("give at least two frequencies"));
        assert!(
            mismatch(BandSpec::Edges(vec![10.0, 5.0]))
                .contains("must increase strictly, but 10 Hz is followed by 5 Hz")
        );
        assert!(mismatch(BandSpec::Edges(vec![-1.0, 5.0])).contains("band edge -1 Hz is not a finite, non-negative"));
        assert!(mismatch(BandSpec::Octave { fraction: 0 }).contains("at least one band per octave"));
        assert!(mismatch(BandSpec::Edges(vec![200.0, 300.0])).contains("no measured line"));
    }

    #[test]
    fn resonance_bands_hold_one_peak_each() {
        // two separated single-degree-of-freedom peaks at 20 and 60 Hz
        let f: Vec<f64> = (1..=200).map(|k| 0.5 * k as f64).collect();
        let sdof = |fr: f64, fq: f64| 1.0 / C64::new(fr * fr - fq * fq, 0.04 * fr * fq);
        let x = set(&f, &[ch(2)], |_, k| sdof(20.0, f[k]) + sdof(60.0, f[k]));
        let peaks = resonances(&x);
        assert_eq!(peaks.len(), 2, "{peaks:?}");
        assert!((peaks[0] - 20.0).abs() <= 0.5 && (peaks[1] - 60.0).abs() <= 0.5);
        let b = bands(&BandSpec::Auto, &x).unwrap();
        assert_eq!(b.len(), 2);
        assert_eq!((b[0].lo_hz, b[1].hi_hz), (0.5, 100.0));
        assert!((b[0].hi_hz - (peaks[0] * peaks[1]).sqrt()).abs() < 1e-9);
        assert!(b[1].label().starts_with("peak at 60"), "{}", b[1].label());
    }
}

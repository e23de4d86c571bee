//! The frequency axis (logarithmic or linear) and the phase of an FRF drawn
//! without the scatter that wrapping leaves.
//!
//! A wrapped phase that hovers near +-180 degrees (a driving point past its
//! first resonance, with a little noise) jumps from one edge of the axis to
//! the other at every line and reads as dots along both edges. Here the
//! measured phase is unwrapped into a continuous curve, and every model's
//! phase is drawn at the turn nearest to the measured one at the same line,
//! so that the distance between the curves is the phase error itself.

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};

use super::{C64, LogAxis, log_tick, tick};

/// How the frequency axis of a figure is scaled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum FrequencyScale {
    /// Logarithmic when the band spans a decade or more, else linear.
    #[default]
    Auto,
    /// Logarithmic.
    Log,
    /// Linear.
    Linear,
}

/// A band spanning at least this ratio of its ends is drawn on a
/// logarithmic axis by default: below it the resonances sit evenly enough
/// on a linear one.
const LOG_FROM_RATIO: f64 = 10.0;

/// A frequency axis from `lo` to `hi` Hz, logarithmic or linear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FreqAxis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl FreqAxis {
    /// The axis over the lines `f` (ascending), scaled as asked. A
    /// logarithmic axis starts at the first positive line; lines at or below
    /// zero are then left out of the figure ([`FreqAxis::shows`]).
    pub(crate) fn new(f: &[f64], scale: FrequencyScale) -> Self {
        let lo = f.first().copied().unwrap_or(0.0);
        let hi = f.last().copied().unwrap_or(1.0).max(lo + 1e-9);
        let positive = f.iter().copied().find(|&v| v > 0.0);
        let log = match (scale, positive) {
            (FrequencyScale::Linear, _) | (_, None) => false,
            (FrequencyScale::Log, Some(p)) => p < hi,
            (FrequencyScale::Auto, Some(p)) => hi / p >= LOG_FROM_RATIO,
        };
        match (log, positive) {
            (true, Some(p)) => FreqAxis { lo: p, hi, log: true },
            _ => FreqAxis { lo, hi, log: false },
        }
    }

    /// Whether the axis is logarithmic.
    pub(crate) fn is_log(&self) -> bool {
        self.log
    }

    /// Whether a line at `f` Hz can be drawn on this axis.
    pub(crate) fn shows(&self, f: f64) -> bool {
        f.is_finite() && (!self.log || f > 0.0) && f >= self.lo * (1.0 - 1e-12) && f <= self.hi * (1.0 + 1e-12)
    }

    /// The axis ends (Hz).
    pub(crate) fn ends(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// Tick label of a value of this axis.
    pub(crate) fn label(&self, v: &f64) -> String {
        if self.log { log_tick(v) } else { tick(v) }
    }

    /// What the axis title says about its scale.
    pub(crate) fn describe(&self) -> &'static str {
        if self.log { "Frequency (Hz, logarithmic)" } else { "Frequency (Hz)" }
    }
}

impl Ranged for FreqAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = if self.log {
            (v.max(self.lo * 1e-3).log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        limit.0 + (f64::from(limit.1 - limit.0) * t).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if self.log {
            return LogAxis { lo: self.lo, hi: self.hi }.key_points(hint);
        }
        linear_ticks(self.lo, self.hi, hint.max_num_points())
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// Ticks of a linear axis on the 1-2-5 steps, at most `max` of them.
pub(crate) fn linear_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span > 0.0) || max == 0 {
        return vec![lo];
    }
    let raw = span / max.max(1) as f64;
    let decade = 10f64.powf(raw.log10().floor());
    let step =
        [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * decade).find(|s| span / s <= max as f64).unwrap_or(10.0 * decade);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// The angle of `v` in degrees, `NaN` when it has none.
fn angle(v: C64) -> f64 {
    if v.is_finite() && v != C64::new(0.0, 0.0) { v.arg().to_degrees() } else { f64::NAN }
}

/// Brings `d` (degrees) into (-180, 180].
fn wrap(d: f64) -> f64 {
    let w = d - 360.0 * (d / 360.0).round();
    if w <= -180.0 { w + 360.0 } else { w }
}

/// The phase of `reference` unwrapped into a continuous curve: its first
/// line as measured, within (-180, 180], and each further line at the turn
/// nearest the line before (so a receptance starts at 0 or 180 degrees and
/// falls by half a turn at each resonance, as an engineer draws it); then
/// each of `others` at the turn nearest the reference's at the same line.
/// Lines without a phase (zero or not finite) are `NaN`.
pub(crate) fn phases(reference: &[C64], others: &[&[C64]]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut r: Vec<f64> = Vec::with_capacity(reference.len());
    let mut prev: Option<f64> = None;
    for &v in reference {
        let a = angle(v);
        let u = match prev {
            Some(p) if a.is_finite() => p + wrap(a - p),
            _ => a,
        };
        if u.is_finite() {
            prev = Some(u);
        }
        r.push(u);
    }
    let o = others
        .iter()
        .map(|curve| {
            let mut last: Option<f64> = None;
            curve
                .iter()
                .zip(&r)
                .map(|(&v, &rk)| {
                    let a = angle(v);
                    let near = if rk.is_finite() { Some(rk) } else { last };
                    let p = match near {
                        Some(n) if a.is_finite() => n + wrap(a - n),
                        _ => a,
                    };
                    if p.is_finite() {
                        last = Some(p);
                    }
                    p
                })
                .collect()
        })
        .collect();
    (r, o)
}

/// A phase axis range covering `values`: on whole quarter turns, at least
/// one turn, and -180 to 180 when the values fit in it.
pub(crate) fn phase_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() || (lo >= -180.0 && hi <= 180.0) {
        return (-180.0, 180.0);
    }
    let (lo, hi) = ((lo / 90.0).floor() * 90.0, (hi / 90.0).ceil() * 90.0);
    if hi - lo < 360.0 { (lo, lo + 360.0) } else { (lo, hi) }
}

/// Ticks of a phase axis: multiples of the smallest of 45, 90, 180, 360,
/// ... degrees that gives at most `max` of them.
pub(crate) fn phase_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let mut step = 45.0;
    while (hi - lo) / step + 1.0 > max.max(2) as f64 {
        step *= 2.0;
    }
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A phase axis from `lo` to `hi` degrees with ticks on multiples of 45
/// degrees and up (the automatic ticks of plotters would fall on multiples
/// of 50).
#[derive(Clone, Copy)]
pub(crate) struct PhaseAxis {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl PhaseAxis {
    /// The axis over `values` ([`phase_range`]).
    pub(crate) fn over(values: impl Iterator<Item = f64>) -> Self {
        let (lo, hi) = phase_range(values);
        PhaseAxis { lo, hi }
    }
}

impl Ranged for PhaseAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.lo) / (self.hi - self.lo);
        limit.0 + (f64::from(limit.1 - limit.0) * t).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        phase_ticks(self.lo, self.hi, hint.max_num_points())
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_bands_get_a_log_axis_by_default_and_zero_is_left_out() {
        let f: Vec<f64> = (0..=600).map(f64::from).collect();
        let a = FreqAxis::new(&f, FrequencyScale::Auto);
        assert!(a.is_log());
        assert_eq!(a.ends(), (1.0, 600.0));
        assert!(!a.shows(0.0) && a.shows(1.0) && a.shows(600.0));
        let narrow: Vec<f64> = (100..=400).map(f64::from).collect();
        assert!(!FreqAxis::new(&narrow, FrequencyScale::Auto).is_log());
        assert!(FreqAxis::new(&narrow, FrequencyScale::Log).is_log());
        assert!(!FreqAxis::new(&f, FrequencyScale::Linear).is_log());
        assert!(FreqAxis::new(&f, FrequencyScale::Linear).shows(0.0));
        // a log axis maps decades evenly
        let m = |v: f64| a.map(&v, (0, 1000));
        assert_eq!(m(1.0), 0);
        assert_eq!(m(600.0), 1000);
        assert!((m(10.0) - 360).abs() <= 1 && (m(100.0) - 720).abs() <= 1);
    }

    #[test]
    fn linear_ticks_fall_on_round_steps() {
        assert_eq!(linear_ticks(0.0, 600.0, 7), vec![0.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0]);
        assert_eq!(linear_ticks(0.0, 600.0, 12).len(), 13, "every 50 Hz");
        assert_eq!(linear_ticks(2.0, 9.0, 12), vec![2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    }

    #[test]
    fn a_phase_near_half_a_turn_is_continuous_and_models_follow_the_measured_turn() {
        // measured: noise around +-180 degrees, which wraps to both edges
        let deg = [178.0f64, -179.0, 179.5, -178.5, 177.0];
        let x: Vec<C64> = deg.iter().map(|d| C64::from_polar(1.0, d.to_radians())).collect();
        // a model 10 degrees ahead, wrapping the other way
        let a: Vec<C64> = deg.iter().map(|d| C64::from_polar(2.0, (d + 10.0).to_radians())).collect();
        let (r, o) = phases(&x, &[&a]);
        for w in r.windows(2) {
            assert!((w[1] - w[0]).abs() < 5.0, "{r:?}");
        }
        for (m, rk) in o[0].iter().zip(&r) {
            assert!((m - rk - 10.0).abs() < 1e-9, "{o:?} {r:?}");
        }
        // the curve starts where the measurement does
        assert_eq!(r[0], 178.0);
        assert!(r.iter().all(|v| (170.0..190.0).contains(v)), "{r:?}");
        assert_eq!(phase_range(r.iter().copied()), (90.0, 450.0));
        assert_eq!(phase_ticks(-180.0, 180.0, 9), vec![-180.0, -135.0, -90.0, -45.0, 0.0, 45.0, 90.0, 135.0, 180.0]);
        assert_eq!(phase_ticks(-180.0, 180.0, 5), vec![-180.0, -90.0, 0.0, 90.0, 180.0]);
        assert_eq!(phase_ticks(-720.0, -90.0, 5), vec![-720.0, -540.0, -360.0, -180.0]);
    }

    #[test]
    fn a_phase_falling_over_several_turns_gets_a_taller_axis() {
        let deg: Vec<f64> = (0..100).map(|k| -9.0 * f64::from(k)).collect();
        let x: Vec<C64> = deg.iter().map(|d| C64::from_polar(1.0, d.to_radians())).collect();
        let (r, _) = phases(&x, &[]);
        assert!((r[99] - r[0] + 891.0).abs() < 1e-9);
        let (lo, hi) = phase_range(r.iter().copied());
        assert!(lo <= r.iter().copied().fold(f64::INFINITY, f64::min) && hi >= r[0]);
        assert_eq!((hi - lo) % 90.0, 0.0);
        // a zero value has no phase and splits nothing else
        let (r, _) = phases(&[C64::new(1.0, 0.0), C64::new(0.0, 0.0), C64::new(-1.0, 1e-9)], &[]);
        assert!(r[1].is_nan() && (r[2] - 180.0).abs() < 1e-6, "{r:?}");
    }
}

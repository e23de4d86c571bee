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

use ::frf::FrfKind;

use super::C64;

/// How the frequency axis of a figure is scaled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum FrequencyScale {
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

/// Padded range of finite values, or `fallback` when there are none.
pub(super) fn range(values: impl Iterator<Item = f64>, fallback: (f64, f64)) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return fallback;
    }
    let pad = ((hi - lo) * 0.05).max(1e-9 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

/// A range for a logarithmic axis: from the 1-2-5 step at or below the
/// smallest positive value to the one at or above the largest.
pub(super) fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    let steps = |v: f64| {
        let d = 10f64.powf(v.log10().floor());
        [d, 2.0 * d, 5.0 * d, 10.0 * d]
    };
    let lo = steps(lo).into_iter().rev().find(|&s| s <= lo * (1.0 + 1e-9)).unwrap_or(lo);
    let hi = steps(hi).into_iter().find(|&s| s >= hi * (1.0 - 1e-9)).unwrap_or(hi);
    if hi <= lo { (lo / 2.0, hi * 2.0) } else { (lo, hi) }
}

/// Tick labels of a logarithmic axis: `1e-5`, `0.01`, `0.2`, `5`, `100`;
/// whole mantissas only (which ticks exist is up to [`LogAxis`]).
pub(super) fn log_tick(v: &f64) -> String {
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    let Some(m) = (1..=10).map(f64::from).find(|x| (m - x).abs() < 1e-6 * x) else {
        return String::new();
    };
    let (m, e) = if m == 10.0 { (1.0, e as i32 + 1) } else { (m, e as i32) };
    match e {
        -2..=3 => crate::table::num(m * 10f64.powi(e)),
        _ if m == 1.0 => format!("1e{e}"),
        _ => format!("{m}e{e}"),
    }
}

/// Tick labels of a linear axis without a trailing `.0`.
pub(super) fn tick(v: &f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// Splits a curve where it is not finite or where a wrapped phase jumps by
/// more than half a turn, so that no line is drawn across the gap.
pub(super) fn segments(x: &[f64], y: &[f64], wrap: Option<f64>) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for (&a, &b) in x.iter().zip(y) {
        if !b.is_finite() {
            if !current.is_empty() {
                out.push(std::mem::take(&mut current));
            }
            continue;
        }
        if let (Some(turn), Some(&(_, prev))) = (wrap, current.last())
            && (b - prev).abs() > turn / 2.0
        {
            out.push(std::mem::take(&mut current));
        }
        current.push((a, b));
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

pub(crate) fn unit(kind: FrfKind) -> &'static str {
    match kind {
        FrfKind::Receptance => "m/N",
        FrfKind::Mobility => "m/s/N",
        FrfKind::Accelerance => "m/s\u{b2}/N",
    }
}

/// A logarithmic axis with ticks on whole decades for wide ranges and on
/// the 1-2-5 steps for narrow ones (plotters' own logarithmic axis leaves
/// narrow ranges with one or two labels).
pub(super) struct LogAxis {
    pub(super) lo: f64,
    pub(super) hi: f64,
}

impl Ranged for LogAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10());
        limit.0 + (f64::from(limit.1 - limit.0) * t).round() as i32
    }

    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let decades = (self.hi / self.lo).log10();
        let light = hint.weight().allow_light_points();
        let all = &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
        let mantissas: &[f64] = if decades <= 0.5 || (light && decades <= 3.0) {
            all
        } else if decades <= 1.2 {
            &[1.0, 2.0, 3.0, 5.0]
        } else if decades <= 2.5 {
            &[1.0, 2.0, 5.0]
        } else {
            &[1.0]
        };
        let max = hint.max_num_points().max(2);
        let step = if mantissas.len() == 1 { (decades / max as f64).ceil().max(1.0) as i32 } else { 1 };
        let (e0, e1) = (self.lo.log10().floor() as i32, self.hi.log10().ceil() as i32);
        let inside = |v: &f64| *v >= self.lo * (1.0 - 1e-9) && *v <= self.hi * (1.0 + 1e-9);
        (e0..=e1)
            .filter(|e| (e - e0) % step == 0)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(inside)
            .collect()
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

    #[test]
    fn wrapped_phase_and_gaps_split_the_curve() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let y = [170.0, 178.0, -178.0, -170.0, f64::NAN, -160.0];
        let s = segments(&x, &y, Some(360.0));
        assert_eq!(s.iter().map(Vec::len).collect::<Vec<_>>(), vec![2, 2, 1]);
        // without wrapping, only the gap splits
        assert_eq!(segments(&x, &y, None).len(), 2);
    }

    #[test]
    fn log_axes_span_1_2_5_steps_and_label_them() {
        assert_eq!(log_range([3e-9, 0.0015, 0.0, f64::NAN].into_iter()), (2e-9, 0.002));
        assert_eq!(log_range([0.4, 3.3].into_iter()), (0.2, 5.0));
        assert_eq!(log_tick(&1e-5), "1e-5");
        assert_eq!(log_tick(&5e-7), "5e-7");
        assert_eq!(log_tick(&100.0), "100");
        assert_eq!(log_tick(&0.2), "0.2");
        assert_eq!(log_tick(&3.0), "3");
        assert_eq!(log_tick(&3.5), "");
        assert_eq!(tick(&50.0), "50");
        assert_eq!(tick(&-0.0), "0");
        assert_eq!(tick(&0.25), "0.25");
    }
}

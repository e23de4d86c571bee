//! Seeded measurement noise for synthesised FRFs.
//!
//! Model, for each channel `c` and line `k`:
//!
//! ```text
//! H_noisy = H (1 + s e1) + f * rms_c * e2
//! ```
//!
//! with `e1`, `e2` independent complex Gaussian numbers of unit mean square
//! (real and imaginary parts each N(0, 1/2)), `s` the relative level (0.06 is
//! "6 % noise": the RMS of the relative error is 6 %), `f` the additive floor
//! relative to `rms_c`, the RMS magnitude of channel `c`. The generator is
//! ChaCha8 seeded with `seed`, so the same seed gives the same data on every
//! platform.
//!
//! Measured data carry such a floor too (the acquisition's noise, a
//! sensor's resolution): where the FRF falls to it, at antiresonances and
//! away from a channel's modes, its relative noise grows as the floor over
//! `|H|`, and a fit of `ln H` that weighs those lines as the others chases
//! the floor. [`floor_weights`] finds such lines on the data alone and
//! weighs them down.

use num_complex::Complex64 as C64;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::set::FrfSet;

/// Noise model parameters; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseModel {
    /// Relative (multiplicative) level.
    pub relative: f64,
    /// Additive floor relative to each channel's RMS magnitude.
    pub floor: f64,
    /// Random seed.
    pub seed: u64,
}

impl NoiseModel {
    /// Multiplicative noise only.
    pub fn relative(level: f64, seed: u64) -> Self {
        NoiseModel { relative: level, floor: 0.0, seed }
    }

    /// True when the model adds nothing.
    pub fn is_zero(&self) -> bool {
        self.relative == 0.0 && self.floor == 0.0
    }

    /// Adds noise to every value of a set, in channel-major order.
    pub fn apply(&self, set: &mut FrfSet) {
        if self.is_zero() {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut gauss = || {
            let re: f64 = StandardNormal.sample(&mut rng);
            let im: f64 = StandardNormal.sample(&mut rng);
            C64::new(re, im) * std::f64::consts::FRAC_1_SQRT_2
        };
        for c in 0..set.channels().len() {
            let values = set.channel_mut(c);
            let rms = (values.iter().map(|v| v.norm_sqr()).sum::<f64>() / values.len().max(1) as f64).sqrt();
            for v in values.iter_mut() {
                let e1 = gauss();
                let e2 = gauss();
                *v = *v * (1.0 + self.relative * e1) + self.floor * rms * e2;
            }
        }
    }
}

/// Weights of the lines at a channel's additive noise floor
/// ([`floor_weights`]), and what was found per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorWeights {
    /// Per channel and line, channel-major: `1`, or `(t / q)^2` on a line
    /// whose relative noise `q` exceeds the channel's threshold `t`.
    pub weights: Vec<f64>,
    /// Per channel: the lines weighted down and the floor estimated from
    /// them (`None` where no line is).
    pub channels: Vec<Option<ChannelFloor>>,
    /// Per channel and line, channel-major: the RMS relative noise of the
    /// value as the floor's reading tells it, `sqrt(r^2 + (F / |H|)^2)`
    /// for its relative part `r` ([`ChannelFloor::relative`]) and its
    /// floor `F` ([`ChannelFloor::floor`]), where the floor covers over
    /// half the lines of every channel and its level holds over them;
    /// infinite on a value of 0. Over so many lines at a floor the
    /// weighted noise of a line runs from the threshold's beside the
    /// resonances to a hundredth of it, and a single level read from the
    /// lines' roughness as a median is the noise of none of them (on a
    /// strip at a floor of 3e-3 of its peak, 0.0041 where the truth's
    /// weighted residual left 0.037). NaN on every value elsewhere: the
    /// data's roughness tells their noise, raised by the spread of their
    /// weighted noise ([`ChannelFloor::spread`]). A floor that some
    /// channels' highest lines alone reach is not always found on them
    /// (the strip's first channel at a floor of 1e-5 of its peak, its
    /// highest lines at a relative noise of 0.1 where one level read over
    /// every line put 0.026), and the level of a channel's quietest lines,
    /// which reads such a floor, reads the curvature of a frame's coarse
    /// lines as a noise of 0.3 where 0.01 was injected: the reading of
    /// some channels only is not mixed with one level for the others. The
    /// same in every kind: a conversion scales the value and its noise
    /// alike.
    pub noise: Vec<f64>,
}

/// A channel's noise floor as [`floor_weights`] reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelFloor {
    /// Lines weighted down.
    pub lines: usize,
    /// The relative noise of the channel's cleanest lines (the tenth of
    /// its lines where it is lowest, among those whose noise stands above
    /// the floor outside the resonances); 0 where fewer than a tenth of
    /// the lines are such.
    pub typical: f64,
    /// The relative noise above which a line is weighted down.
    pub threshold: f64,
    /// The RMS of the relative part of the noise, read from `typical` (of
    /// which it is [`TENTH_OF_MEDIAN_OF_FIVE`] times as much for relative
    /// noise alone); 0 where `typical` is.
    pub relative: f64,
    /// The floor's level (in the data's units): the RMS noise of one value
    /// at the lines weighted down.
    pub floor: f64,
    /// The RMS of the weighted relative noise over its median, on the
    /// lines outside the resonances (at least 1): what turns a noise level
    /// read as a median into the RMS a fit's residual leaves.
    pub spread: f64,
}

impl FloorWeights {
    /// Each channel's [`ChannelFloor::spread`], 1 where it has no floor.
    pub fn spreads(&self) -> Vec<f64> {
        self.channels.iter().map(|c| c.map_or(1.0, |c| c.spread)).collect()
    }
}

/// Median of `v` (sorted in place); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// The median of `|z|` for `z` complex Gaussian of unit mean square,
/// `sqrt(ln 2)`: turns a median of moduli into an RMS level.
const MEDIAN_OF_MODULUS: f64 = 0.832_554_611_157_697_7;

/// The tenth percentile of the median of five moduli of complex Gaussian
/// numbers of unit mean square: `sqrt(-ln(1 - p))` for the `p` at which
/// the third of five order statistics of the uniform distribution has
/// probability 0.1 (`10 p^3 (1 - p)^2 + 5 p^4 (1 - p) + p^5 = 0.1`, `p =
/// 0.246636`). Relative noise alone of RMS `r` reads as a local noise
/// (the median of five lines' fourth differences over `|H|`) whose tenth
/// percentile is this times `r`.
pub const TENTH_OF_MEDIAN_OF_FIVE: f64 = 0.532_172_312_257_883;

/// Finds, per channel, the lines at an additive noise floor and weighs
/// them down; `None` when no line of any channel is.
///
/// A line's relative noise is read from the data alone: the modulus of
/// the complex fourth difference `H[k-2] - 4 H[k-1] + 6 H[k] - 4 H[k+1] +
/// H[k+2]` over `sqrt(70)` (the RMS of one value's noise, for noise
/// independent from line to line), its median over the five lines around
/// `k` (one sharp line does not count), over `|H[k]|`. The fourth
/// difference of a smooth FRF is small beside it, down into its
/// antiresonances (where a second difference still holds the dip's
/// curvature, and 1 % relative noise on a lightly damped strip read as a
/// floor there), except at a resonance whose half-power width the lines
/// do not resolve, where `|H|` is large. A line is
/// weighted down when `|H|` is below that of the tenth of the channel's
/// lines where it is highest (which hold its resonances) and its relative
/// noise `q` exceeds the threshold `t`, both 5 % and 5 times that of the
/// channel's cleanest lines (the tenth of its lines where it is lowest,
/// among those outside the resonances whose noise stands 3 times above
/// that of the quarter of the lines where `|H|` is lowest: the relative
/// part, even where a floor dominates most lines; none is read where
/// fewer than a tenth of the lines are such), when a
/// fiftieth of the channel's lines, and at least 5, are (fewer are the
/// reading's scatter beside sharp features) and their noise is flat (its
/// level does not follow `|H|` across them, as relative noise and the
/// curvature of modes unresolved by the lines do). A line's weight is
/// `(t / q)^2`, its relative noise `q` read as the floor's level over
/// `|H|` on every line, where that level puts at most half as many lines
/// again above the threshold as were found at it (a floor the local
/// reading's scatter would leave partly unweighted), else as the local
/// reading on the lines found; so that its weighted noise `t^2 / q` falls from
/// the threshold's at the threshold to the cleanest lines' where the
/// floor is 5 times the threshold and below beyond: the lines at the floor
/// neither dominate the fit nor raise its misfit above the noise of the
/// others (a weight of `t / q`, proportional to `|H|` there as a fit of
/// `H` itself would weigh them, left every such line at the threshold's
/// noise, and a model that explained the data read 3 to 4 times the
/// noise). Where the floor covers over half the lines of every channel,
/// a value whose modulus is below 4 times the floor's RMS is the floor's
/// more than the response's and weighs 0, and the noise of each value
/// ([`FloorWeights::noise`]) tells what noise the weighted values carry,
/// line by line. Data with relative noise only, or none, have no such
/// lines, and are fitted as before.
///
/// Run it on the data as measured (the floor is flat in the measured
/// quantity, not in a converted one); the weights are the same for every
/// kind. Channels of fewer than 11 lines are left at weight 1.
pub fn floor_weights(set: &FrfSet) -> Option<FloorWeights> {
    let nf = set.n_freq();
    let read = |cut: bool| {
        let mut weights = vec![1.0; nf * set.channels().len()];
        let mut channels = Vec::with_capacity(set.channels().len());
        let mut readings = Vec::with_capacity(set.channels().len());
        for (c, w) in weights.chunks_mut(nf.max(1)).enumerate().take(set.channels().len()) {
            let (found, read) = channel_floor(set.channel(c), w, cut);
            channels.push(found);
            readings.push(read);
        }
        (weights, channels, readings)
    };
    let (mut weights, mut channels, mut readings) = read(true);
    if readings.iter().any(Option::is_none) {
        // the noise of some channels only: the data's roughness reads it
        // over all of them, and no value is left out beside the others
        (weights, channels, _) = read(false);
        readings.fill(None);
    }
    let noise = readings
        .iter()
        .enumerate()
        .flat_map(|(c, r)| {
            set.channel(c).iter().map(move |h| r.map_or(f64::NAN, |(floor, relative)| relative.hypot(floor / h.norm())))
        })
        .collect();
    channels.iter().any(Option::is_some).then_some(FloorWeights { weights, channels, noise })
}

/// [`floor_weights`] for one channel's values `h`, writing `w`; and the
/// channel's noise as (floor, relative part) (see [`FloorWeights::noise`])
/// where a floor is found over more than half the lines and its level
/// holds over them; values indistinct from the floor weigh 0 there when
/// `cut` ([`floor_weight`]).
fn channel_floor(h: &[C64], w: &mut [f64], cut: bool) -> (Option<ChannelFloor>, Option<(f64, f64)>) {
    let n = h.len();
    if n < 11 || h.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        return (None, None);
    }
    // the fourth difference: a dip to an antiresonance, smooth in the
    // complex plane over a few lines, leaves it near zero where a second
    // difference still holds the dip's curvature
    let rough: Vec<f64> = (0..n)
        .map(|k| k.clamp(2, n - 3))
        .map(|k| (h[k - 2] - 4.0 * h[k - 1] + 6.0 * h[k] - 4.0 * h[k + 1] + h[k + 2]).norm() / 70f64.sqrt())
        .collect();
    // the local noise level: the floor is flat, so its level is read over
    // five lines and a sharp line of one does not count
    let smooth: Vec<f64> = (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(2), (k + 3).min(n));
            let mut window = [0.0; 5];
            window[..hi - lo].copy_from_slice(&rough[lo..hi]);
            median(&mut window[..hi - lo]).expect("a window of lines")
        })
        .collect();
    // over the line's own modulus
    let local: Vec<f64> =
        (0..n).map(|k| if h[k].norm() > 0.0 { smooth[k] / h[k].norm() } else { f64::INFINITY }).collect();
    // the tenth of the lines where |H| is highest hold the resonances,
    // whose difference is large where the lines do not resolve them
    let mut by_modulus: Vec<usize> = (0..n).collect();
    by_modulus.sort_by(|&a, &b| h[a].norm().total_cmp(&h[b].norm()));
    let level = h[by_modulus[n - 1 - n / 10]].norm();
    // and a resonance that stands out of its neighbourhood (its peak over
    // 3 times the median modulus of the 21 lines around it, and 10 times
    // the roughness of the quarter of the lines where |H| is lowest: noise
    // at a floor stands out so once in 500 lines, and 6 such peaks of a
    // strip's floor kept their 42 lines at weight 1) is not read at the
    // floor, with 3 lines either side, wherever its modulus ranks
    let lowest = median(&mut by_modulus[..n / 4].iter().map(|&k| rough[k]).collect::<Vec<_>>()).expect("lines");
    let mut resonant = vec![false; n];
    for k in 1..n - 1 {
        let m = h[k].norm();
        if m >= h[k - 1].norm() && m >= h[k + 1].norm() {
            let (lo, hi) = (k.saturating_sub(10), (k + 11).min(n));
            let around = median(&mut h[lo..hi].iter().map(|v| v.norm()).collect::<Vec<_>>()).expect("lines");
            if m > 3.0 * around && m > 10.0 * lowest {
                resonant[k.saturating_sub(3)..(k + 4).min(n)].fill(true);
            }
        }
    }
    // the relative noise of the channel's cleanest lines (the tenth of
    // the lines where it is lowest), read where the noise stands above the
    // floor (three times the roughness of the quarter of the lines where
    // |H| is lowest) outside the resonances, whose roughness is their
    // curvature: the relative part of the noise, even where a floor
    // dominates most lines. Where fewer than a tenth of the lines are
    // such, the floor and the resonances are all there is (a floor at
    // 3e-3 of a strip's peak covers 85 to 96 % of its lines, and the
    // cleanest tenth read 0.3 to 0.5 there, so that only the lines 40
    // times noisier than their value were weighted down), and no relative
    // part is read.
    let mut above: Vec<f64> = (0..n).filter(|&k| !resonant[k] && smooth[k] > 3.0 * lowest).map(|k| local[k]).collect();
    above.sort_by(f64::total_cmp);
    let typical = if above.len() >= n / 10 { above[above.len() / 10] } else { 0.0 };
    let threshold = (5.0 * typical).max(0.05);
    let at_floor: Vec<usize> =
        (0..n).filter(|&k| h[k].norm() < level && !resonant[k] && local[k] > threshold).collect();
    let cut = cut && 2 * at_floor.len() > n;
    for &k in &at_floor {
        w[k] = floor_weight(local[k], threshold, cut);
    }
    // the floor's level itself: the lines found at it were chosen where
    // their reading stood above the threshold, which reads it high where
    // the floor covers few lines (a floor at 3e-3 of the RMS of two modes
    // beside 0.5 % relative noise: 1.2 and 1.37 times the floor injected);
    // the quarter of the lines whose neighbourhood (the median modulus of
    // the 11 lines around) is quietest reads it low where the floor covers
    // most lines, as their moduli are then the floor's noise, and the
    // quietest the smallest (0.85 to 0.94 times on a strip at 3e-3 of its
    // peak, where the lines found read 0.92 to 1.01). Where the quiet
    // lines read lower, the floor is the geometric mean of the two
    // readings (0.89 to 0.97 times on the strip, 0.96 to 1.10 on the two
    // modes); where they read higher, they are not at the floor
    let around: Vec<f64> = (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(5), (k + 6).min(n));
            let mut window = [0.0; 11];
            for (w, v) in window.iter_mut().zip(&h[lo..hi]) {
                *w = v.norm();
            }
            median(&mut window[..hi - lo]).expect("a window of lines")
        })
        .collect();
    let mut by_around: Vec<usize> = (0..n).collect();
    by_around.sort_by(|&a, &b| around[a].total_cmp(&around[b]));
    let quiet = median(&mut by_around[..n / 4].iter().map(|&k| rough[k]).collect::<Vec<_>>()).expect("lines");
    let relative = typical / TENTH_OF_MEDIAN_OF_FIVE;
    // a floor covers a share of the band: a few lines alone are the
    // reading's scatter beside sharp features (1 % relative noise on the
    // tutorial's frame, 1 Hz lines: 1 to 6 of 599 per channel)
    let lines = at_floor.len();
    if lines < (n / 50).max(5) || !flat(&at_floor, h, &rough) {
        w.fill(1.0);
        return (None, None);
    }
    // the median of the floor's lines' roughness, on the local reading's scale
    let at_level = median(&mut at_floor.iter().map(|&k| rough[k]).collect::<Vec<_>>()).expect("lines at the floor");

    // the floor's level over |H| is a line's relative noise, read without
    // the local reading's scatter (lines a scattered reading left at
    // weight 1 at a floor at 3e-3 of a strip's peak, and the lines beside
    // its resonances, ran its moduli to 7 times the truth), where that
    // level puts about the lines found at it above the threshold (at most
    // half as many again: the curvature of modes unresolved by the lines,
    // taken for a floor on 2 channels of 40 of a frame at 1 % relative
    // noise, has a level that puts three times as many there); elsewhere
    // the local reading stays
    let by_level = |k: usize| at_level / h[k].norm();
    let placed = (0..n).filter(|&k| by_level(k) > threshold).count();
    let (lines, level_holds) = if 2 * placed <= 3 * lines {
        let cut = cut && 2 * placed > n;
        for (k, w) in w.iter_mut().enumerate() {
            *w = floor_weight(by_level(k), threshold, cut);
        }
        (placed, true)
    } else {
        (lines, false)
    };
    let floor = (at_level * quiet.min(at_level)).sqrt() / MEDIAN_OF_MODULUS;
    // the weighted noise's RMS over its median outside the resonances
    // (whose reading is their curvature, not their noise): a noise level
    // read as a median of the weighted values' roughness, times this, is
    // the RMS a fit's weighted residual leaves
    let mut weighted: Vec<f64> = (0..n)
        .filter(|&k| h[k].norm() < level && !resonant[k] && w[k] > 0.0)
        .map(|k| w[k] * local[k])
        .filter(|s| s.is_finite())
        .collect();
    let rms = (weighted.iter().map(|s| s * s).sum::<f64>() / weighted.len().max(1) as f64).sqrt();
    let spread = median(&mut weighted).filter(|&m| m > 0.0).map_or(1.0, |m| (rms / m).max(1.0));
    // the noise of each value where the floor covers over half the lines
    // and its level holds over them: there a median over the lines is the
    // noise of none of them (see `FloorWeights::noise`)
    let reading = (level_holds && 2 * lines > n).then_some((floor, relative));
    (Some(ChannelFloor { lines, typical, threshold, relative, floor, spread }), reading)
}

/// The weight of a line whose relative noise (on the median's scale, as
/// [`floor_weights`] reads it) is `q`, against the channel's threshold `t`:
/// 1 up to the threshold, `(t / q)^2` above it, and, where the floor
/// covers over half the channel's lines and the noise of every channel is
/// read from its floor (`cut`), 0 where the value is
/// not clearly above the floor (its modulus below 4 times the floor's RMS,
/// or `q` above twice the threshold where that is higher). There the value is mostly the
/// floor's noise, which tells only that the response lies below it: its
/// logarithm is the noise's, not the response's plus a small error, and a
/// model whose response lies far below the floor leaves a residual of the
/// order of `ln` of their ratio, not of `q` (on a strip whose receptance
/// falls below a floor at 3e-3 of its peak on most lines, such lines,
/// weighted `(t / q)^2` with `|M|` 2 to 3 times the floor by chance, were
/// the largest weighted residuals of the truth, 0.1 to 0.18 where `t^2 /
/// q` put 0.01, and held its misfit at 3.5 times the weighted noise).
/// Elsewhere their weights stay `(t / q)^2`: the noise there is read
/// from the roughness of the lines (see [`FloorWeights::noise`]), which
/// lines left out beside those that weigh would read lower than a fit's
/// residual leaves (the strip at a floor of 1e-5 of its peak: 1.5 times
/// the noise where its update converged at 1.19 with every line weighted).
fn floor_weight(q: f64, t: f64, cut: bool) -> f64 {
    if cut && q > (MEDIAN_OF_MODULUS / INDISTINCT).max(2.0 * t) {
        0.0
    } else if q > t {
        (t / q).powi(2)
    } else {
        1.0
    }
}

/// A value below this many times the floor's RMS is not told from the
/// floor ([`floor_weight`]): pure noise of that RMS exceeds it once in
/// `e^16` (about 9 million) values.
const INDISTINCT: f64 = 4.0;

/// Whether the noise read at `lines` is a floor: a level that does not
/// follow `|H|` (the least-squares slope of `ln` of the local level over
/// `ln |H|` below one half). Relative noise and the curvature of an FRF on
/// lines coarse against its modes both grow with `|H|` (slope near 1):
/// 1 % relative noise on a frame of dense modes read 5 times over on such
/// lines, and taken for a floor its weights raised the loop's noise to
/// 1.4 %.
fn flat(lines: &[usize], h: &[C64], rough: &[f64]) -> bool {
    let points: Vec<(f64, f64)> = lines
        .iter()
        .map(|&k| (h[k].norm().ln(), rough[k].ln()))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let m = points.len() as f64;
    if m < 2.0 {
        return false;
    }
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / m, points.iter().map(|p| p.1).sum::<f64>() / m);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    sxx > 0.0 && sxy / sxx < 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::set::{Channel, FrfKind};
    use fe_model::{Dof, DofRef};

    fn ones(n: usize) -> FrfSet {
        let c = Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy));
        let f: Vec<f64> = (1..=n).map(|i| i as f64).collect();
        let mut s = FrfSet::zeros(f, vec![c], FrfKind::Receptance).unwrap();
        s.channel_mut(0).fill(C64::new(1.0, 0.0));
        s
    }

    #[test]
    fn relative_level_is_the_rms_of_the_relative_error_and_seeds_repeat() {
        let mut a = ones(20000);
        NoiseModel::relative(0.06, 7).apply(&mut a);
        let rms = (a.channel(0).iter().map(|v| (v - 1.0).norm_sqr()).sum::<f64>() / 20000.0).sqrt();
        assert!((rms - 0.06).abs() < 0.002, "rms relative error {rms}");
        let mut b = ones(20000);
        NoiseModel::relative(0.06, 7).apply(&mut b);
        assert_eq!(a, b);
        let mut c = ones(20000);
        NoiseModel::relative(0.06, 8).apply(&mut c);
        assert_ne!(a, c);
    }

    /// Two modes of residues of one sign, 1 % damped, on lines 0.25 Hz apart
    /// from 5 to 200 Hz: resonances at 40 and 120 Hz and an antiresonance
    /// between them, over five decades of `|H|`.
    fn two_modes() -> FrfSet {
        let c = Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(3, Dof::Uy));
        let f: Vec<f64> = (0..781).map(|i| 5.0 + 0.25 * i as f64).collect();
        let mut s = FrfSet::zeros(f.clone(), vec![c], FrfKind::Receptance).unwrap();
        let mode = |fr: f64, f: f64| {
            let (wr, w) = (2.0 * std::f64::consts::PI * fr, 2.0 * std::f64::consts::PI * f);
            C64::new(wr * wr - w * w, 0.02 * wr * w).inv()
        };
        for (k, &f) in f.iter().enumerate() {
            s.set(0, k, mode(40.0, f) + 3.0 * mode(120.0, f));
        }
        s
    }

    /// Relative noise alone, of 0.1 to 6 % (five seeds each), or none: no
    /// line is weighted as at a floor, whatever the decades of `|H|`.
    #[test]
    fn relative_noise_has_no_floor() {
        for level in [0.0, 0.001, 0.01, 0.06] {
            for seed in 1..=5 {
                let mut s = two_modes();
                NoiseModel::relative(level, seed).apply(&mut s);
                let found = floor_weights(&s);
                assert!(found.is_none(), "{level}, seed {seed}: {:?}", found.map(|f| f.channels));
            }
        }
    }

    /// An additive floor (0.3 % and 3 % of the channel's RMS, beside 0.5 %
    /// relative noise) is found at its level, and weighs down the lines
    /// that read below it (their weight proportional to `|H|`) and no line well
    /// above it.
    #[test]
    fn an_additive_floor_is_found_at_its_level_and_weighs_its_lines_down() {
        for floor in [0.003, 0.03] {
            let clean = two_modes();
            let mut s = clean.clone();
            NoiseModel { relative: 0.005, floor, seed: 9 }.apply(&mut s);
            let rms = (clean.channel(0).iter().map(|v| v.norm_sqr()).sum::<f64>() / clean.n_freq() as f64).sqrt();
            let sigma = floor * rms;
            let found = floor_weights(&s).expect("a floor");
            let ch = found.channels[0].expect("on the channel");
            assert!((ch.floor / sigma - 1.0).abs() < 0.3, "floor {:.3e}, injected {sigma:.3e}", ch.floor);
            for (k, ((&w, h), m)) in found.weights.iter().zip(clean.channel(0)).zip(s.channel(0)).enumerate() {
                // what the data show: a line below the floor may read above it
                let snr = h.norm() / sigma;
                if m.norm() < sigma {
                    assert!(w < 0.5, "line {k}: SNR {snr:.2}, weight {w:.2}");
                }
                if snr > 200.0 {
                    assert_eq!(w, 1.0, "line {k}: SNR {snr:.0}");
                }
            }
            assert!(ch.lines >= 10, "{} lines weighted", ch.lines);
        }
    }

    /// A floor over most of the band (the two modes' peaks alone stand
    /// above it): every line whose FRF is below it is weighted down,
    /// those beside the resonances and those whose local reading scatters
    /// low among them (a floor at 3e-3 of a strip's peak left such lines at
    /// weight 1, and its moduli ran to 7 times the truth), and the
    /// resonances' tops are not.
    #[test]
    fn a_floor_over_most_of_the_band_weighs_down_every_line_below_it() {
        for seed in 1..=3 {
            let clean = two_modes();
            let mut s = clean.clone();
            let floor = 1.0;
            NoiseModel { relative: 0.0, floor, seed }.apply(&mut s);
            let rms = (clean.channel(0).iter().map(|v| v.norm_sqr()).sum::<f64>() / clean.n_freq() as f64).sqrt();
            let sigma = floor * rms;
            let below = clean.channel(0).iter().filter(|h| h.norm() < sigma).count();
            assert!(below * 10 > 8 * clean.n_freq(), "{below} of {} lines below the floor", clean.n_freq());
            let found = floor_weights(&s).expect("a floor");
            for (k, ((&w, h), m)) in found.weights.iter().zip(clean.channel(0)).zip(s.channel(0)).enumerate() {
                let snr = h.norm() / sigma;
                if snr < 1.0 {
                    assert!(w < 0.25, "seed {seed}, line {k}: SNR {snr:.2}, weight {w:.3}");
                }
                // a value the floor's noise could make alone tells nothing of ln H
                if m.norm() < 2.0 * sigma {
                    assert_eq!(w, 0.0, "seed {seed}, line {k}: |M| {:.2} times the floor", m.norm() / sigma);
                }
                if snr > 200.0 {
                    assert_eq!(w, 1.0, "seed {seed}, line {k}: SNR {snr:.0}");
                }
            }
        }
    }

    /// The weights are carried by the sets selected from the data, and
    /// by a change of kind.
    #[test]
    fn the_weights_follow_the_lines_and_channels_selected() {
        let mut s = two_modes();
        NoiseModel { relative: 0.0, floor: 0.01, seed: 4 }.apply(&mut s);
        let found = floor_weights(&s).unwrap();
        s.set_floor_weights(found.weights.clone(), found.noise.clone(), found.spreads()).unwrap();
        let picked = s.to_receptance().converted(FrfKind::Accelerance).select_lines(&[3, 400, 500]).unwrap();
        let w = picked.select_channels(&[0]).floor_weights(0).unwrap().to_vec();
        assert_eq!(w, [found.weights[3], found.weights[400], found.weights[500]]);
        assert!(s.set_floor_weights(vec![1.0; 3], found.noise.clone(), found.spreads()).is_err());
        assert_eq!(picked.floor_spread(0), Some(found.spreads()[0]));
        let q = picked.select_channels(&[0]).floor_noise(0).unwrap().to_vec();
        assert_eq!(q, [found.noise[3], found.noise[400], found.noise[500]]);
    }

    /// The noise each value carries, as the floor's reading tells it where
    /// the floor covers over half the lines, is the noise the
    /// values carry: over the lines that weigh, the RMS of the weighted
    /// relative errors injected (0.5 % relative beside a floor at 3 % and
    /// 30 % of the channel's RMS) is within 0.8 and 1.25 times that of the
    /// weighted noise read (seen: 0.98 to 1.17), and a relative part, where
    /// one is read, is read at its level.
    #[test]
    fn the_noise_read_for_each_value_is_the_noise_it_carries() {
        for (floor, seed) in [(0.03, 9), (0.03, 10), (0.3, 9), (0.3, 10)] {
            let clean = two_modes();
            let mut s = clean.clone();
            NoiseModel { relative: 0.005, floor, seed }.apply(&mut s);
            let found = floor_weights(&s).expect("a floor");
            let ch = found.channels[0].expect("on the channel");
            let (mut injected, mut read, mut n) = (0.0, 0.0, 0);
            assert!(2 * ch.lines > clean.n_freq(), "the floor covers {} lines", ch.lines);
            for (k, ((&w, h), m)) in found.weights.iter().zip(clean.channel(0)).zip(s.channel(0)).enumerate() {
                let q = found.noise[k];
                assert!((q - ch.relative.hypot(ch.floor / m.norm())).abs() <= 1e-12 * q, "line {k}");
                if w > 0.0 {
                    injected += (w * (m / h).ln()).norm_sqr();
                    read += (w * q).powi(2);
                    n += 1;
                }
            }
            let ratio = (injected / read).sqrt();
            let rms = (clean.channel(0).iter().map(|v| v.norm_sqr()).sum::<f64>() / clean.n_freq() as f64).sqrt();
            println!(
                "floor {floor}, seed {seed}: relative {:.5}, floor read {:.3}, {n} lines weigh, injected / read {ratio:.3}",
                ch.relative,
                ch.floor / (floor * rms)
            );
            assert!((0.8..1.25).contains(&ratio), "floor {floor}, seed {seed}: injected / read {ratio:.3}");
            assert!(
                ch.relative == 0.0 || (ch.relative / 0.005 - 1.0).abs() < 0.3,
                "floor {floor}, seed {seed}: relative {:.5}",
                ch.relative
            );
        }
    }
}

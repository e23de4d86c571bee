//! Checks of measured FRFs for what test set-ups get wrong, made before any
//! misfit is blamed on the model.
//!
//! Test data carry the set-up as well as the structure: an accelerometer
//! mounted upside down, cables swapped at the front end, a sensor glued at
//! the neighbouring point or along the other axis, a sensitivity typed
//! wrong, an attached part with a resonance of its own. A diagnosis that
//! reads such data as the structure's invents effects (damping patches
//! around an inverted sensor). Each check here compares every channel with
//! the model and with what its neighbours say, and reports a *finding
//! about the data* with its evidence and the correction of the case that
//! removes it ([`Finding`], [`Correction`]).
//!
//! Per channel `c` and line `k` the residual against the model's receptance
//! `H` at a DOF `d` of the channel's reference, with the reference's gain
//! `g` (1 unless gains are fitted), is the complex log
//!
//! ```text
//! r_k(d, s) = ln(M_ck / (s g H_dk)),   J(d, s) = sum_k w_k^2 |r_k(d, s)|^2
//! ```
//!
//! with the phase wrapped to half a turn and `s = +-1`, on lines spread
//! evenly over the band (not the resonance peaks first, where a model
//! error weighs most). The checks, each specific to its error so that a
//! model error does not pass for one:
//!
//! - **Inverted polarity**: at least 70 % of the channel's lines are more
//!   than a quarter turn off the model, while at most 35 % of its
//!   reference's other channels' are (the median): a model error turns the
//!   phase only between its resonances and the measured ones, and in every
//!   channel alike; and negating the channel lowers `J`.
//! - **Sensor at another DOF**: another DOF of the same reference (a node
//!   up to two members away, the other axis at the node, or another
//!   channel's DOF) fits the channel at least four times better than its
//!   own, by more than the noise allows, and the channel then fits like the
//!   others (within three times the median channel's misfit). The other
//!   axis at the node is a *misdirected* sensor; two channels that each fit
//!   the other's DOF so are *swapped* (four times better together, or,
//!   against a model far from the data, from twice what two typical
//!   channels leave to no more than it). Where several DOFs fit alike (within
//!   what the larger of the noise and the fit's own misfit allows: the
//!   axial DOFs of a member that moves as one body), the other axis at the
//!   node is taken first and the rest are named with the finding.
//! - **Calibration**: the channel's mean log-magnitude offset from its
//!   reference's gain exceeds 5 % and five of its standard errors (counted
//!   over the lines that are independent, from the residual's correlation
//!   between adjacent lines), and scaling it removes at least half of its
//!   misfit, which stands above twice the noise.
//! - **A mode the model lacks**: the data hold more modes in the band than
//!   the model (an LSCF estimate paired by MAC); the unpaired ones are
//!   reported with their frequency, as an attached resonator would make
//!   them, and the diagnosis then tries resonators there.
//!
//! With per-channel gains a sensitivity error is a gain and cannot be
//! told from the structure; the polarity check then reads the channel's
//! gain (half a turn from the others'), and the calibration check is left
//! out. A reference with fewer than three channels gives no robust common
//! gain when gains are fitted, and its channels are not checked for
//! polarity or calibration.

mod modes;

use damping::DampedSystem;
use fe_model::case::Gains;
use fe_model::{Dof, DofRef, NodeId, Slot};
use frf::{Channel, FrfSet};
use num_complex::Complex64 as C64;

use crate::error::UpdateError;
use crate::gain::log_gain;

pub use modes::extra_modes;

/// Another DOF is compared with a channel's own only where it has at least
/// this share of the own DOF's usable lines.
const COMPARABLE: f64 = 0.95;

/// A channel's misfit must fall at least this many times for a correction.
const FALL: f64 = 4.0;

/// A channel taken for one measured at another DOF must leave at least this
/// multiple of the median channel's misfit against its own DOF.
const OUTLIER: f64 = 2.0;

/// A channel with at least this share of its lines a quarter turn or more
/// off the model is inverted ...
const INVERTED_SHARE: f64 = 0.7;

/// ... when the median of its reference's other channels has at most this share.
const PEERS_SHARE: f64 = 0.35;

/// A calibration finding needs a level offset of at least this much (5 %).
const CALIBRATION_MIN: f64 = 0.05;

/// ... and this many standard errors.
const CALIBRATION_SE: f64 = 5.0;

/// Options of the checks.
#[derive(Clone, Debug)]
pub struct CheckOptions {
    /// Lines read ([`informative_lines`](crate::diagnose::informative_lines) of the data, as the diagnosis).
    pub lines: usize,
    /// The gains every fit of the case fits.
    pub gains: Gains,
    /// Residual weights at the measured lines, channel-major (`None`: all 1).
    pub weights: Option<Vec<f64>>,
    /// The data's relative noise (RMS per complex value).
    pub noise: f64,
}

/// What a finding is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum FindingKind {
    /// A channel whose sign is inverted (a sensor mounted upside down, a
    /// direction entered the wrong way).
    InvertedPolarity,
    /// Two channels whose data are each other's (swapped cables).
    SwappedChannels,
    /// A channel that measured another axis at its node.
    MisdirectedChannel,
    /// A channel whose sensor sat at another node.
    WrongNode,
    /// A channel whose level is off by a factor (a wrong sensitivity).
    Calibration,
    /// A measured mode without a partner in the model (an attached resonator,
    /// a loose part, a fixture).
    ExtraMode,
}

impl FindingKind {
    /// The name in JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            FindingKind::InvertedPolarity => "inverted_polarity",
            FindingKind::SwappedChannels => "swapped_channels",
            FindingKind::MisdirectedChannel => "misdirected_channel",
            FindingKind::WrongNode => "wrong_node",
            FindingKind::Calibration => "calibration",
            FindingKind::ExtraMode => "extra_mode",
        }
    }
}

/// The correction of one channel that a finding proposes, as the case's
/// `[[measurement.corrections]]` writes it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Correction {
    /// The channel's response as the data name it.
    #[cfg_attr(feature = "serde", serde(serialize_with = "crate::serialize_display"))]
    pub response: DofRef,
    /// Its reference.
    #[cfg_attr(feature = "serde", serde(serialize_with = "crate::serialize_display"))]
    pub reference: DofRef,
    /// 1, or -1 for an inverted sensor.
    pub sign: f64,
    /// The factor that brings its level to the others'.
    pub scale: f64,
    /// The DOF its sensor measured, when not the one it is named by.
    #[cfg_attr(feature = "serde", serde(serialize_with = "crate::serialize_option_display"))]
    pub measured_at: Option<DofRef>,
}

impl Correction {
    fn channel(&self) -> Channel {
        Channel::new(self.response, self.reference)
    }
}

/// A finding about the data: what looks wrong, the evidence, and the
/// correction of the case that removes it.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Finding {
    /// What it is about.
    pub kind: FindingKind,
    /// The channels concerned, as `H(response, reference)`.
    pub channels: Vec<String>,
    /// One sentence for the user.
    pub summary: String,
    /// The numbers it rests on.
    pub evidence: String,
    /// The corrections (one per channel; none for a mode the model lacks).
    pub corrections: Vec<Correction>,
    /// The misfit of the channels concerned before the correction (RMS of
    /// `ln(model / measured)` per value, on the lines read).
    pub misfit_before: f64,
    /// ... and after it.
    pub misfit_after: f64,
    /// The frequency of a measured mode the model lacks (Hz).
    pub frequency_hz: Option<f64>,
    /// How many steps of `rfm fix` were kept before it was found (0: found
    /// against the model as given).
    pub found_after_step: usize,
}

impl Finding {
    /// The `[[measurement.corrections]]` entries of the finding, written
    /// into a case: one per correction, with the summary as its reason.
    pub fn write(&self, editor: &mut fe_model::CaseEditor) -> Result<(), UpdateError> {
        for c in &self.corrections {
            editor.add_correction(c.response, Some(c.reference), c.sign, c.scale, c.measured_at, &self.summary)?;
        }
        Ok(())
    }
}

/// The measured set with the corrections of `findings` applied: channels
/// multiplied by their sign and scale and moved to the DOF their sensor
/// measured (see [`Correction`]).
pub fn corrected(measured: &FrfSet, findings: &[Finding]) -> Result<FrfSet, UpdateError> {
    let mut out = measured.clone();
    let mut names = out.channels().to_vec();
    for c in findings.iter().flat_map(|f| &f.corrections) {
        let i = measured.find(c.channel()).ok_or_else(|| {
            UpdateError::Data(format!("the correction names channel {}, which the data do not hold", c.channel()))
        })?;
        for v in out.channel_mut(i) {
            *v *= c.sign * c.scale;
        }
        if let Some(d) = c.measured_at {
            names[i].response = d;
        }
    }
    out.rename_channels(names)?;
    Ok(out)
}

/// The residual of one channel against one model FRF: per line `ln(M / (s g H))`.
struct Residual {
    /// `ln(M / (g H))` per line (non-finite where a value is unusable).
    r: Vec<C64>,
    /// Squared weights per line.
    w2: Vec<f64>,
}

fn wrap(x: f64) -> f64 {
    (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

impl Residual {
    fn new(m: &[C64], h: &[C64], log_g: C64, w2: &[f64]) -> Residual {
        let r = m.iter().zip(h).map(|(m, h)| (m / h).ln() - log_g).collect();
        Residual { r, w2: w2.to_vec() }
    }

    fn usable(&self) -> impl Iterator<Item = (C64, f64)> + '_ {
        self.r
            .iter()
            .zip(&self.w2)
            .filter(|(r, w2)| r.re.is_finite() && r.im.is_finite() && **w2 > 0.0)
            .map(|(r, w)| (*r, *w))
    }

    /// `J` with sign `s` (the phase shifted by half a turn for -1).
    fn cost(&self, negated: bool) -> f64 {
        let shift = if negated { std::f64::consts::PI } else { 0.0 };
        self.usable().map(|(r, w2)| w2 * (r.re * r.re + wrap(r.im - shift).powi(2))).sum()
    }

    /// Sum of squared weights of the usable lines (the number of complex values when unweighted).
    fn weight(&self) -> f64 {
        self.usable().map(|(_, w2)| w2).sum()
    }

    /// The weighted share of the lines whose phase residual is more than a
    /// quarter turn: about 1 for an inverted channel, and for a model that
    /// is right but for shifted resonances only the lines between its
    /// resonances and the measured ones.
    fn half_turn_share(&self) -> f64 {
        let quarter = std::f64::consts::FRAC_PI_2;
        let (s, t) =
            self.usable().fold((0.0, 0.0), |(s, t), (r, w2)| (s + if r.im.abs() > quarter { w2 } else { 0.0 }, t + w2));
        if t > 0.0 { s / t } else { 0.0 }
    }

    /// The weighted mean log-magnitude offset and its standard error over
    /// the independent lines (the lag-one correlation of the offsets read
    /// as `(1 + rho) / (1 - rho)` lines per independent one).
    fn level(&self) -> (f64, f64) {
        let v: Vec<(f64, f64)> = self.usable().map(|(r, w2)| (r.re, w2)).collect();
        let t: f64 = v.iter().map(|(_, w)| w).sum();
        if v.len() < 3 || t <= 0.0 {
            return (0.0, f64::INFINITY);
        }
        let mean = v.iter().map(|(x, w)| w * x).sum::<f64>() / t;
        let dev: Vec<f64> = v.iter().map(|(x, _)| x - mean).collect();
        let var = v.iter().zip(&dev).map(|((_, w), d)| w * d * d).sum::<f64>() / t;
        let lag: f64 = dev.windows(2).map(|p| p[0] * p[1]).sum::<f64>();
        let all: f64 = dev.iter().map(|d| d * d).sum::<f64>();
        let rho = if all > 0.0 { (lag / all).clamp(0.0, 0.95) } else { 0.0 };
        let per = (1.0 + rho) / (1.0 - rho);
        let n_eff = (v.len() as f64 / per).max(1.0);
        (mean, (var / n_eff).sqrt())
    }
}

/// The model's DOFs a channel's sensor may have measured instead: the
/// translations of its node and of the nodes up to two members away, and
/// the responses of the other channels of its reference (free DOFs only).
fn alternatives(sys: &DampedSystem, channel: Channel, measured: &FrfSet) -> Vec<DofRef> {
    let model = sys.model();
    let dofs = sys.assembly().dofs();
    let mut nodes: Vec<u32> = vec![channel.response.node.0];
    for _ in 0..2 {
        let ring: Vec<u32> = nodes
            .iter()
            .flat_map(|&n| model.beams_at(NodeId(n)).into_iter().flat_map(|i| model.beams()[i].nodes.map(|x| x.0)))
            .collect();
        nodes.extend(ring);
        nodes.sort_unstable();
        nodes.dedup();
    }
    let translations: Vec<Dof> = model.node_dofs().iter().copied().filter(|d| d.is_translation()).collect();
    let mut out: Vec<DofRef> =
        nodes.iter().flat_map(|&n| translations.iter().map(move |&d| DofRef::new(n, d))).collect();
    out.extend(measured.channels().iter().filter(|c| c.reference == channel.reference).map(|c| c.response));
    out.retain(|&d| d != channel.response && matches!(dofs.slot(d), Some(Slot::Free(_))));
    out.sort_by_key(|d| (d.node, d.dof as u8));
    out.dedup();
    out
}

/// The log-gain each channel is compared with: 0 without gains; with a
/// gain per reference, a robust centre of its channels' own gains (the
/// median log-magnitude, and the phase of a channel's gain that is nearest
/// to all the others' on the circle), so that one inverted or miscalibrated
/// channel does not move it; with a gain per channel, the channel's own.
/// `None` for a channel whose reference has too few channels to tell one
/// from the others when gains are fitted.
fn reference_gains(own: &[Option<C64>], channels: &[Channel], gains: Gains) -> Vec<Option<C64>> {
    match gains {
        Gains::None => vec![Some(C64::new(0.0, 0.0)); channels.len()],
        Gains::PerChannel => own.to_vec(),
        Gains::PerReference => channels
            .iter()
            .map(|ch| {
                let peers: Vec<C64> = channels
                    .iter()
                    .zip(own)
                    .filter(|(c, _)| c.reference == ch.reference)
                    .filter_map(|(_, g)| *g)
                    .collect();
                robust_centre(&peers)
            })
            .collect(),
    }
}

/// The robust centre of complex log-gains (three at least): the median
/// real part, and the phase among theirs with the least sum of wrapped
/// distances to the others.
fn robust_centre(logs: &[C64]) -> Option<C64> {
    if logs.len() < 3 {
        return None;
    }
    let mut re: Vec<f64> = logs.iter().map(|z| z.re).collect();
    re.sort_by(f64::total_cmp);
    let median = re[re.len() / 2];
    let phase = logs
        .iter()
        .map(|a| (a.im, logs.iter().map(|b| wrap(b.im - a.im).abs()).sum::<f64>()))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map_or(0.0, |(p, _)| p);
    Some(C64::new(median, phase))
}

/// Everything the checks read of one channel.
struct ChannelFit {
    channel: Channel,
    /// Against its own DOF, with the reference's gain.
    own: Residual,
    /// The reference's log-gain it is compared with (`None`: not checked
    /// for polarity and level).
    centre: Option<C64>,
    /// The channel's own best log-gain.
    gain: Option<C64>,
    /// Every other DOF compared, with its better sign and the cost there.
    others: Vec<(DofRef, bool, f64)>,
}

impl ChannelFit {
    /// The cost against its own DOF with the better sign.
    fn own_cost(&self) -> f64 {
        self.own.cost(false).min(self.own.cost(true))
    }

    /// The better sign and the cost against another DOF, when compared.
    fn at(&self, d: DofRef) -> Option<(bool, f64)> {
        self.others.iter().find(|o| o.0 == d).map(|o| (o.1, o.2))
    }

    /// The other DOF (with its sign and cost) the channel is taken to have
    /// measured, and the others that fit it alike, best first.
    ///
    /// The DOFs that fit alike are those whose cost exceeds the best one's
    /// by less than 25 values' worth of the larger of the noise and the
    /// best fit's own misfit: the data do not tell them apart (the axial
    /// DOFs along a member that moves as one body, or DOFs that a model
    /// error spoils alike). Among them, a DOF that another channel of the
    /// reference measures is not taken (that would be a swap, found
    /// apart, or a duplicate), and the other axis at the channel's own node
    /// comes first: a sensor turned on its mount is likelier than one both
    /// moved and turned. Else the best of them is taken.
    fn taken_for(
        &self,
        s2: f64,
        measured_elsewhere: impl Fn(DofRef) -> bool,
    ) -> Option<((DofRef, bool, f64), Vec<DofRef>)> {
        let best = self.others.iter().map(|o| o.2).min_by(f64::total_cmp)?;
        let weight = self.own.weight();
        let margin = 25.0 * s2.max(if weight > 0.0 { best / weight } else { 0.0 });
        let mut alike: Vec<(DofRef, bool, f64)> =
            self.others.iter().copied().filter(|o| o.2 <= best + margin && !measured_elsewhere(o.0)).collect();
        alike.sort_by(|a, b| a.2.total_cmp(&b.2));
        let node = self.channel.response.node;
        let pick = alike.iter().position(|o| o.0.node == node).unwrap_or(0);
        if alike.is_empty() {
            return None;
        }
        let taken = alike.remove(pick);
        Some((taken, alike.into_iter().map(|o| o.0).collect()))
    }
}

/// Checks measured receptances against a model for set-up errors (see the
/// module docs); returns the findings, the worst first within each kind.
pub fn check(sys: &DampedSystem, measured: &FrfSet, opts: &CheckOptions) -> Result<Vec<Finding>, UpdateError> {
    let mut findings = check_channels(sys, measured, opts)?;
    findings.extend(extra_modes(sys, measured)?);
    Ok(findings)
}

/// The checks of each channel (polarity, DOF, calibration).
pub fn check_channels(sys: &DampedSystem, measured: &FrfSet, opts: &CheckOptions) -> Result<Vec<Finding>, UpdateError> {
    let idx = spread_lines(measured.n_freq(), opts.lines);
    let data = measured.select_lines(&idx)?;
    let nf_all = measured.n_freq();
    let weights2 = |c: usize| -> Vec<f64> {
        idx.iter().map(|&k| opts.weights.as_ref().map_or(1.0, |w| w[c * nf_all + k]).powi(2)).collect()
    };
    // the model at every DOF any channel may have measured, per reference
    let mut wanted: Vec<Channel> = data.channels().to_vec();
    for &ch in data.channels() {
        wanted.extend(alternatives(sys, ch, &data).into_iter().map(|d| Channel::new(d, ch.reference)));
    }
    wanted.sort_by_key(|c| (c.reference.node, c.reference.dof as u8, c.response.node, c.response.dof as u8));
    wanted.dedup();
    let model = frf::synthesize(sys, &wanted, data.frequencies_hz())?;
    let model_at = |d: DofRef, r: DofRef| model.find(Channel::new(d, r)).map(|i| model.channel(i));
    let channels = data.channels().to_vec();
    let own_gains: Vec<Option<C64>> = (0..channels.len())
        .map(|c| {
            let h = model_at(channels[c].response, channels[c].reference).expect("synthesised");
            let w2 = weights2(c);
            log_gain(data.channel(c).iter().zip(h).zip(&w2).map(|((&m, &h), &w2)| (h, m, w2.sqrt())))
        })
        .collect();
    let centres = reference_gains(&own_gains, &channels, opts.gains);
    let fits: Vec<ChannelFit> = (0..channels.len())
        .map(|c| {
            let ch = channels[c];
            let w2 = weights2(c);
            let m = data.channel(c);
            let base = centres[c].unwrap_or(C64::new(0.0, 0.0));
            let h = model_at(ch.response, ch.reference).expect("synthesised");
            let own = Residual::new(m, h, base, &w2);
            let others: Vec<(DofRef, bool, f64)> = alternatives(sys, ch, &data)
                .into_iter()
                .filter_map(|d| {
                    let h = model_at(d, ch.reference)?;
                    // with a gain per channel, each DOF with the channel's best gain for it
                    let g = match opts.gains {
                        Gains::PerChannel => {
                            log_gain(m.iter().zip(h).zip(&w2).map(|((&m, &h), &w2)| (h, m, w2.sqrt())))
                                .unwrap_or_default()
                        }
                        _ => base,
                    };
                    let r = Residual::new(m, h, g, &w2);
                    // a DOF the model does not move for this reference (an
                    // axial DOF of a beam excited across) has no usable line
                    // to compare on, not a small misfit
                    if r.weight() < COMPARABLE * own.weight() {
                        return None;
                    }
                    let (plus, minus) = (r.cost(false), r.cost(true));
                    Some(if minus < plus { (d, true, minus) } else { (d, false, plus) })
                })
                .collect();
            ChannelFit { channel: ch, own, centre: centres[c], gain: own_gains[c], others }
        })
        .collect();
    Ok(judge(&fits, opts))
}

/// `n` line indices spread evenly over `nf` lines (all of them when fewer):
/// the checks read the whole band alike, not the resonance peaks first as
/// the diagnosis does, so that a model's shifted resonances weigh no more
/// in them than their share of the band.
fn spread_lines(nf: usize, n: usize) -> Vec<usize> {
    if n >= nf || n < 2 {
        return (0..nf).collect();
    }
    let mut idx: Vec<usize> = (0..n).map(|i| (i as f64 * (nf - 1) as f64 / (n - 1) as f64).round() as usize).collect();
    idx.dedup();
    idx
}

/// The RMS of the complex log residual per value of a cost over a weight.
fn rms(cost: f64, weight: f64) -> f64 {
    if weight > 0.0 { (cost / weight).sqrt() } else { f64::NAN }
}

/// The findings the channel fits support.
fn judge(fits: &[ChannelFit], opts: &CheckOptions) -> Vec<Finding> {
    let s2 = opts.noise * opts.noise;
    let typical = median_rms(fits);
    let mut findings = Vec::new();
    let mut done: Vec<Channel> = Vec::new();
    let sign = |neg: bool| if neg { -1.0 } else { 1.0 };
    // a channel moved to DOF `d` with cost `cost`: far better than its own,
    // by more than the noise allows (a chi-square fall of 25 values' noise),
    // and then fitting like the other channels do (within twice the median
    // channel's misfit: a channel near a model error that fits a
    // neighbour's DOF better still fits worse than the others, as the
    // table frame's 31:uy at 30:uy, 2.84 against a median of 0.99)
    let better = |f: &ChannelFit, cost: f64| {
        let own = f.own_cost();
        cost * FALL < own && (own - cost) > 25.0 * s2 && rms(cost, f.own.weight()) < 2.0 * opts.noise.max(typical)
    };
    // swaps first: two channels of one reference that each fit the other's DOF
    for (a, fa) in fits.iter().enumerate() {
        for fb in &fits[a + 1..] {
            if fb.channel.reference != fa.channel.reference || done.contains(&fa.channel) || done.contains(&fb.channel)
            {
                continue;
            }
            let (Some((na, ca)), Some((nb, cb))) = (fa.at(fb.channel.response), fb.at(fa.channel.response)) else {
                continue;
            };
            // exchanged, the two together fit far better, each better than
            // before, by more than the noise allows. Far better is four
            // times, or, against a model far from the data (a missing
            // joint leaves every channel at a hundred times the noise, and
            // no exchange brings two channels below the others), from
            // twice the cost of two typical channels to no more than it
            let own = fa.own_cost() + fb.own_cost();
            let typical_pair = (fa.own.weight() + fb.own.weight()) * typical * typical;
            let far_better = (ca + cb) * FALL < own || (own > 2.0 * typical_pair && ca + cb <= typical_pair);
            if !(far_better && ca < fa.own_cost() && cb < fb.own_cost() && (own - ca - cb) > 25.0 * s2) {
                continue;
            }
            let before = fa.own_cost() + fb.own_cost();
            let weight = fa.own.weight() + fb.own.weight();
            findings.push(Finding {
                kind: FindingKind::SwappedChannels,
                channels: vec![fa.channel.to_string(), fb.channel.to_string()],
                summary: format!(
                    "channels {} and {} look swapped: each holds the other's response",
                    fa.channel, fb.channel
                ),
                evidence: format!(
                    "their misfit falls from {:.3} to {:.3} (RMS of ln per value) when exchanged",
                    rms(before, weight),
                    rms(ca + cb, weight)
                ),
                corrections: vec![
                    Correction {
                        response: fa.channel.response,
                        reference: fa.channel.reference,
                        sign: sign(na),
                        scale: 1.0,
                        measured_at: Some(fb.channel.response),
                    },
                    Correction {
                        response: fb.channel.response,
                        reference: fb.channel.reference,
                        sign: sign(nb),
                        scale: 1.0,
                        measured_at: Some(fa.channel.response),
                    },
                ],
                misfit_before: rms(before, weight),
                misfit_after: rms(ca + cb, weight),
                frequency_hz: None,
                found_after_step: 0,
            });
            done.extend([fa.channel, fb.channel]);
        }
    }
    // the share of lines a quarter turn off or more, of the other channels of each reference
    let peer_share = |f: &ChannelFit| {
        let mut v: Vec<f64> = fits
            .iter()
            .filter(|o| o.channel.reference == f.channel.reference && o.channel != f.channel)
            .map(|o| o.own.half_turn_share())
            .collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    for f in fits {
        if done.contains(&f.channel) {
            continue;
        }
        let (plus, minus) = (f.own.cost(false), f.own.cost(true));
        let weight = f.own.weight();
        // polarity: most lines half a turn off while the reference's other
        // channels are not (a model error turns the phase only between its
        // resonances and the measured ones, in every channel alike); with a
        // gain per channel, the channel's own gain half a turn from its
        // reference's others (the gain has taken the sign in)
        let share = f.own.half_turn_share();
        let inverted = match (opts.gains, f.centre, f.gain) {
            (Gains::PerChannel, _, Some(g)) => {
                let others: Vec<C64> = fits
                    .iter()
                    .filter(|o| o.channel.reference == f.channel.reference && o.channel != f.channel)
                    .filter_map(|o| o.gain)
                    .collect();
                others.len() >= 2
                    && robust_centre(&[others.clone(), vec![g]].concat())
                        .is_some_and(|c| wrap(g.im - c.im).abs() > 2.0 * std::f64::consts::FRAC_PI_3)
            }
            (Gains::PerChannel, ..) | (_, None, _) => false,
            _ => {
                share >= INVERTED_SHARE
                    && peer_share(f).is_none_or(|p| p <= PEERS_SHARE)
                    && minus < plus
                    && (plus - minus) > 25.0 * s2
            }
        };
        // a sensor at another DOF explains more than a sign alone (not at a
        // DOF another channel of its reference measures: two channels there
        // would be a swap, found above, or a duplicate)
        let measured_elsewhere =
            |d: DofRef| fits.iter().any(|o| o.channel.reference == f.channel.reference && o.channel.response == d);
        // and the channel stands out from the others: a sensor elsewhere
        // spoils its own channel, a model error spoils them all, and one of
        // many channels spoilt alike can fit a neighbour's DOF better by
        // chance (the table frame's loose corner: 31:uy "at 30:uy")
        let stands_out = rms(f.own_cost(), f.own.weight()) > OUTLIER * typical;
        if let Some(((d, neg, cost), alike)) = f.taken_for(s2, measured_elsewhere)
            && stands_out
            && better(f, cost)
            && (!inverted || cost * 2.0 < minus)
        {
            let same_node = d.node == f.channel.response.node;
            let (kind, what) = if same_node {
                (FindingKind::MisdirectedChannel, format!("measured along {d} instead (the other axis at its node)"))
            } else {
                (FindingKind::WrongNode, format!("measured at {d} instead"))
            };
            let inv = if neg { ", inverted" } else { "" };
            let alike = match alike.len() {
                0 => String::new(),
                _ => format!(
                    "; {} fit{} it about as well (the data do not tell them apart)",
                    alike.iter().map(ToString::to_string).collect::<Vec<_>>().join(", "),
                    if alike.len() == 1 { "s" } else { "" }
                ),
            };
            findings.push(Finding {
                kind,
                channels: vec![f.channel.to_string()],
                summary: format!("channel {} looks {what}{inv}", f.channel),
                evidence: format!(
                    "its misfit is {:.3} against {} and {:.3} against {d}{inv} (RMS of ln per value; the median \
                     channel's is {typical:.3}){alike}",
                    rms(f.own_cost(), weight),
                    f.channel.response,
                    rms(cost, weight),
                ),
                corrections: vec![Correction {
                    response: f.channel.response,
                    reference: f.channel.reference,
                    sign: sign(neg),
                    scale: 1.0,
                    measured_at: Some(d),
                }],
                misfit_before: rms(plus, weight),
                misfit_after: rms(cost, weight),
                frequency_hz: None,
                found_after_step: 0,
            });
            continue;
        }
        if inverted {
            let gain_note = match (opts.gains, f.gain) {
                (Gains::PerChannel, Some(g)) => format!("its fitted gain's phase is {:.0} deg", g.im.to_degrees()),
                _ => format!(
                    "{:.0} % of its lines are more than a quarter turn off the model (its reference's other channels: \
                     {:.0} %)",
                    100.0 * share,
                    100.0 * peer_share(f).unwrap_or(0.0)
                ),
            };
            findings.push(Finding {
                kind: FindingKind::InvertedPolarity,
                channels: vec![f.channel.to_string()],
                summary: format!("channel {} looks inverted (a sensor mounted upside down?)", f.channel),
                evidence: format!(
                    "{gain_note}; negated, its misfit falls from {:.3} to {:.3} (RMS of ln per value)",
                    rms(plus, weight),
                    rms(minus, weight)
                ),
                corrections: vec![Correction {
                    response: f.channel.response,
                    reference: f.channel.reference,
                    sign: -1.0,
                    scale: 1.0,
                    measured_at: None,
                }],
                misfit_before: rms(plus, weight),
                misfit_after: rms(minus, weight),
                frequency_hz: None,
                found_after_step: 0,
            });
            continue;
        }
        // calibration: a level offset from the reference's gain, which the
        // channel's own misfit is mostly made of
        if opts.gains == Gains::PerChannel || f.centre.is_none() {
            continue;
        }
        let (offset, se) = f.own.level();
        let explained = weight * offset * offset;
        if offset.abs() > CALIBRATION_MIN.ln_1p()
            && offset.abs() > CALIBRATION_SE * se
            && explained >= 0.5 * plus
            && rms(plus, weight) > 2.0 * opts.noise
        {
            let scale = (-offset).exp();
            findings.push(Finding {
                kind: FindingKind::Calibration,
                channels: vec![f.channel.to_string()],
                summary: format!(
                    "channel {} reads {:.0} % {} than the model and its reference's other channels (a wrong \
                     sensitivity?)",
                    f.channel,
                    100.0 * (offset.exp() - 1.0).abs(),
                    if offset > 0.0 { "higher" } else { "lower" }
                ),
                evidence: format!(
                    "its level offset is {offset:+.3} (ln) +- {se:.3}; scaled by {scale:.3}, its misfit falls from \
                     {:.3} to {:.3}",
                    rms(plus, weight),
                    rms((plus - explained).max(0.0), weight)
                ),
                corrections: vec![Correction {
                    response: f.channel.response,
                    reference: f.channel.reference,
                    sign: 1.0,
                    scale,
                    measured_at: None,
                }],
                misfit_before: rms(plus, weight),
                misfit_after: rms((plus - explained).max(0.0), weight),
                frequency_hz: None,
                found_after_step: 0,
            });
        }
    }
    findings
}

/// The median channel's RMS misfit against its own DOF.
fn median_rms(fits: &[ChannelFit]) -> f64 {
    let mut v: Vec<f64> = fits.iter().map(|f| rms(f.own.cost(false).min(f.own.cost(true)), f.own.weight())).collect();
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

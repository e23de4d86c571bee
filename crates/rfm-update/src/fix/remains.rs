//! What the loop's final model leaves unexplained, in the user's terms, and
//! why the loop stopped, in full.

use damping::DampedSystem;
use frf::{BandSpec, FrfSet};

use super::explains::Unexplained;
use super::{CONSISTENT, FixStop, LookAhead};
use crate::checks::{self, Finding, FindingKind};
use crate::comparison::{self, GainSource};
use crate::diagnose::DiagnoseOptions;

/// A channel or band holding at least this share of the remaining misfit
/// is named.
const DOMINANT: f64 = 0.4;

/// A paired mode whose damping differs by more than this (relative) while
/// its frequency agrees within [`SAME_FREQUENCY`] is named.
const DAMPING_OFF: f64 = 0.3;

/// Frequencies within this (relative) agree.
const SAME_FREQUENCY: f64 = 0.01;

/// What the final model (`sys`) leaves unexplained in the data: the modes
/// a resonator tuned to them left unexplained (`unexplained`), measured
/// modes it lacks, a channel or a band that holds most of the misfit, a
/// mode whose damping differs while its frequency agrees (a damping form
/// the candidates lack). One sentence each; a comparison that cannot be
/// made is said as such.
pub(super) fn describe(
    sys: &DampedSystem,
    data: &FrfSet,
    opts: &DiagnoseOptions,
    noise: f64,
    findings: &[Finding],
    unexplained: &[Unexplained],
) -> Vec<String> {
    // what a resonator left when it was tried, unless a later step has
    // explained it since (held-out pair trial 79: a band at 44.6 times the
    // noise when the resonator was tried at step 1, said at the end beside
    // a final misfit of 1.98 times the noise), at its level now
    let mut out: Vec<String> = Vec::new();
    let mut still: Vec<&Unexplained> = Vec::new();
    for u in unexplained {
        let (explained, now) = u.explained_by(sys, data, opts, noise);
        if !explained {
            out.push(u.remains(now));
            still.push(u);
        }
    }
    if let Ok(extra) = checks::extra_modes(sys, data) {
        for f in extra {
            // a mode said above already, with what was tried on it
            let said = f.frequency_hz.is_some_and(|hz| still.iter().any(|u| (u.hz / hz - 1.0).abs() < 0.05));
            if !said {
                out.push(f.summary);
            }
        }
    }
    for f in findings.iter().filter(|f| f.kind != FindingKind::ExtraMode && f.corrections.is_empty()) {
        out.push(format!("a finding about the data that no correction removes: {}", f.summary));
    }
    let gains = GainSource::Fit { setting: opts.gains, weights: opts.weights.as_deref() };
    let mut per_channel = Vec::new();
    match comparison::compare(sys, data, gains, &BandSpec::Auto) {
        Ok(c) => {
            per_channel = c.model.gains.clone();
            let cor = &c.correlation;
            if let Some(ch) = cor.channels.iter().max_by(|a, b| a.share.total_cmp(&b.share))
                && ch.share >= DOMINANT
                && cor.channels.len() > 1
            {
                out.push(format!(
                    "channel {} holds {:.0} % of the misfit (its RMS error {:.1} dB): a sensor, its place or the \
                     structure near it",
                    ch.channel,
                    100.0 * ch.share,
                    ch.rms_db
                ));
            }
            if let Some(b) = cor.bands.iter().max_by(|a, b| a.share.total_cmp(&b.share))
                && b.share >= DOMINANT
                && cor.bands.len() > 1
            {
                out.push(format!(
                    "the band {:.1}-{:.1} Hz holds {:.0} % of the misfit (RMS error {:.1} dB)",
                    b.band.lo_hz,
                    b.band.hi_hz,
                    100.0 * b.share,
                    b.rms_db
                ));
            }
        }
        Err(e) => out.push(format!("the final model could not be compared with the data: {e}")),
    }
    if let Ok(m) = comparison::compare_modes(sys, data, &per_channel, 0.5) {
        for p in &m.pairing.pairs {
            let (fm, fx) = (m.model[p.model].frequency_hz, m.measured[p.measured].frequency_hz);
            let (zm, zx) = (m.model[p.model].damping_ratio, m.measured[p.measured].damping_ratio);
            if (fm / fx - 1.0).abs() < SAME_FREQUENCY && zx > 0.0 && (zm / zx - 1.0).abs() > DAMPING_OFF {
                out.push(format!(
                    "the mode at {fx:.1} Hz has {:.2} % damping in the data and {:.2} % in the model at the same \
                     frequency: a damping form (frequency dependence, place) the candidates lack",
                    100.0 * zx,
                    100.0 * zm
                ));
            }
        }
    }
    if out.is_empty() {
        out.push(format!(
            "a misfit above {CONSISTENT} times the noise ({noise:.3e}) spread over channels, bands and modes, with no \
             single place or form standing out"
        ));
    }
    out
}

/// The stop's reason in full: its meaning and what decided it.
pub(super) fn stop_reason(
    stop: FixStop,
    rejected: &[LookAhead],
    equally_good: &[LookAhead],
    diagnosis_error: Option<&str>,
    misfit: f64,
    noise: f64,
) -> String {
    let mut s = format!("{} (final misfit {:.2} times the noise)", stop.describe(), misfit / noise);
    match stop {
        FixStop::ModelInadequate if rejected.is_empty() => {
            s.push_str("; no candidate is both significant and plausible against the model");
        }
        FixStop::ModelInadequate => {
            let why: Vec<String> = rejected
                .iter()
                .map(|r| format!("{}: {}", r.effect, r.rejected.as_deref().unwrap_or("not kept")))
                .collect();
            s.push_str(&format!("; tried and not kept: {}", why.join("; ")));
        }
        FixStop::Ambiguous => {
            let names: Vec<String> = equally_good
                .iter()
                .map(|r| format!("{} (dBIC {})", r.effect, crate::quantities::dbic_text(r.delta_bic)))
                .collect();
            s.push_str(&format!(
                ": {}; more modes (a wider band) or responses nearer to them would tell them apart",
                names.join(", ")
            ));
        }
        FixStop::DiagnosisFailed => {
            s.push_str(&format!(": {}", diagnosis_error.unwrap_or("no reason given")));
        }
        FixStop::NothingSignificant | FixStop::StepsDone | FixStop::MeshTooCoarse => {}
    }
    if stop != FixStop::Ambiguous && equally_good.len() > 1 {
        let others: Vec<&str> = equally_good[1..].iter().map(|r| r.effect.as_str()).collect();
        s.push_str(&format!(
            "; at one step {} was kept, but {} explained the data as well, and nothing after told them apart",
            equally_good[0].effect,
            others.join(", ")
        ));
    }
    s
}

//! Containers for sets of FRFs, shared by synthesised and measured data.

use std::collections::{HashMap, HashSet};
use std::fmt;

use fe_model::DofRef;
use num_complex::Complex64 as C64;

pub use crate::channel::Channel;
use crate::error::{FrfError, MismatchError};

mod merge;

/// What an FRF relates: displacement, velocity or acceleration to force.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrfKind {
    /// Displacement / force (m/N), `H`.
    Receptance,
    /// Velocity / force (m/s/N), `j w H`.
    Mobility,
    /// Acceleration / force (m/s^2/N), `-w^2 H`.
    Accelerance,
}

impl FrfKind {
    /// Factor `(j w)^p` that turns receptance into this kind.
    pub fn from_receptance_factor(self, omega: f64) -> C64 {
        match self {
            FrfKind::Receptance => C64::new(1.0, 0.0),
            FrfKind::Mobility => C64::new(0.0, omega),
            FrfKind::Accelerance => C64::new(-omega * omega, 0.0),
        }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            FrfKind::Receptance => "receptance",
            FrfKind::Mobility => "mobility",
            FrfKind::Accelerance => "accelerance",
        }
    }

    /// Parses a name (`receptance`, `mobility`, `accelerance` and common synonyms).
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "receptance" | "compliance" | "displacement" | "dynamic compliance" => Some(FrfKind::Receptance),
            "mobility" | "velocity" => Some(FrfKind::Mobility),
            "accelerance" | "inertance" | "acceleration" => Some(FrfKind::Accelerance),
            _ => None,
        }
    }
}

impl fmt::Display for FrfKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a set carries of a noise floor found in its data
/// ([`crate::noise::floor_weights`]): per channel and line, channel-major,
/// the weights and the relative noise of each value, and per channel the
/// spread of the weighted noise.
#[derive(Clone, Debug, PartialEq)]
struct FloorNoise {
    weights: Vec<f64>,
    noise: Vec<f64>,
    spread: Vec<f64>,
}

impl FloorNoise {
    /// The values at lines `idx` of every channel (of `nf` lines), and the
    /// channels `channels` (all when `None`).
    fn pick(&self, nf: usize, idx: Option<&[usize]>, channels: &[usize]) -> FloorNoise {
        let per_value = |v: &Vec<f64>| -> Vec<f64> {
            channels
                .iter()
                .flat_map(|&c| match idx {
                    Some(idx) => idx.iter().map(|&k| v[c * nf + k]).collect::<Vec<_>>(),
                    None => v[c * nf..(c + 1) * nf].to_vec(),
                })
                .collect()
        };
        FloorNoise {
            weights: per_value(&self.weights),
            noise: per_value(&self.noise),
            spread: channels.iter().map(|&c| self.spread[c]).collect(),
        }
    }
}

/// A set of FRFs over common frequency lines.
#[derive(Clone, Debug, PartialEq)]
pub struct FrfSet {
    frequencies_hz: Vec<f64>,
    channels: Vec<Channel>,
    kind: FrfKind,
    /// Channel-major values: `data[c * nf + k]`.
    data: Vec<C64>,
    /// Optional coherence per channel and line, same layout.
    coherence: Option<Vec<f64>>,
    /// Optional weights from an additive noise floor per channel and line,
    /// and the relative noise of each value that the floor's reading
    /// tells, both in the same layout ([`crate::noise::floor_weights`]).
    floor_weights: Option<FloorNoise>,
}

impl FrfSet {
    /// A set of zeros. Frequencies must be positive, finite and increasing;
    /// channels must be distinct.
    pub fn zeros(frequencies_hz: Vec<f64>, channels: Vec<Channel>, kind: FrfKind) -> Result<Self, FrfError> {
        check_frequencies(&frequencies_hz)?;
        // a set, not a scan of the channels before: files with 500,000
        // channels must read in linear time
        let mut seen = HashSet::with_capacity(channels.len());
        if let Some(c) = channels.iter().find(|&&c| !seen.insert(c)) {
            return Err(MismatchError::RepeatedChannel { channel: *c }.into());
        }
        let data = vec![C64::new(0.0, 0.0); frequencies_hz.len() * channels.len()];
        Ok(FrfSet { frequencies_hz, channels, kind, data, coherence: None, floor_weights: None })
    }

    /// Frequency lines (Hz).
    pub fn frequencies_hz(&self) -> &[f64] {
        &self.frequencies_hz
    }

    /// Channels.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// What the values relate.
    pub fn kind(&self) -> FrfKind {
        self.kind
    }

    /// Number of frequency lines.
    pub fn n_freq(&self) -> usize {
        self.frequencies_hz.len()
    }

    /// Values of channel `c` over frequency.
    pub fn channel(&self, c: usize) -> &[C64] {
        let nf = self.n_freq();
        &self.data[c * nf..(c + 1) * nf]
    }

    /// Mutable values of channel `c`.
    pub fn channel_mut(&mut self, c: usize) -> &mut [C64] {
        let nf = self.n_freq();
        &mut self.data[c * nf..(c + 1) * nf]
    }

    /// Value of channel `c` at line `k`.
    pub fn get(&self, c: usize, k: usize) -> C64 {
        self.data[c * self.n_freq() + k]
    }

    /// Sets the value of channel `c` at line `k`.
    pub fn set(&mut self, c: usize, k: usize, v: C64) {
        let nf = self.n_freq();
        self.data[c * nf + k] = v;
    }

    /// Index of a channel.
    pub fn find(&self, channel: Channel) -> Option<usize> {
        self.channels.iter().position(|&c| c == channel)
    }

    /// The index of every channel, for looking up many channels at once
    /// ([`FrfSet::find`] scans the channels each time).
    pub fn channel_indices(&self) -> HashMap<Channel, usize> {
        self.channels.iter().enumerate().map(|(i, &c)| (c, i)).collect()
    }

    /// Coherence of channel `c`, when the data carries it.
    pub fn coherence(&self, c: usize) -> Option<&[f64]> {
        let nf = self.n_freq();
        self.coherence.as_ref().map(|v| &v[c * nf..(c + 1) * nf])
    }

    /// Attaches coherence values (channel-major, same layout as the data).
    pub fn set_coherence(&mut self, values: Vec<f64>) -> Result<(), FrfError> {
        if values.len() != self.data.len() {
            return Err(MismatchError::CoherenceLength { values: values.len(), frfs: self.data.len() }.into());
        }
        self.coherence = Some(values);
        Ok(())
    }

    /// The weight of each line of channel `c` for an additive noise floor
    /// ([`crate::noise::floor_weights`]), when one was attached.
    pub fn floor_weights(&self, c: usize) -> Option<&[f64]> {
        let nf = self.n_freq();
        self.floor_weights.as_ref().map(|f| &f.weights[c * nf..(c + 1) * nf])
    }

    /// The RMS relative noise of each line of channel `c` as the reading
    /// of a noise floor tells it ([`crate::noise::FloorWeights::noise`]:
    /// NaN on a channel without a floor), when floor weights were attached.
    pub fn floor_noise(&self, c: usize) -> Option<&[f64]> {
        let nf = self.n_freq();
        self.floor_weights.as_ref().map(|f| &f.noise[c * nf..(c + 1) * nf])
    }

    /// The spread of channel `c`'s weighted noise
    /// ([`crate::noise::ChannelFloor::spread`]), when floor weights were
    /// attached.
    pub fn floor_spread(&self, c: usize) -> Option<f64> {
        self.floor_weights.as_ref().map(|f| f.spread[c])
    }

    /// The relative noise of every value (channel-major, as
    /// [`FrfSet::floor_noise`] per channel), when floor weights were attached.
    pub fn floor_noise_values(&self) -> Option<&[f64]> {
        self.floor_weights.as_ref().map(|f| &f.noise[..])
    }

    /// Attaches noise-floor weights and the relative noise of each value
    /// (both channel-major, same layout as the data; NaN on a channel
    /// whose noise the floor's reading does not tell), and each channel's
    /// spread of the weighted noise, carried by the sets selected from
    /// this one.
    pub fn set_floor_weights(&mut self, values: Vec<f64>, noise: Vec<f64>, spread: Vec<f64>) -> Result<(), FrfError> {
        if values.len() != self.data.len() || noise.len() != self.data.len() || spread.len() != self.channels.len() {
            let values =
                [values.len(), noise.len()].into_iter().find(|&n| n != self.data.len()).unwrap_or(spread.len());
            return Err(MismatchError::WeightsLength { values, frfs: self.data.len() }.into());
        }
        self.floor_weights = Some(FloorNoise { weights: values, noise, spread });
        Ok(())
    }

    /// The same FRFs converted to receptance (dividing by `j w` or `-w^2`).
    pub fn to_receptance(&self) -> FrfSet {
        self.converted(FrfKind::Receptance)
    }

    /// The same FRFs expressed as another kind.
    pub fn converted(&self, kind: FrfKind) -> FrfSet {
        let mut out = self.clone();
        out.kind = kind;
        let nf = self.n_freq();
        for (k, &f) in self.frequencies_hz.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let factor = kind.from_receptance_factor(w) / self.kind.from_receptance_factor(w);
            for c in 0..self.channels.len() {
                out.data[c * nf + k] = self.data[c * nf + k] * factor;
            }
        }
        out
    }

    /// The lines nearest to the requested frequencies (must exist within
    /// 1e-6 relative), as a new set.
    pub fn at_frequencies(&self, freqs_hz: &[f64]) -> Result<FrfSet, FrfError> {
        let idx: Vec<usize> = freqs_hz
            .iter()
            .map(|&f| self.line_of(f).ok_or(FrfError::Mismatch(MismatchError::NoLine { freq_hz: f })))
            .collect::<Result<_, _>>()?;
        self.select_lines(&idx)
    }

    /// Index of the line at `f` Hz, if there is one within 1e-6 relative.
    pub fn line_of(&self, f: f64) -> Option<usize> {
        let k = self.frequencies_hz.partition_point(|&x| x < f);
        [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter(|&i| i < self.n_freq())
            .find(|&i| (self.frequencies_hz[i] - f).abs() <= 1e-6 * f.abs().max(1e-12))
    }

    /// A new set with the given lines (indices, increasing).
    pub fn select_lines(&self, idx: &[usize]) -> Result<FrfSet, FrfError> {
        let freqs: Vec<f64> = idx.iter().map(|&k| self.frequencies_hz[k]).collect();
        let mut out = FrfSet::zeros(freqs, self.channels.clone(), self.kind)?;
        for c in 0..self.channels.len() {
            for (j, &k) in idx.iter().enumerate() {
                out.set(c, j, self.get(c, k));
            }
        }
        let nf = self.n_freq();
        let pick = |per_line: &Vec<f64>| -> Vec<f64> {
            (0..self.channels.len()).flat_map(|c| idx.iter().map(move |&k| per_line[c * nf + k])).collect()
        };
        out.coherence = self.coherence.as_ref().map(pick);
        let all: Vec<usize> = (0..self.channels.len()).collect();
        out.floor_weights = self.floor_weights.as_ref().map(|f| f.pick(nf, Some(idx), &all));
        Ok(out)
    }

    /// A new set with the given channels (indices).
    pub fn select_channels(&self, idx: &[usize]) -> FrfSet {
        let nf = self.n_freq();
        let channels = idx.iter().map(|&c| self.channels[c]).collect();
        let data = idx.iter().flat_map(|&c| self.channel(c).iter().copied()).collect();
        let pick = |per_line: &Vec<f64>| -> Vec<f64> {
            idx.iter().flat_map(|&c| per_line[c * nf..(c + 1) * nf].iter().copied()).collect()
        };
        let coherence = self.coherence.as_ref().map(pick);
        let floor_weights = self.floor_weights.as_ref().map(|f| f.pick(nf, None, idx));
        FrfSet {
            frequencies_hz: self.frequencies_hz.clone(),
            channels,
            kind: self.kind,
            data,
            coherence,
            floor_weights,
        }
    }

    /// Gives the channels other names (one per channel, in order;
    /// distinct), the values unchanged: a channel whose sensor measured
    /// another DOF than its name says, renamed. Refused, and the set left
    /// as it was, when the names are not one per channel or repeat.
    pub fn rename_channels(&mut self, channels: Vec<Channel>) -> Result<(), FrfError> {
        if channels.len() != self.channels.len() {
            return Err(MismatchError::ChannelCount { names: channels.len(), channels: self.channels.len() }.into());
        }
        let mut seen = HashSet::with_capacity(channels.len());
        if let Some(c) = channels.iter().find(|&&c| !seen.insert(c)) {
            return Err(MismatchError::RepeatedChannel { channel: *c }.into());
        }
        self.channels = channels;
        Ok(())
    }

    /// Distinct reference DOFs, in order of first appearance.
    pub fn references(&self) -> Vec<DofRef> {
        let mut out: Vec<DofRef> = Vec::new();
        let mut seen = HashSet::new();
        for c in &self.channels {
            if seen.insert(c.reference) {
                out.push(c.reference);
            }
        }
        out
    }

    /// All values, channel-major.
    pub fn values(&self) -> &[C64] {
        &self.data
    }
}

pub(crate) fn check_frequencies(f: &[f64]) -> Result<(), FrfError> {
    if let Some(&x) = f.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(FrfError::BadFrequency { freq_hz: x });
    }
    if let Some(w) = f.windows(2).find(|w| !(w[1] > w[0])) {
        return Err(MismatchError::NotIncreasing { before: w[0], after: w[1] }.into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    #[test]
    fn kind_conversion_round_trips_and_uses_powers_of_jw() {
        let ch = vec![Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy))];
        let mut h = FrfSet::zeros(vec![1.0, 10.0], ch, FrfKind::Receptance).unwrap();
        h.set(0, 0, C64::new(1.0, 2.0));
        h.set(0, 1, C64::new(-3.0, 0.5));
        let a = h.converted(FrfKind::Accelerance);
        let w = 2.0 * std::f64::consts::PI * 10.0;
        assert!((a.get(0, 1) - C64::new(-3.0, 0.5) * (-w * w)).norm() < 1e-9);
        let back = a.converted(FrfKind::Mobility).to_receptance();
        for k in 0..2 {
            assert!((back.get(0, k) - h.get(0, k)).norm() < 1e-12);
        }
    }

    #[test]
    fn frequencies_must_increase_and_channels_be_distinct() {
        let c = Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy));
        let mismatch = |r: Result<FrfSet, FrfError>| match r {
            Err(FrfError::Mismatch(m)) => m.to_string(),
            other => panic!("expected a mismatch, got {other:?}"),
        };
        let m = mismatch(FrfSet::zeros(vec![1.0, 1.0], vec![c], FrfKind::Receptance));
        assert!(m.contains("must increase strictly, but 1 Hz is followed by 1 Hz"), "{m}");
        assert_eq!(
            FrfSet::zeros(vec![0.0, 1.0], vec![c], FrfKind::Receptance).unwrap_err(),
            FrfError::BadFrequency { freq_hz: 0.0 }
        );
        assert_eq!(
            FrfSet::zeros(vec![1.0, f64::INFINITY], vec![c], FrfKind::Receptance).unwrap_err(),
            FrfError::BadFrequency { freq_hz: f64::INFINITY }
        );
        let m = mismatch(FrfSet::zeros(vec![1.0, 2.0], vec![c, c], FrfKind::Receptance));
        assert!(m.contains(&format!("channel {c} appears twice")), "{m}");
    }
}

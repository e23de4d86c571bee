//! The unknown gains a case fits (`gains`) and those an earlier update
//! fitted (`fitted_gains`).

use crate::dof::DofRef;

/// Which unknown complex gains the model's FRFs are multiplied by before
/// they are compared with the data (`[measurement] gains`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Gains {
    /// `none`: the data are per newton, compared as they are.
    None,
    /// `per-reference`: one gain per reference (an amplifier's or a force
    /// gauge's unknown sensitivity).
    PerReference,
    /// `per-channel`: one gain per channel (each accelerometer's too).
    PerChannel,
}

impl Gains {
    /// Every setting, in the order of the documentation.
    pub const ALL: [Gains; 3] = [Gains::None, Gains::PerReference, Gains::PerChannel];

    /// The name used in case files.
    pub fn name(self) -> &'static str {
        match self {
            Gains::None => "none",
            Gains::PerReference => "per-reference",
            Gains::PerChannel => "per-channel",
        }
    }

    /// The setting of a case-file name.
    pub fn parse(name: &str) -> Option<Gains> {
        Gains::ALL.into_iter().find(|g| g.name() == name.trim())
    }
}

impl std::fmt::Display for Gains {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What a fitted gain belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GainKey {
    /// A reference (`"1:uy"`).
    Reference(DofRef),
    /// A channel (`"H(31:uy,1:uy)"`): response, reference.
    Channel(DofRef, DofRef),
}

impl GainKey {
    /// What it belongs to, in a word: `reference` or `channel`.
    pub fn noun(&self) -> &'static str {
        match self {
            GainKey::Reference(_) => "reference",
            GainKey::Channel(..) => "channel",
        }
    }
}

impl std::fmt::Display for GainKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GainKey::Reference(r) => write!(f, "{r}"),
            GainKey::Channel(a, b) => write!(f, "H({a},{b})"),
        }
    }
}

impl std::str::FromStr for GainKey {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if let Some(inner) = s.strip_prefix("H(").and_then(|r| r.strip_suffix(')')) {
            let (a, b) = inner.split_once(',').ok_or_else(|| format!("`{s}` is not a channel like H(31:uy,1:uy)"))?;
            return Ok(GainKey::Channel(a.trim().parse()?, b.trim().parse()?));
        }
        Ok(GainKey::Reference(s.parse()?))
    }
}

/// A gain fitted by an earlier update, kept in the case it wrote
/// (`fitted_gains = { "1:uy" = [magnitude, phase_deg] }`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedGain {
    /// Its reference or channel.
    pub key: GainKey,
    /// Magnitude.
    pub magnitude: f64,
    /// Phase (degrees).
    pub phase_deg: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A key reads back from what it writes, and says what it belongs to.
    #[test]
    fn a_gain_key_reads_back_and_names_what_it_belongs_to() {
        for (text, noun) in [("1:uy", "reference"), ("H(31:uy,1:uy)", "channel")] {
            let key: GainKey = text.parse().unwrap();
            assert_eq!((key.to_string().as_str(), key.noun()), (text, noun));
        }
    }
}

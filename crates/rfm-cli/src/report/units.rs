//! What a report's numbers are in: the measured data's quantity and unit
//! (an accelerance per volt is labelled so, not as per newton) and the
//! unit of each model parameter.

use fe_model::DofRef;
use frf::{Channel, FrfKind};

/// The quantity and unit of measured FRFs: their kind, and the references
/// whose data are per volt (uncalibrated, an amplifier's voltage as the
/// reference) rather than per newton.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct DataUnits {
    kind: FrfKind,
    per_volt: Vec<DofRef>,
}

impl DataUnits {
    /// FRFs of `kind`, per volt at the references `per_volt`, per newton at
    /// the others.
    pub(crate) fn new(kind: FrfKind, per_volt: &[DofRef]) -> DataUnits {
        DataUnits { kind, per_volt: per_volt.to_vec() }
    }

    fn per_volt(&self, c: &Channel) -> bool {
        self.per_volt.contains(&c.reference)
    }

    /// The unit of channel `c`'s values: `m/s²/V`, `m/N`, ...
    pub(crate) fn of(&self, c: &Channel) -> String {
        format!("{}/{}", numerator(self.kind), if self.per_volt(c) { "V" } else { "N" })
    }

    /// The unit of every channel of `channels` when they share one, else
    /// both (`m/s²/N or m/s²/V, by reference`).
    pub(crate) fn common(&self, channels: &[Channel]) -> String {
        let volts = channels.iter().filter(|c| self.per_volt(c)).count();
        match volts {
            0 => format!("{}/N", numerator(self.kind)),
            v if v == channels.len() => format!("{}/V", numerator(self.kind)),
            _ => format!("{n}/N or {n}/V, by reference", n = numerator(self.kind)),
        }
    }

    /// The data's quantity in words: `accelerance per volt`, `receptance`,
    /// `accelerance (per volt at reference 5:uy)`.
    pub(crate) fn describe(&self, channels: &[Channel]) -> String {
        let volts: Vec<String> = {
            let mut refs: Vec<DofRef> = channels.iter().filter(|c| self.per_volt(c)).map(|c| c.reference).collect();
            refs.sort();
            refs.dedup();
            refs.iter().map(ToString::to_string).collect()
        };
        match volts.len() {
            0 => self.kind.to_string(),
            _ if channels.iter().all(|c| self.per_volt(c)) => format!("{} per volt", self.kind),
            _ => format!("{} (per volt at reference {})", self.kind, volts.join(", ")),
        }
    }
}

/// The unit of an FRF of `kind` above its reference: `m`, `m/s`, `m/s²`.
fn numerator(kind: FrfKind) -> &'static str {
    match kind {
        FrfKind::Receptance => "m",
        FrfKind::Mobility => "m/s",
        FrfKind::Accelerance => "m/s\u{b2}",
    }
}

/// The unit of a model parameter named as case files name it
/// (`spring.corner.kr`, `group.steel.alpha`, `element.5..8.stiffness`);
/// `-` for a factor on a nominal value, empty when the name is not known.
pub(crate) fn parameter_unit(name: &str) -> &'static str {
    let field = name.rsplit('.').next().unwrap_or("");
    let head = name.split('.').next().unwrap_or("");
    match (head, field) {
        ("group", "alpha") => "s",
        ("group", "beta" | "mu") => "1/s",
        ("group" | "element", _) => "-",
        ("material", "E" | "e") => "Pa",
        ("material", "rho") => "kg/m\u{b3}",
        ("spring", "kx" | "ky" | "kz") => "N/m",
        ("spring", f) if f.starts_with("kr") => "N m/rad",
        ("mass", "m") => "kg",
        ("mass", f) if f.starts_with('J') || f.starts_with('j') => "kg m\u{b2}",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    /// Data per volt are labelled per volt, per newton per newton, and a
    /// set with both says so.
    #[test]
    fn per_volt_data_are_labelled_per_volt() {
        let (a, b) = (DofRef::new(5, Dof::Uy), DofRef::new(9, Dof::Uy));
        let per_volt = Channel::new(a, a);
        let per_newton = Channel::new(a, b);
        let u = DataUnits::new(FrfKind::Accelerance, &[a]);
        assert_eq!(u.of(&per_volt), "m/s²/V");
        assert_eq!(u.of(&per_newton), "m/s²/N");
        assert_eq!(u.common(&[per_volt]), "m/s²/V");
        assert_eq!(u.describe(&[per_volt]), "accelerance per volt");
        assert_eq!(u.common(&[per_volt, per_newton]), "m/s²/N or m/s²/V, by reference");
        assert_eq!(u.describe(&[per_volt, per_newton]), "accelerance (per volt at reference 5:uy)");
        let r = DataUnits::new(FrfKind::Receptance, &[]);
        assert_eq!((r.common(&[per_volt]), r.describe(&[per_volt])), ("m/N".into(), "receptance".into()));
    }

    #[test]
    fn parameters_have_their_units() {
        for (name, unit) in [
            ("spring.corner.kr", "N m/rad"),
            ("spring.clamp.ky", "N/m"),
            ("group.corner.alpha", "s"),
            ("group.steel.beta", "1/s"),
            ("group.water.mu", "1/s"),
            ("group.frame.stiffness", "-"),
            ("element.5..8.stiffness", "-"),
            ("material.steel.E", "Pa"),
            ("material.alu.rho", "kg/m³"),
            ("mass.sensor.m", "kg"),
            ("mass.sensor.jz", "kg m²"),
            ("section.strip.h", ""),
        ] {
            assert_eq!(parameter_unit(name), unit, "{name}");
        }
    }
}

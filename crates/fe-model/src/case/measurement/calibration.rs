//! Force-gauge calibrations (`calibration`): the reference each applies to
//! and the sensitivity with its units.

use super::ChannelMap;
use crate::dof::DofRef;
use crate::error::CaseError;

/// The reference a calibration applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CalibrationTarget {
    /// A model DOF (`"1:uy"`): the reference of channels after mapping.
    Model(DofRef),
    /// A test point as a universal file names it (`"1:+Z"`): node and axis
    /// code (1 to 6, without sign).
    Test(i64, i8),
}

impl std::fmt::Display for CalibrationTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CalibrationTarget::Model(d) => write!(f, "{d}"),
            CalibrationTarget::Test(n, c) => {
                let axis = ["S", "X", "Y", "Z", "RX", "RY", "RZ"].get(usize::from(c.unsigned_abs())).unwrap_or(&"?");
                write!(f, "{n}:{axis}")
            }
        }
    }
}

/// The sensitivity of the transducer behind a per-volt reference:
/// `calibration = { "1:+Z" = "10.2 mV/N" }`. Per-volt values are
/// multiplied by it to become per newton (`H_N = H_V s` with `s` in V/N).
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// The reference it applies to.
    pub target: CalibrationTarget,
    /// The sensitivity in volts per newton.
    pub volts_per_newton: f64,
    /// As written (`10.2 mV/N`), for notes.
    pub text: String,
    /// Where it is written, for messages about it ([`CaseError::with_message`]).
    pub place: CaseError,
}

/// A calibration key: a model DOF (`1:uy`) or a test point (`1:+Z`, `1:Z`).
pub(super) fn calibration_target(key: &str) -> Result<CalibrationTarget, String> {
    if let Ok(d) = key.parse::<DofRef>() {
        return Ok(CalibrationTarget::Model(d));
    }
    let (node, code) = ChannelMap::parse_test_point(key)
        .map_err(|_| format!("calibration key `{key}` is neither a model DOF (`1:uy`) nor a test point (`1:+Z`)"))?;
    if code == 0 {
        return Err(format!("calibration key `{key}` names a scalar channel, which has no force"));
    }
    Ok(CalibrationTarget::Test(node, code.abs()))
}

/// A force gauge's sensitivity with its units, in V/N: `10.2 mV/N`,
/// `0.0102 V/N`, `98 N/V`, `45 mV/lbf`. A number without units is refused:
/// V/N and N/V differ by a factor of ten thousand for a common gauge.
pub(super) fn sensitivity(text: &str) -> Result<f64, String> {
    let bad = |why: &str| {
        format!(
            "calibration `{text}`: {why}; write the sensitivity with its units, e.g. \"10.2 mV/N\", \"0.0102 V/N\" or \
             \"98 N/V\""
        )
    };
    let t = text.trim();
    let split = t.find(|c: char| c.is_alphabetic() || c == 'µ').ok_or_else(|| bad("no units"))?;
    let value: f64 = t[..split].trim().parse().map_err(|_| bad("no number before the units"))?;
    if !(value > 0.0 && value.is_finite()) {
        return Err(bad("the sensitivity must be positive and finite"));
    }
    let units: String = t[split..].chars().filter(|c| !c.is_whitespace()).collect();
    let (num, den) = units.split_once('/').ok_or_else(|| bad("units must be a quotient such as mV/N"))?;
    let volts = |u: &str| match u {
        "V" => Some(1.0),
        "mV" => Some(1e-3),
        "uV" | "µV" | "μV" => Some(1e-6),
        _ => None,
    };
    let newtons = |u: &str| match u {
        "N" => Some(1.0),
        "kN" => Some(1e3),
        "lbf" => Some(4.448_221_615_260_5),
        _ => None,
    };
    match (volts(num), newtons(den), newtons(num), volts(den)) {
        (Some(v), Some(n), _, _) => Ok(value * v / n),
        (_, _, Some(n), Some(v)) => Ok(v / (value * n)),
        _ => Err(bad(&format!("`{units}` is not volts per force or force per volt (V, mV, uV; N, kN, lbf)"))),
    }
}

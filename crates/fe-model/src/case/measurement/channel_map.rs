//! The map of test points and directions to model DOFs (`[[measurement.map]]`).

use crate::dof::DofRef;

/// Mapping of a test point and direction to a model DOF: the unit vector of
/// the test direction `test` equals `sign` times the model DOF `model`.
///
/// A measured FRF whose response or reference is at `test` is multiplied by
/// the direction's sign (`-Z` counts -1) and by `sign`, once for the response
/// and once for the reference. Without an entry, measurement readers map
/// `X`, `Y`, `RZ` to `ux`, `uy`, `rz` of the same node (see
/// `docs/measured-data.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelMap {
    /// Test point and direction as written in the measurement file, e.g. `101:+Y`.
    pub test: String,
    /// Model DOF.
    pub model: DofRef,
    /// +1 or -1.
    pub sign: f64,
}

impl ChannelMap {
    /// Parses a test point `node:direction` into the node and a signed
    /// direction code: `X`, `Y`, `Z`, `RX`, `RY`, `RZ` are 1 to 6 (the codes
    /// of UFF dataset 58), negative with a leading `-`; `S` (scalar) is 0.
    /// Letters are case-insensitive, `+` is optional, and the numeric codes
    /// themselves (`101:-3`) are accepted.
    pub fn parse_test_point(s: &str) -> Result<(i64, i8), String> {
        let bad = || {
            format!(
                "`{s}` is not a test point; write node:direction, e.g. `101:+Z` \
                 (directions X, Y, Z, RX, RY, RZ with an optional sign, or S for scalar)"
            )
        };
        let (node, dir) = s.trim().split_once(':').ok_or_else(bad)?;
        let node: i64 = node.trim().parse().map_err(|_| bad())?;
        let dir = dir.trim().to_ascii_uppercase();
        let (sign, axis) = match dir.strip_prefix('-') {
            Some(rest) => (-1, rest),
            None => (1, dir.strip_prefix('+').unwrap_or(&dir)),
        };
        let code: i8 = match axis {
            "X" => 1,
            "Y" => 2,
            "Z" => 3,
            "RX" => 4,
            "RY" => 5,
            "RZ" => 6,
            "S" | "SCALAR" => 0,
            digits => match digits.parse::<i8>() {
                Ok(c) if (0..=6).contains(&c) => c,
                _ => return Err(bad()),
            },
        };
        Ok((node, sign * code))
    }

    /// The node and signed direction code of `test` (see [`ChannelMap::parse_test_point`]).
    pub fn test_point(&self) -> Result<(i64, i8), String> {
        Self::parse_test_point(&self.test)
    }
}

//! From test points and directions to model DOFs.
//!
//! A measured FRF relates a response along a test direction to a force along
//! another. Each test direction `d` at node `n` is the model DOF `m` times a
//! sign `s` (`d = s m`), so that `H_test = s_response s_reference H_model`.
//!
//! - A `[[measurement.map]]` entry whose `test` names the same node and axis
//!   gives `m` and `s = (sign of the file's direction) (sign of the entry's
//!   direction) sign`. `test = "101:-Z"` thus says "the test's -Z axis at 101
//!   is the model DOF"; a file direction `+Z` at node 101 then counts -1.
//! - Without an entry, `X`, `Y` and `RZ` map to `ux`, `uy` and `rz` of the
//!   node with the same number, with the sign of the file's direction, and
//!   in a 3D model `Z`, `RX`, `RY` to `uz`, `rx`, `ry`.
//! - In a planar model `Z`, `RX`, `RY` leave the model's x-y plane, and
//!   scalar channels have no direction: they need an entry; the error says
//!   which line to add.

use fe_model::case::ChannelMap;
use fe_model::{Dimension, Dof, DofRef};

use super::{Direction, TestDof};

/// The model DOF a test DOF measures in a planar model, and the sign:
/// `test = sign * model` (see [`map_test_dof_in`]).
pub fn map_test_dof(dof: TestDof, map: &[ChannelMap]) -> Result<(DofRef, f64), String> {
    map_test_dof_in(dof, map, Dimension::Planar)
}

/// The model DOF a test DOF measures in a model of dimension `dim`, and the
/// sign: `test = sign * model`. The error message names the test DOF and
/// suggests the map entry to add.
pub fn map_test_dof_in(dof: TestDof, map: &[ChannelMap], dim: Dimension) -> Result<(DofRef, f64), String> {
    for entry in map {
        let (node, code) = entry.test_point().map_err(|e| format!("map entry `{}`: {e}", entry.test))?;
        if node == dof.node && code.abs() == dof.direction.code().abs() {
            let entry_sign = if code < 0 { -1.0 } else { 1.0 };
            return Ok((entry.model, dof.direction.sign() * entry_sign * entry.sign));
        }
    }
    let model_dof = match dof.direction.axis() {
        Direction::X => Some(Dof::Ux),
        Direction::Y => Some(Dof::Uy),
        Direction::Z => Some(Dof::Uz),
        Direction::RX => Some(Dof::Rx),
        Direction::RY => Some(Dof::Ry),
        Direction::RZ => Some(Dof::Rz),
        _ => None,
    }
    .filter(|&d| dim.local(d).is_some());
    let suggestion = |model: &str| {
        format!(
            "add to the case file's [measurement] section:\n    [[measurement.map]]\n    test = \"{}:{}\"\n    \
             model = \"{model}\"   # the model DOF this test direction measures\n    sign = 1",
            dof.node,
            dof.direction.axis()
        )
    };
    let Some(model_dof) = model_dof else {
        let guess =
            if dof.direction.axis() == Direction::Z || dof.direction == Direction::SCALAR { "uy" } else { "rz" };
        let what = if dof.direction == Direction::SCALAR {
            "is a scalar channel (no direction)".to_string()
        } else {
            format!("is along {}, outside the model's x-y plane", dof.direction.axis_name())
        };
        return Err(format!(
            "test DOF {dof} {what}, and no [[measurement.map]] entry maps it; {}",
            suggestion(&format!("{}:{guess}", dof.node.max(0)))
        ));
    };
    let node = u32::try_from(dof.node).map_err(|_| {
        format!(
            "test node {} cannot be a model node number; map {dof} explicitly; {}",
            dof.node,
            suggestion(&format!("1:{}", model_dof.name()))
        )
    })?;
    Ok((DofRef::new(node, model_dof), dof.direction.sign()))
}

/// The test DOF a writer uses for a model DOF: `ux`, `uy`, `uz`, `rx`,
/// `ry`, `rz` as `+X`, `+Y`, `+Z`, `+RX`, `+RY`, `+RZ` of the same node (the
/// inverse of the default mapping).
pub fn model_to_test_dof(dof: DofRef) -> TestDof {
    let direction = match dof.dof {
        Dof::Ux => Direction::X,
        Dof::Uy => Direction::Y,
        Dof::Uz => Direction::Z,
        Dof::Rx => Direction::RX,
        Dof::Ry => Direction::RY,
        Dof::Rz => Direction::RZ,
    };
    TestDof::new(i64::from(dof.node.0), direction)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(test: &str, model: &str, sign: f64) -> ChannelMap {
        ChannelMap { test: test.into(), model: model.parse().unwrap(), sign }
    }

    fn t(s: &str) -> TestDof {
        s.parse().unwrap()
    }

    #[test]
    fn default_mapping_keeps_node_and_direction_sign() {
        assert_eq!(map_test_dof(t("7:+Y"), &[]), Ok((DofRef::new(7, Dof::Uy), 1.0)));
        assert_eq!(map_test_dof(t("7:-X"), &[]), Ok((DofRef::new(7, Dof::Ux), -1.0)));
        assert_eq!(map_test_dof(t("7:-RZ"), &[]), Ok((DofRef::new(7, Dof::Rz), -1.0)));
        for dof in [DofRef::new(3, Dof::Ux), DofRef::new(3, Dof::Uy), DofRef::new(3, Dof::Rz)] {
            assert_eq!(map_test_dof(model_to_test_dof(dof), &[]), Ok((dof, 1.0)));
        }
    }

    #[test]
    fn a_3d_model_maps_every_direction_by_default() {
        for dof in Dof::SPATIAL.map(|d| DofRef::new(4, d)) {
            assert_eq!(map_test_dof_in(model_to_test_dof(dof), &[], Dimension::Spatial), Ok((dof, 1.0)));
        }
        assert_eq!(map_test_dof_in(t("4:-Z"), &[], Dimension::Spatial), Ok((DofRef::new(4, Dof::Uz), -1.0)));
        assert!(map_test_dof_in(t("0:S"), &[], Dimension::Spatial).unwrap_err().contains("scalar"));
    }

    #[test]
    fn map_entries_combine_three_signs() {
        let map = [entry("101:+Z", "2:uy", 1.0), entry("102:-Z", "3:uy", 1.0), entry("103:Y", "4:uy", -1.0)];
        assert_eq!(map_test_dof(t("101:+Z"), &map), Ok((DofRef::new(2, Dof::Uy), 1.0)));
        assert_eq!(map_test_dof(t("101:-Z"), &map), Ok((DofRef::new(2, Dof::Uy), -1.0)));
        assert_eq!(map_test_dof(t("102:+Z"), &map), Ok((DofRef::new(3, Dof::Uy), -1.0)));
        assert_eq!(map_test_dof(t("102:-Z"), &map), Ok((DofRef::new(3, Dof::Uy), 1.0)));
        assert_eq!(map_test_dof(t("103:-Y"), &map), Ok((DofRef::new(4, Dof::Uy), 1.0)));
        // an entry overrides the default for in-plane directions too
        assert_eq!(map_test_dof(t("103:+Y"), &map), Ok((DofRef::new(4, Dof::Uy), -1.0)));
    }

    #[test]
    fn out_of_plane_directions_need_an_entry_and_the_error_says_which() {
        let e = map_test_dof(t("101:-Z"), &[]).unwrap_err();
        assert!(e.contains("test DOF 101:-Z is along Z"), "{e}");
        assert!(e.contains("test = \"101:+Z\"") && e.contains("model = \"101:uy\""), "{e}");
        let e = map_test_dof(t("5:+RX"), &[]).unwrap_err();
        assert!(e.contains("model = \"5:rz\""), "{e}");
        let e = map_test_dof(t("0:S"), &[]).unwrap_err();
        assert!(e.contains("scalar"), "{e}");
        let e = map_test_dof(t("-1:+Y"), &[]).unwrap_err();
        assert!(e.contains("test node -1"), "{e}");
    }
}

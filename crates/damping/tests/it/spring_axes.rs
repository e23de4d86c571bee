//! Springs in their own axes (`Model::orient_spring`): a table in space
//! whose corner joint and one foot are springs with a different stiffness
//! in each direction, turned in space with its springs' axes turned with
//! it, keeps its frequencies to 1e-9; the springs in the global axes of the
//! turned table do not.

use damping::normal_modes;
use fe_model::{Assembly, Dimension, Dof, Group, Model, Section};

use super::frames_3d::rotation;

/// The spring axes of the table before it is turned: `None` for the global
/// axes, or a local x axis and a vector in the local x-y plane.
type Axes = Option<([f64; 3], [f64; 3])>;

/// A table in space, as in `frames_3d`, with a joint at one corner and one
/// leg standing on a ground spring instead of a clamp, both stiffer in some
/// directions than in others; every point turned by `rot`, and the springs'
/// axes too when `turn_axes` (else they stay as given, in global components).
fn table(rot: &dyn Fn([f64; 3]) -> [f64; 3], axes: Axes, turn_axes: bool) -> Model {
    let mut m = Model::with_dimension("table on springs", Dimension::Spatial);
    let frame = m.add_group(Group::new("frame")).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    m.set_poisson(steel, 0.3).unwrap();
    let leg = m.add_section(Section::rectangle("leg", 0.03, 0.02)).unwrap();
    let rail = m.add_section(Section::spatial("rail", 6e-4, 2e-8, 9e-8, 4e-8)).unwrap();
    let (w, d, h) = (0.8, 0.5, 0.7);
    let corners = [[0.0, 0.0], [w, 0.0], [w, d], [0.0, d]];
    for (i, c) in corners.iter().enumerate() {
        let i = i as u32;
        m.add_node_at(10 + i, rot([c[0], c[1], 0.0])).unwrap();
        m.add_node_at(20 + i, rot([c[0], c[1], h])).unwrap();
        if i != 3 {
            m.add_support(10 + i, &Dof::SPATIAL).unwrap();
        }
        let b = m.add_beam(1 + i, [10 + i, 20 + i], steel, leg, frame).unwrap();
        m.orient_beam(b, Some(rot([1.0, 0.3, 0.0])), 0.0).unwrap();
    }
    m.add_node_at(30, rot([w, 0.0, h])).unwrap();
    let joint = m.add_spring("joint", 21, Some(30), [4e6, 1e6, 2.5e5, 3e3, 1.2e3, 600.0], frame).unwrap();
    let foot = m.add_spring("foot", 13, None, [3e6, 8e5, 5e6, 2e4, 5e3, 1e3], frame).unwrap();
    for (k, (a, b)) in [(20, 30), (21, 22), (22, 23), (23, 20)].into_iter().enumerate() {
        let e = m.add_beam(5 + k as u32, [a, b], steel, rail, frame).unwrap();
        m.orient_beam(e, Some(rot([0.0, 0.0, 1.0])), 0.3).unwrap();
    }
    m.add_mass("sensor", 22, 0.4, [2e-4, 2e-4, 2e-4], frame).unwrap();
    // the global axes turned, or the given ones
    let (x, xy) = axes.unwrap_or(([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]));
    let (x, xy) = if turn_axes { (rot(x), rot(xy)) } else { (x, xy) };
    if axes.is_some() || turn_axes {
        for s in [joint, foot] {
            m.orient_spring(s, x, xy).unwrap();
        }
    }
    m
}

fn frequencies(m: &Model) -> Vec<f64> {
    normal_modes(&Assembly::new(m).unwrap()).unwrap().frequencies_hz
}

/// The largest difference of two lists of frequencies relative to each.
fn worst(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / x).fold(0.0, f64::max)
}

#[test]
fn a_table_on_springs_turned_with_their_axes_keeps_its_frequencies() {
    let identity = |p: [f64; 3]| p;
    let oblique: Axes = Some(([1.0, 1.0, 0.2], [0.0, 0.3, 1.0]));
    for axes in [None, oblique] {
        // the springs in global axes (None) or their own, on the table as built
        let reference = frequencies(&table(&identity, axes, false));
        assert!(reference.len() > 20);
        for (axis, angle) in [([1.0, 2.0, 3.0], 0.7), ([0.0, 0.0, 1.0], 2.1), ([-1.0, 0.5, 0.2], -1.3)] {
            let rot = rotation(axis, angle);
            let turned = frequencies(&table(&rot, axes, true));
            let e = worst(&reference, &turned);
            assert!(e <= 1e-9, "axes {axes:?}, turned about {axis:?} by {angle}: frequencies differ by {e:e}");
            // the springs left in the axes they were given: another table
            let unturned = frequencies(&table(&rot, axes, false));
            let e = worst(&reference, &unturned);
            assert!(e > 1e-4, "axes {axes:?}, turned about {axis:?}: the test would not see wrong axes ({e:e})");
        }
    }
}

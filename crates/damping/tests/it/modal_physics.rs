//! Undamped modal physics of the element formulation against independent truths.

use damping::normal_modes;
use fe_model::{Assembly, Dof, Group, Model, Section, samples};

/// beta_n L of a clamped-free Euler-Bernoulli beam.
const BETA_L: [f64; 4] = [1.875_104_068_7, 4.694_091_132_9, 7.854_757_438_2, 10.995_540_734_9];

#[test]
fn cantilever_frequencies_match_euler_bernoulli() {
    let model = samples::cantilever(30);
    let a = Assembly::new(&model).unwrap();
    let modes = normal_modes(&a).unwrap();
    let (e, rho, b, h, l): (f64, f64, f64, f64, f64) = (2.0e11, 7800.0, 0.05, 0.01, 1.0);
    let (area, inertia) = (b * h, b * h * h * h / 12.0);
    // Bending modes only: the axial modes of this bar lie far above the fourth
    // bending mode, so the lowest four computed modes are bending modes.
    for (n, bl) in BETA_L.iter().enumerate() {
        let exact = bl * bl / (2.0 * std::f64::consts::PI * l * l) * (e * inertia / (rho * area)).sqrt();
        let fe = modes.frequencies_hz[n];
        let err = (fe - exact).abs() / exact;
        assert!(err < 1e-3, "mode {}: FE {fe:.4} Hz, analytic {exact:.4} Hz, error {err:.2e}", n + 1);
    }
}

/// The L-frame of `samples::frame_with_joint`, with every node rotated by `theta`.
fn rotated_frame(theta: f64) -> Model {
    let (c, s) = (theta.cos(), theta.sin());
    let rot = |x: f64, y: f64| (c * x - s * y, s * x + c * y);
    let mut m = Model::new("rotated L-frame");
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joint = m.add_group(Group::new("joint").rayleigh(1e-3, 0.0).relaxation(300.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("square", 0.03, 0.03)).unwrap();
    for (id, x, y) in [(1, 0.0, 0.0), (2, 0.0, 1.0), (3, 0.0, 1.0), (4, 1.0, 1.0)] {
        let (x, y) = rot(x, y);
        m.add_node(id, x, y).unwrap();
    }
    m.add_beam(1, [1, 2], steel, sec, frame).unwrap();
    m.add_beam(2, [3, 4], steel, sec, frame).unwrap();
    m.add_spring("joint", 2, Some(3), [0.0, 0.0, 2.0e5], joint).unwrap();
    m.add_tie(2, 3, &[Dof::Ux, Dof::Uy]).unwrap();
    m.add_mass("tip", 4, 0.5, 1e-4, frame).unwrap();
    m.add_support(1, &Dof::ALL).unwrap();
    m
}

#[test]
fn frame_frequencies_are_invariant_under_rotating_the_structure() {
    let reference = normal_modes(&Assembly::new(&samples::frame_with_joint()).unwrap()).unwrap();
    for theta in [0.3, 1.0, 2.5, -0.7] {
        let rotated = normal_modes(&Assembly::new(&rotated_frame(theta)).unwrap()).unwrap();
        for (a, b) in reference.frequencies_hz.iter().zip(&rotated.frequencies_hz) {
            assert!((a - b).abs() <= 1e-9 * a, "theta {theta}: {a} Hz vs {b} Hz");
        }
    }
}

/// A portal-like bent beam: column 1-2 and arm 2-3 (rigid corner), or with
/// the arm starting at a coincident node 4 joined to 2 by springs.
fn corner(joined_by: Option<f64>) -> Model {
    let mut m = Model::new("corner");
    let g = m.add_group(Group::new("g")).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("sq", 0.04, 0.04)).unwrap();
    m.add_node(1, 0.0, 0.0).unwrap();
    m.add_node(2, 0.0, 0.8).unwrap();
    m.add_node(3, 0.6, 0.8).unwrap();
    m.add_beam(1, [1, 2], steel, sec, g).unwrap();
    match joined_by {
        None => {
            m.add_beam(2, [2, 3], steel, sec, g).unwrap();
        }
        Some(k) => {
            m.add_node(4, 0.0, 0.8).unwrap();
            m.add_beam(2, [4, 3], steel, sec, g).unwrap();
            m.add_spring("joint", 2, Some(4), [k, k, k], g).unwrap();
        }
    }
    m.add_support(1, &Dof::ALL).unwrap();
    m
}

#[test]
fn very_stiff_joint_springs_reproduce_the_rigid_corner() {
    let rigid = normal_modes(&Assembly::new(&corner(None)).unwrap()).unwrap();
    let sprung = normal_modes(&Assembly::new(&corner(Some(1e14))).unwrap()).unwrap();
    // The sprung model has 3 extra DOFs whose modes are at the spring's
    // (very high) frequency; the structural modes must agree.
    for (k, (a, b)) in rigid.frequencies_hz.iter().zip(&sprung.frequencies_hz).take(6).enumerate() {
        assert!((a - b).abs() <= 1e-6 * a, "mode {}: rigid {a} Hz vs sprung {b} Hz", k + 1);
    }
    // and a soft joint must lower the first frequency
    let soft = normal_modes(&Assembly::new(&corner(Some(1e3))).unwrap()).unwrap();
    assert!(soft.frequencies_hz[0] < 0.9 * rigid.frequencies_hz[0]);
}

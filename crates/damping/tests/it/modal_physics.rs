//! Undamped modal physics of the element formulation against independent truths.

use damping::normal_modes;
use fe_model::{Assembly, Dof, Group, Model, Section, samples};

/// beta_n L of a clamped-free Euler-Bernoulli beam: the roots of
/// `cos(x) cosh(x) = -1`.
pub(crate) const BETA_L: [f64; 6] = [
    1.875_104_068_711_961,
    4.694_091_132_974_175,
    7.854_757_438_237_613,
    10.995_540_734_875_467,
    14.137_168_391_046_47,
    17.278_759_532_088_236,
];

#[test]
fn the_beta_l_table_solves_the_cantilever_frequency_equation() {
    for x in BETA_L {
        // relative to the size of cosh(x), which reaches 1.6e7 for mode 6
        assert!((x.cos() * x.cosh() + 1.0).abs() <= 1e-14 * x.cosh(), "{x}");
    }
}

/// Each of the first six bending frequencies of a 30-element cantilever lies
/// above the exact one (the consistent mass makes the element conforming, so
/// Rayleigh-Ritz bounds it from above) by the leading discretisation error
/// of cubic Hermite elements with consistent mass, `(beta_n h)^4 / 1440`
/// relative, to 5 %. The errors range from 1e-8 (mode 1) to 8e-5 (mode 6):
/// a wrong mass or stiffness coefficient moves them by far more.
#[test]
fn cantilever_frequencies_match_euler_bernoulli() {
    let n = 30;
    let model = samples::cantilever(n);
    let a = Assembly::new(&model).unwrap();
    let modes = normal_modes(&a).unwrap();
    let (e, rho, b, h, l): (f64, f64, f64, f64, f64) = (2.0e11, 7800.0, 0.05, 0.01, 1.0);
    let (area, inertia) = (b * h, b * h * h * h / 12.0);
    // Bending modes only: the axial modes of this bar lie far above the sixth
    // bending mode, so the lowest six computed modes are bending modes.
    for (k, bl) in BETA_L.iter().enumerate() {
        let exact = bl * bl / (2.0 * std::f64::consts::PI * l * l) * (e * inertia / (rho * area)).sqrt();
        let fe = modes.frequencies_hz[k];
        let err = (fe - exact) / exact;
        let expected = (bl / n as f64).powi(4) / 1440.0;
        assert!(
            (err / expected - 1.0).abs() < 0.05,
            "mode {}: FE {fe:.9} Hz, analytic {exact:.9} Hz, error {err:.3e}, expected {expected:.3e}",
            k + 1
        );
    }
}

#[test]
fn frame_frequencies_are_invariant_under_rotating_the_structure() {
    let reference = normal_modes(&Assembly::new(&samples::frame_with_joint()).unwrap()).unwrap();
    for theta in [0.3, 1.0, 2.5, -0.7] {
        let rotated = normal_modes(&Assembly::new(&samples::frame_with_joint_turned(theta)).unwrap()).unwrap();
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
    m.add_support(1, &Dof::PLANAR).unwrap();
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

/// `Model::refined` against the same beam meshed finer from the start: a
/// 10-element cantilever split in three has the frequencies of a
/// 30-element one to round-off, its mass unchanged, and its error against
/// Euler-Bernoulli down by the `h^4` of cubic Hermite elements (3^4 = 81,
/// to 5 % on modes 1 and 2, where the leading term rules).
#[test]
fn a_refined_mesh_is_the_finer_mesh() {
    let coarse = samples::cantilever(10);
    let refined = coarse.refined(3).unwrap();
    let direct = samples::cantilever(30);
    assert_eq!((refined.beams().len(), refined.nodes().len()), (30, direct.nodes().len()));
    assert!((refined.total_mass() - coarse.total_mass()).abs() <= 1e-12 * coarse.total_mass());
    let f = |m: &Model| normal_modes(&Assembly::new(m).unwrap()).unwrap().frequencies_hz;
    let (fc, fr, fd) = (f(&coarse), f(&refined), f(&direct));
    for (a, b) in fr.iter().zip(&fd) {
        assert!((a - b).abs() <= 1e-9 * b, "refined {a} Hz, meshed finer {b} Hz");
    }
    let (e, rho, b, h, l): (f64, f64, f64, f64, f64) = (2.0e11, 7800.0, 0.05, 0.01, 1.0);
    let (area, inertia) = (b * h, b * h * h * h / 12.0);
    for (k, bl) in BETA_L.iter().take(2).enumerate() {
        let exact = bl * bl / (2.0 * std::f64::consts::PI * l * l) * (e * inertia / (rho * area)).sqrt();
        let ratio = (fc[k] - exact) / (fr[k] - exact);
        assert!((ratio / 81.0 - 1.0).abs() < 0.05, "mode {}: error falls {ratio:.1} times", k + 1);
    }
    // ids: the first piece keeps the beam's, the rest are new and distinct
    for b in coarse.beams() {
        assert!(refined.beam_index(b.id).is_some());
    }
    assert_eq!(coarse.refined(1).unwrap().beams().len(), 10);
}

/// In space, each piece of a refined beam keeps its section's orientation
/// (the same local axes as its beam), and the refined portal's modes lie
/// below the coarse one's (Rayleigh-Ritz: a finer conforming mesh can only
/// lower them) by less than the lowest mode's own spacing.
#[test]
fn a_refined_space_frame_keeps_its_sections_turned() {
    let coarse = samples::space_portal();
    let refined = coarse.refined(2).unwrap();
    assert_eq!(refined.beams().len(), 2 * coarse.beams().len());
    for (i, b) in coarse.beams().iter().enumerate() {
        let axes = coarse.beam_axes(i);
        let first = refined.beam_index(b.id).unwrap();
        for (r, row) in refined.beam_axes(first).iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!((v - axes[r][c]).abs() < 1e-12, "element {}: axis {r} moved", b.id);
            }
        }
    }
    let f = |m: &Model| normal_modes(&Assembly::new(m).unwrap()).unwrap().frequencies_hz;
    let (fc, fr) = (f(&coarse), f(&refined));
    for k in 0..6 {
        assert!(fr[k] <= fc[k] * (1.0 + 1e-12) && fr[k] > 0.9 * fc[k], "mode {}: {} -> {} Hz", k + 1, fc[k], fr[k]);
    }
}

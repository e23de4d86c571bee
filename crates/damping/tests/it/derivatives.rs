//! The derivatives of `Z(w)` with respect to every kind of quantity against
//! Richardson-extrapolated central differences of `Z` (or of `j w G(w)`).

use damping::DampedSystem;
use fe_model::{Quantity, samples};
use num_complex::Complex64 as C64;

/// `p dZ/dp` of quantity `q` at `omega` by Richardson-extrapolated central
/// differences (steps of 2 % and 1 % of its value): a large step keeps
/// round-off small even where the derivative is tiny beside `Z` (a rotary
/// inertia at low frequency), and extrapolation removes the step's
/// truncation error. With `via_g` the differences are taken of `j w G(w)`
/// alone, without the stiffness and mass beside it: on a slender beam the
/// damping terms are 1e-7 of `Z` and less, below what a difference of `Z`
/// resolves.
pub(crate) fn by_differences(sys: &DampedSystem, q: Quantity, omega: f64, via_g: bool) -> Vec<C64> {
    let p = sys.get(q);
    let of = |s: &DampedSystem| -> Vec<C64> {
        if via_g { s.g_values(omega).iter().map(|g| C64::new(0.0, omega) * g).collect() } else { s.z_values(omega) }
    };
    let central = |h: f64| -> Vec<C64> {
        let mut plus = sys.clone();
        plus.set(q, p + h).unwrap();
        let mut minus = sys.clone();
        minus.set(q, p - h).unwrap();
        let (zp, zm) = (of(&plus), of(&minus));
        zp.iter().zip(&zm).map(|(a, b)| (a - b) / (2.0 * h) * p).collect()
    };
    let (d1, d2) = (central(0.02 * p), central(0.01 * p));
    d1.iter().zip(&d2).map(|(a, b)| (4.0 * b - a) / 3.0).collect()
}

/// The largest difference of `a` from `b` relative to `b`'s largest entry,
/// which must not be zero (a derivative that changes nothing passes any
/// relative test).
pub(crate) fn relative_error(a: &[C64], b: &[C64]) -> f64 {
    // a zip would pass over a missing vector (an empty G or Z) as equal
    assert_eq!(a.len(), b.len(), "the vectors compared differ in length");
    let scale = b.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(scale > 0.0, "the derivative is zero");
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
}

/// Every kind of quantity, on a model that has all of them, against a
/// central finite difference of Z; the damping parameters also on the
/// two-material beam, whose groups are non-viscous with both alpha and
/// beta (the frame's only beta is viscous, where the kernel factor is 1
/// and a wrong use of it would pass).
#[test]
fn every_parameter_derivative_matches_central_finite_difference() {
    let mut model = samples::frame_with_joint();
    let beam = model.quantity("element.2.added_mass").unwrap();
    model.set(beam, 3.0).unwrap();
    let frame = DampedSystem::new(model).unwrap();
    let beam = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let frame_names = [
        "group.joint.alpha",
        "group.frame.beta",
        "group.frame.alpha",
        "group.joint.mu",
        "group.frame.stiffness",
        "group.frame.mass",
        "group.joint.stiffness",
        "material.steel.E",
        "material.steel.rho",
        "element.1.stiffness",
        "element.2.mass",
        "element.2.added_mass",
        "spring.joint.kr",
        "mass.tip.m",
        "mass.tip.j",
    ];
    let beam_names = ["group.steel.beta", "group.aluminium.beta", "group.steel.alpha", "group.aluminium.mu"];
    // a frame in space: torsion through E, springs and inertias about three axes
    let mut model = samples::space_portal();
    let arm = model.quantity("element.5.added_mass").unwrap();
    model.set(arm, 2.0).unwrap();
    let portal = DampedSystem::new(model).unwrap();
    let portal_names = [
        "group.joint.alpha",
        "group.joint.mu",
        "group.frame.beta",
        "material.steel.E",
        "material.steel.rho",
        "element.5.stiffness",
        "element.5.added_mass",
        "spring.joint.krx",
        "spring.joint.kry",
        "spring.joint.krz",
        "spring.foot.kz",
        "mass.tip.m",
        "mass.tip.jx",
        "mass.tip.jy",
        "mass.tip.jz",
    ];
    // on the slender beam the damping is taken apart from Z (see by_differences)
    let cases =
        [(&frame, &frame_names[..], false), (&beam, &beam_names[..], true), (&portal, &portal_names[..], false)];
    for &(sys, names, via_g) in &cases {
        for (omega, name) in [30.0, 900.0, 5000.0].iter().flat_map(|&w| names.iter().map(move |&n| (w, n))) {
            let q = sys.model().quantity(name).unwrap();
            let analytic = sys.derivative(q, omega).values(sys.assembly());
            let err = relative_error(&by_differences(sys, q, omega, via_g), &analytic);
            assert!(err < 1e-6, "{name} at w = {omega}: relative error {err:e}");
        }
    }
}

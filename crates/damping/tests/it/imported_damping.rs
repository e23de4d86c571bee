//! An imported viscous damping matrix (`[[imported.groups]] damping`): its
//! factor's derivative against finite differences, and the complex modes
//! of a model damped by it against those of the native model it copies.

use damping::{DampedSystem, complex_modes};

use crate::derivatives::{by_differences, relative_error};
use fe_model::imported::{ImportedKind, SymmetricCoo, export};
use fe_model::{Assembly, MatrixKind, Model, samples};
use num_complex::Complex64 as C64;

/// `native` imported, with each group's `alpha K_g + beta M_g` moved into
/// a damping matrix of the group (its alpha and beta then zero). Only for
/// viscous groups is this the same model.
fn with_damping_matrices(native: &Model) -> Model {
    let a = Assembly::new(native).unwrap();
    let exported = export::export(native, &a);
    let mut m = export::as_imported(native).unwrap();
    for (g, group) in native.groups().iter().enumerate() {
        let (k, mass) = (a.group_values(g, MatrixKind::Stiffness), a.group_values(g, MatrixKind::Mass));
        let c: Vec<f64> = k.iter().zip(&mass).map(|(k, m)| group.alpha * k + group.beta * m).collect();
        let c = SymmetricCoo::lower_of(a.pattern(), &c);
        if c.entries.is_empty() {
            continue;
        }
        m.add_imported(g, ImportedKind::Damping, &exported.dofs, &c).unwrap();
        for field in ["alpha", "beta"] {
            let q = m.quantity(&format!("group.{}.{field}", group.name)).unwrap();
            m.set(q, 0.0).unwrap();
        }
    }
    m
}

/// `(dZ/dq) q` of the damping factor, and of the group parameters beside
/// it, against Richardson-extrapolated central differences of `Z`, on the
/// portal whose frame's damping is a matrix and whose joint is non-viscous.
#[test]
fn the_damping_factor_derivative_matches_central_finite_differences() {
    let native = samples::space_portal();
    let a = Assembly::new(&native).unwrap();
    let exported = export::export(&native, &a);
    let mut model = export::as_imported(&native).unwrap();
    // a damping matrix on the frame that is not proportional to its K or M:
    // the joint group's stiffness, and a dashpot on one DOF
    let j = native.group_index("joint").unwrap();
    let stiffness = a.group_values(j, MatrixKind::Stiffness);
    let mut c = SymmetricCoo::lower_of(a.pattern(), &stiffness.iter().map(|k| 4e-4 * k).collect::<Vec<_>>());
    c.entries.push((3, 3, 25.0));
    let f = model.group_index("frame").unwrap();
    model.add_imported(f, ImportedKind::Damping, &exported.dofs, &c).unwrap();
    let q = model.quantity("group.frame.damping").unwrap();
    model.set(q, 1.7).unwrap();
    let sys = DampedSystem::new(model).unwrap();
    let names =
        ["group.frame.damping", "group.frame.alpha", "group.frame.beta", "group.frame.stiffness", "group.joint.mu"];
    for omega in [30.0, 900.0, 5000.0] {
        for name in names {
            let q = sys.model().quantity(name).unwrap();
            let analytic = sys.derivative(q, omega).values(sys.assembly());
            let err = relative_error(&by_differences(&sys, q, omega, false), &analytic);
            assert!(err < 1e-6, "{name} at w = {omega}: relative error {err:e}");
        }
    }
    // the factor acts on the damping matrix alone: its derivative is j w C
    let d = sys.derivative(q, 900.0);
    assert!(d.terms.iter().all(|&(b, t, c)| {
        sys.assembly().blocks()[b].terms()[t].kind() == MatrixKind::Damping && c == C64::new(0.0, 900.0)
    }));
}

/// The complex modes of the viscous portal (its joint made viscous), and
/// of the same portal imported with every group's damping as a damping
/// matrix, are the same.
#[test]
fn complex_modes_with_a_damping_matrix_are_those_of_the_native_viscous_model() {
    let mut native = samples::space_portal();
    let mu = native.quantity("group.joint.mu").unwrap();
    native.set(mu, f64::INFINITY).unwrap();
    let imported = with_damping_matrices(&native);
    assert!(imported.groups().iter().all(|g| g.alpha == 0.0 && g.beta == 0.0), "the damping is in the matrices");
    let (a, b) = (DampedSystem::new(native).unwrap(), DampedSystem::new(imported).unwrap());
    let (ma, mb) = (complex_modes(&a).unwrap(), complex_modes(&b).unwrap());
    assert_eq!(ma.oscillatory.len(), mb.oscillatory.len());
    assert!(ma.oscillatory.len() >= 10);
    for (x, y) in ma.oscillatory.iter().zip(&mb.oscillatory) {
        let e = (x.eigenvalue - y.eigenvalue).norm() / x.eigenvalue.norm();
        assert!(e < 1e-9, "mode at {} Hz: eigenvalues differ by {e:e}", x.frequency_hz);
        let (dx, dy) = (x.damping_ratio, y.damping_ratio);
        assert!((dx - dy).abs() <= 1e-9 * dx.max(1e-6), "damping ratios {dx} and {dy}");
    }
    assert!(ma.oscillatory.iter().any(|m| m.damping_ratio > 1e-3), "damped enough to tell");
}

//! Invariants of the element matrices and the assembly, on random frames.

use fe_model::kinematics::zero_energy_motions;
use fe_model::samples::{TreeMember, tree_frame, tree_members};
use fe_model::{Assembly, element};
use nalgebra::{DMatrix, SymmetricEigen};
use proptest::prelude::*;

/// A random tree of 1 to 5 members: each starts at an earlier node, is
/// 0.2-1 m long, points anywhere and is 10-80 mm deep.
fn members() -> impl Strategy<Value = Vec<TreeMember>> {
    let raw = (any::<usize>(), 0.2..1.0f64, 0.0..std::f64::consts::TAU, 0.01..0.08f64);
    prop::collection::vec(raw, 1..=5).prop_map(|raw| tree_members(&raw))
}

/// A member order: a permutation of `0..n`.
fn shuffled(n: usize) -> impl Strategy<Value = Vec<usize>> {
    Just((0..n).collect::<Vec<_>>()).prop_shuffle()
}

/// Dense stiffness and mass of a free frame (3 DOFs per node, node order),
/// summed element by element: `Assembly` refuses a free body.
fn free_matrices(members: &[TreeMember]) -> (DMatrix<f64>, DMatrix<f64>) {
    let model = tree_frame(members, &(0..members.len()).collect::<Vec<_>>(), false);
    let n = 3 * model.nodes().len();
    let (mut k, mut m) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    for (i, beam) in model.beams().iter().enumerate() {
        let (l, c, s) = model.beam_geometry(i);
        let sec = &model.sections()[beam.section];
        let e = model.materials()[beam.material].e;
        let rho = model.materials()[beam.material].rho;
        let ke = element::frame_stiffness(sec.area, sec.inertia, l, c, s) * e;
        let me = element::frame_mass(sec.area, l, c, s) * rho;
        let at = |end: usize| 3 * (beam.nodes[end].0 as usize - 1);
        for (a, b) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            for r in 0..3 {
                for col in 0..3 {
                    k[(at(a) + r, at(b) + col)] += ke[(3 * a + r, 3 * b + col)];
                    m[(at(a) + r, at(b) + col)] += me[(3 * a + r, 3 * b + col)];
                }
            }
        }
    }
    (k, m)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn element_matrices_are_symmetric_in_any_orientation(
        depth in 0.005..0.2f64, length in 0.05..3.0f64, angle in 0.0..std::f64::consts::TAU,
    ) {
        let (area, inertia) = (0.05 * depth, 0.05 * depth.powi(3) / 12.0);
        let (c, s) = (angle.cos(), angle.sin());
        for m in [element::frame_stiffness(area, inertia, length, c, s), element::frame_mass(area, length, c, s)] {
            let scale = m.abs().max();
            prop_assert!((m - m.transpose()).abs().max() <= 1e-14 * scale);
        }
    }

    /// K of a free frame is positive semi-definite, its null space is
    /// exactly the three rigid motions (so the fourth smallest eigenvalue is
    /// clearly positive), and the kinematic check counts the same three.
    #[test]
    fn a_free_frame_has_exactly_three_rigid_body_modes(members in members()) {
        let (k, m) = free_matrices(&members);
        let model = tree_frame(&members, &(0..members.len()).collect::<Vec<_>>(), false);
        let n = k.nrows();
        // the rigid motions: translations in x and y, a rotation about the origin
        let mut rigid = DMatrix::zeros(n, 3);
        for (i, node) in model.nodes().iter().enumerate() {
            rigid[(3 * i, 0)] = 1.0;
            rigid[(3 * i + 1, 1)] = 1.0;
            rigid[(3 * i, 2)] = -node.y;
            rigid[(3 * i + 1, 2)] = node.x;
            rigid[(3 * i + 2, 2)] = 1.0;
        }
        let scale = k.abs().max();
        prop_assert!((&k * &rigid).abs().max() <= 1e-9 * scale, "K r != 0");
        let mut eig = SymmetricEigen::new(k.clone()).eigenvalues.as_slice().to_vec();
        eig.sort_by(f64::total_cmp);
        let top = eig[n - 1];
        prop_assert!(eig[0] >= -1e-12 * top, "K not PSD: {:?}", &eig[..4]);
        prop_assert!(eig[3] > 1e-10 * top, "a fourth zero-energy mode: {:?}", &eig[..4]);
        prop_assert_eq!(zero_energy_motions(&model).modes, 3);
        // M is positive definite
        let mut eig_m = SymmetricEigen::new(m).eigenvalues.as_slice().to_vec();
        eig_m.sort_by(f64::total_cmp);
        prop_assert!(eig_m[0] > 1e-9 * eig_m[n - 1], "M not positive definite: {:?}", &eig_m[..2]);
    }

    /// The same frame assembled with its elements in another order gives
    /// the same K and M, entry by entry.
    #[test]
    fn assembly_does_not_depend_on_element_order(
        (members, order) in members().prop_flat_map(|m| { let n = m.len(); (Just(m), shuffled(n)) }),
    ) {
        let natural = Assembly::new(&tree_frame(&members, &(0..members.len()).collect::<Vec<_>>(), true)).unwrap();
        let other = Assembly::new(&tree_frame(&members, &order, true)).unwrap();
        for (a, b) in [(natural.stiffness_dense(), other.stiffness_dense()), (natural.mass_dense(), other.mass_dense())] {
            prop_assert_eq!(a.shape(), b.shape());
            prop_assert!((&a - &b).abs().max() <= 1e-12 * a.abs().max());
        }
    }
}

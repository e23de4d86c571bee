//! FRF physics against independent truths: reciprocity and the viscous limit.
//!
//! Reciprocity is checked twice, for two different reasons. The `L D L^T`
//! solver reads one triangle of `Z`, so the FRFs it computes are symmetric
//! whatever the other triangle holds: its test checks that the solver keeps
//! responses and references apart correctly. Whether the *model* is
//! reciprocal (Maxwell-Betti: `Z` symmetric, as every element, spring, mass
//! and damping term must make it) shows only in the whole matrix, so a
//! second test builds `Z` densely from both triangles and inverts it with a
//! pivoting LU that assumes nothing.

use damping::DampedSystem;
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use fe_model::{Dof, DofRef, MatrixKind, Quantity, samples};
use frf::{C64, Channel, synthesize};

fn rel(a: C64, b: C64) -> f64 {
    (a - b).norm() / b.norm()
}

#[test]
fn solver_frfs_are_symmetric_in_response_and_reference() {
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let dofs = [DofRef::new(2, Dof::Ux), DofRef::new(3, Dof::Rz), DofRef::new(4, Dof::Uy), DofRef::new(4, Dof::Rz)];
    let mut channels = Vec::new();
    for &a in &dofs {
        for &b in &dofs {
            channels.push(Channel::new(a, b));
        }
    }
    let freqs: Vec<f64> = (1..=60).map(|i| 7.3 * f64::from(i)).collect();
    let h = synthesize(&sys, &channels, &freqs).unwrap();
    for &a in &dofs {
        for &b in &dofs {
            let ab = h.find(Channel::new(a, b)).unwrap();
            let ba = h.find(Channel::new(b, a)).unwrap();
            for k in 0..freqs.len() {
                let e = rel(h.get(ab, k), h.get(ba, k));
                assert!(e < 1e-9, "H({a},{b}) vs H({b},{a}) at {} Hz: {e:e}", freqs[k]);
            }
        }
    }
}

/// `(K - w^2 M + j w C)^-1` by dense inversion, `C = sum_g alpha_g K_g + beta_g M_g`.
fn dense_viscous_receptance(sys: &DampedSystem, omega: f64) -> Mat<C64> {
    let a = sys.assembly();
    let n = a.n();
    let mut z = Mat::<C64>::zeros(n, n);
    let mut add = |values: &[f64], c: C64| {
        for col in 0..n {
            for p in a.pattern().col_ptr()[col]..a.pattern().col_ptr()[col + 1] {
                z[(a.pattern().row_idx()[p], col)] += c * values[p];
            }
        }
    };
    add(&a.real_values(MatrixKind::Stiffness), C64::new(1.0, 0.0));
    add(&a.real_values(MatrixKind::Mass), C64::new(-omega * omega, 0.0));
    for (g, group) in sys.model().groups().iter().enumerate() {
        add(&a.group_values(g, MatrixKind::Stiffness), C64::new(0.0, omega * group.alpha));
        add(&a.group_values(g, MatrixKind::Mass), C64::new(0.0, omega * group.beta));
    }
    z.partial_piv_lu().inverse()
}

#[test]
fn infinite_mu_is_exactly_viscous_and_large_mu_tends_to_it() {
    let base = samples::frame_with_joint();
    let joint = base.group_index("joint").unwrap();
    let mut viscous = DampedSystem::new(base.clone()).unwrap();
    viscous.set(Quantity::GroupMu(joint), f64::INFINITY).unwrap();
    let mut nearly = DampedSystem::new(base).unwrap();
    nearly.set(Quantity::GroupMu(joint), 1e12).unwrap();

    let dofs: Vec<DofRef> =
        [(2, Dof::Ux), (3, Dof::Rz), (4, Dof::Uy)].iter().map(|&(n, d)| DofRef::new(n, d)).collect();
    let channels: Vec<Channel> = dofs.iter().flat_map(|&a| dofs.iter().map(move |&b| Channel::new(a, b))).collect();
    let freqs = [3.0, 41.0, 157.0, 612.0];
    let hv = synthesize(&viscous, &channels, &freqs).unwrap();
    let hn = synthesize(&nearly, &channels, &freqs).unwrap();
    for (k, &f) in freqs.iter().enumerate() {
        let r = dense_viscous_receptance(&viscous, 2.0 * std::f64::consts::PI * f);
        for (c, ch) in channels.iter().enumerate() {
            let i = frf::equation_of(&viscous, ch.response).unwrap();
            let j = frf::equation_of(&viscous, ch.reference).unwrap();
            let e = rel(hv.get(c, k), r[(i, j)]);
            assert!(e < 1e-10, "mu = inf vs (K - w^2 M + j w C)^-1, {ch} at {f} Hz: {e:e}");
            let e = rel(hn.get(c, k), hv.get(c, k));
            assert!(e < 1e-8, "mu = 1e12 vs viscous, {ch} at {f} Hz: {e:e}");
        }
    }
}

/// `Z(w)` from every stored entry of its pattern, both triangles, as the
/// model assembles it.
fn dense_z(sys: &DampedSystem, omega: f64) -> Mat<C64> {
    let a = sys.assembly();
    let values = sys.z_values(omega);
    let mut z = Mat::<C64>::zeros(a.n(), a.n());
    for col in 0..a.n() {
        for p in a.pattern().col_ptr()[col]..a.pattern().col_ptr()[col + 1] {
            z[(a.pattern().row_idx()[p], col)] += values[p];
        }
    }
    z
}

/// The model obeys Maxwell-Betti reciprocity: on a frame with a lossy
/// non-viscous joint, ties, a lumped mass and non-proportional damping, and
/// on the rotated two-material beam, `Z(w)` built from both triangles is
/// symmetric, its inverse by a dense pivoting LU (which uses every entry and
/// assumes no symmetry) is symmetric, and it equals the FRFs of the `L D L^T`
/// solver. An element, spring or damping term assembled unsymmetrically
/// fails here, where the solver's own FRFs would still look reciprocal.
#[test]
fn the_model_is_reciprocal_by_a_dense_lu_of_the_whole_z() {
    for model in [samples::frame_with_joint(), samples::two_material_cantilever()] {
        let sys = DampedSystem::new(model).unwrap();
        let n = sys.n();
        let eqs: Vec<usize> = (0..n).step_by((n / 12).max(1)).collect();
        let dofs: Vec<DofRef> = eqs.iter().map(|&e| sys.assembly().dofs().dof_of(e)).collect();
        let channels: Vec<Channel> = dofs.iter().flat_map(|&a| dofs.iter().map(move |&b| Channel::new(a, b))).collect();
        let freqs = [2.7, 41.0, 157.0, 612.0];
        let h = synthesize(&sys, &channels, &freqs).unwrap();
        for (k, &f) in freqs.iter().enumerate() {
            let z = dense_z(&sys, 2.0 * std::f64::consts::PI * f);
            let z_max =
                (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| z[(i, j)].norm()).fold(0.0, f64::max);
            for i in 0..n {
                for j in 0..i {
                    let e = (z[(i, j)] - z[(j, i)]).norm();
                    assert!(
                        e <= 1e-14 * z_max,
                        "{}: Z[{i}][{j}] {} vs Z[{j}][{i}] {} at {f} Hz",
                        sys.model().title,
                        z[(i, j)],
                        z[(j, i)]
                    );
                }
            }
            let r = z.partial_piv_lu().inverse();
            for (c, ch) in channels.iter().enumerate() {
                let (i, j) =
                    (frf::equation_of(&sys, ch.response).unwrap(), frf::equation_of(&sys, ch.reference).unwrap());
                // relative to the driving points: a cross FRF may be exactly zero
                // (axial against bending on a straight beam)
                let scale = (r[(i, i)].norm() * r[(j, j)].norm()).sqrt();
                let e = (r[(i, j)] - r[(j, i)]).norm() / scale;
                assert!(e < 1e-9, "{}: R({i},{j}) vs R({j},{i}) at {f} Hz: {e:e}", sys.model().title);
                let e = (h.get(c, k) - r[(i, j)]).norm() / scale;
                assert!(e < 1e-8, "{}: L D L^T vs dense LU, {ch} at {f} Hz: {e:e}", sys.model().title);
            }
        }
    }
}

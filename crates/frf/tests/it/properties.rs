//! Physical invariants of Z(w) and the receptance on random damped frames:
//! reciprocity, passivity, the viscous limit.

use damping::DampedSystem;
use fe_model::samples::{TreeMember, tree_frame, tree_members};
use fe_model::{Model, Quantity};
use frf::{C64, Channel, synthesize};
use proptest::prelude::*;

/// A random tree of 1 to 4 members (as in fe-model's property tests).
fn members() -> impl Strategy<Value = Vec<TreeMember>> {
    let raw = (any::<usize>(), 0.2..1.0f64, 0.0..std::f64::consts::TAU, 0.01..0.08f64);
    prop::collection::vec(raw, 1..=4).prop_map(|raw| tree_members(&raw))
}

/// Damping of one group: alpha (s), beta (1/s), mu (rad/s, `None`: viscous).
fn damping() -> impl Strategy<Value = (f64, f64, Option<f64>)> {
    (1e-7..1e-4f64, 0.0..5.0f64, prop::option::of(10.0..1e5f64))
}

/// A clamped random frame whose two groups have the given damping.
fn frame(members: &[TreeMember], groups: [(f64, f64, Option<f64>); 2]) -> Model {
    let mut m = tree_frame(members, &(0..members.len()).collect::<Vec<_>>(), true);
    for (g, (alpha, beta, mu)) in groups.into_iter().enumerate() {
        m.set(Quantity::GroupAlpha(g), alpha).unwrap();
        m.set(Quantity::GroupBeta(g), beta).unwrap();
        // an infinite mu is the viscous group (`None`)
        m.set(Quantity::GroupMu(g), mu.unwrap_or(f64::INFINITY)).unwrap();
    }
    m
}

fn rel(a: C64, b: C64) -> f64 {
    (a - b).norm() / b.norm()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `H(a, b) = H(b, a)`: Z is complex symmetric whatever the damping.
    #[test]
    fn receptance_is_reciprocal(
        members in members(), d in [damping(), damping()], freq in 1.0..2000.0f64,
        a in any::<prop::sample::Index>(), b in any::<prop::sample::Index>(),
    ) {
        let sys = DampedSystem::new(frame(&members, d)).unwrap();
        let dofs = sys.assembly().dofs();
        let (a, b) = (dofs.dof_of(a.index(sys.n())), dofs.dof_of(b.index(sys.n())));
        prop_assume!(a != b);
        let h = synthesize(&sys, &[Channel::new(a, b), Channel::new(b, a)], &[freq]).unwrap();
        // two DOFs the structure does not couple answer exactly zero both ways
        let (ab, ba) = (h.get(0, 0), h.get(1, 0));
        prop_assert!((ab - ba).norm() <= 1e-9 * ab.norm().max(ba.norm()), "H({a},{b}) = {ab} but H({b},{a}) = {ba}");
    }

    /// `Im(x^H Z(w) x) >= 0` for every x and w > 0 when every C_g is
    /// positive semi-definite and mu_g > 0: no negative dissipation.
    #[test]
    fn dynamic_stiffness_is_passive(
        members in members(), d in [damping(), damping()], freq in 0.1..5000.0f64,
        x in prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64), 16),
    ) {
        let sys = DampedSystem::new(frame(&members, d)).unwrap();
        let a = sys.assembly();
        let z = sys.z_values(2.0 * std::f64::consts::PI * freq);
        let x: Vec<C64> = (0..a.n()).map(|i| C64::new(x[i % 16].0, x[(i * 7 + 3) % 16].1)).collect();
        let mut xzx = C64::new(0.0, 0.0);
        let mut scale = 0.0f64;
        for col in 0..a.n() {
            for p in a.pattern().col_ptr()[col]..a.pattern().col_ptr()[col + 1] {
                let row = a.pattern().row_idx()[p];
                xzx += x[row].conj() * z[p] * x[col];
                scale += x[row].norm() * z[p].norm() * x[col].norm();
            }
        }
        prop_assert!(xzx.im >= -1e-12 * scale, "Im(x^H Z x) = {:e} at {freq} Hz", xzx.im);
    }

    /// A relaxation parameter far above the band behaves as viscous damping.
    #[test]
    fn large_mu_tends_to_viscous(
        members in members(), d in [damping(), damping()], freq in 1.0..2000.0f64,
        a in any::<prop::sample::Index>(),
    ) {
        let mut slow = DampedSystem::new(frame(&members, d)).unwrap();
        let mut viscous = slow.clone();
        for g in 0..2 {
            slow.set(Quantity::GroupMu(g), 1e12).unwrap();
            viscous.set(Quantity::GroupMu(g), f64::INFINITY).unwrap();
        }
        let dof = slow.assembly().dofs().dof_of(a.index(slow.n()));
        let ch = [Channel::new(dof, dof)];
        let (hs, hv) = (synthesize(&slow, &ch, &[freq]).unwrap(), synthesize(&viscous, &ch, &[freq]).unwrap());
        prop_assert!(rel(hs.get(0, 0), hv.get(0, 0)) < 1e-6, "{} vs viscous {}", hs.get(0, 0), hv.get(0, 0));
    }
}

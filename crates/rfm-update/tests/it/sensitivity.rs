//! The sensitivity assembly against independent truths.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, samples};
use frf::{C64, Channel, ZSolver, synthesize};
use rfm_update::sensitivity::{ChannelPlan, Hybrid, assemble};

/// With `Hybrid::Model`, `-S` is the Jacobian `dH/dp p`: compare with
/// central differences of synthesised FRFs for every parameter kind.
#[test]
fn model_sensitivity_is_minus_the_frf_jacobian() {
    let sys = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let names = [
        "group.joint.mu",
        "group.joint.alpha",
        "group.frame.beta",
        "spring.joint.kr",
        "mass.tip.m",
        "material.steel.E",
    ];
    let params: Vec<_> = names.iter().map(|n| sys.model().quantity(n).unwrap()).collect();
    let r = DofRef::new(4, Dof::Uy);
    let channels =
        vec![Channel::new(r, r), Channel::new(DofRef::new(2, Dof::Ux), r), Channel::new(DofRef::new(3, Dof::Rz), r)];
    let freqs = [17.0, 83.0, 240.0];
    let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
    let plan = ChannelPlan::new(&sys, &channels).unwrap();
    let blocks = assemble(&sys, &solver, &plan, &params, &freqs, Hybrid::Model).unwrap();
    for (i, &q) in params.iter().enumerate() {
        let p = sys.get(q);
        let h = 1e-4 * p;
        let at = |v: f64| {
            let mut s = sys.clone();
            s.set(q, v).unwrap();
            synthesize(&s, &channels, &freqs).unwrap()
        };
        let (hp, hm) = (at(p + h), at(p - h));
        for (k, b) in blocks.iter().enumerate() {
            for c in 0..channels.len() {
                let fd: C64 = (hp.get(c, k) - hm.get(c, k)) / (2.0 * h) * p;
                let an = -b.sens[(c, i)];
                let err = (fd - an).norm() / an.norm().max(1e-30);
                assert!(err < 1e-6, "{} {} at {} Hz: {err:e}", names[i], channels[c], freqs[k]);
            }
        }
    }
}

/// The RFM identity: with complete measured data and a parameter that
/// enters Z linearly, `S u = R_FE - R_EX` holds exactly for the true `u`.
#[test]
fn rfm_equation_is_exact_for_linear_parameters_with_complete_data() {
    let truth = DampedSystem::new(samples::frame_with_joint()).unwrap();
    let kr = truth.model().quantity("spring.joint.kr").unwrap();
    let mut model = truth.clone();
    model.set(kr, 3.0 * truth.get(kr)).unwrap();
    let u_true = truth.get(kr) / model.get(kr) - 1.0;
    let r = DofRef::new(4, Dof::Uy);
    let n = model.n();
    let channels: Vec<Channel> = (0..n).map(|e| Channel::new(model.assembly().dofs().dof_of(e), r)).collect();
    let freqs = [23.0, 140.0];
    let measured = synthesize(&truth, &channels, &freqs).unwrap();
    let solver = ZSolver::new(model.assembly().pattern()).unwrap();
    let plan = ChannelPlan::new(&model, &channels).unwrap();
    let blocks = assemble(&model, &solver, &plan, &[kr], &freqs, Hybrid::Measured(&measured)).unwrap();
    for (k, b) in blocks.iter().enumerate() {
        for c in 0..channels.len() {
            let lhs = b.sens[(c, 0)] * u_true;
            let rhs = b.model[c] - measured.get(c, k);
            assert!((lhs - rhs).norm() <= 1e-9 * rhs.norm().max(1e-14), "{} at {} Hz", channels[c], freqs[k]);
        }
    }
}

//! The sparse sensitivity assembly equals the dense textbook formulation
//! (dense inverse of Z, dense dZ/dp, `S = R[meas, :] dZ x`) for every kind of
//! parameter and both hybrid modes.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, Group, Model, Section, samples};
use frf::{Channel, ZSolver, synthesize};
use rfm_update::sensitivity::{ChannelPlan, FrequencyBlock, Hybrid, assemble, naive};

/// An L-frame with every kind of item: two non-viscous groups and a viscous
/// one, two materials, a joint with a rotational spring and ties, a ground
/// spring with kx, ky and kr, a lumped mass with inertia, an added mass.
fn every_kind_model() -> Model {
    let mut m = samples::frame_with_joint();
    let base = m.add_group(Group::new("base").rayleigh(4e-4, 0.2).relaxation(900.0)).unwrap();
    let alu = m.add_material("aluminium", 0.7e11, 2700.0).unwrap();
    let sec = m.add_section(Section::rectangle("strip", 0.04, 0.01)).unwrap();
    let frame = m.group_index("frame").unwrap();
    m.add_node(5, 1.5, 1.0).unwrap();
    m.add_beam(3, [4, 5], alu, sec, frame).unwrap();
    m.add_spring("ground", 5, None, [3e5, 2e5, 4e3], base).unwrap();
    m.add_mass("sensor", 5, 0.2, 3e-4, base).unwrap();
    m.set_added_mass(1, 0.8).unwrap();
    m
}

const EVERY_KIND: [&str; 19] = [
    "group.frame.alpha",
    "group.joint.alpha",
    "group.base.beta",
    "group.frame.beta",
    "group.joint.mu",
    "group.base.mu",
    "group.frame.stiffness",
    "group.frame.mass",
    "group.base.stiffness",
    "material.steel.E",
    "material.aluminium.rho",
    "element.1.stiffness",
    "element.3.mass",
    "element.2.added_mass",
    "spring.ground.kx",
    "spring.ground.ky",
    "spring.joint.kr",
    "mass.sensor.m",
    "mass.sensor.j",
];

/// Largest difference in each parameter's column (and in the model FRFs)
/// relative to that column's largest entry.
fn worst_relative_difference(fast: &[FrequencyBlock], slow: &[FrequencyBlock], names: &[&str]) -> (f64, String) {
    let mut worst = (0.0, String::new());
    assert_eq!(fast.len(), slow.len());
    for (a, b) in fast.iter().zip(slow) {
        assert_eq!(a.freq_hz, b.freq_hz);
        let scale = b.model.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (x, y) in a.model.iter().zip(&b.model) {
            let e = (x - y).norm() / scale;
            if e > worst.0 {
                worst = (e, format!("model FRF at {} Hz", a.freq_hz));
            }
        }
        assert_eq!((a.sens.nrows(), a.sens.ncols()), (b.sens.nrows(), b.sens.ncols()));
        for i in 0..b.sens.ncols() {
            let scale = (0..b.sens.nrows()).map(|c| b.sens[(c, i)].norm()).fold(0.0, f64::max);
            assert!(scale > 0.0, "{} has no effect at {} Hz: the test would prove nothing", names[i], a.freq_hz);
            for c in 0..b.sens.nrows() {
                let e = (a.sens[(c, i)] - b.sens[(c, i)]).norm() / scale;
                if e > worst.0 {
                    worst = (e, format!("{} channel {c} at {} Hz", names[i], a.freq_hz));
                }
            }
        }
    }
    worst
}

fn check(sys: &DampedSystem, names: &[&str], channels: &[Channel], freqs: &[f64], measured: &frf::FrfSet) {
    let params: Vec<_> = names.iter().map(|n| sys.model().quantity(n).unwrap()).collect();
    let solver = ZSolver::new(sys.assembly().pattern()).unwrap();
    let plan = ChannelPlan::new(sys, channels).unwrap();
    for (label, hybrid) in [("model", Hybrid::Model), ("measured", Hybrid::Measured(measured))] {
        let fast = assemble(sys, &solver, &plan, &params, freqs, hybrid).unwrap();
        let slow = naive::assemble(sys, &plan, &params, freqs, hybrid).unwrap();
        let (e, at) = worst_relative_difference(&fast, &slow, names);
        assert!(e < 1e-10, "Hybrid::{label}: relative difference {e:e} in {at}");
    }
}

#[test]
fn fast_assembly_equals_dense_formulation_for_every_parameter_kind() {
    let truth = DampedSystem::new(every_kind_model()).unwrap();
    let mut sys = truth.clone();
    // a model away from the truth, so that measured and model columns differ
    for (name, factor) in [("spring.ground.kx", 1.7), ("group.joint.mu", 0.4), ("mass.sensor.m", 1.3)] {
        let q = sys.model().quantity(name).unwrap();
        sys.set(q, factor * sys.get(q)).unwrap();
    }
    let (tip, mid) = (DofRef::new(5, Dof::Uy), DofRef::new(2, Dof::Ux));
    let responses = [(2, Dof::Ux), (3, Dof::Rz), (4, Dof::Uy), (5, Dof::Ux), (5, Dof::Uy), (5, Dof::Rz)];
    let mut channels = Vec::new();
    for reference in [tip, mid] {
        for &(node, dof) in &responses {
            channels.push(Channel::new(DofRef::new(node, dof), reference));
        }
    }
    let freqs = [11.0, 47.0, 133.0, 410.0];
    let measured = synthesize(&truth, &channels, &freqs).unwrap();
    check(&sys, &EVERY_KIND, &channels, &freqs, &measured);
}

#[test]
fn fast_assembly_equals_dense_formulation_on_the_paper_beam() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let mut sys = truth.clone();
    let names = [
        "group.steel.mu",
        "group.aluminium.mu",
        "group.steel.alpha",
        "group.aluminium.alpha",
        "group.steel.beta",
        "group.aluminium.beta",
    ];
    for (name, factor) in names.iter().zip([0.3, 0.5, 0.4, 0.4, 0.6, 0.6]) {
        let q = sys.model().quantity(name).unwrap();
        sys.set(q, factor * sys.get(q)).unwrap();
    }
    let tip = DofRef::new(31, Dof::Uy);
    let channels: Vec<Channel> = (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
    let freqs = [5.5, 48.0, 157.5, 336.0];
    let measured = synthesize(&truth, &channels, &freqs).unwrap();
    check(&sys, &names, &channels, &freqs, &measured);
}

/// The same on a frame in space: torsion, two bending planes, springs and
/// rotary inertias about three axes, twelve DOFs per beam block.
#[test]
fn fast_assembly_equals_dense_formulation_in_space() {
    let truth = DampedSystem::new(samples::space_portal()).unwrap();
    let mut sys = truth.clone();
    for (name, factor) in [("spring.joint.krx", 1.7), ("group.joint.mu", 0.4), ("mass.tip.m", 1.3)] {
        let q = sys.model().quantity(name).unwrap();
        sys.set(q, factor * sys.get(q)).unwrap();
    }
    let names = [
        "group.frame.alpha",
        "group.joint.mu",
        "material.steel.E",
        "element.5.stiffness",
        "element.3.mass",
        "spring.joint.krx",
        "spring.joint.kry",
        "spring.joint.krz",
        "spring.foot.kx",
        "spring.foot.krz",
        "mass.tip.m",
        "mass.tip.jx",
        "mass.tip.jz",
    ];
    let responses = [(7, Dof::Ux), (7, Dof::Uy), (7, Dof::Uz), (7, Dof::Rx), (5, Dof::Uz), (4, Dof::Ry), (2, Dof::Ux)];
    let channels = portal_channels(&responses);
    // Lines from near the first mode up: at 9 Hz, nearly static, Z is close
    // to K, whose axial terms lie 1e4 above the joint's and torsion's, and
    // the two formulations differ by 1e-9, the round-off of a dense inverse
    // of that conditioning.
    let freqs = [23.0, 61.0, 173.0, 420.0];
    let measured = synthesize(&truth, &channels, &freqs).unwrap();
    check(&sys, &names, &channels, &freqs, &measured);
}

/// The same on an imported model whose frame group has a viscous damping
/// matrix of its own beside its alpha and beta: the damping factor is a
/// parameter like the others, its terms in a class of their own.
#[test]
fn fast_assembly_equals_dense_formulation_with_an_imported_damping_matrix() {
    use fe_model::imported::{ImportedKind, SymmetricCoo, export};
    let native = samples::space_portal();
    let a = fe_model::Assembly::new(&native).unwrap();
    let exported = export::export(&native, &a);
    let mut model = export::as_imported(&native).unwrap();
    // dashpots at a few free DOFs and between two of them
    let c = SymmetricCoo { n: a.n(), entries: vec![(2, 2, 30.0), (5, 5, 12.0), (9, 5, -4.0), (9, 9, 8.0)] };
    let f = model.group_index("frame").unwrap();
    model.add_imported(f, ImportedKind::Damping, &exported.dofs, &c).unwrap();
    let truth = DampedSystem::new(model).unwrap();
    let mut sys = truth.clone();
    for (name, factor) in [("group.frame.damping", 1.8), ("group.joint.mu", 0.4), ("group.frame.stiffness", 1.05)] {
        let q = sys.model().quantity(name).unwrap();
        sys.set(q, factor * sys.get(q)).unwrap();
    }
    let names = [
        "group.frame.damping",
        "group.frame.alpha",
        "group.frame.beta",
        "group.frame.stiffness",
        "group.frame.mass",
        "group.joint.mu",
        "group.joint.stiffness",
    ];
    let responses = [(7, Dof::Ux), (7, Dof::Uy), (7, Dof::Uz), (5, Dof::Uz), (4, Dof::Ry), (2, Dof::Ux)];
    let channels = portal_channels(&responses);
    let freqs = [23.0, 61.0, 173.0, 420.0];
    let measured = synthesize(&truth, &channels, &freqs).unwrap();
    check(&sys, &names, &channels, &freqs, &measured);
}

/// Every response of `responses` per each of the portal's two references
/// (the top's uy and a column's uz).
fn portal_channels(responses: &[(u32, Dof)]) -> Vec<Channel> {
    let references = [DofRef::new(7, Dof::Uy), DofRef::new(5, Dof::Uz)];
    references.iter().flat_map(|&r| responses.iter().map(move |&(n, d)| Channel::new(DofRef::new(n, d), r))).collect()
}

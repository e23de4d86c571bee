//! Tiny canonical models shared by tests, examples, benchmarks and docs.

use crate::dof::Dof;
use crate::model::{Group, Model, Section};

/// A uniform steel cantilever, 1 m long, 50 x 10 mm, clamped at node 1,
/// `n` elements along x, nodes `1..=n+1`, one viscous group `beam`
/// (alpha = 1e-5, beta = 0.5).
pub fn cantilever(n: usize) -> Model {
    let mut m = Model::new("uniform steel cantilever");
    let g = m.add_group(Group::new("beam").rayleigh(1e-5, 0.5)).unwrap();
    let mat = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.05, 0.01)).unwrap();
    for i in 0..=n {
        m.add_node(i as u32 + 1, i as f64 / n as f64, 0.0).unwrap();
    }
    for i in 0..n {
        m.add_beam(i as u32 + 1, [i as u32 + 1, i as u32 + 2], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::ALL).unwrap();
    m
}

/// The paper's two-material cantilever (900 x 50 x 5 mm, 30 elements, steel
/// then aluminium, clamped at the steel end) with the *true* damping of its
/// Table 1: mu = 631.12 / 38274 rad/s, alpha = 1e-5 / 3e-5, beta = 0.1 / 0.2.
pub fn two_material_cantilever() -> Model {
    let mut m = Model::new("two-material cantilever (Arora et al. 2023, Table 1)");
    let steel_g = m.add_group(Group::new("steel").rayleigh(1e-5, 0.1).relaxation(631.12)).unwrap();
    let alu_g = m.add_group(Group::new("aluminium").rayleigh(3e-5, 0.2).relaxation(38274.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let alu = m.add_material("aluminium", 0.69e11, 2700.0).unwrap();
    let sec = m.add_section(Section::rectangle("strip", 0.05, 0.005)).unwrap();
    let n = 30;
    for i in 0..=n {
        m.add_node(i + 1, 0.9 * f64::from(i) / f64::from(n), 0.0).unwrap();
    }
    for i in 0..n {
        let (mat, g) = if i < n / 2 { (steel, steel_g) } else { (alu, alu_g) };
        m.add_beam(i + 1, [i + 1, i + 2], mat, sec, g).unwrap();
    }
    m.add_support(1, &Dof::ALL).unwrap();
    m
}

/// An L-shaped frame with a flexible, lossy joint: a 1 m steel column
/// (nodes 1-2, clamped at 1) and a 1 m arm (nodes 3-4) whose first node 3
/// coincides with 2, tied to it in ux and uy and joined by a rotational
/// spring `joint` (kr = 2e5 N m/rad) in group `joint` (alpha = 1e-3,
/// mu = 300 rad/s). The members are in group `frame` (viscous Rayleigh).
pub fn frame_with_joint() -> Model {
    let mut m = Model::new("L-frame with a lossy joint");
    let frame = m.add_group(Group::new("frame").rayleigh(2e-5, 0.3)).unwrap();
    let joint = m.add_group(Group::new("joint").rayleigh(1e-3, 0.0).relaxation(300.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("square", 0.03, 0.03)).unwrap();
    m.add_node(1, 0.0, 0.0).unwrap();
    m.add_node(2, 0.0, 1.0).unwrap();
    m.add_node(3, 0.0, 1.0).unwrap();
    m.add_node(4, 1.0, 1.0).unwrap();
    m.add_beam(1, [1, 2], steel, sec, frame).unwrap();
    m.add_beam(2, [3, 4], steel, sec, frame).unwrap();
    m.add_spring("joint", 2, Some(3), [0.0, 0.0, 2.0e5], joint).unwrap();
    m.add_tie(2, 3, &[Dof::Ux, Dof::Uy]).unwrap();
    m.add_mass("tip", 4, 0.5, 1e-4, frame).unwrap();
    m.add_support(1, &Dof::ALL).unwrap();
    m
}

/// Two masses on springs along x (a 2-DOF oscillator): ground -k1- m1 -k2- m2,
/// with k1 = 1000 N/m, k2 = 500 N/m, m1 = 1 kg, m2 = 0.5 kg, in one viscous
/// group (alpha = 1e-3, beta = 0.1). The uy and rz DOFs are fixed.
pub fn two_dof_oscillator() -> Model {
    let mut m = Model::new("2-DOF oscillator");
    let g = m.add_group(Group::new("g").rayleigh(1e-3, 0.1)).unwrap();
    m.add_node(1, 0.0, 0.0).unwrap();
    m.add_node(2, 1.0, 0.0).unwrap();
    m.add_spring("k1", 1, None, [1000.0, 0.0, 0.0], g).unwrap();
    m.add_spring("k2", 1, Some(2), [500.0, 0.0, 0.0], g).unwrap();
    m.add_mass("m1", 1, 1.0, 0.0, g).unwrap();
    m.add_mass("m2", 2, 0.5, 0.0, g).unwrap();
    m.add_support(1, &[Dof::Uy, Dof::Rz]).unwrap();
    m.add_support(2, &[Dof::Uy, Dof::Rz]).unwrap();
    m
}

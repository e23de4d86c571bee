//! A planar frame built in space gives the planar results: the 3D frame
//! element restricted to the plane of a planar model (its out-of-plane DOFs
//! held) is the planar element, and everything above the model is the
//! same code for both.

use damping::{DampedSystem, normal_modes};
use fe_model::{Assembly, Dimension, Dof, DofRef, Model, Section, samples};
use frf::{Channel, synthesize};

const NU: f64 = 0.3;

/// `planar` built in space: every node at z = 0 with its out-of-plane DOFs
/// (`uz`, `rx`, `ry`) held, the same items, sections and groups.
fn in_space(planar: &Model) -> Model {
    let mut m = Model::with_dimension(&planar.title, Dimension::Spatial);
    for g in planar.groups() {
        m.add_group(g.clone()).unwrap();
    }
    for mat in planar.materials() {
        let i = m.add_material(&mat.name, mat.e, mat.rho).unwrap();
        m.set_poisson(i, NU).unwrap();
    }
    for s in planar.sections() {
        // any Iy and J: the DOFs they act on are held
        m.add_section(Section::spatial(&s.name, s.area, 3.0 * s.inertia, s.inertia, 2.0 * s.inertia)).unwrap();
    }
    for n in planar.nodes() {
        m.add_node_at(n.id.0, [n.x, n.y, 0.0]).unwrap();
        m.add_support(n.id.0, &[Dof::Uz, Dof::Rx, Dof::Ry]).unwrap();
    }
    for (i, b) in planar.beams().iter().enumerate() {
        let e = m.add_beam(b.id.0, b.nodes.map(|n| n.0), b.material, b.section, b.group).unwrap();
        m.set_added_mass(e, b.added_mass).unwrap();
        assert_eq!(m.beam_axes(e)[2], [0.0, 0.0, 1.0], "beam {i} bends in the plane with Iz");
    }
    for s in planar.springs() {
        m.add_spring(&s.name, s.a.0, s.b.map(|b| b.0), s.k, s.group).unwrap();
    }
    for mass in planar.masses() {
        m.add_mass(&mass.name, mass.node.0, mass.m, mass.j, mass.group).unwrap();
    }
    for s in planar.supports() {
        m.add_support(s.node.0, &s.dofs).unwrap();
    }
    for t in planar.ties() {
        m.add_tie(t.nodes[0].0, t.nodes[1].0, &t.dofs).unwrap();
    }
    m
}

/// The planar samples (a cantilever, the two-material beam, a frame with a
/// lossy non-viscous joint, a tip mass and ties) built in space give the
/// planar frequencies and damped receptances: the 3D element restricted to
/// the plane is the planar element.
#[test]
fn a_planar_frame_built_in_space_gives_the_planar_results() {
    for planar in [samples::cantilever(8), samples::two_material_cantilever(), samples::frame_with_joint()] {
        let spatial = in_space(&planar);
        let (a2, a3) = (Assembly::new(&planar).unwrap(), Assembly::new(&spatial).unwrap());
        assert_eq!(a2.n(), a3.n(), "{}: the same free DOFs", planar.title);
        let (f2, f3) = (normal_modes(&a2).unwrap().frequencies_hz, normal_modes(&a3).unwrap().frequencies_hz);
        for (a, b) in f2.iter().zip(&f3) {
            assert!((a - b).abs() <= 1e-12 * a, "{}: {a} Hz vs {b} Hz", planar.title);
        }
        let tip = planar.nodes().last().unwrap().id.0;
        let channels: Vec<Channel> = [Dof::Ux, Dof::Uy, Dof::Rz]
            .iter()
            .map(|&d| Channel::new(DofRef::new(tip, d), DofRef::new(tip, Dof::Uy)))
            .collect();
        let lines: Vec<f64> = (1..=40).map(|k| 7.3 * f64::from(k)).collect();
        let h2 = synthesize(&DampedSystem::new(planar.clone()).unwrap(), &channels, &lines).unwrap();
        let h3 = synthesize(&DampedSystem::new(spatial).unwrap(), &channels, &lines).unwrap();
        for c in 0..channels.len() {
            for k in 0..lines.len() {
                let (x, y) = (h2.get(c, k), h3.get(c, k));
                assert!(
                    (x - y).norm() <= 1e-10 * x.norm(),
                    "{}: {} at {} Hz: {x} vs {y}",
                    planar.title,
                    channels[c],
                    lines[k]
                );
            }
        }
    }
}

//! A model without damping evaluated on its own resonance is singular at
//! that line (issue 32, item 6): the diagnosis leaves the line out, says
//! which it was, and goes on, instead of stopping the loop with "the
//! dynamic stiffness is singular". The line is placed exactly on the
//! nominal model's first natural frequency from a dense eigen-solution
//! ([`damping::normal_modes`], another road than the sparse factorisation
//! the diagnosis uses); the data come from a damped truth with a tip mass,
//! so they are regular there.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, Group, Model, Section};
use frf::{Channel, NoiseModel, synthesize};
use rfm_update::diagnose::{DiagnoseOptions, EffectKind, diagnose};

/// A 20-element steel cantilever, undamped unless `damped`.
fn cantilever(damped: bool) -> Model {
    let mut m = Model::new("undamped cantilever");
    let g = if damped {
        m.add_group(Group::new("beam").rayleigh(1e-5, 0.5)).unwrap()
    } else {
        m.add_group(Group::new("beam")).unwrap()
    };
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let sec = m.add_section(Section::rectangle("bar", 0.04, 0.008)).unwrap();
    for i in 0..=20 {
        m.add_node(i + 1, f64::from(i) / 20.0, 0.0).unwrap();
    }
    for i in 0..20 {
        m.add_beam(i + 1, [i + 1, i + 2], steel, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

#[test]
fn a_line_on_the_undamped_models_resonance_is_left_out_and_named() {
    let nominal = cantilever(false);
    let sys = DampedSystem::new(nominal.clone()).unwrap();
    let f1 = damping::normal_modes(sys.assembly()).unwrap().frequencies_hz[0];
    let mut lines: Vec<f64> = (1..=200).map(|k| 2.0 * f64::from(k)).collect();
    lines.push(f1);
    lines.sort_by(f64::total_cmp);

    let mut truth = cantilever(true);
    let g = truth.add_group(Group::new("sensor")).unwrap();
    let mass = 0.05 * truth.total_mass();
    truth.add_mass("sensor", 21, mass, 0.0, g).unwrap();
    let uy = |n| DofRef::new(n, Dof::Uy);
    let channels: Vec<Channel> = [6, 11, 16, 21].iter().map(|&n| Channel::new(uy(n), uy(21))).collect();
    let mut measured = synthesize(&DampedSystem::new(truth).unwrap(), &channels, &lines).unwrap();
    NoiseModel::relative(0.01, 32).apply(&mut measured);

    let d = diagnose(&nominal, &measured, &DiagnoseOptions::default()).expect("the diagnosis goes on");
    println!("singular at {:?} Hz (f1 = {f1} Hz); leader {}", d.singular_hz, d.ranking[0].description);
    assert_eq!(d.singular_hz.len(), 1, "{:?}", d.singular_hz);
    assert!((d.singular_hz[0] - f1).abs() < 1e-9 * f1, "{} Hz named, not {f1}", d.singular_hz[0]);
    // the other lines still tell the mass at the tip (the drive point: a
    // shaker's armature there is that mass, its dashpot taking some of the
    // damping the undamped nominal lacks; so is a resonator there tuned
    // above the band, a mass on a spring and dashpot, which the broad
    // residual of the missing damping now offers)
    let top = &d.ranking[0];
    assert!(top.significant, "{}", top.description);
    assert!(
        matches!(
            top.kind,
            EffectKind::LumpedMass | EffectKind::MassChange | EffectKind::Shaker | EffectKind::Resonator
        ) && top.nodes.iter().chain(&top.elements).any(|&n| n >= 19),
        "{}",
        top.description
    );
}

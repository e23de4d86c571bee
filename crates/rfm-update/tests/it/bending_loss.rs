//! A loss of bending stiffness alone (a smaller second moment of area over
//! two elements of an L-frame's post, written as a second section, not with
//! the bending factor the diagnosis fits) is named as such: the bending-only
//! twin of the leading stiffness change ranks first, at exactly the right
//! elements, with the true factor within 3 standard deviations, where the
//! factor on the whole element matrix, which also softens the post
//! axially, misses it.

use damping::DampedSystem;
use fe_model::{Dof, DofRef, Group, Model, Section};
use frf::{Channel, NoiseModel, synthesize};
use rfm_update::diagnose::{DiagnoseOptions, EffectKind, diagnose};

const POST: u32 = 12;
const ARM: u32 = 10;
const FACTOR: f64 = 0.7;

/// A clamped steel L-frame: a post of 12 elements up y, an arm of 10 along
/// x; elements 5 and 6 of the post with the section `weak`.
fn frame(weak: &Section) -> Model {
    let mut m = Model::new("L-frame");
    let g = m.add_group(Group::new("steel").rayleigh(2e-6, 1.0)).unwrap();
    let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
    let bar = m.add_section(Section::rectangle("bar", 0.04, 0.01)).unwrap();
    let weak = m.add_section(weak.clone()).unwrap();
    for i in 0..=POST {
        m.add_node(i + 1, 0.0, 1.2 * f64::from(i) / f64::from(POST)).unwrap();
    }
    for i in 1..=ARM {
        m.add_node(POST + 1 + i, f64::from(i) / f64::from(ARM), 1.2).unwrap();
    }
    for i in 1..=POST + ARM {
        let sec = if (5..=6).contains(&i) { weak } else { bar };
        m.add_beam(i, [i, i + 1], steel, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

#[test]
fn a_loss_of_second_moment_alone_is_named_as_a_bending_stiffness_change() {
    let bar = Section::rectangle("bar", 0.04, 0.01);
    let nominal = frame(&Section { name: "weak".into(), ..bar.clone() });
    let weak = Section { name: "weak".into(), inertia: FACTOR * bar.inertia, ..bar.clone() };
    let truth = DampedSystem::new(frame(&weak)).unwrap();
    // translations only, driven at the tip across the arm
    let tip = DofRef::new(POST + ARM + 1, Dof::Uy);
    let channels: Vec<Channel> = [4, 8, 13, 18, 23]
        .into_iter()
        .flat_map(|n| [Dof::Ux, Dof::Uy].map(|d| Channel::new(DofRef::new(n, d), tip)))
        .collect();
    let lines: Vec<f64> = (4..=1200).map(|i| 0.5 * f64::from(i)).collect();
    let mut measured = synthesize(&truth, &channels, &lines).unwrap();
    NoiseModel::relative(0.01, 11).apply(&mut measured);

    let d = diagnose(&nominal, &measured, &DiagnoseOptions::default()).unwrap();
    let top = &d.ranking[0];
    assert_eq!(top.kind, EffectKind::StiffnessChange, "{}", top.description);
    assert!(top.description.starts_with("bending "), "the bending-only change should lead: {}", top.description);
    assert_eq!(top.elements, vec![5, 6], "{}", top.description);
    let p = &top.parameters[0];
    assert_eq!(p.name, "element.5..6.bending");
    let z = (p.value / FACTOR).ln().abs() / p.relative_std;
    assert!(z < 3.0, "bending factor {} vs {FACTOR}: {z:.1} sd", p.value);
    // its whole-element twin fits worse and puts the factor elsewhere
    let whole = d
        .ranking
        .iter()
        .find(|r| r.description == "stiffness change of elements 5..6")
        .expect("the whole-element change of the same elements was fitted");
    assert!(whole.delta_bic > top.delta_bic + 10.0, "{} vs {}", whole.delta_bic, top.delta_bic);
    let q = &whole.parameters[0];
    let z = (q.value / FACTOR).ln().abs() / q.relative_std;
    assert!(z > 3.0, "the whole-element factor {} is {z:.1} sd from {FACTOR}: the twin would not be needed", q.value);
}

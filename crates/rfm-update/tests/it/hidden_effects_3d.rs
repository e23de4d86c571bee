//! The hidden-effect test in space: a table frame (four legs, four rails,
//! two elements each) with one hidden effect drawn from a seeded family
//! (a loose corner joint, an extra mass of 2-8 % of the frame's, a loss of
//! 30-60 % of one element's stiffness, a flexible, lossy foot), its FRFs
//! synthesised with 1 % noise at the translations of the top corners and
//! the rails' vertical, under two horizontal impacts, 1 to 200 Hz (ten
//! modes, some 2 Hz apart); the diagnosis must rank first the right kind at
//! the right place (a neighbour counts), explaining the data to 1.5 times
//! the noise.
//!
//! Each truth is built here on its own, not by the diagnosis's edits: the
//! loose joint's rail starts on a second node at the corner from the
//! beginning, joined by springs and ties; the flexible foot stands on a
//! ground spring instead of its clamp. Draws whose effect changes the FRFs
//! by less than five times the noise are redrawn, and counted (none were).
//!
//! CI runs two trials of each kind, 8 in all, in about 45 s of the dev
//! profile on two cores, and requires 90 %; all 8 pass.
//! `HIDDEN_3D_TRIALS_PER_KIND=10` runs the larger study with the same
//! criterion: 40 of 40 (4 minutes). Before the screen tried stiffness and
//! mass changes from spread starts, the fits of those candidates stayed in
//! a local minimum next to the nominal model (element 11's factor at
//! 0.9998 for a truth of 0.605, here): a first version of this test (three
//! elements per member, 2 to 400 Hz, no misfit requirement) named 10 of 10
//! joints and supports, 3 of 10 masses and 0 of 10 stiffness losses.

use damping::DampedSystem;
use fe_model::{Dimension, Dof, DofRef, Group, Model, Section};
use frf::{Channel, FrfSet, NoiseModel, synthesize};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rfm_update::diagnose::{DiagnoseOptions, EffectKind, diagnose};

const E: f64 = 2.1e11;
const RHO: f64 = 7850.0;
/// Plan (x, z) of the corners A, B, C, D and the height (y up).
const CORNERS: [[f64; 2]; 4] = [[0.0, 0.0], [0.8, 0.0], [0.8, 0.5], [0.0, 0.5]];
const HEIGHT: f64 = 0.6;
const PER: u32 = 2;
/// The measured lines: `STEP_HZ` to `LINES * STEP_HZ`.
const LINES: u32 = 200;
const STEP_HZ: f64 = 1.0;
/// The noise of the synthesised data (relative, RMS).
const NOISE: f64 = 0.01;

/// What a truth adds to the nominal table.
#[derive(Clone, Debug)]
enum Effect {
    /// Rail `rail` (0..4, from corner `rail` to the next) starts on a
    /// node of its own at its first corner, joined to the corner by
    /// rotational springs (translations tied), viscously damped.
    LooseJoint { rail: usize, k: [f64; 3], alpha: f64 },
    /// A lumped mass at a node.
    Mass { node: u32, m: f64 },
    /// A stiffness factor on one element.
    StiffnessLoss { element: u32, factor: f64 },
    /// Foot `leg` on ground springs: stiff translations, flexible rotations.
    FlexibleFoot { leg: usize, k: [f64; 6], alpha: f64 },
}

/// Node ids: feet 1-4, top corners 5-8, then the nodes inside the legs
/// (upwards) and inside the rails (rail `j` from corner `j` to the next),
/// `PER - 1` each. Elements: the legs' `1..=4 PER`, then the rails', each
/// member's in order from its first node.
fn corner(i: usize) -> u32 {
    5 + i as u32
}

/// The first node inside leg `i` (0..4), or inside rail `i` (4..8 for rails 0..4).
fn first_inside(member: usize) -> u32 {
    9 + (PER - 1) * member as u32
}

/// The first element of rail `j`.
fn first_rail_element(j: usize) -> u32 {
    4 * PER + 1 + PER * j as u32
}

/// The nodes inside the members, and the top corners: where a mass may hide.
fn free_nodes() -> Vec<u32> {
    (5..first_inside(8)).collect()
}

/// The table, with `effect` when it is a truth.
fn table(effect: Option<&Effect>) -> Model {
    let mut m = Model::with_dimension("table in space", Dimension::Spatial);
    let frame = m.add_group(Group::new("frame").rayleigh(2e-6, 1.0)).unwrap();
    let steel = m.add_material("steel", E, RHO).unwrap();
    m.set_poisson(steel, 0.3).unwrap();
    let leg = m.add_section(Section::rectangle("leg", 0.025, 0.025)).unwrap();
    // on edge: h along the local y axis, which the orientations make vertical
    let rail = m.add_section(Section::rectangle("rail", 0.01, 0.04)).unwrap();
    for (i, c) in CORNERS.iter().enumerate() {
        let i = i as u32;
        m.add_node_at(1 + i, [c[0], 0.0, c[1]]).unwrap();
        m.add_node_at(5 + i, [c[0], HEIGHT, c[1]]).unwrap();
    }
    let mut element = 1;
    // a member of PER elements from node a to b through new nodes first..
    let mut member = |m: &mut Model, a: u32, b: u32, first: u32, section: usize, orientation: Option<[f64; 3]>| {
        let (p, q) = (m.node(fe_model::NodeId(a)).unwrap().position(), m.node(fe_model::NodeId(b)).unwrap().position());
        let mut ids = vec![a];
        for k in 1..PER {
            let t = f64::from(k) / f64::from(PER);
            let id = first + k - 1;
            m.add_node_at(id, [0, 1, 2].map(|c| p[c] + t * (q[c] - p[c]))).unwrap();
            ids.push(id);
        }
        ids.push(b);
        for w in ids.windows(2) {
            let i = m.add_beam(element, [w[0], w[1]], steel, section, frame).unwrap();
            if orientation.is_some() {
                m.orient_beam(i, orientation, 0.0).unwrap();
            }
            element += 1;
        }
    };
    for i in 0..4u32 {
        member(&mut m, 1 + i, 5 + i, first_inside(i as usize), leg, None);
    }
    for j in 0..4usize {
        let (a, b) = (corner(j), corner((j + 1) % 4));
        // a loose joint: the rail starts on node 100, beside its corner
        let start = match effect {
            Some(Effect::LooseJoint { rail: r, .. }) if *r == j => {
                let p = m.node(fe_model::NodeId(a)).unwrap().position();
                m.add_node_at(100, p).unwrap();
                100
            }
            _ => a,
        };
        // rails along x bend vertically about global z, rails along z about global x
        let along_x = (CORNERS[j][0] - CORNERS[(j + 1) % 4][0]).abs() > 0.0;
        let orientation = if along_x { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        member(&mut m, start, b, first_inside(4 + j), rail, Some(orientation));
    }
    let flexible_foot = match effect {
        Some(Effect::FlexibleFoot { leg, .. }) => Some(*leg),
        _ => None,
    };
    for i in 0..4 {
        if flexible_foot != Some(i) {
            m.add_support(1 + i as u32, &Dof::SPATIAL).unwrap();
        }
    }
    match effect {
        None | Some(Effect::FlexibleFoot { .. }) | Some(Effect::LooseJoint { .. }) => {}
        Some(Effect::Mass { node, m: mass }) => {
            let g = m.add_group(Group::new("box")).unwrap();
            m.add_mass("box", *node, *mass, [0.0; 3], g).unwrap();
        }
        Some(Effect::StiffnessLoss { element, factor }) => {
            let q = m.quantity(&format!("element.{element}.stiffness")).unwrap();
            m.set(q, *factor).unwrap();
        }
    }
    match effect {
        Some(Effect::LooseJoint { rail, k, alpha }) => {
            let g = m.add_group(Group::new("bolt").rayleigh(*alpha, 0.0)).unwrap();
            let c = corner(*rail);
            m.add_spring("bolt", c, Some(100), [0.0, 0.0, 0.0, k[0], k[1], k[2]], g).unwrap();
            m.add_tie(c, 100, &[Dof::Ux, Dof::Uy, Dof::Uz]).unwrap();
        }
        Some(Effect::FlexibleFoot { leg, k, alpha }) => {
            let g = m.add_group(Group::new("pad").rayleigh(*alpha, 0.0)).unwrap();
            m.add_spring("pad", 1 + *leg as u32, None, *k, g).unwrap();
        }
        _ => {}
    }
    m
}

/// The nodes and elements where an effect acts, for the place check.
fn place(e: &Effect) -> (Vec<u32>, Vec<u32>) {
    match e {
        Effect::LooseJoint { rail, .. } => (vec![corner(*rail)], vec![first_rail_element(*rail)]),
        Effect::Mass { node, .. } => (vec![*node], vec![]),
        Effect::StiffnessLoss { element, .. } => (vec![], vec![*element]),
        Effect::FlexibleFoot { leg, .. } => (vec![1 + *leg as u32], vec![]),
    }
}

/// One effect of kind `k` drawn from the family.
fn draw(k: EffectKind, rng: &mut ChaCha8Rng) -> Effect {
    // log-uniform between a and b
    let log = |rng: &mut ChaCha8Rng, a: f64, b: f64| (rng.random_range(a.ln()..b.ln())).exp();
    match k {
        EffectKind::FlexibleJoint => Effect::LooseJoint {
            rail: rng.random_range(0..4),
            k: [log(rng, 2e3, 3e4), log(rng, 2e3, 3e4), log(rng, 5e3, 8e4)],
            alpha: log(rng, 2e-5, 2e-4),
        },
        EffectKind::LumpedMass => {
            // a free node: a top corner or inside a leg or rail
            let nodes = free_nodes();
            let node = nodes[rng.random_range(0..nodes.len())];
            let total = table(None).total_mass();
            Effect::Mass { node, m: total * rng.random_range(0.02..0.08) }
        }
        EffectKind::StiffnessChange => {
            Effect::StiffnessLoss { element: rng.random_range(1..=8 * PER), factor: rng.random_range(0.4..0.7) }
        }
        EffectKind::FlexibleSupport => {
            // the leg's bending stiffness 4 E I / L of one element sets the
            // scale of the rotations; translations near rigid
            let ei = E * 0.025f64.powi(4) / 12.0;
            let le = HEIGHT / f64::from(PER);
            let kr = 4.0 * ei / le;
            let kt = 1e3 * 12.0 * ei / le.powi(3);
            let r = |rng: &mut ChaCha8Rng| kr * log(rng, 0.05, 0.5);
            Effect::FlexibleFoot {
                leg: rng.random_range(0..4),
                k: [kt, kt, kt, r(rng), r(rng), r(rng)],
                alpha: log(rng, 1e-5, 1e-4),
            }
        }
        _ => unreachable!("not drawn"),
    }
}

/// Horizontal impacts at corners B (x) and D (z); the corners' translations
/// and the rails' vertical inside, 2 to 400 Hz every 2 Hz.
fn measure(truth: &Model, noise: f64, seed: u64) -> FrfSet {
    let references = [DofRef::new(corner(1), Dof::Ux), DofRef::new(corner(3), Dof::Uz)];
    let mut responses: Vec<DofRef> =
        (5..=8).flat_map(|n| [Dof::Ux, Dof::Uy, Dof::Uz].map(|d| DofRef::new(n, d))).collect();
    // inside each rail, the node nearest its middle
    responses.extend((4..8).map(|j| DofRef::new(first_inside(j) + (PER - 1) / 2, Dof::Uy)));
    let channels: Vec<Channel> =
        references.iter().flat_map(|&r| responses.iter().map(move |&o| Channel::new(o, r))).collect();
    let lines: Vec<f64> = (1..=LINES).map(|i| STEP_HZ * f64::from(i)).collect();
    let sys = DampedSystem::new(truth.clone()).unwrap();
    let mut set = synthesize(&sys, &channels, &lines).unwrap();
    NoiseModel::relative(noise, seed).apply(&mut set);
    set
}

/// RMS relative difference between the nominal table's FRFs and clean data.
fn systematic_misfit(truth: &Model) -> f64 {
    let clean = measure(truth, 0.0, 0);
    let nominal = DampedSystem::new(table(None)).unwrap();
    let h = synthesize(&nominal, clean.channels(), clean.frequencies_hz()).unwrap();
    let n = clean.values().len() as f64;
    (h.values().iter().zip(clean.values()).map(|(a, b)| ((a - b) / b.norm()).norm_sqr()).sum::<f64>() / n).sqrt()
}

#[test]
fn diagnosis_names_hidden_effects_in_a_space_frame() {
    let kinds =
        [EffectKind::FlexibleJoint, EffectKind::LumpedMass, EffectKind::StiffnessChange, EffectKind::FlexibleSupport];
    let per_kind = std::env::var("HIDDEN_3D_TRIALS_PER_KIND").ok().and_then(|v| v.parse().ok()).unwrap_or(2);
    let nominal = table(None);
    let opts = DiagnoseOptions::default();
    let mut rng = ChaCha8Rng::seed_from_u64(2027);
    let (mut named, mut total) = (0, 0);
    for (k, &kind) in kinds.iter().enumerate() {
        let mut redrawn = 0;
        for t in 0..per_kind {
            let effect = loop {
                let e = draw(kind, &mut rng);
                if systematic_misfit(&table(Some(&e))) >= 5.0 * NOISE {
                    break e;
                }
                redrawn += 1;
            };
            let measured = measure(&table(Some(&effect)), NOISE, 100 * k as u64 + t as u64);
            let d = diagnose(&nominal, &measured, &opts).unwrap();
            let top = &d.ranking[0];
            let (nodes, elements) = place(&effect);
            // the right kind at the right place, explaining the data to the noise
            let right = top.kind == kind
                && d.candidates[top.candidate].near(&nominal, &nodes, &elements)
                && top.misfit <= 1.5 * NOISE;
            println!(
                "{:<22} trial {t}: {effect:?}\n    misfit nominal {:.3}, noise {:.3}; top = {} (dBIC {:.0}, misfit {:.3}): {}",
                kind.label(),
                d.nominal_misfit,
                d.noise,
                top.description,
                top.delta_bic,
                top.misfit,
                if right { "right" } else { "WRONG" }
            );
            if !right {
                // what the hidden kind's best candidate reached: a fit left
                // near its start is a local minimum of the misfit
                for r in d.ranking.iter().filter(|r| r.kind == kind).take(2) {
                    let values: Vec<String> =
                        r.parameters.iter().map(|p| format!("{} = {:.4e}", p.name, p.value)).collect();
                    println!("    best of its kind: {} (misfit {:.3}): {}", r.description, r.misfit, values.join(", "));
                }
            }
            named += usize::from(right);
            total += 1;
        }
        println!("{}: {redrawn} draws below five times the noise were redrawn", kind.label());
    }
    let rate = named as f64 / total as f64;
    println!("named first at the right place: {named}/{total} ({:.0} %)", 100.0 * rate);
    assert!(rate >= 0.9, "the hidden effect was named first at its place in only {named} of {total} trials");
}

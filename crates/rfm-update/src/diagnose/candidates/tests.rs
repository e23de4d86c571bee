use super::*;
use fe_model::{Assembly, Group, samples};

/// Two members meeting at a right angle at node 3, clamped at node 1.
fn l_frame() -> Model {
    let mut m = Model::new("L-frame");
    let g = m.add_group(Group::new("frame").rayleigh(1e-5, 0.5)).unwrap();
    let steel = m.add_material("steel", 2.1e11, 7850.0).unwrap();
    let sec = m.add_section(fe_model::Section::rectangle("bar", 0.02, 0.02)).unwrap();
    for (id, x, y) in [(1, 0.0, 0.0), (2, 0.0, 0.3), (3, 0.0, 0.6), (4, 0.25, 0.6), (5, 0.5, 0.6)] {
        m.add_node(id, x, y).unwrap();
    }
    for (id, a, b) in [(1, 1, 2), (2, 2, 3), (3, 3, 4), (4, 4, 5)] {
        m.add_beam(id, [a, b], steel, sec, g).unwrap();
    }
    m.add_support(1, &Dof::PLANAR).unwrap();
    m
}

/// Every candidate's change applies to the whole model, which still
/// assembles (a candidate carries no whole model that could be checked
/// beforehand), and its parameters start at the same values there as in
/// its part; so do the variants that hold a spring rigid.
#[test]
fn every_candidate_applies_to_the_whole_model() {
    for model in [samples::frame_grid(2, 2, 3), samples::frame_with_joint(), samples::cantilever(6), l_frame()] {
        let all = generate(&model, &CandidateOptions { per_element_limit: 40, ..CandidateOptions::default() });
        assert!(all.iter().any(|c| c.kind == EffectKind::FlexibleSupport));
        // a change that fails on its part drops its candidate: none may
        let new_joints = all.iter().filter(|c| matches!(c.edit, Edit::Joint { in_line: false, .. })).count();
        let corners = model
            .nodes()
            .iter()
            .filter(|n| {
                let at = model.beams_at(n.id);
                at.len() == 2 && {
                    let (_, c0, s0) = model.beam_geometry(at[0]);
                    let (_, c1, s1) = model.beam_geometry(at[1]);
                    (c0 * c1 + s0 * s1).abs() < 0.5
                }
            })
            .count();
        assert!(new_joints >= corners, "{new_joints} new joints for {corners} corners in {}", model.title);
        let mut held = 0;
        let mut per_direction = 0;
        for c in &all {
            check(&model, c);
            // its variant with a group per direction, from its starting values
            if let Some(v) = per_direction_variant(&model, c, &c.start_values()) {
                per_direction += 1;
                check(&model, &v);
                assert!(v.description.ends_with("one group per direction)"), "{}", v.description);
                assert_eq!(v.start_values().len(), v.parameters.len());
                // a held spring takes its own group's damping along
                let springs: Vec<usize> = (0..v.roles.len())
                    .filter(|&i| matches!(v.roles[i], Role::Spring(d) if d.is_translation()))
                    .collect();
                if let Some(h) = v.holding(&model, &springs[..1]) {
                    let Role::Spring(d) = v.roles[springs[0]] else { unreachable!() };
                    let (Edit::Support { name, dim, .. } | Edit::Joint { name, dim, .. }) = &v.edit else {
                        unreachable!()
                    };
                    let group = format!("group.{}.", edit::direction_name(name, *dim, d));
                    assert!(h.parameters.iter().all(|p| !p.starts_with(&group)), "{:?}", h.parameters);
                    assert!(h.held.iter().any(|p| p.starts_with(&group)), "{:?}", h.held);
                    let n_springs = |c: &Candidate| c.roles.iter().filter(|r| matches!(r, Role::Spring(_))).count();
                    assert_eq!(n_springs(&h) + 1, n_springs(&v));
                    check(&model, &h);
                }
            }
            // hold every spring that can be held
            let springs: Vec<usize> =
                (0..c.roles.len()).filter(|&i| matches!(c.roles[i], Role::Spring(d) if d.is_translation())).collect();
            if let Some(h) = c.holding(&model, &springs) {
                held += 1;
                assert!(h.parameters.len() < c.parameters.len() && !h.held.is_empty(), "{}", h.description);
                check(&model, &h);
            }
        }
        assert!(held > 0, "no candidate of {} held a spring", model.title);
        assert!(per_direction > 0, "no candidate of {} has a variant per direction", model.title);
    }
}

fn check(model: &Model, c: &Candidate) {
    let whole = c.model(model).unwrap();
    assert!(Assembly::new(&whole).is_ok(), "{} breaks the model", c.description);
    let (pw, pp) = (c.parameters_in(&whole).unwrap(), c.parameters_in(c.part()).unwrap());
    for (w, p) in pw.iter().zip(&pp) {
        assert_eq!(whole.get(w.quantities[0]), c.part().get(p.quantities[0]), "{}", w.name);
    }
}

/// On a straight member every interior node gets an in-line joint, single
/// elements come at every offset and longer windows at their stride (the
/// last flush with the end), and each window carries the four changes.
#[test]
fn small_models_get_in_line_joints_and_windows_at_every_offset() {
    let model = samples::cantilever(10);
    let all = generate(&model, &CandidateOptions::default());
    let in_line: Vec<u32> = all
        .iter()
        .filter(|c| matches!(c.edit, Edit::Joint { in_line: true, .. }) && c.damping() == Some("viscous"))
        .map(|c| c.nodes[0])
        .collect();
    let interior = model.nodes().iter().filter(|n| model.beams_at(n.id).len() == 2).count();
    assert_eq!(in_line.len(), interior, "{in_line:?}");
    for (size, stride, expected) in [(1usize, 1, 10), (2, 0, 0), (3, 2, 5), (4, 0, 0), (6, 3, 3), (8, 0, 0)] {
        let n = all.iter().filter(|c| c.kind == EffectKind::StiffnessChange && c.elements.len() == size).count();
        assert_eq!(n, expected, "stiffness windows of {size} at stride {stride}");
        for kind in [EffectKind::MassChange, EffectKind::ViscousDamping, EffectKind::NonViscousDamping] {
            assert_eq!(all.iter().filter(|c| c.kind == kind && c.elements.len() == size).count(), n, "{kind:?}");
        }
    }
    // descriptions name a candidate uniquely
    let mut seen = std::collections::HashSet::new();
    for c in &all {
        assert!(seen.insert(c.description.clone()), "{} twice", c.description);
    }
}

/// Large models get coarse windows, and the refinement around a leader
/// adds every window and in-line joint near it, and the fuller variants.
#[test]
fn large_models_refine_windows_and_variants_around_the_leaders() {
    let model = samples::cantilever(30);
    let opts = CandidateOptions { per_element_limit: 10, ..CandidateOptions::default() };
    let first = generate(&model, &opts);
    assert!(!first.iter().any(|c| matches!(c.edit, Edit::Joint { in_line: true, .. })));
    let tried: std::collections::HashSet<String> = first.iter().map(|c| c.description.clone()).collect();
    let leader = first.iter().find(|c| c.kind == EffectKind::StiffnessChange && c.elements.contains(&15)).unwrap();
    let mass = first.iter().find(|c| c.kind == EffectKind::LumpedMass && c.nodes == [20]).unwrap();
    let refined = refine(&model, &opts, &[leader, mass], &tried);
    assert!(refined.iter().any(|c| c.kind == EffectKind::StiffnessChange && c.elements == [15]));
    assert!(refined.iter().any(|c| matches!(c.edit, Edit::Joint { in_line: true, node: 16, .. })));
    assert!(refined.iter().any(|c| c.description == "lumped mass with rotary inertia at node 20"));
    assert!(refined.iter().all(|c| !tried.contains(&c.description)));
}

/// The least and largest loss factors over the band equal a brute-force
/// search of `Im / Re` of the kernel factor `1 + j w h(w) alpha` to first
/// order, for relaxation parameters below, inside and above the band and
/// viscous.
#[test]
fn the_least_and_largest_loss_factors_are_found_over_the_band() {
    let band = (2.0 * std::f64::consts::PI * 5.0, 2.0 * std::f64::consts::PI * 500.0);
    let alpha = 2e-4;
    for mu in [Some(3.0), Some(100.0), Some(1000.0), Some(1e5), None] {
        let brute = (0..=20000)
            .map(|k| band.0 * (band.1 / band.0).powf(k as f64 / 20000.0))
            .map(|w| {
                let h = match mu {
                    Some(m) => num_complex::Complex64::new(m, 0.0) / num_complex::Complex64::new(m, w),
                    None => num_complex::Complex64::new(1.0, 0.0),
                };
                // the imaginary part of j w h alpha is the loss factor to first order
                (num_complex::Complex64::new(0.0, w) * h * alpha).im
            })
            .fold((f64::INFINITY, 0.0), |(lo, hi): (f64, f64), eta| (lo.min(eta), hi.max(eta)));
        let got = loss_factor_range(alpha, mu, band);
        assert!((got.0 / brute.0 - 1.0).abs() < 1e-6, "mu {mu:?}: least {} vs {}", got.0, brute.0);
        assert!((got.1 / brute.1 - 1.0).abs() < 1e-6, "mu {mu:?}: most {} vs {}", got.1, brute.1);
    }
}

/// A support with a group per direction whose translational springs are
/// held (the data see only its rotation) is the plain support with kr
/// alone, under the plain one's names and description: the diagnosis then
/// finds it among its candidates instead of offering it twice.
#[test]
fn a_support_per_direction_left_with_one_spring_is_the_plain_support() {
    let model = samples::cantilever(6);
    let all = generate(&model, &CandidateOptions::default());
    for c in all.iter().filter(|c| c.kind == EffectKind::FlexibleSupport) {
        let v = per_direction_variant(&model, c, &c.start_values()).unwrap();
        assert_eq!(v.parameters.len(), 3 * (c.parameters.len() - 2), "{:?}", v.parameters);
        let translations: Vec<usize> =
            (0..v.roles.len()).filter(|&i| matches!(v.roles[i], Role::Spring(d) if d.is_translation())).collect();
        let h = v.holding(&model, &translations).unwrap();
        let plain = c.holding(&model, &[0, 1]).unwrap();
        assert_eq!(h.description, plain.description);
        assert_eq!(h.parameters, plain.parameters);
        assert_eq!(h.edit, plain.edit);
        assert_eq!(h.held.len(), v.parameters.len() - h.parameters.len(), "{:?}", h.held);
    }
}

/// A viscous damper beside a support's spring whose loss factor is 0.3 at
/// 100 Hz (1.2 at the band's top, 400 Hz) is plausible; the same alpha in a
/// group of elements (a material losing more than it stores) is not, and
/// neither is a support damper above 1 over the whole band.
#[test]
fn a_damper_beside_a_spring_may_dominate_it_at_the_top_of_the_band() {
    let model = l_frame();
    let all = generate(&model, &CandidateOptions::default());
    let band = (2.0 * std::f64::consts::PI * 1.0, 2.0 * std::f64::consts::PI * 400.0);
    let alpha = 0.3 / (2.0 * std::f64::consts::PI * 100.0);
    let viscous = |c: &&Candidate| c.roles.contains(&Role::Alpha) && !c.roles.contains(&Role::Mu);
    let judge = |c: &Candidate, alpha: f64| {
        let mut c = c.clone();
        c.band_rad = band;
        let values: Vec<f64> =
            c.roles.iter().zip(c.start_values()).map(|(&r, v)| if r == Role::Alpha { alpha } else { v }).collect();
        c.implausible(&values, &vec![true; values.len()])
    };
    let support = all
        .iter()
        .filter(viscous)
        .find(|c| c.kind == EffectKind::FlexibleSupport)
        .expect("a viscous support candidate");
    assert_eq!(judge(support, alpha), None, "{}", support.description);
    let whole_band = judge(support, 2.0 / band.0).expect("above 1 over the whole band");
    assert!(whole_band.contains("over the whole band"), "{whole_band}");
    let region = all.iter().filter(viscous).find(|c| matches!(c.edit, Edit::Region { .. })).expect("a viscous region");
    let e = judge(region, alpha).expect("a material above 1 in the band");
    assert!(e.contains("a loss factor of 1.20 (above 1) in the band"), "{e}");
}

/// A kind's name is its JSON name (the reports read the one a case's
/// history keeps as the other), names its kind back and is one of the
/// names fe-model accepts in a history; every kind has one of its own.
#[test]
fn effect_kind_names_are_their_json_names_and_read_back() {
    let mut seen = std::collections::HashSet::new();
    for k in EffectKind::ALL {
        assert_eq!(serde_json::to_value(k).unwrap(), serde_json::Value::from(k.name()), "{k:?}");
        assert_eq!(EffectKind::from_name(k.name()), Some(k));
        assert!(seen.insert(k.name()), "{k:?}");
    }
    assert_eq!(EffectKind::from_name("flexible joint"), None);
    // the names a case's history may use are these, in this order
    assert_eq!(EffectKind::ALL.map(EffectKind::name), fe_model::case::EFFECT_KINDS);
}

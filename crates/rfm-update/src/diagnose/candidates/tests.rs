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

/// The resonators of `model` tuned to `hz` over the band 1-400 Hz.
fn resonators_of(model: &Model, hz: &[f64]) -> Vec<Candidate> {
    let opts = CandidateOptions { band_hz: (1.0, 400.0), resonator_hz: hz.to_vec(), ..CandidateOptions::default() };
    generate(model, &opts).into_iter().filter(|c| c.kind == EffectKind::Resonator).collect()
}

/// `model`'s receptances at `channels` and `lines` (Hz).
fn receptances(model: &Model, channels: &[frf::Channel], lines: &[f64]) -> frf::FrfSet {
    frf::synthesize(&damping::DampedSystem::new(model.clone()).unwrap(), channels, lines).unwrap()
}

/// `Z(w)` of a model at `f` Hz by the pair of DOFs of each entry of its
/// pattern (in order), so that two models numbered apart compare.
fn z_by_dofs(
    model: &Model,
    f: f64,
) -> std::collections::HashMap<(fe_model::DofRef, fe_model::DofRef), num_complex::Complex64> {
    let sys = damping::DampedSystem::new(model.clone()).unwrap();
    let z = sys.z_values(2.0 * std::f64::consts::PI * f);
    let (pattern, dofs) = (sys.assembly().pattern(), sys.assembly().dofs());
    let mut out = std::collections::HashMap::new();
    for col in 0..pattern.n() {
        for (k, &row) in pattern.rows(col).iter().enumerate() {
            let (a, b) = (dofs.dof_of(row), dofs.dof_of(col));
            out.insert((a.min(b), a.max(b)), z[pattern.col_ptr()[col] + k]);
        }
    }
    out
}

/// The whole model of `c` with its parameters at `values`.
fn whole_at(model: &Model, c: &Candidate, values: &[f64]) -> Model {
    let mut m = c.model(model).unwrap();
    for (p, &v) in c.parameters_in(&m).unwrap().iter().zip(values) {
        for &q in &p.quantities {
            m.set(q, v).unwrap();
        }
    }
    m
}

/// Without frequencies to tune to there is no resonator; with some, a
/// resonator tuned to each (two a description cannot tell apart are one)
/// at every node free in a translation, in each free translation and, in a
/// plane, in both, viscous and non-viscous: its mass 2 % of the
/// structure's, its springs tuned to the frequency, its damper losing 5 %
/// there. Each applies to the whole model, which passes the kinematic
/// check (its mass node held where it does not act), with its parameters
/// at the same start in its part.
#[test]
fn resonators_are_tuned_to_each_extra_mode_at_every_node_that_can_move() {
    let mut model = l_frame();
    assert!(!generate(&model, &CandidateOptions::default()).iter().any(|c| c.kind == EffectKind::Resonator));
    // a roller at the tip: free in ux alone
    model.add_support(5, &[Dof::Uy]).unwrap();
    let all = resonators_of(&model, &[106.2, 106.24, 40.0]);
    // nodes 2, 3, 4: ux, uy and both; node 5: ux; viscous and not; two frequencies
    assert_eq!(all.len(), (3 * 3 + 1) * 2 * 2);
    assert!(all.iter().filter(|c| c.nodes == [5]).all(|c| c.dofs == [Dof::Ux]));
    let total = model.total_mass();
    for c in &all {
        check(&model, c);
        let v = c.start_values();
        let Edit::Resonator { dofs, .. } = &c.edit else { panic!("{}", c.description) };
        let m = v[0];
        assert_eq!((c.roles[0], m / total), (Role::Mass, 0.02), "{}", c.description);
        let hz = if c.description.contains("106.2 Hz") { 106.2 } else { 40.0 };
        let w = 2.0 * std::f64::consts::PI * hz;
        for (i, d) in dofs.iter().enumerate() {
            assert_eq!(c.roles[1 + i], Role::Spring(*d));
            assert!(((v[1 + i] / m).sqrt() / w - 1.0).abs() < 1e-12, "{}", c.description);
        }
        let alpha = v[1 + dofs.len()];
        let mu = c.roles.contains(&Role::Mu).then(|| v[v.len() - 1]);
        let eta = alpha * w * mu.map_or(1.0, |mu| mu * mu / (mu * mu + w * w));
        assert!((eta - 0.05).abs() < 1e-12, "{}: loss factor {eta}", c.description);
        assert_eq!(c.damping(), Some(if mu.is_some() { "non-viscous" } else { "viscous" }));
    }
    for d in ["resonator at node 3 (uy; 106.2 Hz; viscous)", "resonator at node 4 (ux, uy; 40.0 Hz; non-viscous)"] {
        assert!(all.iter().any(|c| c.description == d), "no {d}");
    }
    // in space: one per translation, none in two at once
    let space = samples::space_portal();
    let all = resonators_of(&space, &[50.0]);
    assert!(all.iter().all(|c| c.dofs.len() == 1) && all.iter().any(|c| c.dofs == [Dof::Uz]));
    for c in &all {
        check(&space, c);
    }
}

/// A resonator's driving-point receptances are the bare structure's
/// coupled with the dynamic stiffness of a mass on a complex spring in each
/// direction it acts in, `z = k* - k*^2 / (k* - w^2 m)` with `k* = k (1 +
/// j w h(w) alpha)`: `H = (I + H_0 Z)^-1 H_0` over the node's translations,
/// `Z = diag(z)`, for every variant, away from the starting values and
/// across the tuning frequency.
#[test]
fn a_resonators_driving_point_is_the_structure_coupled_with_its_dynamic_stiffness() {
    use num_complex::Complex64 as C64;
    let model = samples::cantilever(8);
    let tip = 9;
    let (ux, uy) = (fe_model::DofRef::new(tip, Dof::Ux), fe_model::DofRef::new(tip, Dof::Uy));
    let channels: Vec<frf::Channel> =
        [(ux, ux), (uy, ux), (ux, uy), (uy, uy)].into_iter().map(|(r, f)| frf::Channel::new(r, f)).collect();
    let lines = [5.0, 61.0, 90.0, 95.5, 104.0, 311.0];
    let bare = receptances(&model, &channels, &lines);
    let candidates: Vec<Candidate> = resonators_of(&model, &[90.0]).into_iter().filter(|c| c.nodes == [tip]).collect();
    assert_eq!(candidates.len(), 6);
    for c in &candidates {
        // heavier, detuned, damped otherwise
        let values: Vec<f64> = c
            .roles
            .iter()
            .zip(c.start_values())
            .map(|(r, v)| match r {
                Role::Mass => 1.3 * v,
                Role::Spring(Dof::Ux) => 0.8 * v,
                Role::Spring(_) => 1.1 * v,
                Role::Alpha => 2.0 * v,
                _ => 0.7 * v,
            })
            .collect();
        let got = receptances(&whole_at(&model, c, &values), &channels, &lines);
        let value = |r: Role| c.roles.iter().position(|&x| x == r).map(|i| values[i]);
        let m = value(Role::Mass).unwrap();
        let alpha = value(Role::Alpha).unwrap();
        for (k, &f) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let jw = C64::new(0.0, w);
            let h = value(Role::Mu).map_or(C64::new(1.0, 0.0), |mu| C64::new(mu, 0.0) / (mu + jw));
            let z = |d: Dof| {
                value(Role::Spring(d)).map_or(C64::new(0.0, 0.0), |kd| {
                    let ks = kd * (1.0 + jw * h * alpha);
                    ks - ks * ks / (ks - w * w * m)
                })
            };
            let (zx, zy) = (z(Dof::Ux), z(Dof::Uy));
            // H_0 over (ux, uy) of the tip, and A = I + H_0 Z
            let h0 = [[bare.get(0, k), bare.get(2, k)], [bare.get(1, k), bare.get(3, k)]];
            let a = [[1.0 + h0[0][0] * zx, h0[0][1] * zy], [h0[1][0] * zx, 1.0 + h0[1][1] * zy]];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            let inv = [[a[1][1] / det, -a[0][1] / det], [-a[1][0] / det, a[0][0] / det]];
            let want = |i: usize, j: usize| inv[i][0] * h0[0][j] + inv[i][1] * h0[1][j];
            for (ch, (i, j)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let (g, e) = (got.get(ch, k), want(i, j));
                assert!(
                    (g - e).norm() <= 1e-9 * e.norm().max(1e-12 * h0[1][1].norm()),
                    "{}: {f} Hz, channel {ch}: {g} vs {e}",
                    c.description
                );
            }
        }
    }
}

/// A resonator is plausible with a mass up to a quarter of the
/// structure's, tuned within the band widened twice either way, and with a
/// damper judged as a joint's (implausible only above a loss factor of 1
/// over the whole band); a spring the data do not determine is not judged.
#[test]
fn a_resonator_is_plausible_with_a_light_mass_tuned_near_the_band() {
    let model = samples::cantilever(8);
    let c = resonators_of(&model, &[90.0]).into_iter().find(|c| c.damping() == Some("viscous")).unwrap();
    let (total, start) = (model.total_mass(), c.start_values());
    let judge = |m: f64, hz: f64, alpha: f64, determined: bool| {
        let k = m * (2.0 * std::f64::consts::PI * hz).powi(2);
        let mut values = vec![m];
        values.extend(std::iter::repeat_n(k, c.parameters.len() - 2));
        values.push(alpha);
        let mut det = vec![true; values.len()];
        det[1] = determined;
        c.implausible(&values, &det)
    };
    let alpha = *start.last().unwrap();
    assert_eq!(judge(0.02 * total, 90.0, alpha, true), None, "{}", c.description);
    let heavy = judge(0.26 * total, 90.0, alpha, true).expect("more than a quarter of the structure");
    assert!(heavy.contains("more than a quarter of the structure's mass"), "{heavy}");
    assert_eq!(judge(0.24 * total, 90.0, alpha, true), None);
    for (hz, plausible) in [(0.49, false), (0.51, true), (790.0, true), (810.0, false)] {
        let e = judge(0.02 * total, hz, alpha, true);
        assert_eq!(e.is_none(), plausible, "{hz} Hz: {e:?}");
        if let Some(e) = e {
            assert!(e.contains("outside 0.5 .. 800.0 Hz (the band widened 2 times either way)"), "{e}");
        }
        // a spring the data do not determine says nothing
        assert_eq!(judge(0.02 * total, hz, alpha, false), None);
    }
    // a damper losing 0.3 at 100 Hz is plausible (1.2 at 400 Hz), one losing above 1 everywhere is not
    let w = |hz: f64| 2.0 * std::f64::consts::PI * hz;
    assert_eq!(judge(0.02 * total, 90.0, 0.3 / w(100.0), true), None);
    let lossy = judge(0.02 * total, 90.0, 1.1 / w(1.0), true).expect("above 1 over the band");
    assert!(lossy.contains("over the whole band"), "{lossy}");
}

/// A resonator in x and y whose kx the data do not determine is the
/// resonator in y alone, named and described as that candidate is; one
/// left acting nowhere is no candidate.
#[test]
fn a_resonator_direction_the_data_do_not_see_is_dropped() {
    let model = samples::cantilever(8);
    let all = resonators_of(&model, &[90.0]);
    for form in ["viscous", "non-viscous"] {
        let at =
            |dofs: &[Dof]| all.iter().find(|c| c.nodes == [9] && c.dofs == dofs && c.damping() == Some(form)).unwrap();
        let (both, uy) = (at(&[Dof::Ux, Dof::Uy]), at(&[Dof::Uy]));
        let kx = both.roles.iter().position(|&r| r == Role::Spring(Dof::Ux)).unwrap();
        let h = both.holding(&model, &[kx]).expect("the resonator in y");
        assert_eq!(
            (&h.description, &h.parameters, &h.edit, &h.dofs),
            (&uy.description, &uy.parameters, &uy.edit, &uy.dofs)
        );
        assert_eq!(h.held, vec![both.parameters[kx].clone()]);
        check(&model, &h);
        let ky = uy.roles.iter().position(|&r| r == Role::Spring(Dof::Uy)).unwrap();
        assert!(uy.holding(&model, &[ky]).is_none());
        // its damping and mass cannot be held
        assert!(uy.holding(&model, &[0, uy.parameters.len() - 1]).is_none());
    }
}

/// The description after a fit names the tuning of the fitted values; the
/// candidate keeps the one it was started at.
#[test]
fn a_fitted_resonator_is_described_at_its_fitted_tuning() {
    let model = samples::cantilever(8);
    let all = resonators_of(&model, &[90.0]);
    let c = all.iter().find(|c| c.nodes == [9] && c.dofs.len() == 2 && c.damping() == Some("viscous")).unwrap();
    let mut v = c.start_values();
    // kx to 81 Hz, ky to 99 Hz at the same mass
    v[1] *= 0.81;
    v[2] *= 1.21;
    assert_eq!(c.description, "resonator at node 9 (ux, uy; 90.0 Hz; viscous)");
    assert_eq!(c.description_at(&v), "resonator at node 9 (ux 81.0 Hz, uy 99.0 Hz; viscous)");
    v[1] = v[2];
    v[0] *= 1.21;
    assert_eq!(c.description_at(&v), "resonator at node 9 (ux, uy; 90.0 Hz; viscous)");
    // the other starts keep it tuned, at the other masses
    for (s, f) in c.other_starts().iter().zip([0.005, 0.08]) {
        let start = c.start_values();
        assert!((s[0] / model.total_mass() - f).abs() < 1e-15);
        assert_eq!(c.description_at(s), c.description);
        assert_eq!(s[3..], start[3..]);
    }
}

/// A resonator written into a case (`Edit::write`: a `[[resonators]]`
/// entry and its group) at fitted values reads back as the model
/// `Edit::apply` makes at those values: the same `Z(w)` entry by entry,
/// the resonator's own DOFs included, and the same parameter values, for
/// every variant; the snippet shown to the user is the same text.
#[test]
fn a_written_resonator_reads_back_as_the_applied_one() {
    let text = "title = \"cantilever\"\n[materials.steel]\nE = 2e11\nrho = 7800\n[sections.bar]\nb = 0.04\nh = 0.008\n\
                [groups.beam]\nalpha = 1e-5\nbeta = 0.5\n[[lines]]\nfrom = [0.0, 0.0]\nto = [1.0, 0.0]\nelements = 8\n\
                material = \"steel\"\nsection = \"bar\"\ngroup = \"beam\"\n[[supports]]\nnode = 1\n";
    let case = fe_model::CaseFile::parse(std::path::Path::new("beam.toml"), text).unwrap();
    let model = &case.model;
    let all: Vec<Candidate> = resonators_of(model, &[90.0]).into_iter().filter(|c| c.nodes == [6]).collect();
    assert_eq!(all.len(), 6);
    let lines = [3.0, 77.0, 89.0, 150.0];
    for c in &all {
        let values: Vec<f64> = c.start_values().iter().enumerate().map(|(i, v)| v * (1.0 + 0.1 * i as f64)).collect();
        let mut editor = case.editor().unwrap();
        c.edit.write(&mut editor, &c.parameters, &values, "a resonator").unwrap();
        let written = editor.text_at(&case.path).unwrap();
        assert!(written.contains(&c.edit.snippet(&c.parameters, &values).unwrap()), "{written}");
        let back = fe_model::CaseFile::parse(&case.path, &written).unwrap().model;
        for (name, &v) in c.parameters.iter().zip(&values) {
            let p = back.parameter(name).unwrap();
            assert_eq!(back.get(p.quantities[0]), v, "{name}");
        }
        let applied = whole_at(model, c, &values);
        for f in lines {
            let (a, b) = (z_by_dofs(&applied, f), z_by_dofs(&back, f));
            assert_eq!(a.len(), b.len(), "{}: the patterns differ", c.description);
            let scale = a.values().map(|v| v.norm()).fold(0.0, f64::max);
            for (key, x) in &a {
                let y = b.get(key).unwrap_or_else(|| panic!("{}: no entry {key:?} read back", c.description));
                assert!((x - y).norm() <= 1e-14 * scale, "{}: Z{key:?} at {f} Hz: {x} vs {y}", c.description);
            }
        }
    }
}

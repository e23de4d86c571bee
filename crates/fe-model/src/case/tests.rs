//! Tests of the case-file reader.

use std::path::Path;

use super::dof_list::parse_dof_list;
use super::*;
use crate::dof::{Dof, DofRef, PerDof};
use crate::model::NodeId;

fn parse(text: &str) -> Result<CaseFile, CaseError> {
    CaseFile::parse(Path::new("test.toml"), text)
}

/// A clamped beam of four elements, the case tests' model.
pub(super) const BEAM: &str = include_str!("../../tests/cases/beam.toml");

#[test]
fn a_line_generates_nodes_and_elements() {
    let c = parse(BEAM).unwrap();
    assert_eq!(c.model.nodes().len(), 5);
    assert_eq!(c.model.beams().len(), 4);
    assert_eq!(c.model.node(NodeId(5)).unwrap().x, 1.0);
}

#[test]
fn unknown_group_is_reported_with_line_column_and_suggestion() {
    let text = BEAM.replace("group = \"beam\"", "group = \"bean\"");
    let e = parse(&text).unwrap_err();
    assert!(e.message.contains("unknown group `bean`; did you mean `beam`?"), "{e}");
    let loc = e.location.unwrap();
    assert_eq!(text.lines().nth(loc.line - 1).unwrap().trim(), "group = \"bean\"");
}

#[test]
fn toml_syntax_errors_are_located() {
    let e = parse("title = \n").unwrap_err();
    assert_eq!(e.location.unwrap().line, 1);
    assert!(e.to_string().starts_with("test.toml:1:"), "{e}");
}

#[test]
fn a_joint_splits_a_node_ties_translations_and_adds_a_rotational_spring() {
    let text = format!(
        "{BEAM}\n[groups.j]\nalpha = 1e-3\n[[joints]]\nname = \"j3\"\nnode = 3\nelements = [3]\nkr = 5e3\ngroup = \"j\"\n"
    );
    let c = parse(&text).unwrap();
    assert_eq!(c.model.nodes().len(), 6);
    let e3 = &c.model.beams()[c.model.beam_index(crate::model::ElementId(3)).unwrap()];
    assert_eq!(e3.nodes[0], NodeId(6));
    assert_eq!(c.model.springs()[0].k, [0.0, 0.0, 5e3].into());
    assert_eq!(c.model.ties()[0].dofs, vec![Dof::Ux, Dof::Uy]);
    let bad = text.replace("elements = [3]", "elements = [1]");
    assert!(parse(&bad).unwrap_err().message.contains("does not end at node 3"));
}

/// Entries on the same node pair are one joint with a spring per entry, each
/// in its own group (as `rfm diagnose --apply` writes a joint with a loss
/// per direction): the node is split once and only the DOFs none of them
/// springs are tied. Such entries must detach the same elements and not
/// spring a DOF twice.
#[test]
fn joint_entries_on_one_node_pair_are_one_joint_with_a_group_per_spring() {
    let entry = |name: &str, key: &str, elements: &str| {
        format!(
            "[groups.{name}]\nalpha = 1e-3\n[[joints]]\nname = \"{name}\"\nnode = 3\nelements = {elements}\nnew_node = \
             9\n{key} = 5e3\ngroup = \"{name}\"\n"
        )
    };
    let text = format!("{BEAM}\n{}{}", entry("j_r", "kr", "[3]"), entry("j_x", "kx", "[3]"));
    let c = parse(&text).unwrap();
    assert_eq!(c.model.nodes().len(), 6);
    let e3 = &c.model.beams()[c.model.beam_index(crate::model::ElementId(3)).unwrap()];
    assert_eq!(e3.nodes[0], NodeId(9));
    let springs: Vec<(&str, PerDof, &str)> =
        c.model.springs().iter().map(|s| (s.name.as_str(), s.k, c.model.groups()[s.group].name.as_str())).collect();
    assert_eq!(springs, vec![("j_r", [0.0, 0.0, 5e3].into(), "j_r"), ("j_x", [5e3, 0.0, 0.0].into(), "j_x")]);
    assert!(c.model.springs().iter().all(|s| (s.a, s.b) == (NodeId(3), Some(NodeId(9)))));
    assert_eq!(c.model.ties().len(), 1);
    assert_eq!(c.model.ties()[0].dofs, vec![Dof::Uy]);
    // a translational entry alone on its pair is a joint without kr
    let alone = format!("{BEAM}\n{}", entry("j_x", "kx", "[3]"));
    assert!(parse(&alone).unwrap_err().message.contains("`j_x` needs `kr`"));
    let other = format!("{BEAM}\n{}{}", entry("j_r", "kr", "[3]"), entry("j_x", "kx", "[2]"));
    let e = parse(&other).unwrap_err();
    assert!(e.message.contains("lists the same elements"), "{e}");
    // at the second entry
    let second = other[..other.rfind("[[joints]]").unwrap()].lines().count() + 1;
    assert!(e.location.unwrap().line >= second, "{e}");
    let twice = format!("{BEAM}\n{}{}", entry("j_r", "kr", "[3]"), entry("j_x", "kr", "[3]"));
    assert!(parse(&twice).unwrap_err().message.contains("`kr` of the joint at node 3 is given by an earlier entry"));
}

/// A mass may sit at the node a joint makes (as `rfm diagnose --apply`
/// writes it), wherever the joint comes in the file.
#[test]
fn a_mass_may_sit_at_the_node_a_joint_makes() {
    let text = format!(
        "{BEAM}\n[[masses]]\nname = \"m\"\nnode = 6\nm = 0.2\ngroup = \"j\"\n\
         [groups.j]\nalpha = 1e-3\n[[joints]]\nname = \"j3\"\nnode = 3\nelements = [3]\nkr = 5e3\ngroup = \"j\"\n"
    );
    let c = parse(&text).unwrap();
    assert_eq!(c.model.masses()[0].node, NodeId(6));
    let e3 = &c.model.beams()[c.model.beam_index(crate::model::ElementId(3)).unwrap()];
    assert_eq!(e3.nodes[0], NodeId(6));
}

#[test]
fn assign_moves_a_range_of_elements_to_a_group() {
    let text = format!("{BEAM}\n[groups.patch]\nalpha = 1e-3\n[[assign]]\nelements = \"2..3\"\ngroup = \"patch\"\n");
    let c = parse(&text).unwrap();
    let g = c.model.group_index("patch").unwrap();
    let groups: Vec<usize> = c.model.beams().iter().map(|b| b.group).collect();
    assert_eq!(groups, vec![0, g, g, 0]);
    let e = parse(&text.replace("2..3", "3..9")).unwrap_err();
    assert!(e.message.contains("element 5 does not exist"), "{e}");
}

#[test]
fn update_bounds_must_hold_the_start_and_name_a_parameter() {
    let text = format!(
        "{BEAM}\n[measurement]\nfrequencies = [10.0, 20.0]\nreferences = [\"5:uy\"]\nresponses = [\"2..5:uy\"]\n[truth]\n[update]\nparameters = [\"group.beam.alpha\", \"element.1..2.stiffness\"]\nbounds = {{ \"group.beam.alpha\" = [1e-6, 1e-4] }}\n"
    );
    let c = parse(&text).unwrap();
    let u = c.update.unwrap();
    assert_eq!(u.bounds, vec![Some((1e-6, 1e-4)), None]);
    assert_eq!(u.parameters[1].quantities.len(), 2);
    let e = parse(&text.replace("[1e-6, 1e-4]", "[1e-4, 1e-3]")).unwrap_err();
    assert!(e.message.contains("outside its bounds"), "{e}");
    let e = parse(&text.replace("bounds = { \"group.beam.alpha\"", "bounds = { \"group.beam.beta\"")).unwrap_err();
    assert!(e.message.contains("not in the parameters list"), "{e}");
}

#[test]
fn test_points_parse_with_signs_and_codes() {
    assert_eq!(ChannelMap::parse_test_point("101:+Z"), Ok((101, 3)));
    assert_eq!(ChannelMap::parse_test_point(" 7 : -rz "), Ok((7, -6)));
    assert_eq!(ChannelMap::parse_test_point("5:Y"), Ok((5, 2)));
    assert_eq!(ChannelMap::parse_test_point("5:-4"), Ok((5, -4)));
    assert_eq!(ChannelMap::parse_test_point("-1:S"), Ok((-1, 0)));
    for bad in ["101", "101:W", "x:+Z", "101:7", "101:+-Z"] {
        assert!(ChannelMap::parse_test_point(bad).unwrap_err().contains("is not a test point"), "{bad}");
    }
}

#[test]
fn measurement_map_errors_are_located() {
    let base = format!(
        "{BEAM}[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\ndata = \"m.uff\"\n"
    );
    let ok = format!("{base}[[measurement.map]]\ntest = \"105:-Z\"\nmodel = \"5:uy\"\nsign = -1\n");
    let c = parse(&ok).unwrap();
    let m = &c.measurement.unwrap().map[0];
    assert_eq!((m.test_point(), m.model, m.sign), (Ok((105, -3)), DofRef::new(5, Dof::Uy), -1.0));

    let text = format!("{base}[[measurement.map]]\ntest = \"105:Q\"\nmodel = \"5:uy\"\n");
    let e = parse(&text).unwrap_err();
    assert!(e.message.contains("`105:Q` is not a test point"), "{e}");
    assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), "test = \"105:Q\"");

    let text = format!(
        "{base}[[measurement.map]]\ntest = \"105:+Z\"\nmodel = \"5:uy\"\n\
         [[measurement.map]]\ntest = \"105:-z\"\nmodel = \"4:uy\"\n"
    );
    let e = parse(&text).unwrap_err();
    assert!(e.message.contains("`105:-z` is already mapped by `105:+Z`"), "{e}");
    assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), "test = \"105:-z\"");
}

#[test]
fn unknown_keys_get_the_closest_valid_key_of_their_table() {
    for (good, bad, table_line) in [
        ("alpha = 1e-5", "alpah = 1e-5", "alpah = 1e-5"),
        ("elements = 4", "elemnts = 4", "elemnts = 4"),
        ("rho = 7800", "rh0 = 7800", "rh0 = 7800"),
    ] {
        let text = BEAM.replace(good, bad);
        let e = parse(&text).unwrap_err();
        let want = good.split(' ').next().unwrap();
        assert!(e.message.contains(&format!("did you mean `{want}`?")), "{e}");
        assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap(), table_line);
    }
    // a key far from every valid one gets the list, not a guess
    let e = parse(&BEAM.replace("alpha = 1e-5", "zzzzzz = 1")).unwrap_err();
    assert!(e.message.contains("unknown field `zzzzzz`") && !e.message.contains("did you mean"), "{e}");
}

#[test]
fn mask_rules_are_named_checked_and_need_a_data_file() {
    let base = format!("{BEAM}[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n");
    let with_data = format!("{base}data = \"m.csv\"\n");
    let c = parse(&format!("{with_data}mask = [\"non-finite\", \"unmodelled-channels\"]\n")).unwrap();
    assert_eq!(c.measurement.unwrap().mask, vec![MaskRule::NonFinite, MaskRule::UnmodelledChannels]);
    let e = parse(&format!("{with_data}mask = [\"non-finit\"]\n")).unwrap_err();
    assert!(e.message.contains("unknown mask `non-finit`; did you mean `non-finite`?"), "{e}");
    let e = parse(&format!("{with_data}mask = [\"nan\", \"x\"]\n")).unwrap_err();
    assert!(e.message.contains("(available: non-finite, duplicate-lines, unmodelled-channels, bad-coherence)"), "{e}");
    let e = parse(&format!("{with_data}mask = [\"non-finite\", \"non-finite\"]\n")).unwrap_err();
    assert!(e.message.contains("listed twice"), "{e}");
    let e = parse(&format!("{base}mask = [\"non-finite\"]\n")).unwrap_err();
    assert!(e.message.contains("has none"), "{e}");
    assert_eq!(e.location.unwrap().line, base.lines().count() + 1);
}

/// The beam with a truth and an update, for the `[check]` tests.
fn checked(check: &str) -> String {
    format!(
        "{BEAM}[measurement]\nfrequencies = [10.0, 20.0]\nreferences = [\"5:uy\"]\nresponses = [\"2..5:uy\"]\n\
         [truth]\nnoise = 0.01\n[update]\nparameters = [\"group.beam.alpha\", \"group.beam.stiffness\"]\n{check}"
    )
}

/// The line of `text` an error points at.
fn line_of<'a>(text: &'a str, e: &CaseError) -> &'a str {
    text.lines().nth(e.location.as_ref().expect("a located error").line - 1).unwrap().trim()
}

#[test]
fn check_tables_are_read_per_run() {
    let text = checked(
        "[check.rfm]\nstatus = [\"converged\"]\nmax_error = 1e-8\n\
         [check.output-error]\nstatus = [\"converged\", \"model_inadequate\"]\nwithin_sd = 3\nweak = [\"group.beam.stiffness\"]\nnoise = 0.1\n\
         [check.diagnosis]\nleader = \"joint at node 3\"\nmisfit_fall = 10\n",
    );
    let c = parse(&text).unwrap().check.unwrap();
    let rfm = c.rfm.unwrap();
    assert_eq!(
        (rfm.status, rfm.max_error, rfm.within_sd, rfm.noise),
        (vec!["converged".into()], Some(1e-8), None, None)
    );
    let oe = c.output_error.unwrap();
    assert_eq!(oe.status, vec!["converged".to_string(), "model_inadequate".into()]);
    assert_eq!((oe.within_sd, oe.noise, oe.weak), (Some(3.0), Some(0.1), vec!["group.beam.stiffness".to_string()]));
    let d = c.diagnosis.unwrap();
    assert_eq!((d.leader.as_str(), d.misfit_fall), ("joint at node 3", Some(10.0)));
    assert!(d.status.is_empty() && d.truth.is_none() && d.compare.is_empty());
    assert!(parse(&checked("")).unwrap().check.is_none());
    // the update of the loop against the truth that made the data, from the case's folder
    let text = checked(
        "[check.diagnosis]\nleader = \"joint\"\nstatus = [\"converged\"]\ntruth = \"t.toml\"\n\
         compare = { \"spring.j.kr\" = \"spring.lap.kr\" }\nwithin_sd = 3\nnoise = 0.2\n",
    );
    let d = parse(&text).unwrap().check.unwrap().diagnosis.unwrap();
    assert_eq!(d.status, vec!["converged".to_string()]);
    assert_eq!(d.compare, vec![("spring.j.kr".to_string(), "spring.lap.kr".to_string())]);
    assert_eq!((d.within_sd, d.noise), (Some(3.0), Some(0.2)));
    assert_eq!(d.truth.as_deref().and_then(|p| p.file_name()), Some(std::ffi::OsStr::new("t.toml")));
}

#[test]
fn check_errors_name_the_key_and_its_line() {
    let cases = [
        // a misspelt key of a run check
        ("[check.rfm]\nstatus = [\"converged\"]\nmax_eror = 1e-8\n", "max_eror = 1e-8", "did you mean `max_error`?"),
        // a misspelt run
        ("[check.rfn]\nstatus = [\"converged\"]\n", "[check.rfn]", "unknown field `rfn`"),
        (
            "[check.rfm]\nstatus = [\"convergd\"]\n",
            "status = [\"convergd\"]",
            "unknown status `convergd`; did you mean `converged`?",
        ),
        (
            "[check.rfm]\nstatus = [\"ok\"]\n",
            "status = [\"ok\"]",
            "(available: converged, model_inadequate, local_minimum, stalled, max_iterations, runaway, failed)",
        ),
        ("[check.rfm]\nstatus = []\n", "[check.rfm]", "needs at least one `status`"),
        ("[check.rfm]\nmax_error = 1e-8\n", "[check.rfm]", "missing field `status`"),
        (
            "[check.rfm]\nstatus = [\"converged\"]\nmax_error = -1\n",
            "max_error = -1",
            "`max_error` must be positive and finite",
        ),
        (
            "[check.rfm]\nstatus = [\"converged\"]\nwithin_sd = 0\n",
            "within_sd = 0",
            "`within_sd` must be positive and finite",
        ),
        (
            "[check.output-error]\nstatus = [\"converged\"]\nweak = [\"group.beam.stifness\"]\n",
            "weak = [\"group.beam.stifness\"]",
            "`group.beam.stifness` is not an [update] parameter; did you mean `group.beam.stiffness`?",
        ),
        ("[check.diagnosis]\nleader = \" \"\n", "leader = \" \"", "`leader` must name the effect"),
        ("[check.diagnosis]\nleader = \"joint\"\nmisfit_fall = 0.5\n", "misfit_fall = 0.5", "a factor of at least 1"),
        (
            "[check.diagnosis]\nleader = \"joint\"\nstatus = [\"convergd\"]\n",
            "status = [\"convergd\"]",
            "unknown status `convergd`; did you mean `converged`?",
        ),
        (
            "[check.diagnosis]\nleader = \"joint\"\nwithin_sd = 3\n",
            "within_sd = 3",
            "`within_sd` compares with the truth that made the data: name its case in `truth`",
        ),
        (
            "[check.diagnosis]\nleader = \"joint\"\ntruth = \"t.toml\"\nwithin_sd = 3\n",
            "within_sd = 3",
            "`within_sd` checks the parameters `compare` names, and it names none",
        ),
        (
            "[check.diagnosis]\nleader = \"joint\"\ntruth = \"t.toml\"\ncompare = { \"a.b.c\" = \"d.e.f\" }\n",
            "compare = { \"a.b.c\" = \"d.e.f\" }",
            "`compare` names updated parameters and their true quantities for `within_sd`, which needs both",
        ),
        (
            "[check.diagnosis]\nleader = \"joint\"\ntruth = \"t.toml\"\nnoise = -1\n",
            "noise = -1",
            "`noise` must be positive and finite",
        ),
    ];
    for (check, line, words) in cases {
        let text = checked(check);
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains(words), "{check}: {e}");
        assert_eq!(line_of(&text, &e), line, "{check}: {e}");
    }
    // checks against the truth need one, and checks of an update need an update
    let no_truth =
        checked("[check.rfm]\nstatus = [\"converged\"]\nnoise = 0.1\n").replace("[truth]\nnoise = 0.01\n", "");
    let no_truth = no_truth.replace("frequencies = [10.0, 20.0]", "frequencies = [10.0, 20.0]\ndata = \"m.csv\"");
    let e = parse(&no_truth).unwrap_err();
    assert!(e.message.contains("`noise` compares with the truth's noise level, and the case has no [truth]"), "{e}");
    assert_eq!(line_of(&no_truth, &e), "noise = 0.1");
    let silent =
        checked("[check.output-error]\nstatus = [\"converged\"]\nnoise = 0.1\n").replace("noise = 0.01", "noise = 0.0");
    let e = parse(&silent).unwrap_err();
    assert!(e.message.contains("the truth has no noise"), "{e}");
    let no_update = format!("{BEAM}[check.rfm]\nstatus = [\"converged\"]\n");
    let e = parse(&no_update).unwrap_err();
    assert!(e.message.contains("[check.rfm] checks an update, and the case has no [update]"), "{e}");
    assert_eq!(line_of(&no_update, &e), "[check.rfm]");
}

#[test]
fn dof_lists_expand_ranges() {
    let v = parse_dof_list("2..4:uy").unwrap();
    assert_eq!(v, vec![DofRef::new(2, Dof::Uy), DofRef::new(3, Dof::Uy), DofRef::new(4, Dof::Uy)]);
    let e = parse_dof_list("4..2:uy").unwrap_err();
    assert!(e.contains("range `4..2:uy` is empty (last node before first)"), "{e}");
    let e = parse_dof_list("4").unwrap_err();
    assert!(e.contains("`4` is not of the form node:dof"), "{e}");
}

/// A frame in space: two columns and a beam, a spring in six DOFs, a mass
/// with three inertias, a joint with rotational springs.
const SPACE: &str = r#"
title = "portal in space"
nodes = [[100, 0.5, 1.0, 0.25]]
[model]
dimension = 3
[materials]
steel = { E = 2e11, rho = 7800, nu = 0.3 }
alu = { E = 0.7e11, rho = 2700, G = 2.6e10 }
[sections]
bar = { b = 0.03, h = 0.02 }
flat = { A = 6e-4, Iy = 2e-8, Iz = 9e-8, J = 4e-8 }
[groups.frame]
alpha = 1e-5
[[lines]]
from = [0.0, 0.0, 0.0]
to = [0.0, 1.0, 0.0]
elements = 2
first_node = 1
material = "steel"
section = "bar"
group = "frame"
[[lines]]
from = 3
to = [1.0, 1.0, 0.5]
elements = 2
first_node = 4
material = "alu"
section = "flat"
group = "frame"
orientation = [0.0, 1.0, 0.0]
angle = 30.0
[[springs]]
name = "foot"
node = 5
kx = 1e6
kz = 2e6
krx = 3e3
krz = 4e3
group = "frame"
[[masses]]
name = "m"
node = 4
m = 0.2
jx = 1e-4
jz = 3e-4
group = "frame"
[[supports]]
node = 1
[[supports]]
node = 5
dofs = ["uy", "ry"]
[[ties]]
nodes = [4, 100]
dofs = ["ux", "uy", "uz", "rx", "ry", "rz"]
[[beams]]
id = 9
nodes = [100, 5]
material = "steel"
section = "bar"
group = "frame"
"#;

#[test]
fn a_3d_case_builds_a_frame_in_space() {
    let c = parse(SPACE).unwrap();
    let m = &c.model;
    assert_eq!(m.dimension(), crate::Dimension::Spatial);
    assert_eq!(m.node(NodeId(5)).unwrap().position(), [1.0, 1.0, 0.5]);
    assert_eq!(m.supports()[0].dofs, Dof::SPATIAL.to_vec());
    assert_eq!(m.springs()[0].k, [1e6, 0.0, 2e6, 3e3, 0.0, 4e3].into());
    assert_eq!(m.masses()[0].j, [1e-4, 0.0, 3e-4]);
    // G is turned into nu: E / (2 G) - 1
    let alu = &m.materials()[m.material_index("alu").unwrap()];
    assert!((alu.nu.unwrap() - (0.7e11 / 5.2e10 - 1.0)).abs() < 1e-15);
    let b = &m.beams()[m.beam_index(crate::ElementId(3)).unwrap()];
    assert_eq!((b.reference, b.angle), (Some([0.0, 1.0, 0.0]), 30f64.to_radians()));
    for name in ["spring.foot.kz", "spring.foot.krx", "mass.m.jz"] {
        let q = m.quantity(name).unwrap();
        assert_eq!(m.quantity_name(q).to_string(), name);
    }
    assert_eq!(m.parameter("mass.m.j").unwrap().quantities.len(), 3, "j scales jx, jy, jz together");
    crate::Assembly::new(m).unwrap();
}

/// What one dimension has is refused in the other, where it is written.
#[test]
fn dofs_and_keys_of_the_other_dimension_are_refused_where_written() {
    let planar = format!(
        "{BEAM}[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uz\"]\n[truth]\n"
    );
    let e = parse(&planar).unwrap_err();
    assert!(e.message.contains("`uz` is not a DOF of a planar model") && e.message.contains("dimension = 3"), "{e}");
    assert_eq!(line_of(&planar, &e), "responses = [\"5:uz\"]");
    let cases = [
        // planar: what only a frame in space has
        (
            BEAM.replace("[[supports]]\nnode = 1", "[[supports]]\nnode = 1\ndofs = [\"rx\"]"),
            "dofs = [\"rx\"]",
            "`rx` is not a DOF",
        ),
        (
            BEAM.replace("title = \"beam\"", "title = \"beam\"\nnodes = [[50, 0.0, 0.0, 1.0]]"),
            "nodes = [[50, 0.0, 0.0, 1.0]]",
            "has a z coordinate",
        ),
        (
            format!("{BEAM}[[springs]]\nname = \"s\"\nnode = 5\nkz = 1e3\ngroup = \"beam\"\n"),
            "kz = 1e3",
            "`kz` is a stiffness of a frame in space",
        ),
        (
            format!("{BEAM}[[masses]]\nname = \"m\"\nnode = 5\nm = 1.0\njx = 1e-3\ngroup = \"beam\"\n"),
            "jx = 1e-3",
            "`jx` is a rotary inertia of a frame in space",
        ),
        (
            BEAM.replace("b = 0.05\nh = 0.01", "A = 1e-4\nIy = 1e-8\nIz = 1e-8\nJ = 1e-8"),
            "[sections.bar]",
            "Iy, Iz and J describe",
        ),
        (
            BEAM.replace(
                "group = \"beam\"\n[[supports]]",
                "group = \"beam\"\norientation = [0.0, 0.0, 1.0]\n[[supports]]",
            ),
            "orientation = [0.0, 0.0, 1.0]",
            "only a beam of a 3D model",
        ),
        (
            BEAM.replace("title = \"beam\"", "title = \"beam\"\n[model]\ndimension = 4"),
            "dimension = 4",
            "`dimension` is 2",
        ),
        // in space: what would not say which axis, or lacks torsion
        (SPACE.replace("krx = 3e3", "kr = 3e3"), "kr = 3e3", "krx, kry and krz (`kr` does not say"),
        (SPACE.replace("jx = 1e-4", "j = 1e-4"), "j = 1e-4", "jx, jy and jz (`j` does not say"),
        (
            SPACE.replace("flat = { A = 6e-4, Iy = 2e-8, Iz = 9e-8, J = 4e-8 }", "flat = { A = 6e-4, I = 9e-8 }"),
            "flat = { A = 6e-4, I = 9e-8 }",
            "give Iy, Iz and J instead of I",
        ),
        (SPACE.replace(", nu = 0.3", ""), "[[lines]]", "no Poisson's ratio `nu`"),
        (
            SPACE.replace("orientation = [0.0, 1.0, 0.0]", "orientation = [1.0, 0.0, 0.5]"),
            "orientation = [1.0, 0.0, 0.5]",
            "along the beam",
        ),
    ];
    for (text, line, words) in cases {
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains(words), "{line}: {e}");
        assert_eq!(line_of(&text, &e), line, "{e}");
    }
}

#[test]
fn a_truth_group_that_replaces_a_model_group_is_checked_as_the_model_group_is() {
    let measurement = "[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n";
    let truth = format!("{BEAM}{measurement}[truth.groups.beam]\nalpha = -1e-5\n");
    let e = parse(&truth).unwrap_err();
    assert!(e.message.contains("group `beam`: alpha must be zero or positive and finite, got -1e-5"), "{e}");
    assert_eq!(line_of(&truth, &e), "[truth.groups.beam]");
    // the same value in the model's own group is refused with the same words
    let model = format!("{}{measurement}", BEAM.replace("alpha = 1e-5", "alpha = -1e-5"));
    let e = parse(&model).unwrap_err();
    assert!(e.message.contains("group `beam`: alpha must be zero or positive and finite, got -1e-5"), "{e}");
    // a valid one replaces the group's damping in the truth only
    let c = parse(&format!("{BEAM}{measurement}[truth.groups.beam]\nalpha = 2e-5\n")).unwrap();
    assert_eq!(c.model.groups()[0].alpha, 1e-5);
    assert_eq!(c.truth.unwrap().model.groups()[0].alpha, 2e-5);
}

/// A `[[resonators]]` entry is the node, spring, mass and supports a user
/// would write by hand (the case below, with the lines numbered
/// explicitly), made after the lines wherever it is written, so that the
/// lines' nodes keep their ids; what it cannot be is refused where written.
#[test]
fn a_resonator_is_a_mass_on_a_spring_at_a_new_node_held_in_its_other_dofs() {
    let entry =
        "[groups.tmd]\nalpha = 2e-4\n[[resonators]]\nname = \"tmd\"\nnode = 5\nm = 0.3\nky = 4e4\ngroup = \"tmd\"\n";
    // written before the line, without a node id: made last all the same
    let (head, tail) = BEAM.split_at(BEAM.find("[[lines]]").unwrap());
    let c = parse(&format!("{head}{entry}{tail}")).unwrap();
    let by_hand = parse(&format!(
        "nodes = [[1, 0.0, 0.0], [6, 1.0, 0.0]]\n{}\n[groups.tmd]\nalpha = 2e-4\n\
         [[springs]]\nname = \"tmd\"\nnodes = [5, 6]\nky = 4e4\ngroup = \"tmd\"\n\
         [[masses]]\nname = \"tmd\"\nnode = 6\nm = 0.3\ngroup = \"tmd\"\n\
         [[supports]]\nnode = 6\ndofs = [\"ux\", \"rz\"]\n",
        BEAM.replace("from = [0.0, 0.0]", "from = 1\nfirst_node = 2")
    ))
    .unwrap();
    let (a, b) = (&c.model, &by_hand.model);
    assert_eq!(a.node(NodeId(6)).unwrap().position(), [1.0, 0.0, 0.0]);
    for id in 1..=6 {
        assert_eq!(a.node(NodeId(id)).unwrap().position(), b.node(NodeId(id)).unwrap().position(), "node {id}");
    }
    assert_eq!(a.springs().len(), 1);
    let (sa, sb) = (&a.springs()[0], &b.springs()[0]);
    assert_eq!((sa.a, sa.b, sa.k, &a.groups()[sa.group]), (sb.a, sb.b, sb.k, &b.groups()[sb.group]));
    assert_eq!(a.masses().len(), 1);
    let (ma, mb) = (&a.masses()[0], &b.masses()[0]);
    assert_eq!((ma.node, ma.m, ma.j), (mb.node, mb.m, mb.j));
    assert_eq!(a.groups()[ma.group].name, "tmd");
    let held: Vec<&crate::model::Support> = a.supports().iter().filter(|s| s.node == NodeId(6)).collect();
    assert_eq!(held.len(), 1);
    assert_eq!(held[0].dofs, vec![Dof::Ux, Dof::Rz]);
    // the mass node left free only in uy, held by the spring there
    crate::Assembly::new(a).unwrap();
    for name in ["mass.tmd.m", "spring.tmd.ky", "group.tmd.alpha"] {
        a.quantity(name).unwrap();
    }
    // in both directions, at a chosen id
    let both = parse(&format!("{BEAM}{}", entry.replace("ky = 4e4", "kx = 3e4\nky = 4e4\nnew_node = 40"))).unwrap();
    let s = both.model.supports().iter().find(|s| s.node == NodeId(40)).unwrap();
    assert_eq!(s.dofs, vec![Dof::Rz]);
    crate::Assembly::new(&both.model).unwrap();
    // a truth may add one too
    let measurement = "[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n";
    let truth = format!(
        "{BEAM}{measurement}[truth.groups.tmd]\nalpha = 2e-4\n\
         [[truth.resonators]]\nname = \"tmd\"\nnode = 5\nm = 0.3\nky = 4e4\ngroup = \"tmd\"\n"
    );
    let t = parse(&truth).unwrap().truth.unwrap();
    assert_eq!(t.model.masses()[0].node, NodeId(6));
    for (text, line, words) in [
        (entry.replace("ky = 4e4", "kr = 4e4"), "kr = 4e4", "`kr`: a resonator's spring acts in translations (kx, ky)"),
        (entry.replace("ky = 4e4", "kx = 0.0"), "[[resonators]]", "give the stiffness of its spring in the directions"),
        (entry.replace("node = 5", "node = 9"), "[[resonators]]", "resonator `tmd`: node 9 does not exist"),
        (entry.replace("m = 0.3", "m = -0.3"), "[[resonators]]", "must be zero or positive"),
    ] {
        let text = format!("{BEAM}{text}");
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains(words), "{line}: {e}");
        assert_eq!(line_of(&text, &e), line, "{e}");
    }
}

/// A `[[shakers]]` entry is the node, tie, supports, mass and spring to
/// ground a user would write by hand: the armature moves with the drive
/// point in the drive's direction only, its suspension holds it to ground;
/// a suspension in two directions, or in a rotation, is refused where written.
#[test]
fn a_shaker_is_an_armature_tied_to_its_drive_point_on_a_suspension_to_ground() {
    let entry =
        "[groups.coil]\nalpha = 1e-4\n[[shakers]]\nname = \"coil\"\nnode = 5\nm = 0.05\nky = 3e3\ngroup = \"coil\"\n";
    let (head, tail) = BEAM.split_at(BEAM.find("[[lines]]").unwrap());
    let c = parse(&format!("{head}{entry}{tail}")).unwrap();
    let by_hand = parse(&format!(
        "nodes = [[1, 0.0, 0.0], [6, 1.0, 0.0]]\n{}\n[groups.coil]\nalpha = 1e-4\n\
         [[springs]]\nname = \"coil\"\nnode = 6\nky = 3e3\ngroup = \"coil\"\n\
         [[masses]]\nname = \"coil\"\nnode = 6\nm = 0.05\ngroup = \"coil\"\n\
         [[ties]]\nnodes = [5, 6]\ndofs = [\"uy\"]\n\
         [[supports]]\nnode = 6\ndofs = [\"ux\", \"rz\"]\n",
        BEAM.replace("from = [0.0, 0.0]", "from = 1\nfirst_node = 2")
    ))
    .unwrap();
    let (a, b) = (&c.model, &by_hand.model);
    assert_eq!(a.node(NodeId(6)).unwrap().position(), [1.0, 0.0, 0.0]);
    let (sa, sb) = (&a.springs()[0], &b.springs()[0]);
    assert_eq!((sa.a, sa.b, sa.k, &a.groups()[sa.group]), (sb.a, sb.b, sb.k, &b.groups()[sb.group]));
    assert_eq!(sa.b, None, "to ground");
    let (ma, mb) = (&a.masses()[0], &b.masses()[0]);
    assert_eq!((ma.node, ma.m, ma.j), (mb.node, mb.m, mb.j));
    assert_eq!(a.ties().len(), 1);
    assert_eq!((a.ties()[0].nodes, &a.ties()[0].dofs), (b.ties()[0].nodes, &b.ties()[0].dofs));
    let held: Vec<&crate::model::Support> = a.supports().iter().filter(|s| s.node == NodeId(6)).collect();
    assert_eq!(held[0].dofs, vec![Dof::Ux, Dof::Rz]);
    // the same matrices as the hand-written model
    let (ka, kb) = (crate::Assembly::new(a).unwrap(), crate::Assembly::new(b).unwrap());
    // (the equations in another order: the by-hand case names node 6 first)
    let sorted = |m: nalgebra::DMatrix<f64>| {
        let mut v: Vec<f64> = m.iter().copied().collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let (m_a, m_b) = (ka.mass_dense(), kb.mass_dense());
    assert_eq!(m_a.trace(), m_b.trace());
    assert_eq!(sorted(m_a), sorted(m_b));
    assert_eq!(sorted(ka.stiffness_dense()), sorted(kb.stiffness_dense()));
    // the armature adds its mass to the drive point's uy alone
    let beam_only = crate::Assembly::new(&parse(BEAM).unwrap().model).unwrap().mass_dense();
    assert!((ka.mass_dense().trace() - beam_only.trace() - 0.05).abs() < 1e-12);
    for name in ["mass.coil.m", "spring.coil.ky", "group.coil.alpha"] {
        a.quantity(name).unwrap();
    }
    let measurement = "[measurement]\nfrequencies = [10.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n";
    let truth = format!(
        "{BEAM}{measurement}[truth.groups.coil]\nalpha = 1e-4\n\
         [[truth.shakers]]\nname = \"coil\"\nnode = 5\nm = 0.05\nky = 3e3\ngroup = \"coil\"\n"
    );
    let t = parse(&truth).unwrap().truth.unwrap();
    assert_eq!(t.model.masses()[0].node, NodeId(6));
    for (text, line, words) in [
        (entry.replace("ky = 3e3", "kr = 3e3"), "kr = 3e3", "`kr`: a shaker drives in a translation (kx, ky)"),
        (entry.replace("ky = 3e3", "kx = 1e3\nky = 3e3"), "[[shakers]]", "in the one direction it drives (kx or ky)"),
        (entry.replace("node = 5", "node = 9"), "[[shakers]]", "shaker `coil`: node 9 does not exist"),
    ] {
        let text = format!("{BEAM}{text}");
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains(words), "{line}: {e}");
        assert_eq!(line_of(&text, &e), line, "{e}");
    }
}

/// A measurement without data in a case without `[truth]` is the lines and
/// channels to synthesise a model written apart (`rfm simulate`): it loads,
/// and the commands that compare ask [`CaseFile::measured_source`], which
/// points at the `[measurement]` table.
#[test]
fn a_measurement_without_data_or_truth_loads_and_is_refused_where_data_are_needed() {
    let text =
        format!("{BEAM}\n[measurement]\nfrequencies = [10.0, 20.0]\nreferences = [\"5:uy\"]\nresponses = [\"5:uy\"]\n");
    let c = parse(&text).unwrap();
    let m = c.measurement.as_ref().unwrap();
    assert_eq!((m.frequencies_hz.len(), m.data.is_none(), c.truth.is_none()), (2, true, true));
    let e = c.measured_source().unwrap_err();
    assert!(e.message.contains("has no `data` file and the case has no [truth]"), "{e}");
    assert_eq!(text.lines().nth(e.location.unwrap().line - 1).unwrap().trim(), "[measurement]");
    // with a truth, or a data file, there is something to compare with
    let with_truth = parse(&format!("{text}[truth]\n")).unwrap();
    assert!(with_truth.measured_source().is_ok());
    let with_data = parse(&text.replace("frequencies = [10.0, 20.0]", "data = \"any.uff\"")).unwrap();
    assert!(with_data.measured_source().is_ok());
    assert!(parse(BEAM).unwrap().measured_source().is_ok());
}

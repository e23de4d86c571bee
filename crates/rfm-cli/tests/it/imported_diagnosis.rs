//! The diagnosis of an imported model proposes what it can without element
//! geometry (issue 18: "masses and springs at nodes, and changes per
//! group") and names a hidden one first: a small stand in space exported
//! as a solid's matrices would be (translations only, the rotations of its
//! nodes held), its feet held by `[[supports]]`; the truth of each trial is
//! a case file of its own with the effect, its FRFs synthesised by `rfm
//! simulate` with 1 % noise, and `rfm diagnose` runs the nominal case on
//! them.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use fe_model::imported::{SymmetricCoo, export, matrix_market};
use fe_model::{Assembly, CaseFile, Dof};

/// The stand built natively: four legs of three elements from the floor
/// (nodes 1-4) to the top corners (5-8), four rails of three elements
/// between them (nodes 17-24 inside the rails: 17 and 18 on 5-6, 19 and 20
/// on 6-7, 21 and 22 on 7-8, 23 and 24 on 8-5).
fn native() -> String {
    let mut text = String::from(
        r#"
title = "stand"
nodes = [[1, 0.0, 0.0, 0.0], [2, 0.8, 0.0, 0.0], [3, 0.8, 0.5, 0.0], [4, 0.0, 0.5, 0.0],
         [5, 0.0, 0.0, 0.6], [6, 0.8, 0.0, 0.6], [7, 0.8, 0.5, 0.6], [8, 0.0, 0.5, 0.6]]
[model]
dimension = 3
[materials]
steel = { E = 2.1e11, rho = 7850, nu = 0.3 }
[sections]
bar = { b = 0.03, h = 0.02 }
[groups.frame]
"#,
    );
    for (from, to) in [(1, 5), (2, 6), (3, 7), (4, 8), (5, 6), (6, 7), (7, 8), (8, 5)] {
        let _ = write!(
            text,
            "[[lines]]\nfrom = {from}\nto = {to}\nelements = 3\nmaterial = \"steel\"\nsection = \"bar\"\ngroup = \"frame\"\n"
        );
    }
    for node in 1..=4 {
        let _ = writeln!(text, "[[supports]]\nnode = {node}");
    }
    text
}

/// The nominal imported case: the matrices, its feet held in translation
/// (rfm holds the rotations no table lists), measured at the top.
const CASE: &str = r#"title = "stand from a solid's matrices"
[model]
dimension = 3
[groups.frame]
alpha = 2e-6
beta = 2.0
[imported]
nodes = "nodes.txt"
[[imported.groups]]
group = "frame"
dofs = "dofs.txt"
stiffness = "K.mtx"
mass = "M.mtx"
[[supports]]
node = 1
dofs = ["ux", "uy", "uz"]
[[supports]]
node = 2
dofs = ["ux", "uy", "uz"]
[[supports]]
node = 3
dofs = ["ux", "uy", "uz"]
[[supports]]
node = 4
dofs = ["ux", "uy", "uz"]
[measurement]
frequencies = { from = 5.0, to = 800.0, step = 2.5 }
references = ["7:ux", "5:uz"]
responses = ["5..8:ux", "5..8:uy", "5..8:uz", "18:uz", "20:uz", "22:uz", "24:uz", "10:ux", "14:uy"]
"#;

/// The nominal case's text turned into a truth's.
type TruthEdit = fn(&str) -> String;

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

/// Writes the stand's matrices over the translations of every node (the
/// feet too: the supports are the case's), its DOF table and node file
/// into `dir`.
fn write_matrices(dir: &Path) {
    let native = CaseFile::parse(Path::new("stand.toml"), &native()).unwrap().model;
    let mut free = native.clone();
    for n in 1..=4 {
        free.remove_support(n);
    }
    let a = Assembly::of_part(&free).unwrap();
    let exported = export::export(&free, &a);
    // the rows of translations, renumbered
    let keep: Vec<usize> = (0..exported.dofs.len()).filter(|&i| exported.dofs[i].dof.is_translation()).collect();
    let mut new_index = vec![usize::MAX; exported.dofs.len()];
    for (k, &i) in keep.iter().enumerate() {
        new_index[i] = k;
    }
    let cut = |m: &SymmetricCoo| SymmetricCoo {
        n: keep.len(),
        entries: m
            .entries
            .iter()
            .filter(|&&(r, c, _)| new_index[r] != usize::MAX && new_index[c] != usize::MAX)
            .map(|&(r, c, v)| (new_index[r], new_index[c], v))
            .collect(),
    };
    let g = &exported.groups[0];
    std::fs::write(dir.join("K.mtx"), matrix_market::write(&cut(&g.stiffness), "stiffness")).unwrap();
    std::fs::write(dir.join("M.mtx"), matrix_market::write(&cut(&g.mass), "mass")).unwrap();
    let mut table = String::from("# node dof\n");
    for &i in &keep {
        writeln!(table, "{} {}", exported.dofs[i].node, exported.dofs[i].dof).unwrap();
    }
    std::fs::write(dir.join("dofs.txt"), table).unwrap();
    std::fs::write(dir.join("nodes.txt"), export::node_file(&native)).unwrap();
    assert!(exported.dofs.iter().any(|r| r.node.0 == 1 && r.dof == Dof::Ux), "the feet are in the table");
}

/// Runs one trial: the truth (`CASE` edited by `truth`) written as a case
/// of its own, its FRFs synthesised, the nominal case diagnosed on them;
/// returns the ranked descriptions and the first effect's JSON.
fn trial(dir: &Path, name: &str, truth: impl Fn(&str) -> String, seed: u64) -> (Vec<String>, serde_json::Value) {
    let truth_case = dir.join(format!("{name}-truth.toml"));
    // a [truth] without changes makes the case valid without data: the
    // model itself is the truth
    std::fs::write(&truth_case, truth(CASE) + "[truth]\n").unwrap();
    let data = dir.join(format!("{name}.csv"));
    let seed = seed.to_string();
    let out = rfm(&[
        "simulate",
        truth_case.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "--noise",
        "0.01",
        "--seed",
        &seed,
    ]);
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
    // the nominal case reads them as measured data
    let nominal = dir.join(format!("{name}.toml"));
    std::fs::write(&nominal, CASE.replace("[measurement]\n", &format!("[measurement]\ndata = \"{name}.csv\"\n")))
        .unwrap();
    let out = rfm(&["diagnose", nominal.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let ranking = d["ranking"].as_array().unwrap();
    let names = ranking.iter().map(|r| r["description"].as_str().unwrap().to_string()).collect();
    (names, ranking[0].clone())
}

#[test]
fn diagnose_names_a_hidden_support_spring_or_mass_of_an_imported_model_first() {
    let dir = tempfile::tempdir().unwrap();
    write_matrices(dir.path());
    // the foot at node 2 on a lossy pad instead of its clamp
    let pad = |c: &str| {
        c.replace("[[supports]]\nnode = 2\ndofs = [\"ux\", \"uy\", \"uz\"]\n", "")
            + "[groups.pad]\nalpha = 2e-4\n\
               [[springs]]\nname = \"pad\"\nnode = 2\nkx = 4e6\nky = 4e6\nkz = 2e7\ngroup = \"pad\"\n"
    };
    // a stop under the middle of rail 6-7 (node 20, vertically) that the model lacks
    let stop = |c: &str| {
        c.to_string()
            + "[groups.stop]\nalpha = 1e-4\n\
               [[springs]]\nname = \"stop\"\nnode = 20\nkz = 3e5\ngroup = \"stop\"\n"
    };
    // a 0.4 kg box on rail 7-8 (node 21)
    let box_ =
        |c: &str| c.to_string() + "[groups.box]\n[[masses]]\nname = \"box\"\nnode = 21\nm = 0.4\ngroup = \"box\"\n";
    let trials: [(&str, TruthEdit, &str); 3] = [
        ("pad", pad, "flexible, lossy support at node 2 ("),
        ("stop", stop, "spring to ground at node 20 ("),
        ("box", box_, "lumped mass at node 21"),
    ];
    for (k, (name, truth, want)) in trials.into_iter().enumerate() {
        let (ranked, first) = trial(dir.path(), name, truth, 11 + k as u64);
        assert!(ranked[0].starts_with(want), "{name}: ranked {:?}", &ranked[..ranked.len().min(6)]);
        assert_eq!(first["significant"], true, "{name}: {first}");
        if name == "box" {
            continue; // a mass is written as in any case
        }
        // the support and spring written into the case: it loads, with them
        let case = dir.path().join(format!("{name}.toml"));
        let new = dir.path().join(format!("{name}-fixed.toml"));
        let out = rfm(&["diagnose", case.to_str().unwrap(), "--apply", "1", "--out", new.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let fixed = CaseFile::load(&new).unwrap().model;
        match name {
            "pad" => {
                let s = fixed.springs().iter().find(|s| s.a.0 == 2 && s.b.is_none()).expect("a spring under the foot");
                assert!(s.k[Dof::Ux] > 0.0 && s.k[Dof::Uz] > 0.0, "{s:?}");
                // the rotations stay held, as before
                let held: Vec<Dof> =
                    fixed.supports().iter().filter(|s| s.node.0 == 2).flat_map(|s| s.dofs.clone()).collect();
                assert!(
                    [Dof::Rx, Dof::Ry, Dof::Rz].iter().all(|d| held.contains(d)) && !held.contains(&Dof::Ux),
                    "{held:?}"
                );
            }
            "stop" => {
                let s = fixed.springs().iter().find(|s| s.a.0 == 20 && s.b.is_none()).expect("a spring to ground");
                assert!(s.k[Dof::Uz] > 0.0, "{s:?}");
                assert!(fixed.supports().iter().all(|s| s.node.0 != 20 || !s.dofs.iter().any(|d| d.is_translation())));
            }
            _ => unreachable!(),
        }
    }
}

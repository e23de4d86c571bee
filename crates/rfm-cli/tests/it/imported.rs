//! An imported model (cases/imported/table.toml: matrices in Matrix Market
//! files with a DOF table and node coordinates) through the binary:
//! compare and update run on it and recover its truth; a malformed matrix
//! file or a DOF table naming an unknown node is refused at its file, line
//! and column.

use std::path::{Path, PathBuf};
use std::process::Command;

use fe_model::CaseFile;

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/imported")
}

#[test]
fn compare_and_update_run_on_an_imported_model_and_recover_its_truth() {
    let case = example().join("table.toml");
    let c = case.to_str().unwrap();
    let out = rfm(&["compare", c, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let dir = tempfile::tempdir().unwrap();
    let out = rfm(&["update", c, "--json", "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let u: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(u["status"], "converged");
    let truth = CaseFile::load(&case).unwrap().truth.unwrap();
    let model = &truth.model;
    for p in u["uncertainty"]["parameters"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let want = model.get(model.quantity(name).unwrap());
        let z = (p["value"].as_f64().unwrap() / want).ln().abs() / p["relative_std"].as_f64().unwrap();
        assert!(z < 3.0, "{name}: {p} vs the truth's {want}");
    }
    assert!(dir.path().join("updated.toml").exists() && dir.path().join("report.html").exists());
    // named by a path relative to the working folder, written into a new one
    // elsewhere: the updated case reaches the matrices through `..` while its
    // folder is still being staged
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let elsewhere = tempfile::tempdir().unwrap();
    let out = elsewhere.path().join("new/up");
    let run = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .current_dir(&root)
        .args(["update", "cases/imported/table.toml", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    CaseFile::load(out.join("updated.toml")).unwrap();
}

/// The example's files in `dir`, with `edit` applied to the file `name`.
fn copy_with(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    for entry in std::fs::read_dir(example()).unwrap() {
        let path = entry.unwrap().path();
        let file = path.file_name().unwrap().to_str().unwrap().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(dir.join(&file), if file == name { edit(&text) } else { text }).unwrap();
    }
    dir.join("table.toml")
}

/// An edit of a file's text.
type Edit = fn(&str) -> String;

#[test]
fn a_bad_matrix_file_or_dof_table_is_refused_at_its_line_and_column() {
    let cases: [(&str, Edit, &str); 3] = [
        // the third entry's value is not a number
        ("table-frame-K.mtx", |t| replace_nth_entry_value(t, 3, "1.0e7x"), "table-frame-K.mtx:6:"),
        // a node the node file does not have
        (
            "table-dofs.txt",
            |t| t.replacen("\n2 uy\n", "\n99 uy\n", 1),
            "table-dofs.txt:3:1: node 99 is not in the node file",
        ),
        // a matrix of another size than the DOF table
        (
            "table-dofs.txt",
            |t| t.trim_end().rsplit_once('\n').unwrap().0.to_string() + "\n",
            "table-frame-K.mtx:3:1: the matrix is 192 x 192, and its DOF table",
        ),
    ];
    for (file, edit, want) in cases {
        let dir = tempfile::tempdir().unwrap();
        let case = copy_with(dir.path(), file, edit);
        let out = rfm(&["compare", case.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{file}: {err}");
        assert!(err.contains(want), "{file}: {err}");
    }
}

/// `text` (a Matrix Market file) with the value of its `k`-th entry
/// (1-based) replaced.
fn replace_nth_entry_value(text: &str, k: usize, value: &str) -> String {
    let mut seen = 0;
    let mut size_read = false;
    text.lines()
        .map(|line| {
            if line.starts_with('%') {
                return line.to_string();
            }
            if !size_read {
                size_read = true;
                return line.to_string();
            }
            seen += 1;
            if seen == k {
                let mut f: Vec<&str> = line.split_whitespace().collect();
                f[2] = value;
                return f.join(" ");
            }
            line.to_string()
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The example with a viscous damping matrix in its group: dashpots at
/// four top corners (the rows of `table-dofs.txt` named here), in
/// `table-frame-C.mtx`, and the truth's with its factor 1.6.
fn with_dashpots(dir: &Path, matrix: impl Fn(&[(usize, f64)]) -> String) -> PathBuf {
    let case = copy_with(dir, "table.toml", |t| {
        t.replacen(
            "mass = \"table-frame-M.mtx\"\n",
            "mass = \"table-frame-M.mtx\"\ndamping = \"table-frame-C.mtx\"\n",
            1,
        )
        .replacen("[truth.set]\n", "[truth.set]\n\"group.frame.damping\" = 1.6\n", 1)
        .replacen("\"group.frame.beta\"]", "\"group.frame.beta\", \"group.frame.damping\"]", 1)
    });
    let table = std::fs::read_to_string(dir.join("table-dofs.txt")).unwrap();
    let rows: Vec<&str> = table.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()).collect();
    let row = |dof: &str| rows.iter().position(|l| l.trim() == dof).unwrap() + 1;
    let dashpots: Vec<(usize, f64)> =
        [("5 ux", 40.0), ("10 uz", 60.0), ("15 uy", 40.0), ("20 ux", 60.0)].map(|(d, c)| (row(d), c)).to_vec();
    std::fs::write(dir.join("table-frame-C.mtx"), matrix(&dashpots)).unwrap();
    case
}

/// A damping matrix's factor is updated like the group's other parameters
/// and found within three standard deviations of the truth.
#[test]
fn update_finds_the_factor_of_an_imported_damping_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let case = with_dashpots(dir.path(), |d| {
        let mut s = format!("%%MatrixMarket matrix coordinate real symmetric\n192 192 {}\n", d.len());
        for &(r, c) in d {
            s.push_str(&format!("{r} {r} {c}\n"));
        }
        s
    });
    let out_dir = dir.path().join("out");
    let out = rfm(&["update", case.to_str().unwrap(), "--json", "--out", out_dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let u: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(u["status"], "converged");
    let truth = CaseFile::load(&case).unwrap().truth.unwrap();
    let model = &truth.model;
    let parameters = u["uncertainty"]["parameters"].as_array().unwrap();
    let damping = parameters.iter().find(|p| p["name"] == "group.frame.damping").expect("the factor is a parameter");
    assert!(damping["relative_std"].as_f64().unwrap() < 0.1, "the data determine it: {damping}");
    for p in parameters {
        let name = p["name"].as_str().unwrap();
        let want = model.get(model.quantity(name).unwrap());
        let z = (p["value"].as_f64().unwrap() / want).ln().abs() / p["relative_std"].as_f64().unwrap();
        assert!(z < 3.0, "{name}: {p} vs the truth's {want}");
    }
}

#[test]
fn a_bad_damping_matrix_is_refused_at_its_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    // a row beyond the matrix's 192
    let case =
        with_dashpots(dir.path(), |_| "%%MatrixMarket matrix coordinate real symmetric\n192 192 1\n193 1 5.0\n".into());
    let out = rfm(&["compare", case.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("table-frame-C.mtx:3:1:"), "{err}");
}

/// With the damping matrix's factor the only change in the truth, and the
/// factor declared under `[update]`, the diagnosis updates it first (step
/// 0) to its value, and nothing significant remains; without it declared,
/// the diagnosis ranks the change of that matrix first, with its value.
#[test]
fn diagnose_names_a_change_of_an_imported_damping_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let case = with_dashpots(dir.path(), |d| {
        let mut s = format!("%%MatrixMarket matrix coordinate real symmetric\n192 192 {}\n", d.len());
        for &(r, c) in d {
            s.push_str(&format!("{r} {r} {c}\n"));
        }
        s
    });
    let text = std::fs::read_to_string(&case).unwrap();
    let text = text.replace("\"group.frame.stiffness\" = 0.94\n", "").replace("\"group.frame.alpha\" = 3.0e-6\n", "");
    std::fs::write(&case, text).unwrap();
    let out = rfm(&["diagnose", case.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let declared = d["declared"]["parameters"].as_array().expect("a step 0");
    let factor = declared.iter().find(|p| p["name"] == "group.frame.damping").expect("the factor updated at step 0");
    assert!((factor["updated"].as_f64().unwrap() / 1.6 - 1.0).abs() < 0.01, "{factor}");
    assert_eq!(d["ranking"][0]["significant"], false, "{}", d["ranking"][0]);

    // not declared (nor the Rayleigh coefficients, which step 0 would fit
    // to mimic the dashpots): the change of the matrix is what the
    // diagnosis names
    let text = std::fs::read_to_string(&case).unwrap().replace(
        "parameters = [\"group.frame.stiffness\", \"group.frame.mass\", \"group.frame.alpha\", \"group.frame.beta\", \"group.frame.damping\"]",
        "parameters = [\"group.frame.stiffness\"]",
    );
    assert!(text.contains("parameters = [\"group.frame.stiffness\"]\n"), "{text}");
    std::fs::write(&case, text).unwrap();
    let out = rfm(&["diagnose", case.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let first = &d["ranking"][0];
    assert_eq!(first["description"], "change of the damping matrix of group `frame`", "{first}");
    let value = first["parameters"][0]["value"].as_f64().unwrap();
    assert!((value / 1.6 - 1.0).abs() < 0.01, "{first}");
}

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

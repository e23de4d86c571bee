//! Reports written once per test run and shared by the tests that read
//! them (the report checks and the browser check), so that the slow ones
//! (`rfm fix` diagnoses the tutorial up to three times) run once.
//!
//! They are written under cargo's target temporary folder, in a folder of
//! the test process's own ([`reports_dir`]).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::Duration;

/// The folder of this process's reports, `reports/run-PID` under cargo's
/// target temporary folder, made empty at the first call. nextest runs
/// every test in a process of its own, several at once: a folder per
/// process keeps two of them from writing (and removing) one report at
/// the same time; each writes the reports its own tests read. Folders an
/// hour old or more (earlier runs) are removed.
pub(crate) fn reports_dir() -> &'static Path {
    static D: OnceLock<PathBuf> = OnceLock::new();
    D.get_or_init(|| {
        let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reports");
        for e in std::fs::read_dir(&root).into_iter().flatten().flatten() {
            let age = e.metadata().and_then(|m| m.modified()).ok().and_then(|t| t.elapsed().ok());
            if age.is_some_and(|a| a > Duration::from_secs(3600)) {
                let path = e.path();
                let _ = if path.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
            }
        }
        let dir = root.join(format!("run-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("the reports folder");
        dir
    })
}

/// Runs `rfm` with `args`.
pub(crate) fn rfm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

/// A case file under `cases/`.
pub(crate) fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases").join(format!("{name}.toml"))
}

/// The tutorial's case text (`cases/tutorial/l-frame.toml`) without its
/// `[check]` tables, each line passed through `edit` (`None` drops it), for
/// a case written beside the test's own data.
pub(crate) fn tutorial_text(edit: impl Fn(&str) -> Option<String>) -> String {
    let text = std::fs::read_to_string(case("tutorial/l-frame")).unwrap();
    text.lines()
        .take_while(|l| !l.starts_with("# What `cargo xtask reproduce"))
        .filter_map(|l| edit(l).map(|l| format!("{l}\n")))
        .collect()
}

/// A command's output as text.
pub(crate) fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A written report: its folder and the command's output.
pub(crate) struct Written {
    /// The `--out` folder.
    pub(crate) dir: PathBuf,
    /// What the command printed and its exit code.
    pub(crate) output: Output,
}

/// [`write_case`] with a case file under `cases/`.
fn write(name: &str, command: &str, case_name: &str, extra: &[&str]) -> Written {
    write_case(name, command, &case(case_name), extra)
}

/// Runs `rfm <command> <case> --out DIR [extra...]` into a fresh folder
/// named `name` and returns it.
fn write_case(name: &str, command: &str, case: &Path, extra: &[&str]) -> Written {
    let dir = reports_dir().join(name);
    let mut args = vec![command, case.to_str().expect("a UTF-8 path"), "--out", dir.to_str().expect("a UTF-8 path")];
    args.extend_from_slice(extra);
    let output = rfm(&args);
    Written { dir, output }
}

/// `rfm compare` of the tutorial (8 channels, a bolted corner the model lacks).
pub(crate) fn tutorial_compare() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write("tutorial-compare", "compare", "tutorial/l-frame", &[]))
}

/// `rfm fix` of the tutorial: the loop that adds the joint.
pub(crate) fn tutorial_fix() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write("tutorial-fix", "fix", "tutorial/l-frame", &[]))
}

/// `rfm update` of the walkthrough's guess (`docs/walkthrough.md`, section
/// 3): the tutorial case with the lines of the walkthrough's first `toml`
/// block added, as `cargo xtask figures` builds it.
pub(crate) fn tutorial_update() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
        let doc = std::fs::read_to_string(root.join("docs/walkthrough.md")).expect("the walkthrough");
        let start = doc.find("```toml\n").expect("a toml block") + "```toml\n".len();
        let block = &doc[start..start + doc[start..].find("```").expect("a closed toml block")];
        let tutorial = root.join("cases/tutorial");
        let data = tutorial.join("l-frame-measured.csv").canonicalize().expect("the tutorial data");
        let case = std::fs::read_to_string(tutorial.join("l-frame.toml"))
            .expect("the tutorial case")
            .replace("data = \"l-frame-measured.csv\"", &format!("data = {:?}", data.display().to_string()));
        let dir = reports_dir();
        let guess = dir.join("l-frame-guess.toml");
        std::fs::write(&guess, format!("{case}\n{block}")).expect("the guess");
        write_case("tutorial-update", "update", &guess, &[])
    })
}

/// The tutorial case with the diagnosis's leader (the corner joint) added
/// by `rfm diagnose --apply 1`: a case whose history holds the nominal
/// model and the added joint.
fn tutorial_applied() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| {
        let dir = reports_dir();
        let applied = dir.join("l-frame-applied.toml");
        let _ = std::fs::remove_file(&applied);
        let case = case("tutorial/l-frame");
        let out = rfm(&["diagnose", case.to_str().unwrap(), "--apply", "1", "--out", applied.to_str().unwrap()]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        applied
    })
}

/// `rfm update` of the case `rfm diagnose --apply 1` wrote from the tutorial.
pub(crate) fn tutorial_applied_update() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write_case("tutorial-applied-update", "update", tutorial_applied(), &[]))
}

/// `rfm compare` of the case `rfm diagnose --apply 1` wrote from the tutorial.
pub(crate) fn tutorial_applied_compare() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write_case("tutorial-applied-compare", "compare", tutorial_applied(), &[]))
}

/// `rfm compare` of the lap-joint tutorial (accelerance per volt, a fitted gain).
pub(crate) fn lap_compare() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write("lap-compare", "compare", "tutorial/lap-joint", &[]))
}

/// `rfm fix` of the lap-joint tutorial.
pub(crate) fn lap_fix() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write("lap-fix", "fix", "tutorial/lap-joint", &[]))
}

/// `rfm update` of the lap-joint tutorial with the diagnosis's leader (the
/// lap) added by `rfm diagnose --apply 1`: data per volt, its gain
/// estimated with the parameters.
pub(crate) fn lap_update() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| {
        let dir = reports_dir();
        let applied = dir.join("lap-with-joint.toml");
        let _ = std::fs::remove_file(&applied);
        let case = case("tutorial/lap-joint");
        let out = rfm(&["diagnose", case.to_str().unwrap(), "--apply", "1", "--out", applied.to_str().unwrap()]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        write_case("lap-update", "update", &applied, &[])
    })
}

/// `rfm diagnose --report` of the tutorial.
pub(crate) fn tutorial_diagnose_report() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| {
        let dir = reports_dir().join("tutorial-diagnose");
        let case = case("tutorial/l-frame");
        let output = rfm(&["diagnose", case.to_str().unwrap(), "--report", dir.to_str().unwrap()]);
        Written { dir, output }
    })
}

/// `rfm update` of the flexible-clamp cantilever (it stalls short of the
/// tolerance, exit code 5, and writes its report all the same).
pub(crate) fn clamp_update() -> &'static Written {
    static W: OnceLock<Written> = OnceLock::new();
    W.get_or_init(|| write("clamp-update", "update", "cantilever-flexible-clamp", &[]))
}

/// The SVG files of a report folder, sorted.
pub(crate) fn svg_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("the report folder")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "svg"))
        .collect();
    v.sort();
    v
}

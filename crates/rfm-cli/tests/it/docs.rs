//! The walkthroughs, run: every `rfm` command of their `sh` blocks is run
//! as a reader would run it (from a folder holding a copy of the
//! repository's `cases/`), and every line of the `text` block that follows a command
//! must appear, in order, in what that command printed. When the tool
//! prints other numbers or words than the documentation shows, this fails.
//!
//! In a `text` block a line `...` stands for lines left out, and `...`
//! inside a line for text left out there; runs of spaces count as one
//! (tables are aligned to their widest cell, which an excerpt need not
//! show). The user guide's glossary names every quantity the tool reports
//! ([`rfm_update::quantities::GLOSSARY`]).
//!
//! The commands run the release binary when it is built and no older than
//! the tests' (`cargo build --release` first makes this test quicker),
//! else the tests' own; `RFM_BIN` chooses another.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::fixtures::text;

/// The repository's root.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repository")
}

/// The `rfm` binary the walkthroughs run (see the module docs).
fn binary() -> PathBuf {
    if let Some(p) = std::env::var_os("RFM_BIN") {
        return PathBuf::from(p);
    }
    let tests = PathBuf::from(env!("CARGO_BIN_EXE_rfm"));
    let release = tests.parent().and_then(Path::parent).map(|t| t.join("release").join(tests.file_name().unwrap()));
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    match (release, modified(&tests)) {
        (Some(r), Some(t)) if modified(&r).is_some_and(|m| m >= t) => r,
        _ => tests,
    }
}

/// One command of a walkthrough and the excerpts of its output that follow it.
#[derive(Debug)]
struct Step {
    /// The command line, `rfm ...`.
    command: String,
    /// The `text` blocks after it, each a list of line patterns.
    excerpts: Vec<Vec<String>>,
    /// The line of the walkthrough where the command is.
    line: usize,
}

/// The `rfm` commands of `doc` with the `text` blocks after each.
fn steps(doc: &str) -> Vec<Step> {
    let mut steps: Vec<Step> = Vec::new();
    let mut block: Option<(String, Vec<String>)> = None;
    for (i, line) in doc.lines().enumerate() {
        match (&mut block, line.trim_start().strip_prefix("```")) {
            (None, Some(lang)) => block = Some((lang.trim().to_string(), Vec::new())),
            (Some(_), Some(_)) => {
                let (lang, lines) = block.take().expect("in a block");
                match lang.as_str() {
                    "sh" => {
                        for (k, l) in lines.iter().enumerate() {
                            let command = l.split(" #").next().unwrap_or("").trim();
                            if command.starts_with("rfm ") {
                                steps.push(Step {
                                    command: command.to_string(),
                                    excerpts: Vec::new(),
                                    line: i - lines.len() + k,
                                });
                            }
                        }
                    }
                    "text" => {
                        if let Some(last) = steps.last_mut() {
                            last.excerpts.push(lines);
                        }
                    }
                    _ => {}
                }
            }
            (Some((_, lines)), None) => lines.push(line.to_string()),
            (None, None) => {}
        }
    }
    steps
}

/// `s` with each run of whitespace one space, trimmed.
fn squeezed(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Whether `line` holds the parts of `pattern` between its `...`, in order.
fn matches(line: &str, pattern: &str) -> bool {
    let line = squeezed(line);
    let mut rest = line.as_str();
    for (k, part) in pattern.split("...").map(squeezed).enumerate() {
        if part.is_empty() {
            continue;
        }
        // the first part starts the line unless the pattern starts with `...`
        let found = if k == 0 { rest.starts_with(&part).then_some(0) } else { rest.find(&part) };
        match found {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    true
}

/// The first pattern of `excerpt` not found, in order, among `output`'s lines.
fn missing<'a>(output: &str, excerpt: &'a [String]) -> Option<&'a str> {
    let lines: Vec<&str> = output.lines().collect();
    let mut at = 0;
    for pattern in excerpt.iter().map(|p| p.trim()).filter(|p| !p.is_empty() && *p != "...") {
        match lines[at..].iter().position(|l| matches(l, pattern)) {
            Some(k) => at += k + 1,
            None => return Some(pattern),
        }
    }
    None
}

/// Copies the folder `from` to `to` (a reader's checkout of `cases/`: the
/// walkthroughs write beside it, never into the repository's).
fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("a folder for the walkthrough");
    for entry in std::fs::read_dir(from).expect("the cases") {
        let entry = entry.expect("an entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("its type").is_dir() {
            copy_folder(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("a case file copied");
        }
    }
}

/// Runs the walkthrough `name` of `docs/` (at least `commands` commands)
/// from a fresh folder that holds a copy of the repository's `cases/`, each
/// command's output checked against the excerpts after it.
fn run_walkthrough(name: &str, commands: usize) {
    let doc = std::fs::read_to_string(root().join("docs").join(name)).expect("the walkthrough");
    let steps = steps(&doc);
    assert!(steps.len() >= commands, "{name}: only {} commands found, of {commands}", steps.len());
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("docs").join(name.trim_end_matches(".md"));
    let _ = std::fs::remove_dir_all(&dir);
    copy_folder(&root().join("cases"), &dir.join("cases"));
    let rfm = binary();
    let mut failures = Vec::new();
    for step in &steps {
        let args: Vec<&str> = step.command.split_whitespace().skip(1).collect();
        let out = Command::new(&rfm).args(&args).current_dir(&dir).output().expect("rfm runs");
        let printed = format!("{}{}", text(&out.stdout), text(&out.stderr));
        if !out.status.success() {
            failures.push(format!(
                "{name}:{}: `{}` exited with {}:\n{printed}",
                step.line + 1,
                step.command,
                out.status
            ));
            continue;
        }
        for excerpt in &step.excerpts {
            if let Some(line) = missing(&printed, excerpt) {
                failures.push(format!(
                    "{name}:{}: `{}` no longer prints\n    {line}\n(as the walkthrough shows it); it printed:\n{printed}",
                    step.line + 1,
                    step.command
                ));
                break;
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn the_walkthrough_prints_what_it_shows() {
    run_walkthrough("walkthrough.md", 5);
}

#[test]
fn the_test_data_walkthrough_prints_what_it_shows() {
    run_walkthrough("walkthrough-test-data.md", 4);
}

#[test]
fn the_lab_walkthrough_prints_what_it_shows() {
    run_walkthrough("walkthrough-lab.md", 1);
}

/// Excerpts match with `...` for what is left out, and a changed number
/// does not: the check can fail.
#[test]
fn excerpts_match_what_is_printed_and_nothing_else() {
    let printed = "noise 0.01095; misfit of the nominal model 1.448 (132.2 x the noise)\n\
                   rank  effect   explained\n\
                   1     joint      100.0 %  -56,161,045\n";
    let excerpt = |lines: &[&str]| lines.iter().map(|l| l.to_string()).collect::<Vec<_>>();
    assert_eq!(missing(printed, &excerpt(&["noise 0.01095; misfit ... 1.448 (132.2 x the noise)"])), None);
    assert_eq!(missing(printed, &excerpt(&["...", "1 joint 100.0 % -56,161,045"])), None);
    assert_eq!(
        missing(printed, &excerpt(&["noise 0.01095; misfit ... 1.45 (132.2 x the noise)"])),
        Some("noise 0.01095; misfit ... 1.45 (132.2 x the noise)")
    );
    // in order: a line shown after another must be printed after it
    assert!(missing(printed, &excerpt(&["rank effect", "noise 0.01095..."])).is_some());
    let doc = "text\n```sh\nrfm compare a.toml   # the first\ncargo build\n```\n\n```text\nmisfit 1\n...\n```\n";
    let s = steps(doc);
    assert_eq!((s.len(), s[0].command.as_str(), s[0].excerpts.len()), (1, "rfm compare a.toml", 1));
}

/// The user guide's glossary names every quantity the tool reports, by
/// the name the tool gives it.
#[test]
fn the_user_guide_names_every_reported_quantity() {
    let guide = std::fs::read_to_string(root().join("docs/user-guide.md")).expect("the user guide");
    let glossary = &guide[guide.find("## 5. The numbers").expect("the guide's glossary")..];
    for q in rfm_update::quantities::GLOSSARY {
        assert!(glossary.contains(&format!("| {} |", q.name)), "the user guide's glossary lacks `{}`", q.name);
    }
}

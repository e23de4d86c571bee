//! `cargo xtask figures`: the figures the documentation shows, drawn by
//! the tool as it is today. Writes the tutorial's compare and fix reports
//! and the walkthrough's update report under `<target>/figures/` and copies
//! [`FIGURES`] into `docs/images/`; `RFM_BIN=PATH` uses that `rfm` binary
//! instead of building one (release).

use std::ffi::OsStr;
use std::path::PathBuf;
use std::process::Command;

use crate::root;

/// The figures of `docs/`: (report, figure in it, name under `docs/images/`).
/// `update` is the walkthrough's update from its hand-written guess
/// (`cases/tutorial/l-frame-guess.toml`).
const FIGURES: [(&str, &str, &str); 10] = [
    ("compare", "frf-23uy-23uy.svg", "tutorial-before-23uy.svg"),
    ("compare", "error-vs-frequency.svg", "tutorial-error-before.svg"),
    ("compare", "frf-channels.svg", "tutorial-channels.svg"),
    ("compare", "mac-matrix.svg", "tutorial-mac.svg"),
    ("compare", "stabilisation.svg", "tutorial-stabilisation.svg"),
    ("compare", "mode-shapes.svg", "tutorial-mode-shapes.svg"),
    ("fix", "misfit-steps.svg", "tutorial-fix-misfit.svg"),
    ("fix", "structure.svg", "tutorial-fix-structure.svg"),
    ("update", "convergence.svg", "tutorial-convergence.svg"),
    ("update", "frf-23uy-23uy.svg", "tutorial-after-23uy.svg"),
];

/// Writes the tutorial's compare and fix reports and the walkthrough's
/// update report, and copies [`FIGURES`] into `docs/images/`, so that every
/// figure the documentation shows is what the tool draws today.
pub(crate) fn figures() -> Result<(), String> {
    // a binary already built (`RFM_BIN=target/debug/rfm`) spares the release build
    let rfm = match std::env::var_os("RFM_BIN") {
        Some(bin) => PathBuf::from(bin),
        None => crate::release_build(&["-p", "rfm-cli", "--bin", "rfm"], "rfm")?,
    };
    let case = root().join("cases/tutorial/l-frame.toml");
    let base = crate::target_dir()?.join("figures");
    std::fs::create_dir_all(&base).map_err(|e| format!("{}: {e}", base.display()))?;
    let guess = root().join("cases/tutorial/l-frame-guess.toml");
    for (command, case) in [("compare", &case), ("fix", &case), ("update", &guess)] {
        println!("rfm {command} {} --out {}", case.display(), base.join(command).display());
        let out = Command::new(&rfm)
            .args([OsStr::new(command), case.as_os_str(), OsStr::new("--out"), base.join(command).as_os_str()])
            .output()
            .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
        if !out.status.success() {
            return Err(format!("rfm {command} failed:\n{}", String::from_utf8_lossy(&out.stderr)));
        }
    }
    let images = root().join("docs/images");
    for (report, figure, name) in FIGURES {
        let (from, to) = (base.join(report).join(figure), images.join(name));
        std::fs::copy(&from, &to).map_err(|e| format!("{} -> {}: {e}", from.display(), to.display()))?;
        println!("wrote {}", to.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every image the README and `docs/` show is one `cargo xtask figures`
    /// draws, and is there: a figure nobody can redraw would drift from
    /// what the tool draws.
    #[test]
    fn every_image_the_documentation_shows_is_drawn_by_figures() {
        let mut pages = vec![root().join("README.md")];
        for e in std::fs::read_dir(root().join("docs")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "md") {
                pages.push(p);
            }
        }
        let drawn: Vec<&str> = FIGURES.iter().map(|f| f.2).collect();
        let mut shown = 0;
        for page in &pages {
            let text = std::fs::read_to_string(page).unwrap();
            for (i, _) in text.match_indices("images/") {
                let rest = &text[i + "images/".len()..];
                let name = &rest[..rest.find([')', '"', ' ', '\n']).unwrap_or(rest.len())];
                assert!(
                    drawn.contains(&name),
                    "{} shows images/{name}, which cargo xtask figures does not draw",
                    page.display()
                );
                assert!(root().join("docs/images").join(name).is_file(), "docs/images/{name} is missing");
                shown += 1;
            }
        }
        assert!(shown >= FIGURES.len(), "only {shown} images shown");
    }
}

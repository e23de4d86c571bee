//! One module per subcommand. Only this crate prints.

mod compare;
mod diagnose;
pub(crate) mod fix;
mod inspect;
mod simulate;
mod update;

use std::path::Path;

use fe_model::CaseFile;

pub(crate) use compare::compare;
pub(crate) use diagnose::{DiagnoseArgs, diagnose};
pub(crate) use fix::{FixArgs, fix};
pub(crate) use inspect::inspect;
pub(crate) use simulate::simulate;
pub(crate) use update::{Overrides as UpdateOverrides, update};

pub(crate) type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

pub(crate) fn load_case(path: &Path) -> Result<CaseFile> {
    CaseFile::load(path).map_err(|e| e.render().into())
}

/// Tells what the case's `[measurement] mask` left out of the measured data:
/// on standard output with the tables, on standard error beside `--json`
/// so that the JSON stays whole.
pub(crate) fn print_masked(masked: &[String], json: bool) -> Result<()> {
    if masked.is_empty() {
        return Ok(());
    }
    const SHOWN: usize = 10;
    let mut text =
        format!("left out of the measured data, as the case's [measurement] mask allows ({}):", masked.len());
    for m in masked.iter().take(SHOWN) {
        text.push_str(&format!("\n  - {m}"));
    }
    if masked.len() > SHOWN {
        text.push_str(&format!("\n  ... and {} more", masked.len() - SHOWN));
    }
    if json {
        eprintln!("{text}");
    } else {
        outln!("{text}");
    }
    Ok(())
}

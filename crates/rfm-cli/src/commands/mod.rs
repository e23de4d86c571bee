//! One module per subcommand. Only this crate prints.

mod compare;
mod diagnose;
mod inspect;
mod simulate;
mod update;

use std::path::Path;

use fe_model::CaseFile;

pub(crate) use compare::compare;
pub(crate) use diagnose::{DiagnoseArgs, diagnose};
pub(crate) use inspect::inspect;
pub(crate) use simulate::simulate;
pub(crate) use update::{Overrides as UpdateOverrides, update};

pub(crate) type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

pub(crate) fn load_case(path: &Path) -> Result<CaseFile> {
    CaseFile::load(path).map_err(|e| e.render().into())
}

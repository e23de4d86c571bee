//! What runs into a target left behind when they were killed, removed (or
//! restored) by the next run into it.

use std::ffi::OsString;
use std::fs;
use std::path::Path;

use super::{Kind, OutputError, io};

/// Removes what runs into this target left behind when they were killed:
/// staging folders and (from older versions of rfm) temporary files; puts
/// back an old folder that a killed two-rename swap left aside. Called with
/// the lock held, so none of it belongs to a running process.
pub(super) fn clean_leftovers(parent: &Path, name: &OsString, target: &Path, kind: Kind) -> Result<(), OutputError> {
    let name = name.to_string_lossy();
    let staging = format!(".{name}.rfm-staging-");
    let old = format!(".{name}.rfm-old-");
    let legacy = format!(".{name}.tmp-");
    let entries = fs::read_dir(parent).map_err(io(parent, "list"))?;
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        if file.starts_with(&staging) || file.starts_with(&legacy) {
            remove_all(&path).map_err(io(&path, "remove the unfinished outputs of an earlier run"))?;
            eprintln!(
                "note: removed {}, the unfinished outputs of an earlier run that was stopped before it ended",
                path.display()
            );
        } else if file.starts_with(&old) {
            if fs::symlink_metadata(target).is_err() {
                fs::rename(&path, target).map_err(io(&path, "restore the earlier outputs"))?;
                eprintln!(
                    "note: restored {} from {}, where a run stopped while replacing it had left it",
                    target.display(),
                    path.display()
                );
            } else {
                remove_all(&path).map_err(io(&path, "remove the old outputs of an earlier run"))?;
            }
        }
    }
    if kind == Kind::Folder && target.is_dir() {
        for entry in fs::read_dir(target).map_err(io(target, "list"))?.flatten() {
            if is_legacy_temporary(&entry.file_name()) {
                let path = entry.path();
                fs::remove_file(&path).map_err(io(&path, "remove a temporary file of an earlier run"))?;
                eprintln!("note: removed {}, a temporary file of an earlier run that was stopped", path.display());
            }
        }
    }
    Ok(())
}

/// `.NAME.tmp-PID`, the temporary file of an atomic write by earlier
/// versions of rfm.
pub(super) fn is_legacy_temporary(name: &std::ffi::OsStr) -> bool {
    let name = name.to_string_lossy();
    name.starts_with('.')
        && name.rsplit_once(".tmp-").is_some_and(|(_, pid)| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
}

fn remove_all(path: &Path) -> std::io::Result<()> {
    if fs::symlink_metadata(path)?.is_dir() { fs::remove_dir_all(path) } else { fs::remove_file(path) }
}

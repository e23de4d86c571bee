//! The commit of a folder target: the files the run does not write carried
//! over, then the staging folder swapped with the target in one step.

use std::ffi::OsString;
use std::fs::{self, File};
use std::path::Path;

use super::leftovers::is_legacy_temporary;
use super::{COMMAND_LINE, MANIFEST, OutputError, Outputs, find_input, io, previous_run, split, sync_dir};

impl Outputs {
    pub(super) fn swap_folder(&self) -> Result<(), OutputError> {
        let top: Vec<OsString> = self
            .written
            .iter()
            .filter_map(|n| Path::new(n).components().next().map(|c| c.as_os_str().to_os_string()))
            .collect();
        let exists = self.target.is_dir();
        if exists {
            let previous: Vec<OsString> = previous_run(&self.target).1.into_iter().map(OsString::from).collect();
            let entries = fs::read_dir(&self.target).map_err(io(&self.target, "list"))?;
            for entry in entries {
                let entry = entry.map_err(io(&self.target, "list"))?;
                let name = entry.file_name();
                let path = entry.path();
                if name == MANIFEST || is_legacy_temporary(&name) {
                    continue;
                }
                let replaced = top.contains(&name);
                let stale = previous.contains(&name);
                let input = find_input(&path, &self.inputs);
                match (replaced, stale, input) {
                    (true, _, Some(p)) => return Err(OutputError::Input { path: p }),
                    (true, _, None) | (false, true, None) => {}
                    (false, _, _) => carry(&path, &self.staging.join(&name))?,
                }
            }
            if let Ok(meta) = fs::metadata(&self.target) {
                let _ = fs::set_permissions(&self.staging, meta.permissions());
            }
        }
        let mut manifest: Vec<String> = top.iter().map(|n| n.to_string_lossy().into_owned()).collect();
        manifest.sort();
        manifest.dedup();
        if let Some(command) = self.command {
            manifest.insert(0, format!("{COMMAND_LINE}{command}"));
        }
        let listing = self.staging.join(MANIFEST);
        fs::write(&listing, manifest.join("\n") + "\n").map_err(io(&self.path(MANIFEST), "write"))?;
        File::open(&listing).and_then(|f| f.sync_all()).map_err(io(&self.path(MANIFEST), "write"))?;
        sync_dir(&self.staging);
        if !exists {
            return fs::rename(&self.staging, &self.target).map_err(io(&self.target, "move into place"));
        }
        match exchange(&self.staging, &self.target) {
            Ok(()) => {
                // the staging path now holds the old folder
                let _ = fs::remove_dir_all(&self.staging);
                Ok(())
            }
            Err(_) => self.swap_by_two_renames(),
        }
    }

    /// The swap where the file system cannot exchange two folders: the old
    /// folder goes aside first, so a crash between the two renames leaves
    /// it complete under `.NAME.rfm-old-PID`, which the next run restores.
    fn swap_by_two_renames(&self) -> Result<(), OutputError> {
        let (parent, name) = split(&self.target)?;
        let old = parent.join(format!(".{}.rfm-old-{}", name.to_string_lossy(), std::process::id()));
        fs::rename(&self.target, &old).map_err(io(&self.target, "move the old outputs aside"))?;
        if let Err(e) = fs::rename(&self.staging, &self.target) {
            let _ = fs::rename(&old, &self.target);
            return Err(io(&self.target, "move into place")(e));
        }
        let _ = fs::remove_dir_all(&old);
        Ok(())
    }
}

/// Puts `from` (a file, a folder or a symlink of the old folder) at `to` in
/// the new one without copying data: a hard link shares the file, so an
/// input stays the same file; a copy where links are not possible.
fn carry(from: &Path, to: &Path) -> Result<(), OutputError> {
    let meta = fs::symlink_metadata(from).map_err(io(from, "read"))?;
    if meta.file_type().is_symlink() {
        let link = fs::read_link(from).map_err(io(from, "read the symlink"))?;
        #[cfg(unix)]
        return std::os::unix::fs::symlink(link, to).map_err(io(to, "carry over the symlink"));
        #[cfg(not(unix))]
        return fs::copy(from, to).map(drop).map_err(io(to, format!("carry over (symlink to {})", link.display())));
    }
    if meta.is_dir() {
        fs::create_dir(to).map_err(io(to, "carry over the folder"))?;
        for entry in fs::read_dir(from).map_err(io(from, "list"))? {
            let entry = entry.map_err(io(from, "list"))?;
            carry(&entry.path(), &to.join(entry.file_name()))?;
        }
        let _ = fs::set_permissions(to, meta.permissions());
        return Ok(());
    }
    if fs::hard_link(from, to).is_ok() {
        return Ok(());
    }
    fs::copy(from, to).map(drop).map_err(io(from, "carry over into the new outputs"))
}

/// Swaps two folders in one step.
#[cfg(any(target_os = "linux", target_os = "macos"))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

/// Swaps two folders in one step: not available here, see
/// [`Outputs::swap_by_two_renames`].
#[cfg(not(any(target_os = "linux", target_os = "macos")))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

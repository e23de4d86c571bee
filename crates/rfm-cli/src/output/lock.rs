//! The lock that keeps a second run out of a target while the first
//! writes into it.

use std::fs::{self, File};
use std::io::{Read as _, Write as _};
use std::path::{Path, PathBuf};

use frf::io::FileId;

use super::{OutputError, io};

/// An exclusive lock on `.NAME.rfm-lock` beside a target, held while the
/// value lives; the file is removed when it is dropped.
pub(super) struct Lock {
    pub(super) path: PathBuf,
    _file: File,
}

impl Lock {
    pub(super) fn take(path: &Path, target: &Path) -> Result<Lock, OutputError> {
        // A run that removes the lock file at its end may do so between our
        // opening and locking it; we would then hold a lock on a file no
        // one else can find. Locking, then checking that the path still
        // names the locked file, closes that gap.
        for _ in 0..100 {
            let mut file = File::options()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(io(path, "create the lock file"))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    let mut holder = String::new();
                    let _ = file.read_to_string(&mut holder);
                    let holder = match holder.trim() {
                        "" => "lock file ".to_string() + &path.display().to_string(),
                        pid => format!("process {pid}"),
                    };
                    return Err(OutputError::Busy { target: target.to_path_buf(), holder });
                }
                Err(fs::TryLockError::Error(e)) => return Err(io(path, "lock")(e)),
            }
            if FileId::of(path) != FileId::of_file(&file, path) {
                continue;
            }
            // who holds it, for the message of a second run
            file.set_len(0).map_err(io(path, "write the lock file"))?;
            file.write_all(std::process::id().to_string().as_bytes()).map_err(io(path, "write the lock file"))?;
            return Ok(Lock { path: path.to_path_buf(), _file: file });
        }
        Err(OutputError::Target { target: target.to_path_buf(), message: "its lock file keeps changing".into() })
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // removed while still locked (the file closes after this), see `take`
        let _ = fs::remove_file(&self.path);
    }
}

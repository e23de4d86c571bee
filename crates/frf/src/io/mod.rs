//! File input and output of FRF sets. This module is the only place in the
//! crate that touches the file system.
//!
//! Every writer goes through [`atomic_write`]: the data is written to a
//! temporary file beside the target and renamed over it, so an interrupted
//! run never leaves a half-written file, and [`atomic_write`] refuses to
//! replace a file the caller marks as an input.

pub mod csv;

use std::io::Write;
use std::path::{Path, PathBuf};

use fe_model::case::ChannelMap;

use crate::error::FrfError;
use crate::set::FrfSet;

/// Reads a measured FRF file, choosing the format from its extension, and
/// maps its channels to model DOFs. CSV files name model DOFs directly (the
/// map is not used).
pub fn read_measured(path: &Path, map: &[ChannelMap]) -> Result<FrfSet, FrfError> {
    let _ = map;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "csv" | "txt" => csv::read_csv(path),
        _ => Err(FrfError::Io {
            path: path.to_path_buf(),
            message: format!("unsupported measured-data format `.{ext}` (supported: .csv)"),
        }),
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder,
/// flushed and synced, then renamed). Fails if `path` is one of `inputs`.
pub fn atomic_write(path: &Path, bytes: &[u8], inputs: &[PathBuf]) -> Result<(), FrfError> {
    let io = |message: String| FrfError::Io { path: path.to_path_buf(), message };
    if let Ok(target) = path.canonicalize() {
        for input in inputs {
            if input.canonicalize().is_ok_and(|i| i == target) {
                return Err(io("refusing to overwrite an input file; choose another output path".into()));
            }
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| io(format!("cannot create folder {}: {e}", dir.display())))?;
    let name = path.file_name().ok_or_else(|| io("not a file path".into()))?;
    let tmp = dir.join(format!(".{}.tmp-{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(format!("cannot write: {e}")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_outputs_but_never_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        atomic_write(&out, b"one", &[]).unwrap();
        atomic_write(&out, b"two", &[]).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "two");
        let e = atomic_write(&out, b"three", std::slice::from_ref(&out)).unwrap_err();
        assert!(e.to_string().contains("refusing to overwrite an input"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "two");
        // no temporary files are left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}

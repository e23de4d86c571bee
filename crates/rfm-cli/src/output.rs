//! All-or-nothing outputs: a run's files appear together or not at all.
//!
//! A command that writes files opens an [`Outputs`] for its target (a
//! folder given with `--out`, or a single file) *before* it computes
//! anything, writes every file through [`Outputs::write`], and calls
//! [`Outputs::commit`] at the end:
//!
//! ```text
//! let mut out = Outputs::folder(dir, &inputs, &["results.json", "report.html"])?;  // lock, checks
//! ... compute ...
//! out.write("results.json", &json)?;                                                 // into staging
//! out.write("figure.svg", &svg)?;
//! let written = out.commit()?;                                                       // one rename
//! ```
//!
//! - **Lock.** Opening takes an exclusive lock on `.NAME.rfm-lock` beside
//!   the target, so a second run into the same target refuses at once
//!   ([`OutputError::Busy`]) instead of mixing its files with the first's.
//!   The lock is the operating system's (`flock`), so a run killed with
//!   SIGKILL does not leave it held; the file itself is removed at the end.
//! - **Inputs.** Every input is recognised by device and inode
//!   ([`frf::io::FileId`]), so a hard link or a second mount point of the
//!   same folder does not hide it. The names a command declares are checked
//!   when it opens, every written name again before the commit; an input
//!   inside the folder under another name is carried into the new folder.
//! - **Staging.** Files are written into `.NAME.rfm-staging-PID` beside the
//!   target, on the same file system, each synced.
//! - **Commit.** A folder is swapped with its staging folder in one
//!   `renameat2(RENAME_EXCHANGE)` (Linux; `renamex_np(RENAME_SWAP)` on
//!   macOS), so that at every instant the target is either the complete old
//!   folder or the complete new one, whatever kills the process. Files in
//!   the old folder that this run does not write are carried over by hard
//!   link, except those the previous run wrote (listed in `.rfm-outputs`),
//!   which the new set replaces. A single file is renamed over its target.
//!   Where the swap is not supported, the old folder is renamed aside to
//!   `.NAME.rfm-old-PID` and the new one into place; the next run restores
//!   the old one if it finds the target missing.
//! - **Leftovers.** A run that dies before its commit leaves its staging
//!   folder. The next run into the same target (holding the lock, so no
//!   other run can own it) removes it and says so on standard error. Ctrl-C,
//!   SIGTERM and SIGHUP remove it at once ([`abandon_all`]).
//!
//! The lock is in `lock.rs`, the swap of a folder in `swap.rs`, the
//! clean-up after killed runs in `leftovers.rs`.

mod leftovers;
mod lock;
mod swap;

use std::ffi::OsString;
use std::fs::{self, File};
use std::io::Write as _;
use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use frf::io::FileId;

use self::leftovers::clean_leftovers;
use self::lock::Lock;

/// The file in a folder target that lists the names the last run wrote,
/// so that the next run can replace them without touching other files.
/// Its first line names the command that wrote them (`# rfm update`).
pub(crate) const MANIFEST: &str = ".rfm-outputs";

/// How the manifest's first line begins.
const COMMAND_LINE: &str = "# rfm ";

/// What the manifest of `dir` says the last run wrote: the command (when
/// it names one; folders written before commands were recorded do not) and
/// the names.
pub(crate) fn previous_run(dir: &Path) -> (Option<String>, Vec<String>) {
    let text = fs::read_to_string(dir.join(MANIFEST)).unwrap_or_default();
    let command = text.lines().find_map(|l| l.strip_prefix(COMMAND_LINE)).map(str::to_string);
    let names = text.lines().filter(|l| !l.starts_with('#') && !l.is_empty()).map(str::to_string).collect();
    (command, names)
}

/// Why a run's outputs could not be written. In every case the target is
/// as it was before the run.
#[derive(Debug, thiserror::Error)]
pub(crate) enum OutputError {
    /// Another run holds the target's lock.
    #[error(
        "{}: another rfm run ({holder}) is writing into it; wait until it ends, or choose another output path",
        target.display()
    )]
    Busy {
        /// The target.
        target: PathBuf,
        /// Who holds the lock (`process 1234`).
        holder: String,
    },
    /// An output would replace one of the run's inputs.
    #[error("{}: refusing to overwrite an input file; choose another output path", path.display())]
    Input {
        /// The output path that is an input.
        path: PathBuf,
    },
    /// The target cannot take the outputs.
    #[error("{}: {message}", target.display())]
    Target {
        /// The target.
        target: PathBuf,
        /// Why.
        message: String,
    },
    /// The folder holds the results of another command, which this run
    /// would replace.
    #[error(
        "{}: holds the results of `rfm {command}` ({}); give another folder, or --replace to replace them with \
         this run's",
        target.display(),
        list_names(files)
    )]
    OtherCommand {
        /// The target.
        target: PathBuf,
        /// The command that wrote it (`update`).
        command: String,
        /// What it wrote there.
        files: Vec<String>,
    },
    /// A file system operation failed.
    #[error("{}: cannot {what}: {source}; nothing of this run was written", path.display())]
    Io {
        /// The path the operation was on.
        path: PathBuf,
        /// What was being done (`write`, `create the staging folder`).
        what: String,
        /// The error.
        source: std::io::Error,
    },
}

/// A few of `names`, and how many more.
fn list_names(names: &[String]) -> String {
    const SHOWN: usize = 4;
    let mut shown: Vec<&str> = names.iter().map(String::as_str).take(SHOWN).collect();
    let more = names.len().saturating_sub(SHOWN);
    let extra = format!("and {more} more");
    if more > 0 {
        shown.push(&extra);
    }
    shown.join(", ")
}

fn io(path: &Path, what: impl Into<String>) -> impl FnOnce(std::io::Error) -> OutputError {
    let path = path.to_path_buf();
    let what = what.into();
    move |source| OutputError::Io { path, what, source }
}

/// Whether the target is a folder of files or one file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Folder,
    File,
}

/// Staging folders and lock files of the runs in this process, removed by
/// [`abandon_all`] when a signal ends the process before their commit.
static ACTIVE: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

fn register(staging: &Path, lock: &Path) {
    ACTIVE.lock().unwrap_or_else(PoisonError::into_inner).push((staging.to_path_buf(), lock.to_path_buf()));
}

fn deregister(staging: &Path) {
    ACTIVE.lock().unwrap_or_else(PoisonError::into_inner).retain(|(s, _)| s != staging);
}

/// What the checkpoints of this process have kept, for the message of an
/// interrupt (see [`Outputs::checkpoint`]).
static CHECKPOINTED: Mutex<Option<String>> = Mutex::new(None);

/// Records what the last checkpoint kept, in words.
pub(crate) fn note_checkpoint(what: String) {
    *CHECKPOINTED.lock().unwrap_or_else(PoisonError::into_inner) = Some(what);
}

/// Removes the staging folders (and lock files) of every uncommitted
/// output of this process, and returns what its checkpoints kept, if any.
/// The signal handler calls it while it holds the output phase
/// ([`crate::writing`]), so no commit is under way.
pub(crate) fn abandon_all() -> Option<String> {
    for (staging, lock) in ACTIVE.lock().unwrap_or_else(PoisonError::into_inner).drain(..) {
        let _ = fs::remove_dir_all(&staging);
        let _ = fs::remove_file(&lock);
    }
    CHECKPOINTED.lock().unwrap_or_else(PoisonError::into_inner).take()
}

/// The outputs of one run into one target, written all or nothing; see the
/// module documentation.
pub(crate) struct Outputs {
    target: PathBuf,
    kind: Kind,
    staging: PathBuf,
    inputs: Vec<FileId>,
    written: Vec<String>,
    committed: bool,
    lock: Option<Lock>,
    /// The command whose outputs these are (`compare`), recorded in the
    /// manifest.
    command: Option<&'static str>,
}

impl Outputs {
    /// Outputs into the folder `dir` (created if needed). `names` are the
    /// files the command will write that it knows now: each is checked
    /// against `inputs` here, before any work.
    pub(crate) fn folder(dir: &Path, inputs: &[PathBuf], names: &[&str]) -> Result<Outputs, OutputError> {
        let out = Outputs::open(dir, Kind::Folder, inputs)?;
        for name in names {
            out.check_name(name)?;
            out.refuse_input_at(&out.target.join(name))?;
        }
        Ok(out)
    }

    /// Output of the single file `path`, checked against `inputs` here.
    pub(crate) fn file(path: &Path, inputs: &[PathBuf]) -> Result<Outputs, OutputError> {
        let out = Outputs::open(path, Kind::File, inputs)?;
        out.refuse_input_at(&out.target)?;
        Ok(out)
    }

    fn open(target: &Path, kind: Kind, inputs: &[PathBuf]) -> Result<Outputs, OutputError> {
        crate::files_to_write();
        let target = resolve(target, kind)?;
        let (parent, name) = split(&target)?;
        let lock = Lock::take(&parent.join(format!(".{}.rfm-lock", name.to_string_lossy())), &target)?;
        clean_leftovers(&parent, &name, &target, kind)?;
        let staging = parent.join(format!(".{}.rfm-staging-{}", name.to_string_lossy(), std::process::id()));
        fs::create_dir(&staging).map_err(io(&staging, "create the staging folder"))?;
        register(&staging, &lock.path);
        Ok(Outputs {
            target,
            kind,
            staging,
            inputs: inputs.iter().filter_map(|p| FileId::of(p)).collect(),
            written: Vec::new(),
            committed: false,
            lock: Some(lock),
            command: None,
        })
    }

    /// Marks a folder's outputs as those of `rfm command`. A folder whose
    /// last run was another command's is refused
    /// ([`OutputError::OtherCommand`]) unless `replace`: a `compare` into
    /// the folder of an `update` would otherwise replace its results and
    /// its updated case without a word. Checked here, before any work.
    pub(crate) fn of_command(mut self, command: &'static str, replace: bool) -> Result<Outputs, OutputError> {
        if self.kind == Kind::Folder && !replace {
            let (previous, files) = previous_run(&self.target);
            if let Some(previous) = previous.filter(|p| p != command) {
                return Err(OutputError::OtherCommand { target: self.target.clone(), command: previous, files });
            }
        }
        self.command = Some(command);
        Ok(self)
    }

    /// Where `name` will be once committed.
    pub(crate) fn path(&self, name: &str) -> PathBuf {
        match self.kind {
            Kind::Folder => self.target.join(name),
            Kind::File => self.target.clone(),
        }
    }

    /// Writes `name` (a path relative to the folder; for a single-file
    /// target, its file name) into the staging folder, synced. Returns
    /// where it will be once committed.
    pub(crate) fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        self.check_name(name)?;
        let staged = self.staging.join(name);
        if let Some(dir) = staged.parent() {
            fs::create_dir_all(dir).map_err(io(&self.path(name), "write"))?;
        }
        let result = (|| {
            // a new file, never through a link a checkpoint left: writing
            // through it would change the committed file in place
            if fs::symlink_metadata(&staged).is_ok() {
                fs::remove_file(&staged)?;
            }
            let mut f = File::create(&staged)?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        result.map_err(io(&self.path(name), "write"))?;
        if !self.written.iter().any(|w| w == name) {
            self.written.push(name.to_string());
        }
        Ok(self.path(name))
    }

    /// Writes the single file of a single-file target.
    pub(crate) fn write_file(&mut self, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let name = self.target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        self.write(&name, bytes)
    }

    /// Takes `name` back out of the staged files: the commit does not
    /// write it, and where a checkpoint put it in place, removes it (a file
    /// that only an unfinished run needs, such as `rfm fix`'s progress).
    pub(crate) fn forget(&mut self, name: &str) -> Result<(), OutputError> {
        self.check_name(name)?;
        if let Some(k) = self.written.iter().position(|w| w == name) {
            self.written.remove(k);
            let staged = self.staging.join(name);
            if fs::symlink_metadata(&staged).is_ok() {
                fs::remove_file(&staged).map_err(io(&self.path(name), "take back"))?;
            }
        }
        Ok(())
    }

    /// Where the files written so far will be once committed.
    pub(crate) fn written(&self) -> Vec<PathBuf> {
        self.written.iter().map(|n| self.path(n)).collect()
    }

    fn check_name(&self, name: &str) -> Result<(), OutputError> {
        let plain = !name.is_empty()
            && Path::new(name).components().all(|c| matches!(c, Component::Normal(_)))
            && name != MANIFEST;
        let fits = match self.kind {
            Kind::Folder => plain,
            Kind::File => plain && self.target.file_name().is_some_and(|n| n == name),
        };
        if fits {
            Ok(())
        } else {
            Err(OutputError::Target {
                target: self.target.clone(),
                message: format!("`{name}` is not a name this output can take (a bug in rfm)"),
            })
        }
    }

    /// Fails if `path`, or a file under it, is one of the inputs.
    fn refuse_input_at(&self, path: &Path) -> Result<(), OutputError> {
        match find_input(path, &self.inputs) {
            Some(p) => Err(OutputError::Input { path: p }),
            None => Ok(()),
        }
    }

    /// Moves every written file into place at once and returns where they
    /// are. An interrupt waits for it ([`crate::writing`]).
    pub(crate) fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let _writing = crate::writing();
        for name in &self.written {
            self.refuse_input_at(&self.path(name))?;
        }
        match self.kind {
            Kind::File => {
                let name = self.target.file_name().unwrap_or_default().to_os_string();
                if self.written.is_empty() {
                    // a run that wrote nothing leaves the target as it was
                } else {
                    fs::rename(self.staging.join(&name), &self.target).map_err(io(&self.target, "move into place"))?;
                }
                let _ = fs::remove_dir_all(&self.staging);
            }
            Kind::Folder => self.swap_folder()?,
        }
        if let Ok((parent, _)) = split(&self.target) {
            sync_dir(&parent);
        }
        deregister(&self.staging);
        self.committed = true;
        Ok(self.written())
    }
}

impl Outputs {
    /// Moves what a folder's run has written so far into place, as a
    /// commit does, and goes on with the same names staged: each file
    /// committed is linked back into a fresh staging folder, so that the
    /// final commit holds it too unless the run writes it again. A run
    /// stopped after a checkpoint (Ctrl-C, a failure) leaves the folder as
    /// the checkpoint left it; `rfm fix` checkpoints after each step.
    pub(crate) fn checkpoint(&mut self) -> Result<(), OutputError> {
        if self.kind != Kind::Folder {
            return Err(OutputError::Target {
                target: self.target.clone(),
                message: "only a folder's outputs can be committed in parts (a bug in rfm)".into(),
            });
        }
        {
            let _writing = crate::writing_part();
            for name in &self.written {
                self.refuse_input_at(&self.path(name))?;
            }
            self.swap_folder()?;
            if let Ok((parent, _)) = split(&self.target) {
                sync_dir(&parent);
            }
            fs::create_dir(&self.staging).map_err(io(&self.staging, "create the staging folder"))?;
        }
        for name in &self.written {
            let (from, to) = (self.target.join(name), self.staging.join(name));
            if let Some(dir) = to.parent() {
                fs::create_dir_all(dir).map_err(io(&self.path(name), "stage again"))?;
            }
            fs::hard_link(&from, &to)
                .or_else(|_| fs::copy(&from, &to).map(drop))
                .map_err(io(&self.path(name), "stage again"))?;
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
            deregister(&self.staging);
        }
        drop(self.lock.take());
    }
}

/// The absolute target, through a final symlink (so that the folder it
/// points to is replaced, not the link), its parent created.
fn resolve(target: &Path, kind: Kind) -> Result<PathBuf, OutputError> {
    let bad = |message: &str| OutputError::Target { target: target.to_path_buf(), message: message.into() };
    let cwd = std::env::current_dir().map_err(io(Path::new("."), "find the current folder"))?;
    let mut path = cwd.join(target);
    if path.file_name().is_none() || path.components().next_back() == Some(Component::CurDir) {
        path = path.canonicalize().map_err(io(target, "resolve"))?;
    }
    let (parent, name) = split(&path)?;
    fs::create_dir_all(&parent).map_err(io(&parent, "create the folder"))?;
    let mut path = parent.canonicalize().map_err(io(&parent, "resolve"))?.join(name);
    if fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
        path = path.canonicalize().map_err(io(target, "resolve the symlink"))?;
    }
    match (kind, fs::metadata(&path)) {
        (Kind::Folder, Ok(m)) if !m.is_dir() => return Err(bad("is a file, not a folder for the outputs")),
        (Kind::File, Ok(m)) if m.is_dir() => return Err(bad("is a folder; give a file name")),
        _ => {}
    }
    // Replacing the folder a shell is in would leave that shell in a
    // removed folder: outputs go into a folder of their own.
    if kind == Kind::Folder && cwd.canonicalize().is_ok_and(|c| c.starts_with(&path)) {
        return Err(bad("is the current folder (or holds it); give a folder for the outputs, such as `--out results`"));
    }
    Ok(path)
}

fn split(path: &Path) -> Result<(PathBuf, OsString), OutputError> {
    match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => Ok((parent.to_path_buf(), name.to_os_string())),
        _ => Err(OutputError::Target { target: path.to_path_buf(), message: "is not a path rfm can write to".into() }),
    }
}

/// The first input at `path` or under it (a folder), if any.
fn find_input(path: &Path, inputs: &[FileId]) -> Option<PathBuf> {
    let meta = fs::symlink_metadata(path).ok()?;
    if meta.is_dir() {
        let entries = fs::read_dir(path).ok()?;
        return entries.flatten().find_map(|e| find_input(&e.path(), inputs));
    }
    FileId::of(path).filter(|id| inputs.contains(id)).map(|_| path.to_path_buf())
}

/// Makes a folder's entries durable (renames in it survive a power cut).
fn sync_dir(dir: &Path) {
    // Not every platform can open a folder for syncing; the data files are
    // synced already, so this only narrows the window of a power cut.
    if let Ok(f) = File::open(dir) {
        let _ = f.sync_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contents(dir: &Path) -> Vec<(String, String)> {
        let mut v: Vec<(String, String)> = fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| (e.file_name().to_string_lossy().into_owned(), fs::read_to_string(e.path()).unwrap_or_default()))
            .collect();
        v.sort();
        v
    }

    fn siblings(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir.parent().unwrap())
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_folder_appears_complete_at_the_commit_and_not_before() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let mut out = Outputs::folder(&dir, &[], &["a.txt"]).unwrap();
        out.write("a.txt", b"one").unwrap();
        out.write("sub/b.txt", b"two").unwrap();
        assert!(!dir.exists(), "nothing appears before the commit");
        let written = out.commit().unwrap();
        assert_eq!(written, vec![dir.join("a.txt"), dir.join("sub/b.txt")]);
        assert_eq!(fs::read_to_string(dir.join("sub/b.txt")).unwrap(), "two");
        assert_eq!(siblings(&dir), vec!["out"], "no staging folder or lock file is left");
    }

    #[test]
    fn a_second_run_replaces_the_first_runs_files_and_keeps_the_users() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap();
        out.write("a.txt", b"one").unwrap();
        out.write("old-figure.svg", b"<svg/>").unwrap();
        out.commit().unwrap();
        fs::write(dir.join("notes.md"), "mine").unwrap();
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap();
        out.write("a.txt", b"two").unwrap();
        out.commit().unwrap();
        let names: Vec<String> = contents(&dir).into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, vec![MANIFEST, "a.txt", "notes.md"]);
        assert_eq!(fs::read_to_string(dir.join("a.txt")).unwrap(), "two");
        assert_eq!(fs::read_to_string(dir.join("notes.md")).unwrap(), "mine");
    }

    #[test]
    fn an_uncommitted_run_leaves_the_old_folder_and_nothing_else() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        fs::create_dir(&dir).unwrap();
        fs::write(dir.join("a.txt"), "old").unwrap();
        let before = contents(&dir);
        {
            let mut out = Outputs::folder(&dir, &[], &[]).unwrap();
            out.write("a.txt", b"new").unwrap();
            // dropped on an error path
        }
        assert_eq!(contents(&dir), before);
        assert_eq!(siblings(&dir), vec!["out"]);
    }

    #[test]
    fn a_second_run_into_the_same_target_is_refused_while_the_first_holds_it() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let first = Outputs::folder(&dir, &[], &[]).unwrap();
        let e = Outputs::folder(&dir, &[], &[]).err().expect("refused");
        assert!(matches!(e, OutputError::Busy { .. }), "{e:?}");
        assert!(e.to_string().contains(&format!("another rfm run (process {})", std::process::id())), "{e}");
        drop(first);
        Outputs::folder(&dir, &[], &[]).unwrap();
    }

    #[test]
    fn a_stale_staging_folder_is_removed_by_the_next_run() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let stale = root.path().join(".out.rfm-staging-999999");
        fs::create_dir(&stale).unwrap();
        fs::write(stale.join("half.json"), "{").unwrap();
        fs::write(root.path().join(".out.rfm-lock"), "999999").unwrap();
        let out = Outputs::folder(&dir, &[], &[]).unwrap();
        assert!(!stale.exists());
        out.commit().unwrap();
        assert_eq!(siblings(&dir), vec!["out"]);
    }

    #[test]
    fn an_old_folder_left_aside_by_a_killed_swap_is_restored() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let aside = root.path().join(".out.rfm-old-999999");
        fs::create_dir(&aside).unwrap();
        fs::write(aside.join("a.txt"), "old").unwrap();
        drop(Outputs::folder(&dir, &[], &[]).unwrap());
        assert_eq!(fs::read_to_string(dir.join("a.txt")).unwrap(), "old");
        assert_eq!(siblings(&dir), vec!["out"]);
    }

    #[test]
    fn inputs_are_refused_by_identity_and_carried_over_when_not_replaced() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        fs::create_dir(&dir).unwrap();
        let case = root.path().join("case.toml");
        fs::write(&case, "case").unwrap();
        // the case reached under another name inside the output folder
        fs::hard_link(&case, dir.join("updated.toml")).unwrap();
        let inputs = vec![case.clone()];
        let e = Outputs::folder(&dir, &inputs, &["updated.toml"]).err().expect("refused");
        assert!(matches!(e, OutputError::Input { .. }), "{e:?}");
        // a name found only while writing: refused at the commit, nothing changed
        let mut out = Outputs::folder(&dir, &inputs, &[]).unwrap();
        out.write("updated.toml", b"new").unwrap();
        let e = out.commit().expect_err("refused");
        assert!(e.to_string().contains("refusing to overwrite an input"), "{e}");
        assert_eq!(fs::read_to_string(&case).unwrap(), "case");
        // not replaced: carried into the new folder as the same file
        let mut out = Outputs::folder(&dir, &inputs, &[]).unwrap();
        out.write("results.json", b"{}").unwrap();
        out.commit().unwrap();
        assert_eq!(FileId::of(&dir.join("updated.toml")), FileId::of(&case));
    }

    /// A folder another command wrote is refused before any work, and
    /// replaced only when asked; the same command replaces its own.
    #[test]
    fn another_commands_folder_is_refused_unless_replace_is_given() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap().of_command("update", false).unwrap();
        out.write("results.json", b"{}").unwrap();
        out.write("updated.toml", b"x").unwrap();
        out.commit().unwrap();
        assert_eq!(previous_run(&dir), (Some("update".into()), vec!["results.json".into(), "updated.toml".into()]));
        let e = Outputs::folder(&dir, &[], &[]).unwrap().of_command("compare", false).err().expect("refused");
        assert!(matches!(e, OutputError::OtherCommand { .. }), "{e:?}");
        assert!(
            e.to_string().contains("holds the results of `rfm update` (results.json, updated.toml)")
                && e.to_string().contains("--replace"),
            "{e}"
        );
        assert_eq!(fs::read_to_string(dir.join("updated.toml")).unwrap(), "x");
        // its own command replaces it, and so does another with --replace
        Outputs::folder(&dir, &[], &[]).unwrap().of_command("update", false).unwrap();
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap().of_command("compare", true).unwrap();
        out.write("compare.json", b"{}").unwrap();
        out.commit().unwrap();
        assert!(!dir.join("updated.toml").exists());
        assert_eq!(previous_run(&dir).0.as_deref(), Some("compare"));
    }

    /// A checkpoint puts what was written so far in place; the run goes
    /// on, and its final commit holds the files of the checkpoint, rewritten
    /// or not, and never changes a committed file in place. A run dropped
    /// after a checkpoint leaves the checkpoint's folder.
    #[test]
    fn a_checkpoint_commits_what_was_written_and_the_run_goes_on() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap().of_command("fix", false).unwrap();
        out.write("step-1.toml", b"one").unwrap();
        out.checkpoint().unwrap();
        assert_eq!(fs::read_to_string(dir.join("step-1.toml")).unwrap(), "one");
        out.write("step-1.toml", b"one, revised").unwrap();
        // the committed file is untouched until the next commit
        assert_eq!(fs::read_to_string(dir.join("step-1.toml")).unwrap(), "one");
        out.write("step-2.toml", b"two").unwrap();
        out.checkpoint().unwrap();
        out.write("report.html", b"<html>").unwrap();
        drop(out);
        let names: Vec<String> = contents(&dir).into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, vec![MANIFEST, "step-1.toml", "step-2.toml"], "the second checkpoint stays");
        assert_eq!(fs::read_to_string(dir.join("step-1.toml")).unwrap(), "one, revised");
        assert_eq!(siblings(&dir), vec!["out"], "no staging folder or lock is left");
        // a run that finishes holds every file of its checkpoints
        let mut out = Outputs::folder(&dir, &[], &[]).unwrap().of_command("fix", false).unwrap();
        out.write("step-1.toml", b"1").unwrap();
        out.checkpoint().unwrap();
        out.write("progress.json", b"{}").unwrap();
        out.checkpoint().unwrap();
        assert!(dir.join("progress.json").exists());
        out.write("results.json", b"{}").unwrap();
        // what only an unfinished run needs goes at the final commit
        out.forget("progress.json").unwrap();
        out.commit().unwrap();
        let names: Vec<String> = contents(&dir).into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, vec![MANIFEST, "results.json", "step-1.toml"]);
    }

    #[test]
    fn a_single_file_is_replaced_whole_and_never_when_it_is_an_input() {
        let root = tempfile::tempdir().unwrap();
        let path = root.path().join("h.csv");
        fs::write(&path, "old").unwrap();
        let mut out = Outputs::file(&path, &[]).unwrap();
        out.write_file(b"new").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        out.commit().unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(siblings(&path), vec!["h.csv"]);
        let e = Outputs::file(&path, std::slice::from_ref(&path)).err().expect("refused");
        assert!(matches!(e, OutputError::Input { .. }), "{e:?}");
    }
}

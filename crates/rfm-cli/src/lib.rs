//! The commands of `rfm` as a library: the binary (`src/main.rs`) parses the
//! command line and calls them, and the Python package (`crates/rfm-py`)
//! calls their non-printing parts, so that its results serialise as
//! `--json` does and its `save` writes the files the commands write:
//! [`CompareRun`] (`rfm compare`), [`diagnosis_data`], [`run_diagnosis`],
//! [`diagnosis_json`] and [`write_applied`] (`rfm diagnose`, `--apply`), [`UpdateSetup`], [`finish_update`] and
//! [`save_update`] (`rfm update`), [`fix_options`] and [`save_fix`] (`rfm
//! fix`), with [`Failure`] for their errors.
//!
//! Printing stays where the commands print (through `outln!`): the entries
//! named above print nothing.

/// `println!` through [`print_line`]: a closed standard output does not
/// panic, and other write errors (a full disk) are handed back with `?`.
macro_rules! outln {
    ($($arg:tt)*) => {
        crate::print_line(format_args!($($arg)*))?
    };
}

mod commands;
mod exit;
mod output;
mod report;
mod table;

use std::io::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

pub use commands::{
    CompareRun, DiagnoseArgs, FixArgs, Result, SimulateArgs, UpdateOverrides, UpdateSetup, WithNotes, compare,
    diagnose, diagnosis_data, diagnosis_json, finish_update, fix, fix_exit, fix_options, fix_progress_lines, inspect,
    run_diagnosis, save_fix, save_update, simulate, synthesised, update, updated_case, write_applied,
};
pub use exit::{Exit, Failure};
pub use report::ReportOptions;
pub use report::plot::axes::FrequencyScale;

/// Set by a command that has files to write (`--out`, `--apply`).
static FILES_TO_WRITE: AtomicBool = AtomicBool::new(false);

/// Tells [`print_line`] that the command has files to write.
pub(crate) fn files_to_write() {
    FILES_TO_WRITE.store(true, Ordering::Relaxed);
}

/// Prints a line on standard output. When the reader has gone (`rfm ... |
/// head`), a command with files to write goes on without printing, and any
/// other stops at once and quietly: nothing would be lost.
pub(crate) fn print_line(args: std::fmt::Arguments<'_>) -> std::io::Result<()> {
    match writeln!(std::io::stdout().lock(), "{args}") {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            if FILES_TO_WRITE.load(Ordering::Relaxed) {
                Ok(())
            } else {
                std::process::exit(0)
            }
        }
        other => other,
    }
}

/// Held while a command writes its outputs.
static WRITING: Mutex<()> = Mutex::new(());

/// Set when a command's output phase has ended.
static WRITTEN: AtomicBool = AtomicBool::new(false);

/// The output phase of a command, from [`writing`] until dropped.
pub(crate) struct Writing {
    _guard: MutexGuard<'static, ()>,
}

impl Drop for Writing {
    fn drop(&mut self) {
        WRITTEN.store(true, Ordering::Relaxed);
    }
}

/// Marks the output phase of a command (the commit of its
/// [`output::Outputs`]): an interrupt (Ctrl-C, SIGTERM, SIGHUP) waits until
/// the guard is dropped, so that a run stops either before its outputs move
/// into place or after, never while they do.
pub(crate) fn writing() -> Writing {
    Writing { _guard: WRITING.lock().unwrap_or_else(PoisonError::into_inner) }
}

/// What an interrupt (Ctrl-C, SIGTERM, SIGHUP) does to the outputs: waits
/// for a commit under way, removes the staging folders of this process,
/// and returns the guard that keeps any other commit from starting until
/// the process ends, with whether this run's outputs were written.
pub fn interrupt_outputs() -> (MutexGuard<'static, ()>, bool) {
    let held = WRITING.lock().unwrap_or_else(PoisonError::into_inner);
    output::abandon_all();
    (held, WRITTEN.load(Ordering::Relaxed))
}

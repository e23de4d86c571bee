//! Long work from Python: run with the GIL released, on a rayon pool whose
//! size the user sets, interruptible by Ctrl-C between stages.
//!
//! The work runs on a thread of its own (inside the pool) while the calling
//! thread, Python's main thread in a notebook or script, waits with the GIL
//! released and every [`POLL`] takes it back for a moment to let Python
//! handle its signals. A KeyboardInterrupt (or any exception a signal
//! handler raises) marks the run cancelled; the work stops at its next
//! stage boundary, where the library calls its progress callback
//! ([`Progress::say`]): the callback unwinds the work's stack with a
//! private payload, so that everything the work held is dropped and nothing
//! is written, and the exception is raised in Python. A progress callback
//! given from Python is called at the same boundaries, with the GIL taken
//! only for it; an exception it raises stops the work the same way.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use pyo3::prelude::*;

use crate::errors::{Class, Error};

/// How often the waiting thread lets Python handle its signals.
const POLL: Duration = Duration::from_millis(50);

/// The pool the work runs in; `None` until first used or after
/// [`set_num_threads`] asks for the default again.
static POOL: Mutex<Option<Arc<rayon::ThreadPool>>> = Mutex::new(None);

/// The number of threads asked for (0: rayon's default, which honours
/// `RAYON_NUM_THREADS`, else one per CPU).
static THREADS: Mutex<usize> = Mutex::new(0);

/// Sets the number of threads of the computations that follow (0: one per
/// CPU, or `RAYON_NUM_THREADS`).
#[pyfunction]
pub(crate) fn set_num_threads(py: Python<'_>, n: usize) -> PyResult<()> {
    let pool = build_pool(n).map_err(|e| e.into_pyerr(py))?;
    *THREADS.lock().unwrap_or_else(PoisonError::into_inner) = n;
    *POOL.lock().unwrap_or_else(PoisonError::into_inner) = Some(pool);
    Ok(())
}

/// The number of threads the computations run on.
#[pyfunction]
pub(crate) fn get_num_threads(py: Python<'_>) -> PyResult<usize> {
    Ok(pool().map_err(|e| e.into_pyerr(py))?.current_num_threads())
}

fn build_pool(n: usize) -> Result<Arc<rayon::ThreadPool>, Error> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("rfm-{i}"))
        .build()
        .map(Arc::new)
        .map_err(|e| Error::argument(format!("cannot start {n} threads: {e}")))
}

fn pool() -> Result<Arc<rayon::ThreadPool>, Error> {
    let mut guard = POOL.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(p) = guard.as_ref() {
        return Ok(p.clone());
    }
    let p = build_pool(*THREADS.lock().unwrap_or_else(PoisonError::into_inner))?;
    *guard = Some(p.clone());
    Ok(p)
}

/// The payload that unwinds a cancelled run.
struct Cancelled;

/// What the work reports through, and how it learns that it is cancelled.
pub(crate) struct Progress {
    callback: Option<Py<PyAny>>,
    cancelled: AtomicBool,
    /// The exception that cancelled the run (a signal's, or the callback's).
    error: Mutex<Option<PyErr>>,
}

impl Progress {
    /// A stage boundary: stops the work here when the run is cancelled,
    /// else tells the callback (if any) `message`.
    pub(crate) fn say(&self, message: &str) {
        self.checkpoint();
        if let Some(callback) = &self.callback {
            let result = Python::attach(|py| callback.call1(py, (message,)).map(drop));
            if let Err(e) = result {
                self.cancel(e);
            }
            // an interrupt while the callback ran stops the work here too
            self.checkpoint();
        }
    }

    /// Stops the work here when the run is cancelled.
    pub(crate) fn checkpoint(&self) {
        if self.cancelled.load(Ordering::Relaxed) {
            // not a panic: no hook runs and nothing is printed
            resume_unwind(Box::new(Cancelled));
        }
    }

    fn cancel(&self, e: PyErr) {
        let mut error = self.error.lock().unwrap_or_else(PoisonError::into_inner);
        error.get_or_insert(e);
        self.cancelled.store(true, Ordering::Relaxed);
    }
}

/// Runs `work` with the GIL released on the pool, handling Python's
/// signals while it runs (see the module documentation); `callback`, a
/// Python callable taking a string, hears every stage.
pub(crate) fn run<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&Progress) -> Result<T, Error> + Send,
) -> PyResult<T> {
    let pool = pool().map_err(|e| e.into_pyerr(py))?;
    let progress = Progress { callback, cancelled: AtomicBool::new(false), error: Mutex::new(None) };
    let outcome = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel::<()>();
            let progress = &progress;
            let worker = scope.spawn(move || {
                let result = pool.install(|| catch_unwind(AssertUnwindSafe(|| work(progress))));
                let _ = done.send(());
                result
            });
            // the waiting thread lets Python run its signal handlers
            while let Err(mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(POLL) {
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    progress.cancel(e);
                }
            }
            worker.join().unwrap_or_else(Err)
        })
    });
    let error = progress.error.lock().unwrap_or_else(PoisonError::into_inner).take();
    match outcome {
        // a Ctrl-C after the last stage still stops the caller
        Ok(_) if error.is_some() => Err(error.expect("an error")),
        Ok(Ok(value)) => Ok(value),
        Ok(Err(e)) => Err(e.into_pyerr(py)),
        Err(payload) if payload.is::<Cancelled>() => {
            Err(error.unwrap_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err("interrupted")))
        }
        Err(_) => Err(Error::new(
            Class::Internal,
            rfm_cli::Exit::Internal,
            "internal error (a bug in rfm): please report it with the call and its input files",
        )
        .into_pyerr(py)),
    }
}

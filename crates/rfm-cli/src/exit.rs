//! The exit codes of `rfm`, in one table ([`Exit::TABLE`]) that every
//! command returns through, that `rfm --help` prints and that
//! `docs/reliability.md` copies (a test keeps the two equal).
//!
//! Errors are classified where they are turned into a [`Failure`]: the
//! `From` conversions below say which library error means bad input and
//! which failed numerics. An updating run's [`Status`] maps to a code in
//! one function, [`Exit::of_status`].

use std::fmt;

use fe_model::{CaseError, ModelError};
use frf::{FileError, FrfError};
use rfm_update::UpdateError;
use rfm_update::status::Status;

use crate::output::OutputError;

/// How a run of `rfm` ended, as its exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// The command did what was asked (an update converged).
    Success,
    /// An error rfm did not foresee: a bug, please report it.
    Internal,
    /// The command line is wrong (clap's own code for usage errors).
    Usage,
    /// A case file or measured file is unreadable, malformed or
    /// inconsistent with the model; the message locates it.
    InvalidInput,
    /// The model could not be evaluated or the fit produced non-finite
    /// numbers (a singular dynamic stiffness at a line, a NaN misfit).
    Numerics,
    /// An update reached its iteration limit; its outputs hold the best
    /// iterate. For `rfm fix`: the steps asked for were done, or the
    /// diagnosis after the last failed, with more than the noise left.
    NotConverged,
    /// The outputs could not be written (a full disk, no permission, an
    /// output that would replace an input); none of them were.
    Output,
    /// Another run is writing into the same output; nothing was done.
    Busy,
    /// An update stopped where no step lowers the misfit, above the noise.
    Stalled,
    /// The misfit stays above the noise where nothing more can be done: an
    /// update's restarts confirm its minimum, or `rfm fix` finds no effect
    /// with evidence of its own (or one only a finer mesh explains).
    ModelInadequate,
    /// An update stopped above the noise and its restarts disagree.
    LocalMinimum,
    /// An update ended with a larger misfit than the initial model's (the
    /// RFM can); its outputs say so.
    WorseThanStart,
    /// An update's misfit is within the noise, but a parameter ended on its
    /// bound or ran away: its value is no estimate.
    Runaway,
    /// Ctrl-C, SIGTERM or SIGHUP stopped the run (128 + SIGINT).
    Interrupted,
}

impl Exit {
    /// Every code with its meaning, in order: printed by `rfm --help` and
    /// copied in `docs/reliability.md`.
    pub const TABLE: [(Exit, &'static str); 14] = [
        (Exit::Success, "success (for update: the fit converged)"),
        (Exit::Internal, "internal error (a bug in rfm; please report it)"),
        (Exit::Usage, "wrong command line"),
        (Exit::InvalidInput, "invalid input: a case file or measured file is malformed or inconsistent"),
        (Exit::Numerics, "failed numerics: the model cannot be evaluated, or the fit gave non-finite numbers"),
        (
            Exit::NotConverged,
            "not converged: an update reached its iteration limit (best iterate written), or rfm fix did the steps asked for, or could not diagnose the model after the last, with more than the noise left (its steps written)",
        ),
        (Exit::Output, "outputs not written: cannot write, or an output would replace an input"),
        (Exit::Busy, "busy: another rfm run is writing into the same output"),
        (Exit::Stalled, "stalled: no step lowers the misfit, which stays above the noise (best iterate written)"),
        (
            Exit::ModelInadequate,
            "model inadequate: the misfit stays above the noise and nothing the tool can add explains it (update: restarts confirm the minimum; fix: no effect has its own evidence, or only a finer mesh would; results written)",
        ),
        (Exit::LocalMinimum, "local minimum: above the noise, and restarts disagree (best fit written)"),
        (Exit::WorseThanStart, "worse than the start: the update raised the misfit (results written, marked so)"),
        (
            Exit::Runaway,
            "run-away: a parameter ended on its bound or moved a hundredfold where the data do not hold it (results written)",
        ),
        (Exit::Interrupted, "interrupted by Ctrl-C, SIGTERM or SIGHUP (outputs all old or all new)"),
    ];

    /// The process exit code.
    pub fn code(self) -> u8 {
        match self {
            Exit::Success => 0,
            Exit::Internal => 1,
            Exit::Usage => 2,
            Exit::InvalidInput => 3,
            Exit::Numerics => 4,
            Exit::NotConverged => 5,
            Exit::Output => 6,
            Exit::Busy => 7,
            Exit::Stalled => 8,
            Exit::ModelInadequate => 9,
            Exit::LocalMinimum => 10,
            Exit::WorseThanStart => 11,
            Exit::Runaway => 12,
            Exit::Interrupted => 130,
        }
    }

    /// What the code means, from [`Exit::TABLE`].
    pub fn meaning(self) -> &'static str {
        Exit::TABLE.iter().find(|(e, _)| *e == self).map_or("", |(_, m)| m)
    }

    /// The code for how an updating run ended: 0 only when it converged.
    pub fn of_status(status: &Status) -> Exit {
        match status {
            Status::Converged => Exit::Success,
            Status::MaxIterations => Exit::NotConverged,
            Status::Stalled => Exit::Stalled,
            Status::ModelInadequate => Exit::ModelInadequate,
            Status::LocalMinimum => Exit::LocalMinimum,
            Status::Runaway => Exit::Runaway,
            Status::Failed(_) => Exit::Numerics,
        }
    }

    /// The code for an update's outcome: a run that made the misfit worse
    /// than the start's is never a success, whatever its status.
    pub fn of_outcome(outcome: &rfm_update::UpdateOutcome) -> Exit {
        match Exit::of_status(&outcome.status) {
            Exit::Success if outcome.worse_than_start => Exit::WorseThanStart,
            exit => exit,
        }
    }

    /// The table as `rfm --help` shows it.
    pub fn help() -> String {
        let mut text = String::from("Exit codes:\n");
        for (exit, meaning) in Exit::TABLE {
            text.push_str(&format!("  {:>3}  {meaning}\n", exit.code()));
        }
        text
    }
}

/// Why a command failed, with the exit code that tells a script so.
#[derive(Debug)]
pub struct Failure {
    /// The exit code.
    pub exit: Exit,
    /// The message for standard error.
    pub message: String,
}

impl Failure {
    /// A failure of the given kind.
    pub fn new(exit: Exit, message: impl Into<String>) -> Failure {
        Failure { exit, message: message.into() }
    }

    /// Invalid input, with the message that locates it.
    pub(crate) fn input(message: impl Into<String>) -> Failure {
        Failure::new(Exit::InvalidInput, message)
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// What a library error means for the user.
pub(crate) fn frf_exit(e: &FrfError) -> Exit {
    match e {
        FrfError::Singular { .. }
        | FrfError::NonFiniteZ { .. }
        | FrfError::Factorization(_)
        | FrfError::NoLdltFactors { .. }
        | FrfError::CliqueOutOfRange { .. } => Exit::Numerics,
        FrfError::File(FileError::Unwritable { .. }) => Exit::Output,
        FrfError::UnknownDof { .. }
        | FrfError::FixedDof { .. }
        | FrfError::BadFrequency { .. }
        | FrfError::File(FileError::Io { .. } | FileError::Parse { .. })
        | FrfError::Mismatch(_) => Exit::InvalidInput,
    }
}

impl From<FrfError> for Failure {
    fn from(e: FrfError) -> Self {
        Failure::new(frf_exit(&e), e.to_string())
    }
}

impl From<UpdateError> for Failure {
    fn from(e: UpdateError) -> Self {
        match e {
            UpdateError::Case(c) => Failure::input(c.render()),
            UpdateError::Frf(f) => f.into(),
            UpdateError::Numerics(m) => Failure::new(Exit::Numerics, m),
            UpdateError::Model(_)
            | UpdateError::Data(_)
            | UpdateError::Lines(_)
            | UpdateError::NoParameters
            | UpdateError::Method(_) => Failure::input(e.to_string()),
        }
    }
}

impl From<ModelError> for Failure {
    fn from(e: ModelError) -> Self {
        Failure::input(e.to_string())
    }
}

impl From<CaseError> for Failure {
    fn from(e: CaseError) -> Self {
        Failure::input(e.render())
    }
}

impl From<OutputError> for Failure {
    fn from(e: OutputError) -> Self {
        let exit = if matches!(e, OutputError::Busy { .. }) { Exit::Busy } else { Exit::Output };
        Failure::new(exit, e.to_string())
    }
}

/// A failed print: standard output is full or broken (a closed pipe is
/// handled before, see `print_line` in `lib.rs`).
impl From<std::io::Error> for Failure {
    fn from(e: std::io::Error) -> Self {
        Failure::new(Exit::Output, format!("standard output: cannot write: {e}"))
    }
}

/// A figure that cannot be drawn is rfm's fault, not the data's.
impl From<crate::report::plot::PlotError> for Failure {
    fn from(e: crate::report::plot::PlotError) -> Self {
        Failure::new(Exit::Internal, e.to_string())
    }
}

impl From<serde_json::Error> for Failure {
    fn from(e: serde_json::Error) -> Self {
        Failure::new(Exit::Internal, format!("cannot serialise the results: {e}"))
    }
}

/// The messages commands give for a setup they cannot work with (`the case
/// has no [update] section`) are about the input.
impl From<String> for Failure {
    fn from(message: String) -> Self {
        Failure::input(message)
    }
}

impl From<&str> for Failure {
    fn from(message: &str) -> Self {
        Failure::input(message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_distinct_and_listed_in_order() {
        let codes: Vec<u8> = Exit::TABLE.iter().map(|(e, _)| e.code()).collect();
        assert!(codes.windows(2).all(|w| w[0] < w[1]), "{codes:?}");
        assert_eq!(Exit::Success.code(), 0);
        assert_eq!(Exit::Interrupted.code(), 130);
    }

    #[test]
    fn only_a_converged_update_exits_with_zero() {
        assert_eq!(Exit::of_status(&Status::Converged), Exit::Success);
        assert_eq!(Exit::of_status(&Status::Stalled), Exit::Stalled);
        assert_eq!(Exit::of_status(&Status::MaxIterations), Exit::NotConverged);
        assert_eq!(Exit::of_status(&Status::ModelInadequate), Exit::ModelInadequate);
        assert_eq!(Exit::of_status(&Status::LocalMinimum), Exit::LocalMinimum);
        assert_eq!(Exit::of_status(&Status::Runaway), Exit::Runaway);
        // one code per outcome that is not a success
        let codes: Vec<u8> =
            [Status::Stalled, Status::MaxIterations, Status::ModelInadequate, Status::LocalMinimum, Status::Runaway]
                .iter()
                .map(|s| Exit::of_status(s).code())
                .collect();
        assert_eq!(codes, [8, 5, 9, 10, 12]);
        assert_eq!(Exit::of_status(&Status::Failed("singular".into())), Exit::Numerics);
    }

    fn outcome(status: Status, worse_than_start: bool) -> rfm_update::UpdateOutcome {
        rfm_update::UpdateOutcome {
            method: "rfm".into(),
            iteration_end: status.clone(),
            status,
            parameters: Vec::new(),
            history: Vec::new(),
            residual: 0.01,
            frequencies_hz: Vec::new(),
            natural_frequencies_hz: rfm_update::study::FrequencyTable {
                initial: Vec::new(),
                updated: Vec::new(),
                truth: None,
                paper: None,
                kind: "none".into(),
            },
            uncertainty: None,
            gains: Vec::new(),
            noise_estimate: Some(0.01),
            residual_noise: Some(0.01),
            masked: Vec::new(),
            notes: Vec::new(),
            warnings: Vec::new(),
            noise_ratio: Some(1.0),
            restarts: Vec::new(),
            worse_than_start,
            gain_setting: "none".into(),
            coherence_weighted: false,
            pairing: Vec::new(),
            system: damping::DampedSystem::new(fe_model::samples::two_dof_oscillator()).unwrap(),
        }
    }

    /// A run that made the misfit worse than the start never exits with 0,
    /// even when its residual is at the noise level.
    #[test]
    fn an_update_worse_than_its_start_is_not_a_success() {
        assert_eq!(Exit::of_outcome(&outcome(Status::Converged, false)), Exit::Success);
        assert_eq!(Exit::of_outcome(&outcome(Status::Converged, true)), Exit::WorseThanStart);
        assert_eq!(Exit::WorseThanStart.code(), 11);
        // a run that did not converge keeps its own code
        assert_eq!(Exit::of_outcome(&outcome(Status::Stalled, true)), Exit::Stalled);
    }

    #[test]
    fn a_singular_line_is_failed_numerics_and_a_parse_error_invalid_input() {
        let singular: Failure = FrfError::Singular { freq_hz: 15.9 }.into();
        assert_eq!(singular.exit, Exit::Numerics);
        let parse: Failure =
            FrfError::from(FileError::Parse { path: "m.csv".into(), line: 3, message: "x".into() }).into();
        assert_eq!((parse.exit, parse.message.as_str()), (Exit::InvalidInput, "m.csv:3: x"));
    }
}

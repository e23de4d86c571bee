//! What every updating run reports the same way, whichever solver ran it:
//! one record per iteration and the status it ended with. The response
//! function method ([`crate::response_function`]) and the output-error fit
//! ([`crate::output_error`]) both speak these words, and the study
//! ([`crate::verdict`]) turns a solver's stop into the status outputs print.

/// One iteration's record.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct IterationRecord {
    /// 0 for the initial model.
    pub iteration: usize,
    /// RMS of `|R_FE - R_EX| / |R_EX|` over the chosen lines and channels,
    /// before the step.
    pub residual: f64,
    /// Largest `|u_i|` of the step taken (0 for the initial record).
    pub max_correction: f64,
    /// Number of corrections limited to a factor of 100 in this step.
    pub limited: usize,
    /// Rank of the scaled sensitivity matrix.
    pub rank: usize,
    /// Damping `lambda` of the step taken (0 = the plain RFM step).
    pub lambda: f64,
    /// Parameter values after the step.
    pub values: Vec<f64>,
}

/// How an updating run ended, in the words every output uses (terminal,
/// JSON, report, `updated.toml`).
///
/// The solvers themselves end with [`Status::Converged`] (a stationary
/// point), [`Status::Stalled`], [`Status::MaxIterations`] or
/// [`Status::Failed`]; the study then compares the residual with the data's
/// noise ([`crate::verdict`]) and, for the output-error fit, restarts it to
/// tell a global minimum from a local one; for the RFM, it checks that no
/// parameter ended on a bound or ran away. So `converged` in a result means
/// that the residual is consistent with the noise, never only that the
/// iteration stopped.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Status {
    /// The iteration reached a stationary point and the residual is within
    /// [`crate::verdict::NOISE_FACTOR`] times the noise (or the noise is not
    /// known).
    Converged,
    /// Restarts from spread starts end at the same minimum, but its residual
    /// stays above the noise: the parameters cannot represent the data
    /// (something is missing from the model). A step of `rfm fix` whose
    /// update reached a stationary point above the noise shows it too
    /// ([`crate::fix::step_status`]): the loop looks for what is missing next.
    ModelInadequate,
    /// The iteration stopped at a point above the noise, and restarts from
    /// spread starts disagree about the minimum: the fit is not known to be
    /// global.
    LocalMinimum,
    /// No step lowers the misfit further while the residual stays above the
    /// noise (for the RFM: its iteration stopped there, with no restart to
    /// confirm a minimum); the best iterate is returned.
    Stalled,
    /// The iteration limit was reached; the best iterate is returned.
    MaxIterations,
    /// The misfit is within the noise, but a parameter ended on its bound or
    /// ran away (moved by more than [`crate::verdict::RUNAWAY_FACTOR`] where
    /// the data do not hold it): its value is no estimate. Only the RFM
    /// ends so (see [`crate::verdict::with_parameters`]).
    Runaway,
    /// The model could not be evaluated any more; the best iterate is returned.
    Failed(String),
}

impl Status {
    /// The name outputs and case checks use (`converged`, `model_inadequate`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::ModelInadequate => "model_inadequate",
            Status::LocalMinimum => "local_minimum",
            Status::Stalled => "stalled",
            Status::MaxIterations => "max_iterations",
            Status::Runaway => "runaway",
            Status::Failed(_) => "failed",
        }
    }

    /// The name with what it means, as the report shows it.
    pub fn describe(&self) -> String {
        format!("{}: {}", self.name(), self.meaning())
    }

    /// What the status means, in a sentence.
    pub fn meaning(&self) -> String {
        match self {
            Status::Converged => "the residual is consistent with the noise".to_string(),
            Status::ModelInadequate => "the fit reached a minimum (restarts from spread starts confirm it where they \
                                        were made), but the residual stays above the noise: something the \
                                        parameters cannot represent remains (try rfm diagnose on the updated case)"
                .to_string(),
            Status::LocalMinimum => "the residual stays above the noise and restarts from spread starts disagree \
                                     about the minimum (the best fit is reported)"
                .to_string(),
            Status::Stalled => {
                "no step lowers the misfit, which stays above the noise (the best iterate is reported)".to_string()
            }
            Status::MaxIterations => "the iteration limit was reached (the best iterate is reported)".to_string(),
            Status::Runaway => "a parameter ended on its bound or ran away (moved by more than a factor of 100 \
                                where the data do not hold it): its value is no estimate, whatever the misfit"
                .to_string(),
            Status::Failed(why) => format!("{why} (the best iterate is reported)"),
        }
    }
}

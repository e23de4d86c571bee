//! What the output-error iteration fits: model receptances and their
//! sensitivities as a function of the parameters, of the whole model here.

use damping::DampedSystem;
use faer::Mat;
use frf::ZSolver;
use num_complex::Complex64 as C64;

use crate::error::UpdateError;
use crate::params::ParameterSet;
use crate::sensitivity::{self, ChannelPlan, Hybrid};

/// Model receptances at the fitted lines and channels and their
/// sensitivities, as a function of the parameters: what the iteration fits.
/// The full model ([`FullModel`]) is the normal source; the diagnosis screens
/// candidates that change `Z` only locally with an exact low-rank update of
/// the nominal model instead (`crate::diagnose::local`).
pub(crate) trait Response {
    /// Sets the physical parameter values.
    fn set(&mut self, values: &[f64]) -> Result<(), UpdateError>;

    /// Model receptances `[line][channel]` at the current values and, with
    /// `jacobian`, per line the channels x parameters block `-(dH/dp) p`;
    /// `None` when the model cannot be evaluated.
    fn evaluate(&mut self, lines: &[f64], jacobian: bool) -> Option<Evaluated>;

    /// True when the sensitivities cost little beside the receptances: each
    /// trial step is then evaluated with them, and an accepted step needs
    /// no second evaluation.
    fn cheap_jacobian(&self) -> bool {
        false
    }
}

/// Model receptances `[line][channel]` and optional sensitivity blocks.
pub(crate) type Evaluated = (Vec<Vec<C64>>, Option<Vec<Mat<C64>>>);

/// [`Response`] of a whole damped system: one sparse factorisation per line
/// and the shared sensitivity assembly.
pub(super) struct FullModel<'a> {
    pub(super) sys: &'a mut DampedSystem,
    pub(super) params: &'a ParameterSet,
    pub(super) solver: ZSolver,
    pub(super) plan: ChannelPlan,
}

impl Response for FullModel<'_> {
    fn set(&mut self, values: &[f64]) -> Result<(), UpdateError> {
        self.params.set_values(self.sys, values)
    }

    /// The sensitivity assembly factorises each line once for both, and
    /// its receptances are bit for bit those of the synthesis (the same
    /// factorisation and substitutions), so evaluating a trial step with
    /// its sensitivities changes no iterate: it adds the sensitivities'
    /// solves to a step the fit rejects, and spares a step it accepts a
    /// second factorisation of every line (a quarter of the update's time
    /// in `rfm fix` on a 300-DOF beam).
    fn cheap_jacobian(&self) -> bool {
        true
    }

    fn evaluate(&mut self, lines: &[f64], jacobian: bool) -> Option<Evaluated> {
        if jacobian {
            let blocks = sensitivity::assemble(
                self.sys,
                &self.solver,
                &self.plan,
                self.params.quantities(),
                lines,
                Hybrid::Model,
            )
            .ok()?;
            let sens = blocks.iter().map(|b| self.params.combine(b)).collect();
            Some((blocks.into_iter().map(|b| b.model).collect(), Some(sens)))
        } else {
            let set = frf::synthesize_with(self.sys, &self.solver, &self.plan.channels, lines).ok()?;
            let nc = self.plan.channels.len();
            Some(((0..lines.len()).map(|k| (0..nc).map(|c| set.get(c, k)).collect()).collect(), None))
        }
    }
}

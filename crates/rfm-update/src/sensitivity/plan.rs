//! The channels of a fit resolved to equations, once per set of channels.

use damping::DampedSystem;
use frf::{Channel, equation_of};

use crate::error::UpdateError;

/// Channel layout resolved to equations, reusable across iterations.
#[derive(Clone, Debug)]
pub struct ChannelPlan {
    /// Channels in data order.
    pub channels: Vec<Channel>,
    /// Distinct excitation equations.
    pub(super) ref_eqs: Vec<usize>,
    /// Distinct response equations (solved as unit columns).
    pub(super) resp_eqs: Vec<usize>,
    /// Per channel: (index into ref_eqs, index into resp_eqs).
    pub(super) picks: Vec<(usize, usize)>,
}

impl ChannelPlan {
    /// Resolves channels to equations of a system.
    pub fn new(sys: &DampedSystem, channels: &[Channel]) -> Result<Self, UpdateError> {
        let mut ref_eqs = Vec::new();
        let mut resp_eqs = Vec::new();
        let mut picks = Vec::new();
        for c in channels {
            let r = equation_of(sys, c.reference)?;
            let m = equation_of(sys, c.response)?;
            let ri = ref_eqs.iter().position(|&e| e == r).unwrap_or_else(|| {
                ref_eqs.push(r);
                ref_eqs.len() - 1
            });
            let mi = resp_eqs.iter().position(|&e| e == m).unwrap_or_else(|| {
                resp_eqs.push(m);
                resp_eqs.len() - 1
            });
            picks.push((ri, mi));
        }
        Ok(ChannelPlan { channels: channels.to_vec(), ref_eqs, resp_eqs, picks })
    }

    /// Number of linear solves per frequency.
    pub fn solves_per_frequency(&self) -> usize {
        self.ref_eqs.len() + self.resp_eqs.len()
    }
}

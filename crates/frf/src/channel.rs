//! A channel: one FRF, response over reference. Its own file so that the
//! errors that name a channel need not import the FRF set.

use std::fmt;

use fe_model::DofRef;

/// One FRF: response DOF over reference (excitation) DOF.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Channel {
    /// Response DOF (row of the FRF matrix).
    pub response: DofRef,
    /// Reference DOF (column).
    pub reference: DofRef,
}

impl Channel {
    /// Shorthand constructor.
    pub fn new(response: DofRef, reference: DofRef) -> Self {
        Channel { response, reference }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "H({},{})", self.response, self.reference)
    }
}

//! Set-up errors of the test corrected after reading
//! (`[[measurement.corrections]]`): a sensor mounted upside down, one whose
//! sensitivity was entered wrong, one that sat at another DOF than the
//! channel says.
//!
//! A correction names a channel by its response as the data name it (after
//! the map), and optionally its reference (otherwise every reference's
//! channel at that response). Its values are multiplied by `sign` and
//! `scale`, and with `measured_at` the channel is moved to the DOF the
//! sensor really measured. The case keeps listing the response the test
//! named; the correction says where it really was.

use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use crate::dof::DofRef;
use crate::error::CaseError;
use crate::model::Model;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::case) struct RawCorrection {
    response: Spanned<String>,
    reference: Option<Spanned<String>>,
    sign: Option<Spanned<f64>>,
    scale: Option<Spanned<f64>>,
    measured_at: Option<Spanned<String>>,
    why: Option<String>,
}

/// A set-up error of one response channel, corrected after reading.
#[derive(Clone, Debug)]
pub struct ChannelCorrection {
    /// The response as the data name it (after the map).
    pub response: DofRef,
    /// The reference whose channel it is; `None`: every reference's.
    pub reference: Option<DofRef>,
    /// 1, or -1 for an inverted sensor.
    pub sign: f64,
    /// Multiplies the values (a sensitivity entered wrong); positive.
    pub scale: f64,
    /// The DOF the sensor really measured, when not the one the data name.
    pub measured_at: Option<DofRef>,
    /// Why (written by rfm with the evidence; free text).
    pub why: Option<String>,
    /// Where the entry is written, for messages about it.
    pub place: CaseError,
}

impl ChannelCorrection {
    /// Whether it applies to the channel of `response` over `reference`.
    pub fn applies_to(&self, response: DofRef, reference: DofRef) -> bool {
        self.response == response && self.reference.is_none_or(|r| r == reference)
    }

    /// The response the channel really measured.
    pub fn corrected_response(&self) -> DofRef {
        self.measured_at.unwrap_or(self.response)
    }
}

/// The corrections of a `[measurement]`, checked against the model and the
/// measured responses and references.
pub(super) fn parse_corrections(
    err: &dyn Fn(Range<usize>, String) -> CaseError,
    raw: &[Spanned<RawCorrection>],
    model: &Model,
    responses: &[DofRef],
    references: &[DofRef],
) -> Result<Vec<ChannelCorrection>, CaseError> {
    let dof = |s: &Spanned<String>| -> Result<DofRef, CaseError> {
        let d: DofRef = s.get_ref().parse().map_err(|e: String| err(s.span(), e))?;
        model.dimension().check(d.dof).map_err(|e| err(s.span(), e))?;
        if model.node(d.node).is_none() {
            return Err(err(s.span(), format!("node {} does not exist in the model", d.node)));
        }
        Ok(d)
    };
    let mut out: Vec<ChannelCorrection> = Vec::new();
    for entry in raw {
        let c = entry.get_ref();
        let response = dof(&c.response)?;
        if !responses.contains(&response) {
            return Err(err(c.response.span(), format!("`{response}` is not one of the measurement's responses")));
        }
        let reference = c.reference.as_ref().map(&dof).transpose()?;
        if let (Some(r), Some(s)) = (reference, &c.reference)
            && !references.contains(&r)
        {
            return Err(err(s.span(), format!("`{r}` is not one of the measurement's references")));
        }
        let sign = match &c.sign {
            None => 1.0,
            Some(s) if *s.get_ref() == 1.0 || *s.get_ref() == -1.0 => *s.get_ref(),
            Some(s) => return Err(err(s.span(), "sign must be 1 or -1".into())),
        };
        let scale = match &c.scale {
            None => 1.0,
            Some(s) if *s.get_ref() > 0.0 && s.get_ref().is_finite() => *s.get_ref(),
            Some(s) => return Err(err(s.span(), format!("scale must be positive and finite, got {}", s.get_ref()))),
        };
        let measured_at = c.measured_at.as_ref().map(&dof).transpose()?;
        if c.sign.is_none() && c.scale.is_none() && measured_at.is_none() {
            return Err(err(entry.span(), "a correction needs `sign`, `scale` or `measured_at`".into()));
        }
        // two corrections of one channel would depend on their order
        if out.iter().any(|p| {
            p.response == response && (p.reference.is_none() || reference.is_none() || p.reference == reference)
        }) {
            return Err(err(c.response.span(), format!("the channel at `{response}` is corrected twice")));
        }
        out.push(ChannelCorrection {
            response,
            reference,
            sign,
            scale,
            measured_at,
            why: c.why.clone(),
            place: err(entry.span(), String::new()),
        });
    }
    Ok(out)
}

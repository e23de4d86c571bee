//! The serde mirror of a case file: what the TOML says, with the place of
//! every value a later check may refuse (`Spanned`). Nothing here checks
//! meaning; `build.rs` and the other readers do, with the places kept here.

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;

use super::measurement::RawMeasurement;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCase {
    pub(super) title: Option<String>,
    pub(super) description: Option<String>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<RawMaterial>>,
    #[serde(default)]
    pub(super) sections: BTreeMap<String, Spanned<RawSection>>,
    #[serde(default)]
    pub(super) groups: BTreeMap<String, Spanned<RawGroup>>,
    #[serde(default)]
    pub(super) nodes: Vec<Spanned<(u32, f64, f64)>>,
    #[serde(default)]
    pub(super) lines: Vec<Spanned<RawLine>>,
    #[serde(default)]
    pub(super) beams: Vec<Spanned<RawBeam>>,
    #[serde(default)]
    pub(super) springs: Vec<Spanned<RawSpring>>,
    #[serde(default)]
    pub(super) masses: Vec<Spanned<RawMass>>,
    #[serde(default)]
    pub(super) supports: Vec<Spanned<RawSupport>>,
    #[serde(default)]
    pub(super) ties: Vec<Spanned<RawTie>>,
    #[serde(default)]
    pub(super) joints: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    pub(super) assign: Vec<Spanned<RawAssign>>,
    #[serde(default)]
    pub(super) set: BTreeMap<String, Spanned<f64>>,
    pub(super) measurement: Option<Spanned<RawMeasurement>>,
    pub(super) truth: Option<Spanned<RawTruth>>,
    pub(super) update: Option<Spanned<RawUpdate>>,
    pub(super) paper: Option<Spanned<RawPaper>>,
    #[serde(default)]
    pub(super) history: Vec<Spanned<RawHistory>>,
    pub(super) check: Option<Spanned<RawCheck>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    #[serde(rename = "E")]
    pub(super) e: f64,
    pub(super) rho: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSection {
    #[serde(rename = "A")]
    pub(super) area: Option<f64>,
    #[serde(rename = "I")]
    pub(super) inertia: Option<f64>,
    pub(super) b: Option<f64>,
    pub(super) h: Option<f64>,
    pub(super) od: Option<f64>,
    pub(super) id: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGroup {
    #[serde(default)]
    pub(super) alpha: f64,
    #[serde(default)]
    pub(super) beta: f64,
    pub(super) mu: Option<f64>,
    #[serde(default = "one")]
    pub(super) stiffness: f64,
    #[serde(default = "one")]
    pub(super) mass: f64,
}

pub(super) fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLine {
    pub(super) from: Spanned<toml::Value>,
    pub(super) to: Spanned<toml::Value>,
    pub(super) elements: Spanned<u32>,
    pub(super) material: Spanned<String>,
    pub(super) section: Spanned<String>,
    pub(super) group: Spanned<String>,
    pub(super) first_node: Option<u32>,
    pub(super) first_element: Option<u32>,
    #[serde(default)]
    pub(super) added_mass: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBeam {
    pub(super) id: u32,
    pub(super) nodes: [u32; 2],
    pub(super) material: Spanned<String>,
    pub(super) section: Spanned<String>,
    pub(super) group: Spanned<String>,
    #[serde(default)]
    pub(super) added_mass: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSpring {
    pub(super) name: String,
    pub(super) nodes: Option<[u32; 2]>,
    pub(super) node: Option<u32>,
    #[serde(default)]
    pub(super) kx: f64,
    #[serde(default)]
    pub(super) ky: f64,
    #[serde(default)]
    pub(super) kr: f64,
    pub(super) group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMass {
    pub(super) name: String,
    pub(super) node: u32,
    #[serde(default)]
    pub(super) m: f64,
    #[serde(default)]
    pub(super) j: f64,
    pub(super) group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSupport {
    pub(super) node: u32,
    pub(super) dofs: Option<Vec<Spanned<String>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTie {
    pub(super) nodes: [u32; 2],
    pub(super) dofs: Vec<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawAssign {
    pub(super) elements: Spanned<String>,
    pub(super) group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawJoint {
    pub(super) name: String,
    pub(super) node: u32,
    pub(super) elements: Vec<u32>,
    pub(super) new_node: Option<u32>,
    pub(super) kx: Option<f64>,
    pub(super) ky: Option<f64>,
    pub(super) kr: f64,
    pub(super) group: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTruth {
    #[serde(default)]
    pub(super) noise: f64,
    #[serde(default)]
    pub(super) floor: f64,
    #[serde(default)]
    pub(super) seed: u64,
    #[serde(default)]
    pub(super) set: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    pub(super) springs: Vec<Spanned<RawSpring>>,
    #[serde(default)]
    pub(super) masses: Vec<Spanned<RawMass>>,
    #[serde(default)]
    pub(super) joints: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    pub(super) groups: BTreeMap<String, Spanned<RawGroup>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawUpdate {
    pub(super) parameters: Vec<Spanned<String>>,
    pub(super) frequencies: Option<Spanned<toml::Value>>,
    pub(super) method: Option<Spanned<String>>,
    pub(super) max_iterations: Option<u32>,
    pub(super) tolerance: Option<f64>,
    #[serde(default)]
    pub(super) bounds: BTreeMap<String, Spanned<[f64; 2]>>,
    pub(super) regularization: Option<Spanned<f64>>,
    #[serde(default)]
    pub(super) gains: bool,
    pub(super) misfit: Option<Spanned<String>>,
    pub(super) coherence: Option<bool>,
    #[serde(default)]
    pub(super) weights: Vec<Spanned<RawBandWeight>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBandWeight {
    pub(super) from: f64,
    pub(super) to: f64,
    pub(super) weight: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHistory {
    pub(super) step: String,
    pub(super) misfit: f64,
    pub(super) noise: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPaper {
    pub(super) source: String,
    #[serde(default)]
    pub(super) values: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    pub(super) frequencies_hz: Vec<f64>,
    pub(super) note: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCheck {
    pub(super) rfm: Option<Spanned<RawRunCheck>>,
    #[serde(rename = "output-error")]
    pub(super) output_error: Option<Spanned<RawRunCheck>>,
    pub(super) diagnosis: Option<Spanned<RawDiagnosisCheck>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRunCheck {
    pub(super) status: Vec<Spanned<String>>,
    pub(super) max_error: Option<Spanned<f64>>,
    pub(super) within_sd: Option<Spanned<f64>>,
    #[serde(default)]
    pub(super) weak: Vec<Spanned<String>>,
    pub(super) noise: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDiagnosisCheck {
    pub(super) leader: Spanned<String>,
    pub(super) misfit_fall: Option<Spanned<f64>>,
}

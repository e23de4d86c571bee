//! The serde mirror of a case file: what the TOML says, with the place of
//! every value a later check may refuse (`Spanned`). Nothing here checks
//! meaning; `build.rs` and the other readers do, with the places kept here.

use std::collections::BTreeMap;
use std::fmt;

use serde::Deserialize;
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use toml::Spanned;

use super::measurement::RawMeasurement;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCase {
    pub(super) title: Option<String>,
    pub(super) description: Option<String>,
    pub(super) model: Option<Spanned<RawModel>>,
    pub(super) imported: Option<Spanned<RawImported>>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<RawMaterial>>,
    #[serde(default)]
    pub(super) sections: BTreeMap<String, Spanned<RawSection>>,
    #[serde(default)]
    pub(super) groups: BTreeMap<String, Spanned<RawGroup>>,
    #[serde(default)]
    pub(super) nodes: Vec<Spanned<RawNode>>,
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
    pub(super) resonators: Vec<Spanned<RawResonator>>,
    #[serde(default)]
    pub(super) shakers: Vec<Spanned<RawShaker>>,
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

/// `[imported]` (read in `imported.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawImported {
    pub(super) nodes: Option<Spanned<String>>,
    #[serde(default)]
    pub(super) groups: Vec<Spanned<RawImportedGroup>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawImportedGroup {
    pub(super) group: Spanned<String>,
    pub(super) dofs: Spanned<String>,
    pub(super) stiffness: Option<Spanned<String>>,
    pub(super) mass: Option<Spanned<String>>,
    pub(super) damping: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModel {
    pub(super) dimension: Option<Spanned<i64>>,
}

/// A node as written: `[id, x, y]`, or `[id, x, y, z]` in a 3D model.
pub(super) struct RawNode {
    pub(super) id: u32,
    pub(super) at: [f64; 3],
    /// True when the node was written with its z.
    pub(super) with_z: bool,
}

impl<'de> Deserialize<'de> for RawNode {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Node;
        impl<'de> Visitor<'de> for Node {
            type Value = RawNode;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a node [id, x, y] or, in a 3D model, [id, x, y, z]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawNode, A::Error> {
                let id: u32 = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let x: f64 = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(1, &self))?;
                let y: f64 = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(2, &self))?;
                let z: Option<f64> = seq.next_element()?;
                if seq.next_element::<IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(5, &self));
                }
                Ok(RawNode { id, at: [x, y, z.unwrap_or(0.0)], with_z: z.is_some() })
            }
        }
        d.deserialize_seq(Node)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    #[serde(rename = "E")]
    pub(super) e: f64,
    pub(super) rho: f64,
    pub(super) nu: Option<Spanned<f64>>,
    #[serde(rename = "G")]
    pub(super) g: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSection {
    #[serde(rename = "A")]
    pub(super) area: Option<f64>,
    #[serde(rename = "I")]
    pub(super) inertia: Option<f64>,
    #[serde(rename = "Iy")]
    pub(super) iy: Option<f64>,
    #[serde(rename = "Iz")]
    pub(super) iz: Option<f64>,
    #[serde(rename = "J")]
    pub(super) torsion: Option<f64>,
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
    /// Factor on the group's imported damping matrices.
    #[serde(default = "one")]
    pub(super) damping: f64,
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
    pub(super) orientation: Option<Spanned<[f64; 3]>>,
    pub(super) angle: Option<Spanned<f64>>,
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
    pub(super) orientation: Option<Spanned<[f64; 3]>>,
    pub(super) angle: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSpring {
    pub(super) name: String,
    pub(super) nodes: Option<[u32; 2]>,
    pub(super) node: Option<u32>,
    pub(super) kx: Option<Spanned<f64>>,
    pub(super) ky: Option<Spanned<f64>>,
    pub(super) kz: Option<Spanned<f64>>,
    pub(super) kr: Option<Spanned<f64>>,
    pub(super) krx: Option<Spanned<f64>>,
    pub(super) kry: Option<Spanned<f64>>,
    pub(super) krz: Option<Spanned<f64>>,
    pub(super) group: Spanned<String>,
    /// In space: the spring's local x axis ...
    pub(super) x_axis: Option<Spanned<[f64; 3]>>,
    /// ... and a vector in its local x-y plane.
    pub(super) xy_vector: Option<Spanned<[f64; 3]>>,
}

impl RawSpring {
    /// The stiffnesses as written, by key.
    pub(super) fn stiffnesses(&self) -> [(&'static str, Option<&Spanned<f64>>); 7] {
        [
            ("kx", self.kx.as_ref()),
            ("ky", self.ky.as_ref()),
            ("kz", self.kz.as_ref()),
            ("kr", self.kr.as_ref()),
            ("krx", self.krx.as_ref()),
            ("kry", self.kry.as_ref()),
            ("krz", self.krz.as_ref()),
        ]
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMass {
    pub(super) name: String,
    pub(super) node: u32,
    #[serde(default)]
    pub(super) m: f64,
    pub(super) j: Option<Spanned<f64>>,
    pub(super) jx: Option<Spanned<f64>>,
    pub(super) jy: Option<Spanned<f64>>,
    pub(super) jz: Option<Spanned<f64>>,
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
    pub(super) kx: Option<Spanned<f64>>,
    pub(super) ky: Option<Spanned<f64>>,
    pub(super) kz: Option<Spanned<f64>>,
    pub(super) kr: Option<Spanned<f64>>,
    pub(super) krx: Option<Spanned<f64>>,
    pub(super) kry: Option<Spanned<f64>>,
    pub(super) krz: Option<Spanned<f64>>,
    pub(super) group: Spanned<String>,
}

impl RawJoint {
    /// The stiffnesses as written, by key.
    pub(super) fn stiffnesses(&self) -> [(&'static str, Option<&Spanned<f64>>); 7] {
        [
            ("kx", self.kx.as_ref()),
            ("ky", self.ky.as_ref()),
            ("kz", self.kz.as_ref()),
            ("kr", self.kr.as_ref()),
            ("krx", self.krx.as_ref()),
            ("kry", self.kry.as_ref()),
            ("krz", self.krz.as_ref()),
        ]
    }
}

/// `[[resonators]]`: a mass on a spring attached at a node (read in `build.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawResonator {
    pub(super) name: String,
    pub(super) node: u32,
    pub(super) new_node: Option<u32>,
    pub(super) m: f64,
    pub(super) kx: Option<Spanned<f64>>,
    pub(super) ky: Option<Spanned<f64>>,
    pub(super) kz: Option<Spanned<f64>>,
    /// Rotational stiffnesses, read only to be refused where written.
    pub(super) kr: Option<Spanned<f64>>,
    pub(super) krx: Option<Spanned<f64>>,
    pub(super) kry: Option<Spanned<f64>>,
    pub(super) krz: Option<Spanned<f64>>,
    pub(super) group: Spanned<String>,
}

impl RawResonator {
    /// The stiffnesses as written, by key.
    pub(super) fn stiffnesses(&self) -> [(&'static str, Option<&Spanned<f64>>); 7] {
        [
            ("kx", self.kx.as_ref()),
            ("ky", self.ky.as_ref()),
            ("kz", self.kz.as_ref()),
            ("kr", self.kr.as_ref()),
            ("krx", self.krx.as_ref()),
            ("kry", self.kry.as_ref()),
            ("krz", self.krz.as_ref()),
        ]
    }
}

/// `[[shakers]]`: a shaker's armature and suspension at its drive point
/// (read in `build.rs`); the keys of a resonator, with one direction.
pub(super) type RawShaker = RawResonator;

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
    pub(super) resonators: Vec<Spanned<RawResonator>>,
    #[serde(default)]
    pub(super) shakers: Vec<Spanned<RawShaker>>,
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
    pub(super) effect: Option<String>,
    #[serde(default)]
    pub(super) nodes: Vec<u32>,
    #[serde(default)]
    pub(super) elements: Vec<u32>,
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
    #[serde(default)]
    pub(super) status: Vec<Spanned<String>>,
    pub(super) truth: Option<Spanned<String>>,
    pub(super) compare: Option<Spanned<BTreeMap<String, Spanned<String>>>>,
    pub(super) within_sd: Option<Spanned<f64>>,
    pub(super) noise: Option<Spanned<f64>>,
}

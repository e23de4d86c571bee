//! Scalar quantities of a model that can be read, set and updated by name.
//!
//! Names are dotted paths, the same in case files, outputs and the API:
//!
//! | name | meaning |
//! |---|---|
//! | `group.<g>.alpha` / `.beta` / `.mu` | damping of group g (`mu` in rad/s) |
//! | `group.<g>.stiffness` / `.mass` | factors on `K_g` and `M_g` (nominal 1) |
//! | `group.<g>.damping` | factor on the group's imported viscous damping matrix `C_g` (nominal 1) |
//! | `material.<m>.E` / `.rho` | Young's modulus, density |
//! | `element.<id>.stiffness` / `.mass` | factors on one element (nominal 1) |
//! | `element.<id>.bending` | factor on one element's bending stiffness alone (nominal 1) |
//! | `element.<id>.added_mass` | non-structural transverse mass per length (kg/m) |
//! | `spring.<name>.kx` / `.ky` / `.kr` | spring stiffnesses (planar) |
//! | `spring.<name>.kx` / `.ky` / `.kz` / `.krx` / `.kry` / `.krz` | spring stiffnesses (3D) |
//! | `mass.<name>.m` / `.j` | lumped mass and rotary inertia (planar) |
//! | `mass.<name>.m` / `.jx` / `.jy` / `.jz` | lumped mass and rotary inertias (3D) |
//!
//! An updating [`Parameter`] is one quantity, or several scaled together:
//! `element.<first>..<last>.<field>` links the field of every element with an
//! id in the inclusive range (a region's stiffness or mass factor), and in a
//! 3D model `mass.<name>.j` links `jx`, `jy` and `jz` (a rotary inertia the
//! same about every axis).

use std::fmt;

use crate::dof::{Dimension, Dof};
use crate::error::ModelError;
use crate::model::{ElementId, Model};

/// A scalar model quantity (indices refer to the model's lists).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Quantity {
    /// Stiffness-proportional damping coefficient of a group.
    GroupAlpha(usize),
    /// Mass-proportional damping coefficient of a group.
    GroupBeta(usize),
    /// Relaxation parameter of a group's kernel.
    GroupMu(usize),
    /// Stiffness factor of a group.
    GroupStiffness(usize),
    /// Mass factor of a group.
    GroupMass(usize),
    /// Young's modulus of a material.
    MaterialE(usize),
    /// Density of a material.
    MaterialRho(usize),
    /// Stiffness factor of one beam.
    ElementStiffness(usize),
    /// Factor on the bending stiffness of one beam (its axial and
    /// torsional stiffness unchanged).
    ElementBending(usize),
    /// Mass factor of one beam.
    ElementMass(usize),
    /// Added transverse mass per length of one beam.
    ElementAddedMass(usize),
    /// One stiffness of a spring.
    SpringK(usize, Dof),
    /// Mass of a lumped mass.
    MassM(usize),
    /// Rotary inertia of a lumped mass about the axis of a rotation DOF.
    MassJ(usize, Dof),
    /// Factor on a group's imported viscous damping matrices (last, so
    /// that the order of the others is as it was).
    GroupDamping(usize),
}

/// How a quantity enters the dynamic stiffness.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuantityKind {
    /// Multiplies some stiffness, mass or damping terms (E, rho, k, m, factors).
    Factor,
    /// A damping coefficient or relaxation parameter of a group.
    Damping,
}

impl Quantity {
    /// Whether this quantity scales matrix terms or is a damping parameter.
    pub fn kind(self) -> QuantityKind {
        match self {
            Quantity::GroupAlpha(_) | Quantity::GroupBeta(_) | Quantity::GroupMu(_) => QuantityKind::Damping,
            _ => QuantityKind::Factor,
        }
    }
}

/// A quantity with the model it belongs to, for display.
pub struct QuantityName<'a> {
    model: &'a Model,
    q: Quantity,
}

impl fmt::Display for QuantityName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.model;
        match self.q {
            Quantity::GroupAlpha(g) => write!(f, "group.{}.alpha", m.groups[g].name),
            Quantity::GroupBeta(g) => write!(f, "group.{}.beta", m.groups[g].name),
            Quantity::GroupMu(g) => write!(f, "group.{}.mu", m.groups[g].name),
            Quantity::GroupStiffness(g) => write!(f, "group.{}.stiffness", m.groups[g].name),
            Quantity::GroupMass(g) => write!(f, "group.{}.mass", m.groups[g].name),
            Quantity::GroupDamping(g) => write!(f, "group.{}.damping", m.groups[g].name),
            Quantity::MaterialE(i) => write!(f, "material.{}.E", m.materials[i].name),
            Quantity::MaterialRho(i) => write!(f, "material.{}.rho", m.materials[i].name),
            Quantity::ElementStiffness(i) => write!(f, "element.{}.stiffness", m.beams[i].id),
            Quantity::ElementBending(i) => write!(f, "element.{}.bending", m.beams[i].id),
            Quantity::ElementMass(i) => write!(f, "element.{}.mass", m.beams[i].id),
            Quantity::ElementAddedMass(i) => write!(f, "element.{}.added_mass", m.beams[i].id),
            Quantity::SpringK(i, d) => write!(f, "spring.{}.{}", m.springs[i].name, m.dimension.spring_key(d)),
            Quantity::MassM(i) => write!(f, "mass.{}.m", m.masses[i].name),
            Quantity::MassJ(i, d) => write!(f, "mass.{}.{}", m.masses[i].name, m.dimension.inertia_key(d)),
        }
    }
}

/// An updating parameter: one or several quantities scaled by a common factor.
///
/// Its value is the value of its first quantity; changing it by a factor
/// changes every quantity by that factor.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name as written (`group.steel.mu`, `element.5..8.stiffness`).
    pub name: String,
    /// The quantities it scales (at least one).
    pub quantities: Vec<Quantity>,
}

impl Parameter {
    /// A parameter of a single quantity, named after it.
    pub fn single(model: &Model, q: Quantity) -> Self {
        Parameter { name: model.quantity_name(q).to_string(), quantities: vec![q] }
    }
}

const FORMS: &str = "group.<name>.{alpha,beta,mu,stiffness,mass,damping}, material.<name>.{E,rho}, \
                     element.<id>.{stiffness,bending,mass,added_mass}, spring.<name>.{kx,ky,kr}, mass.<name>.{m,j}";

const FORMS_3D: &str = "group.<name>.{alpha,beta,mu,stiffness,mass,damping}, material.<name>.{E,rho}, \
                        element.<id>.{stiffness,bending,mass,added_mass}, spring.<name>.{kx,ky,kz,krx,kry,krz}, \
                        mass.<name>.{m,jx,jy,jz}";

impl Model {
    /// Resolves a dotted name such as `group.steel.mu` to a quantity.
    pub fn quantity(&self, name: &str) -> Result<Quantity, ModelError> {
        let err = |reason: String| ModelError::UnknownQuantity { name: name.into(), reason };
        let dim = self.dimension;
        let forms = if dim == Dimension::Planar { FORMS } else { FORMS_3D };
        let (head, rest) = name.split_once('.').ok_or_else(|| err(format!("expected one of {forms}")))?;
        let (item, field) = rest.rsplit_once('.').ok_or_else(|| err(format!("expected one of {forms}")))?;
        let bad_field = |valid: &str| err(format!("`{field}` is not a field of a {head}; valid: {valid}"));
        match head {
            "group" => {
                let g = self.group_index(item).ok_or_else(|| {
                    err(format!("no group `{item}` (groups: {})", names(self.groups.iter().map(|g| &g.name))))
                })?;
                Ok(match field {
                    "alpha" => Quantity::GroupAlpha(g),
                    "beta" => Quantity::GroupBeta(g),
                    "mu" => Quantity::GroupMu(g),
                    "stiffness" => Quantity::GroupStiffness(g),
                    "mass" => Quantity::GroupMass(g),
                    "damping" => Quantity::GroupDamping(g),
                    _ => return Err(bad_field("alpha, beta, mu, stiffness, mass, damping")),
                })
            }
            "material" => {
                let i = self.material_index(item).ok_or_else(|| {
                    err(format!("no material `{item}` (materials: {})", names(self.materials.iter().map(|m| &m.name))))
                })?;
                Ok(match field {
                    "E" | "e" => Quantity::MaterialE(i),
                    "rho" => Quantity::MaterialRho(i),
                    _ => return Err(bad_field("E, rho")),
                })
            }
            "element" => {
                let id: u32 = item.parse().map_err(|_| err(format!("`{item}` is not an element id")))?;
                let i = self.beam_index(ElementId(id)).ok_or_else(|| err(format!("no element {id}")))?;
                Ok(match field {
                    "stiffness" => Quantity::ElementStiffness(i),
                    "bending" => Quantity::ElementBending(i),
                    "mass" => Quantity::ElementMass(i),
                    "added_mass" => Quantity::ElementAddedMass(i),
                    _ => return Err(bad_field("stiffness, bending, mass, added_mass")),
                })
            }
            "spring" => {
                let i = self.spring_index(item).ok_or_else(|| {
                    err(format!("no spring `{item}` (springs: {})", names(self.springs.iter().map(|s| &s.name))))
                })?;
                let keys: Vec<&str> = dim.dofs().iter().map(|&d| dim.spring_key(d)).collect();
                let d = dim.spring_dof(field).ok_or_else(|| bad_field(&keys.join(", ")))?;
                Ok(Quantity::SpringK(i, d))
            }
            "mass" => {
                let i = self.mass_index(item).ok_or_else(|| {
                    err(format!("no mass `{item}` (masses: {})", names(self.masses.iter().map(|m| &m.name))))
                })?;
                if field == "m" {
                    return Ok(Quantity::MassM(i));
                }
                match dim.inertia_dof(field) {
                    Some(d) => Ok(Quantity::MassJ(i, d)),
                    None if dim == Dimension::Planar => Err(bad_field("m, j")),
                    None => Err(bad_field("m, jx, jy, jz")),
                }
            }
            _ => Err(err(format!("`{head}` is not a kind of item; expected one of {forms}"))),
        }
    }

    /// Resolves an updating parameter name: a quantity name, or
    /// `element.<first>..<last>.<field>` for a range of elements.
    pub fn parameter(&self, name: &str) -> Result<Parameter, ModelError> {
        let err = |reason: String| ModelError::UnknownQuantity { name: name.into(), reason };
        if let Some(rest) = name.strip_prefix("element.")
            && let Some((range, field)) = rest.rsplit_once('.')
            && let Some((a, b)) = range.split_once("..")
        {
            let a: u32 = a.parse().map_err(|_| err(format!("`{a}` is not an element id")))?;
            let b: u32 = b.parse().map_err(|_| err(format!("`{b}` is not an element id")))?;
            if b < a {
                return Err(err(format!("the range {a}..{b} is empty")));
            }
            let quantities = (a..=b)
                .map(|id| self.quantity(&format!("element.{id}.{field}")))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| err(e.to_string()))?;
            return Ok(Parameter { name: name.into(), quantities });
        }
        // in space, `mass.<name>.j` is a rotary inertia the same about every
        // axis (a compact body): jx, jy and jz scaled together
        if self.dimension == Dimension::Spatial
            && let Some(item) = name.strip_prefix("mass.").and_then(|r| r.strip_suffix(".j"))
            && let Some(i) = self.mass_index(item)
        {
            let quantities = Dof::SPATIAL[3..].iter().map(|&d| Quantity::MassJ(i, d)).collect();
            return Ok(Parameter { name: name.into(), quantities });
        }
        Ok(Parameter { name: name.into(), quantities: vec![self.quantity(name)?] })
    }

    /// The dotted name of a quantity.
    pub fn quantity_name(&self, q: Quantity) -> QuantityName<'_> {
        QuantityName { model: self, q }
    }

    /// Current value of a quantity (`mu` of a viscous group is infinity).
    pub fn get(&self, q: Quantity) -> f64 {
        match q {
            Quantity::GroupAlpha(g) => self.groups[g].alpha,
            Quantity::GroupBeta(g) => self.groups[g].beta,
            Quantity::GroupMu(g) => self.groups[g].mu.unwrap_or(f64::INFINITY),
            Quantity::GroupStiffness(g) => self.groups[g].stiffness,
            Quantity::GroupMass(g) => self.groups[g].mass,
            Quantity::GroupDamping(g) => self.groups[g].damping,
            Quantity::MaterialE(i) => self.materials[i].e,
            Quantity::MaterialRho(i) => self.materials[i].rho,
            Quantity::ElementStiffness(i) => self.beams[i].stiffness_factor,
            Quantity::ElementBending(i) => self.beams[i].bending_factor,
            Quantity::ElementMass(i) => self.beams[i].mass_factor,
            Quantity::ElementAddedMass(i) => self.beams[i].added_mass,
            Quantity::SpringK(i, d) => self.springs[i].k[d],
            Quantity::MassM(i) => self.masses[i].m,
            Quantity::MassJ(i, d) => self.masses[i].j[d.axis()],
        }
    }

    /// Sets a quantity. Values must be finite and positive, except damping
    /// coefficients, added mass, spring stiffnesses and lumped masses that may
    /// be zero, and `mu` that may be infinite (viscous).
    pub fn set(&mut self, q: Quantity, value: f64) -> Result<(), ModelError> {
        let name = self.quantity_name(q).to_string();
        let may_be_zero = matches!(
            q,
            Quantity::GroupAlpha(_)
                | Quantity::GroupBeta(_)
                | Quantity::ElementAddedMass(_)
                | Quantity::SpringK(..)
                | Quantity::MassM(_)
                | Quantity::MassJ(..)
        );
        let ok = if matches!(q, Quantity::GroupMu(_)) {
            value > 0.0 && !value.is_nan()
        } else if may_be_zero {
            value.is_finite() && value >= 0.0
        } else {
            value.is_finite() && value > 0.0
        };
        if !ok {
            return Err(ModelError::Invalid { what: name, reason: format!("cannot be set to {value}") });
        }
        match q {
            Quantity::GroupAlpha(g) => self.groups[g].alpha = value,
            Quantity::GroupBeta(g) => self.groups[g].beta = value,
            Quantity::GroupMu(g) => self.groups[g].mu = value.is_finite().then_some(value),
            Quantity::GroupStiffness(g) => self.groups[g].stiffness = value,
            Quantity::GroupMass(g) => self.groups[g].mass = value,
            Quantity::GroupDamping(g) => self.groups[g].damping = value,
            Quantity::MaterialE(i) => self.materials[i].e = value,
            Quantity::MaterialRho(i) => self.materials[i].rho = value,
            Quantity::ElementStiffness(i) => self.beams[i].stiffness_factor = value,
            Quantity::ElementBending(i) => self.beams[i].bending_factor = value,
            Quantity::ElementMass(i) => self.beams[i].mass_factor = value,
            Quantity::ElementAddedMass(i) => self.beams[i].added_mass = value,
            Quantity::SpringK(i, d) => self.springs[i].k[d] = value,
            Quantity::MassM(i) => self.masses[i].m = value,
            Quantity::MassJ(i, d) => self.masses[i].j[d.axis()] = value,
        }
        Ok(())
    }
}

fn names<'a>(it: impl Iterator<Item = &'a String>) -> String {
    let v: Vec<&str> = it.map(String::as_str).collect();
    if v.is_empty() { "none".into() } else { v.join(", ") }
}

#[cfg(test)]
mod tests {
    use crate::ModelError;
    use crate::samples;

    #[test]
    fn names_resolve_and_print_back() {
        let model = samples::frame_with_joint();
        for name in ["group.joint.mu", "spring.joint.kr", "material.steel.E", "element.1.stiffness"] {
            let q = model.quantity(name).unwrap();
            assert_eq!(model.quantity_name(q).to_string(), name);
        }
        let reason = |r: Result<_, ModelError>, name: &str| match r {
            Err(ModelError::UnknownQuantity { name: n, reason }) if n == name => reason,
            other => panic!("{name}: expected an unknown quantity, got {other:?}"),
        };
        let e = reason(model.quantity("group.nope.mu"), "group.nope.mu");
        assert!(e.contains("no group `nope`"), "{e}");
        let e = reason(model.quantity("spring.joint.kz"), "spring.joint.kz");
        assert!(e.contains("kx, ky, kr"), "{e}");
    }

    #[test]
    fn element_ranges_link_quantities() {
        let model = samples::cantilever(6);
        let p = model.parameter("element.2..4.stiffness").unwrap();
        assert_eq!(p.quantities.len(), 3);
        assert_eq!(model.quantity_name(p.quantities[2]).to_string(), "element.4.stiffness");
        match model.parameter("element.5..9.mass") {
            Err(ModelError::UnknownQuantity { name, reason }) => {
                assert_eq!(name, "element.5..9.mass");
                assert!(reason.contains("no element 7"), "{reason}");
            }
            other => panic!("expected an unknown quantity, got {other:?}"),
        }
        assert_eq!(
            model.parameter("element.4..2.mass").unwrap_err(),
            ModelError::UnknownQuantity { name: "element.4..2.mass".into(), reason: "the range 4..2 is empty".into() }
        );
        assert_eq!(model.parameter("group.beam.alpha").unwrap().quantities.len(), 1);
    }

    #[test]
    fn set_rejects_non_physical_values() {
        let mut model = samples::frame_with_joint();
        let q = model.quantity("material.steel.E").unwrap();
        let invalid = |reason: &str| ModelError::Invalid { what: "material.steel.E".into(), reason: reason.into() };
        assert_eq!(model.set(q, -1.0).unwrap_err(), invalid("cannot be set to -1"));
        assert_eq!(model.set(q, f64::NAN).unwrap_err(), invalid("cannot be set to NaN"));
        model.set(q, 1e11).unwrap();
        assert_eq!(model.get(q), 1e11);
        let mu = model.quantity("group.joint.mu").unwrap();
        model.set(mu, f64::INFINITY).unwrap();
        assert_eq!(model.groups()[model.group_index("joint").unwrap()].mu, None);
    }
}

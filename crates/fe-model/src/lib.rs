//! Frame finite element models, planar or in space, for FRF-based model
//! updating.
//!
//! This crate is the bottom layer of the workspace. It describes a structure
//! in the x-y plane — nodes with three DOFs each (`ux`, `uy`, `rz`) — or in
//! space (`[model] dimension = 3`: six DOFs, `ux` .. `rz`), with
//! Euler-Bernoulli frame elements (in space with torsion and two bending
//! planes), springs between nodes (joints and flexible supports modelled
//! with coincident nodes), lumped masses, supports and ties, and the user's
//! own stiffness and mass matrices imported from another code
//! ([`imported`]) — and assembles it into sparse matrices that keep each
//! group's share:
//!
//! ```text
//! K = sum_g K_g,   M = sum_g M_g,   C_g = alpha_g K_g + beta_g M_g
//! ```
//!
//! Every element, spring and mass belongs to a [`model::Group`], whose damping
//! parameters (`alpha`, `beta`, relaxation `mu`) are stored here as plain data;
//! the `damping` crate turns them into the frequency-dependent kernel. This
//! crate knows nothing of frequencies.
//!
//! Key types: [`Model`] (the description), [`Assembly`] (equations: DOF map,
//! shared sparsity pattern, per-element blocks of unit matrices times model
//! quantities), [`Quantity`] (a named scalar such as `group.steel.mu` or
//! `spring.clamp.kr` that can be read, set and differentiated), and
//! [`CaseFile`] (the TOML case format with located errors).
//!
//! # Example
//!
//! ```
//! use fe_model::{Assembly, Dof, Group, Model, Section};
//!
//! let mut m = Model::new("cantilever");
//! let g = m.add_group(Group::new("beam").rayleigh(1e-5, 0.5)).unwrap();
//! let steel = m.add_material("steel", 2.0e11, 7800.0).unwrap();
//! let bar = m.add_section(Section::rectangle("bar", 0.05, 0.01)).unwrap();
//! for i in 0..=4 {
//!     m.add_node(i + 1, 0.25 * f64::from(i), 0.0).unwrap();
//! }
//! for i in 1..=4 {
//!     m.add_beam(i, [i, i + 1], steel, bar, g).unwrap();
//! }
//! m.add_support(1, &Dof::PLANAR).unwrap();
//!
//! let a = Assembly::new(&m).unwrap();
//! assert_eq!(a.n(), 12); // 5 nodes x 3 DOFs, minus the clamped node
//! let k = a.stiffness_dense();
//! assert!((&k - k.transpose()).norm() <= 1e-9 * k.norm());
//!
//! // quantities are addressed by name
//! let e = m.quantity("material.steel.E").unwrap();
//! assert_eq!(m.get(e), 2.0e11);
//! ```

pub mod assembly;
pub mod case;
pub mod dof;
pub mod element;
pub mod error;
pub mod imported;
pub mod kinematics;
pub mod model;
pub mod quantity;
#[cfg(any(test, feature = "samples"))]
pub mod samples;
pub mod suggest;
pub mod text;
mod union_find;

pub use assembly::{Assembly, Block, BlockSource, MatrixKind, Pattern, Term};
pub use case::{CaseEditor, CaseFile, HistoryEntry};
pub use dof::{Dimension, Dof, DofMap, DofRef, PerDof, Slot};
pub use error::{CaseError, Location, ModelError};
pub use model::{
    Beam, ElementId, Group, LumpedMass, Material, Model, Node, NodeId, PartIndex, RotaryInertia, Section, Spring,
};
pub use quantity::{Parameter, Quantity, QuantityKind};

/// A number for a message: as written for ordinary magnitudes, in exponent
/// notation when huge or tiny, so that `1e300` is not printed as a
/// 301-digit integer.
pub fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e15).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}

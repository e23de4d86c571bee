//! A `[[springs]]` entry's own axes in a 3D case: `x_axis`, its local x
//! axis, and `xy_vector`, a vector in its local x-y plane (as Abaqus's
//! `*ORIENTATION` and Nastran's `CBUSH` define them); its stiffnesses `kx`
//! .. `krz` then act along and about those axes.
//!
//! ```toml
//! [[springs]]
//! name = "mount"
//! node = 4
//! kx = 2e6                        # along the local x axis
//! ky = 5e5
//! x_axis = [1.0, 1.0, 0.0]
//! xy_vector = [0.0, 0.0, 1.0]     # local y is global z here
//! group = "mounts"
//! ```

use super::Ctx;
use super::raw::RawSpring;
use crate::dof::Dimension;
use crate::error::CaseError;
use crate::model::{Model, SpringAxesError, spring_axes};

/// Orients spring `i` as its entry `r` says (nothing when it gives no
/// axes); every refusal at the key it concerns.
pub(super) fn orient(ctx: &Ctx<'_>, model: &mut Model, i: usize, r: &RawSpring) -> Result<(), CaseError> {
    let (x, xy) = match (&r.x_axis, &r.xy_vector) {
        (None, None) => return Ok(()),
        (Some(x), Some(xy)) => (x, xy),
        (Some(given), None) | (None, Some(given)) => {
            return Err(ctx.err(
                given.span(),
                format!(
                    "spring `{}`: give both `x_axis` (its local x axis) and `xy_vector` (a vector in its local x-y plane)",
                    r.name
                ),
            ));
        }
    };
    // the key a bad value sits at (the first, in a planar model)
    let span = match spring_axes(*x.get_ref(), *xy.get_ref()) {
        Err(SpringAxesError::XyVector | SpringAxesError::Parallel) if model.dimension() == Dimension::Spatial => {
            xy.span()
        }
        _ => x.span(),
    };
    model.orient_spring(i, *x.get_ref(), *xy.get_ref()).map_err(|e| ctx.model_err(span, e))
}

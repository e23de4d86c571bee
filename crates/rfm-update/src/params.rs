//! Updating parameters: named, possibly linked, scaled by relative factors.
//!
//! A [`fe_model::Parameter`] scales one or several model quantities by a
//! common factor (`element.5..8.stiffness` scales four element factors). Its
//! relative derivative is the sum of its quantities' relative derivatives,
//! `(dZ/dp) p = sum_q (dZ/dq) q`, so sensitivities are assembled per
//! quantity and summed per parameter ([`ParameterSet::combine`]).

use damping::DampedSystem;
use faer::Mat;
use fe_model::{Model, Parameter, Quantity};
use num_complex::Complex64 as C64;

use crate::error::UpdateError;
use crate::sensitivity::FrequencyBlock;

/// The value of every quantity of `params` in `model`, by name: what an
/// updated case file records (`rfm update`'s `updated.toml`, each step of
/// `rfm fix`).
pub fn quantity_values(params: &[Parameter], model: &Model) -> Vec<(String, f64)> {
    params
        .iter()
        .flat_map(|p| p.quantities.iter().map(|&q| (model.quantity_name(q).to_string(), model.get(q))))
        .collect()
}

/// The parameters of an updating run, with their quantities flattened.
#[derive(Clone, Debug)]
pub struct ParameterSet {
    params: Vec<Parameter>,
    flat: Vec<Quantity>,
    owner: Vec<usize>,
}

impl ParameterSet {
    /// A set from parameters (their quantities must not overlap).
    pub fn new(params: Vec<Parameter>) -> Self {
        let mut flat = Vec::new();
        let mut owner = Vec::new();
        for (i, p) in params.iter().enumerate() {
            for &q in &p.quantities {
                flat.push(q);
                owner.push(i);
            }
        }
        ParameterSet { params, flat, owner }
    }

    /// A set of single-quantity parameters.
    pub fn of_quantities(sys: &DampedSystem, qs: &[Quantity]) -> Self {
        Self::new(qs.iter().map(|&q| Parameter::single(sys.model(), q)).collect())
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// True when there is no parameter.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters.
    pub fn params(&self) -> &[Parameter] {
        &self.params
    }

    /// Every quantity of every parameter, in parameter order.
    pub fn quantities(&self) -> &[Quantity] {
        &self.flat
    }

    /// Names.
    pub fn names(&self) -> Vec<String> {
        self.params.iter().map(|p| p.name.clone()).collect()
    }

    /// Current values (each parameter's first quantity).
    pub fn values(&self, sys: &DampedSystem) -> Vec<f64> {
        self.params.iter().map(|p| sys.get(p.quantities[0])).collect()
    }

    /// Sets parameter values: every quantity of parameter `i` is scaled by
    /// `values[i] / current value of i`.
    pub fn set_values(&self, sys: &mut DampedSystem, values: &[f64]) -> Result<(), UpdateError> {
        for (p, &v) in self.params.iter().zip(values) {
            let current = sys.get(p.quantities[0]);
            let factor = v / current;
            for &q in &p.quantities {
                let x = sys.get(q);
                sys.set(q, if q == p.quantities[0] { v } else { x * factor })?;
            }
        }
        Ok(())
    }

    /// Per-parameter sensitivities from per-quantity ones: sums the columns
    /// of each parameter's quantities.
    pub fn combine(&self, block: &FrequencyBlock) -> Mat<C64> {
        let n_ch = block.sens.nrows();
        let mut out = Mat::<C64>::zeros(n_ch, self.params.len());
        for (j, &i) in self.owner.iter().enumerate() {
            for c in 0..n_ch {
                out[(c, i)] += block.sens[(c, j)];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::samples;

    #[test]
    fn linked_parameters_scale_every_quantity_together() {
        let mut sys = DampedSystem::new(samples::cantilever(6)).unwrap();
        let p = sys.model().parameter("element.2..4.stiffness").unwrap();
        let set = ParameterSet::new(vec![p.clone()]);
        set.set_values(&mut sys, &[0.6]).unwrap();
        for &q in &p.quantities {
            assert_eq!(sys.get(q), 0.6);
        }
        let e5 = sys.model().quantity("element.5.stiffness").unwrap();
        assert_eq!(sys.get(e5), 1.0);
        assert_eq!(set.values(&sys), vec![0.6]);
    }
}

//! The stabilisation check over consecutive orders and the choice of the
//! modes: runs of stable poles, each mode represented by its run's last pole.

use num_complex::Complex64 as C64;

use super::{LscfOptions, OrderPoles, PoleStatus, StabilisationPole};
use crate::mac::mac;

pub(super) fn status(pole: &StabilisationPole, prev: &[StabilisationPole], opts: &LscfOptions) -> PoleStatus {
    let Some(near) = nearest(prev, pole.frequency_hz).map(|k| &prev[k]) else {
        return PoleStatus::New;
    };
    if (near.frequency_hz - pole.frequency_hz).abs() > opts.tol_frequency * near.frequency_hz {
        return PoleStatus::New;
    }
    if (near.damping_ratio - pole.damping_ratio).abs() > opts.tol_damping * near.damping_ratio {
        return PoleStatus::Frequency;
    }
    if mac(&near.participation, &pole.participation) < 1.0 - opts.tol_vector {
        return PoleStatus::Damping;
    }
    PoleStatus::Stable
}

/// Index of the pole of `prev` nearest in frequency to `f`.
fn nearest(prev: &[StabilisationPole], f: f64) -> Option<usize> {
    (0..prev.len()).min_by(|&a, &b| (prev[a].frequency_hz - f).abs().total_cmp(&(prev[b].frequency_hz - f).abs()))
}

/// Follows each pole back through the orders (to the nearest pole of the
/// previous order) and keeps the unbroken runs of [`PoleStatus::Stable`]
/// at least `min_stable_orders` long, one per mode: `(pole, participation,
/// run length)` of the run's last (highest-order) pole.
pub(super) fn select(stab: &[OrderPoles], opts: &LscfOptions) -> Vec<(C64, Vec<C64>, usize)> {
    // run[i][j]: consecutive orders, ending at pole j of order i, in which
    // the pole was stable with respect to its predecessor
    let mut run: Vec<Vec<usize>> = Vec::with_capacity(stab.len());
    for (i, order) in stab.iter().enumerate() {
        let row = order
            .poles
            .iter()
            .map(|p| match (p.status, i.checked_sub(1)) {
                (PoleStatus::Stable, Some(h)) => 1 + nearest(&stab[h].poles, p.frequency_hz).map_or(0, |k| run[h][k]),
                _ => 0,
            })
            .collect();
        run.push(row);
    }
    let min_run = opts.min_stable_orders.max((opts.min_stable_fraction * stab.len() as f64).ceil() as usize);
    // the ends of runs: not continued by a stable pole of the next order
    let mut ends: Vec<(usize, usize, usize)> = Vec::new();
    for (i, order) in stab.iter().enumerate() {
        for (j, _) in order.poles.iter().enumerate() {
            let continued = stab.get(i + 1).is_some_and(|next| {
                next.poles
                    .iter()
                    .enumerate()
                    .any(|(k, q)| run[i + 1][k] > 0 && nearest(&order.poles, q.frequency_hz) == Some(j))
            });
            if run[i][j] >= min_run && !continued {
                ends.push((run[i][j], i, j));
            }
        }
    }
    // longest runs first; a shorter run of the same mode (broken once) is dropped
    ends.sort_by(|a, b| b.0.cmp(&a.0).then(b.1.cmp(&a.1)));
    let mut out: Vec<(C64, Vec<C64>, usize)> = Vec::new();
    for (len, i, j) in ends {
        let p = &stab[i].poles[j];
        let f = p.frequency_hz;
        if out.iter().all(|(q, _, _)| (q.norm() / (2.0 * std::f64::consts::PI) - f).abs() > opts.tol_frequency * f) {
            out.push((p.pole, p.participation.clone(), len));
        }
    }
    out.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
    out
}

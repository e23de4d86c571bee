//! Automatic choice of frequency points for updating.
//!
//! The response function method works best away from resonances (where
//! small frequency errors dominate the FRF difference) and anti-resonances
//! (where the FRF is tiny and noise dominates). The paper chooses points by
//! hand; here the resonances (peaks of the summed FRF magnitude) and the
//! anti-resonances of driving-point FRFs (dips of channels whose response is
//! their reference: the structure's anti-resonances, rather than every
//! sensor's) of both the model and the measurement are marked, and the points are shared among the gaps between
//! consecutive marks in proportion to each gap's width on a log-frequency
//! scale, placed evenly (in log frequency) inside each gap and snapped to
//! measured lines. The open-ended gaps below the first and above the last
//! mark count as one octave at most, so the quasi-static band does not take
//! most of the points.

use frf::FrfSet;

/// Indices of local maxima of `y` that stand out from their neighbourhood
/// (`prominence` = ratio to the smallest value within `reach` lines each side).
fn peaks(y: &[f64], reach: usize, prominence: f64) -> Vec<usize> {
    let n = y.len();
    (1..n.saturating_sub(1))
        .filter(|&k| y[k] >= y[k - 1] && y[k] >= y[k + 1])
        .filter(|&k| {
            let lo = k.saturating_sub(reach);
            let hi = (k + reach).min(n - 1);
            let left = y[lo..k].iter().copied().fold(f64::INFINITY, f64::min);
            let right = y[k + 1..=hi].iter().copied().fold(f64::INFINITY, f64::min);
            y[k] >= prominence * left.max(right)
        })
        .collect()
}

/// Resonance frequencies (Hz) seen in a set of FRFs, and anti-resonances of
/// its driving-point channels.
pub fn features(set: &FrfSet) -> Vec<f64> {
    let f = set.frequencies_hz();
    let nf = f.len();
    if nf < 3 {
        return Vec::new();
    }
    let reach = (nf / 100).max(3);
    let mut out = Vec::new();
    let sum: Vec<f64> = (0..nf).map(|k| (0..set.channels().len()).map(|c| set.get(c, k).norm()).sum()).collect();
    out.extend(peaks(&sum, reach, 1.5).into_iter().map(|k| f[k]));
    for c in (0..set.channels().len()).filter(|&c| set.channels()[c].response == set.channels()[c].reference) {
        let inv: Vec<f64> = set.channel(c).iter().map(|v| 1.0 / v.norm().max(1e-300)).collect();
        out.extend(peaks(&inv, reach, 1.5).into_iter().map(|k| f[k]));
    }
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

/// Picks `n` lines of `candidates_hz` away from `avoid_hz` and from each
/// other (see the module docs). Returned in increasing order, distinct.
pub fn choose(candidates_hz: &[f64], avoid_hz: &[f64], n: usize) -> Vec<f64> {
    let (Some(&lo), Some(&hi)) = (candidates_hz.first(), candidates_hz.last()) else {
        return Vec::new();
    };
    let mut marks: Vec<f64> = avoid_hz.iter().copied().filter(|&f| f > lo && f < hi).collect();
    marks.sort_by(f64::total_cmp);
    marks.dedup();
    // gaps as (start, end) in log frequency
    let mut edges = vec![lo.ln()];
    edges.extend(marks.iter().map(|f| f.ln()));
    edges.push(hi.ln());
    let last = edges.len() - 2;
    let gaps: Vec<(f64, f64)> = edges
        .windows(2)
        .enumerate()
        .map(|(i, w)| {
            let octave = std::f64::consts::LN_2;
            match (i == 0 && !marks.is_empty(), i == last && !marks.is_empty()) {
                (true, _) => ((w[1] - octave).max(w[0]), w[1]),
                (_, true) => (w[0], (w[0] + octave).min(w[1])),
                _ => (w[0], w[1]),
            }
        })
        .collect();
    let mut counts = vec![0usize; gaps.len()];
    let wanted = n.min(candidates_hz.len());
    for _ in 0..wanted {
        // fewest points first, then the widest gap
        let g = (0..gaps.len())
            .max_by(|&a, &b| {
                counts[b].cmp(&counts[a]).then((gaps[a].1 - gaps[a].0).total_cmp(&(gaps[b].1 - gaps[b].0)))
            })
            .expect("at least one gap");
        counts[g] += 1;
    }
    let mut chosen: Vec<f64> = Vec::new();
    for (g, &(a, b)) in gaps.iter().enumerate() {
        for i in 0..counts[g] {
            let target = a + (b - a) * (i as f64 + 1.0) / (counts[g] as f64 + 1.0);
            let best = candidates_hz
                .iter()
                .copied()
                .filter(|f| !chosen.contains(f))
                .min_by(|x, y| (x.ln() - target).abs().total_cmp(&(y.ln() - target).abs()));
            if let Some(f) = best {
                chosen.push(f);
            }
        }
    }
    chosen.sort_by(f64::total_cmp);
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chosen_points_avoid_marks_and_spread() {
        let cands: Vec<f64> = (1..=1000).map(|i| i as f64 * 0.4).collect();
        let avoid = [5.0, 31.0, 87.0, 170.0, 280.0];
        let pts = choose(&cands, &avoid, 8);
        assert_eq!(pts.len(), 8);
        for p in &pts {
            for a in avoid {
                assert!((p / a).ln().abs() > 0.05, "{p} Hz is too close to {a} Hz");
            }
        }
        // spread: at least one point between each pair of marks above 31 Hz
        for w in avoid[1..].windows(2) {
            assert!(pts.iter().any(|p| *p > w[0] && *p < w[1]), "nothing between {} and {}", w[0], w[1]);
        }
    }
}

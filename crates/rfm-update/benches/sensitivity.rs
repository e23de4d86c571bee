//! Sensitivity assembly benchmarks (`cargo bench -p rfm-update`).
//!
//! Each benchmark times one call of `sensitivity::assemble` (every line,
//! threads over lines, `Hybrid::Model`) and declares the lines as its
//! throughput, so criterion's `elem/s` is frequency lines per second (time
//! per line = 1 / throughput):
//!
//! - `a_paper_beam`: the paper's two-material cantilever (90 equations), six
//!   damping parameters, 30 measured DOFs, its 10 updating lines;
//! - `b_2k`: a 2,002-equation beam, 30 parameters (five per damping group:
//!   alpha, beta, mu, stiffness and mass factors), 20 measured DOFs, 20
//!   lines, beside the dense formulation (`sensitivity::naive`: dense
//!   inverse of Z and dense dZ/dp per parameter) on 2 lines for the ratio;
//! - `c_100k`: a 100,001-equation beam, 30 parameters, 20 measured DOFs, 10
//!   lines;
//! - `d_diagnosis`: a 10,065-equation frame, 1,000 candidate parameters (the
//!   ten group parameters, then stiffness and mass factors of 495 elements),
//!   20 measured DOFs, 200 lines.
//!
//! `cargo xtask bench` runs quick versions of these in separate processes to
//! measure peak memory and fit the scaling exponents.

mod common;

use std::hint::black_box;
use std::time::Duration;

use common::{Family, Workload, workload};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use frf::ZSolver;
use rfm_update::sensitivity::{self, ChannelPlan, Hybrid};

fn fast(c: &mut Criterion, group: &str, w: &Workload, samples: usize) {
    let solver = ZSolver::new(w.sys.assembly().pattern()).unwrap();
    let plan = ChannelPlan::new(&w.sys, &w.channels).unwrap();
    let mut g = c.benchmark_group(group);
    g.sample_size(samples).throughput(Throughput::Elements(w.freqs.len() as u64));
    let id = format!("sparse/{}: {} dofs, {} params, {} lines", w.label, w.sys.n(), w.params.len(), w.freqs.len());
    g.bench_function(id, |b| {
        b.iter(|| black_box(sensitivity::assemble(&w.sys, &solver, &plan, &w.params, &w.freqs, Hybrid::Model).unwrap()))
    });
    g.finish();
}

fn a_paper_beam(c: &mut Criterion) {
    fast(c, "a_paper_beam", &workload(Family::Paper, 6, 30, 10), 50);
}

fn b_2k(c: &mut Criterion) {
    let w = workload(Family::Beam { elements: 690 }, 30, 20, 20);
    fast(c, "b_2k", &w, 30);
    // the dense formulation costs seconds per line: two lines are enough
    let lines = &w.freqs[..2];
    let plan = ChannelPlan::new(&w.sys, &w.channels).unwrap();
    let mut g = c.benchmark_group("b_2k");
    g.sample_size(10).warm_up_time(Duration::from_secs(1)).throughput(Throughput::Elements(lines.len() as u64));
    let id = format!("dense/{}: {} dofs, {} params, {} lines", w.label, w.sys.n(), w.params.len(), lines.len());
    g.bench_function(id, |b| {
        b.iter(|| black_box(sensitivity::naive::assemble(&w.sys, &plan, &w.params, lines, Hybrid::Model).unwrap()))
    });
    g.finish();
}

fn c_100k(c: &mut Criterion) {
    fast(c, "c_100k", &workload(Family::Beam { elements: 34_483 }, 30, 20, 10), 10);
}

fn d_diagnosis(c: &mut Criterion) {
    fast(c, "d_diagnosis", &workload(Family::Frame { bays: 10, storeys: 11, per: 15 }, 1000, 20, 200), 10);
}

criterion_group!(benches, a_paper_beam, b_2k, c_100k, d_diagnosis);
criterion_main!(benches);

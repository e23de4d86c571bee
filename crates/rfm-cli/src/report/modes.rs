//! The modal comparison of a model with the measurement, for the reports
//! and `rfm compare --json`: the measured modes (LSCF over the measured
//! band), paired with the model's complex modes by MAC; the mode table, the
//! MAC matrix, the stabilisation diagram and the paired mode shapes drawn
//! on the structure.
//!
//! The comparison itself is [`rfm_update::comparison::compare_modes`]; this file turns it
//! into the table, the JSON and the figures.

use std::collections::HashMap;

use fe_model::{Model, PerDof};
use frf::comparison::{measured_on_model, real_shape};
use frf::{FrfSet, ModalComparison};
use serde::Serialize;

use super::html::{Block, Section, Table, Tone};
use super::plot::{self, modes::StabilisationPoint, structure::ShapePanel};
use super::{ReportOptions, Result, short};
use crate::output::Outputs;

/// Least MAC of a pair.
pub(crate) const MIN_MAC: f64 = 0.5;

/// One measured mode and its model partner.
#[derive(Serialize)]
pub(crate) struct ModeRow {
    measured_hz: Option<f64>,
    measured_damping_ratio: Option<f64>,
    model_hz: Option<f64>,
    model_damping_ratio: Option<f64>,
    frequency_error_pct: Option<f64>,
    damping_error_pct: Option<f64>,
    mac: Option<f64>,
    reading: String,
}

/// The mode table.
#[derive(Serialize)]
pub(crate) struct ModesJson {
    /// Band of the modal estimation (Hz).
    band_hz: (f64, f64),
    rows: Vec<ModeRow>,
}

/// The mode table: each measured mode with its partner and what the
/// pair suggests, then the model modes nothing was paired with, by frequency.
pub(crate) fn rows(c: &ModalComparison) -> ModesJson {
    let outside = |hz: f64| hz < c.band_hz.0 || hz > c.band_hz.1;
    let mut rows = Vec::new();
    for (i, m) in c.measured.iter().enumerate() {
        let row = match c.pairing.pairs.iter().find(|p| p.measured == i) {
            Some(p) => {
                let x = &c.model[p.model];
                ModeRow {
                    measured_hz: Some(m.frequency_hz),
                    measured_damping_ratio: Some(m.damping_ratio),
                    model_hz: Some(x.frequency_hz),
                    model_damping_ratio: Some(x.damping_ratio),
                    frequency_error_pct: Some(p.frequency_error_pct),
                    damping_error_pct: Some(p.damping_error_pct),
                    mac: Some(p.mac),
                    reading: if outside(x.frequency_hz) {
                        format!(
                            "its model partner ({:.2} Hz) lies outside the band {}-{} Hz",
                            x.frequency_hz,
                            short(c.band_hz.0),
                            short(c.band_hz.1)
                        )
                    } else {
                        frf::symptom(x, m, p.mac).reading().to_string()
                    },
                }
            }
            None => ModeRow {
                measured_hz: Some(m.frequency_hz),
                measured_damping_ratio: Some(m.damping_ratio),
                model_hz: None,
                model_damping_ratio: None,
                frequency_error_pct: None,
                damping_error_pct: None,
                mac: None,
                reading: format!(
                    "no model mode up to {} Hz with a similar shape (MAC < {MIN_MAC})",
                    short(frf::comparison::MODEL_REACH * c.band_hz.1)
                ),
            },
        };
        rows.push(row);
    }
    for &j in &c.pairing.unpaired_model {
        let x = &c.model[j];
        if outside(x.frequency_hz) {
            continue;
        }
        rows.push(ModeRow {
            measured_hz: None,
            measured_damping_ratio: None,
            model_hz: Some(x.frequency_hz),
            model_damping_ratio: Some(x.damping_ratio),
            frequency_error_pct: None,
            damping_error_pct: None,
            mac: None,
            reading: "not seen in the measurement (not excited, not observed, or not in the structure)".into(),
        });
    }
    rows.sort_by(|a, b| {
        let fa = a.measured_hz.or(a.model_hz).unwrap_or(0.0);
        let fb = b.measured_hz.or(b.model_hz).unwrap_or(0.0);
        fa.total_cmp(&fb)
    });
    ModesJson { band_hz: c.band_hz, rows }
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map(f).unwrap_or_else(|| "-".into())
}

/// Header and rows of the mode table, for the terminal and the report.
pub(crate) fn mode_table_rows(m: &ModesJson) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let header = vec!["mode", "measured Hz", "model Hz", "error %", "zeta meas. %", "zeta model %", "MAC", "reading"];
    let rows = m
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            vec![
                format!("{}", i + 1),
                opt(r.measured_hz, |f| format!("{f:.2}")),
                opt(r.model_hz, |f| format!("{f:.2}")),
                opt(r.frequency_error_pct, |e| format!("{e:+.2}")),
                opt(r.measured_damping_ratio, |z| format!("{:.3}", 100.0 * z)),
                opt(r.model_damping_ratio, |z| format!("{:.3}", 100.0 * z)),
                opt(r.mac, |m| format!("{m:.3}")),
                r.reading.clone(),
            ]
        })
        .collect();
    (header, rows)
}

/// The figures of a modal comparison: the MAC matrix, the stabilisation
/// diagram and the paired mode shapes on `model`'s geometry.
fn figures(
    c: &ModalComparison,
    model: &Model,
    measured: &FrfSet,
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<Vec<Block>> {
    let mut blocks = Vec::new();
    let meas_hz: Vec<f64> = c.measured.iter().map(|m| m.frequency_hz).collect();
    // the model modes in the band and those paired from above it
    let (lo, hi) = c.band_hz;
    let columns: Vec<usize> = (0..c.model.len())
        .filter(|&j| {
            let f = c.model[j].frequency_hz;
            (lo..=hi).contains(&f) || c.pairing.pairs.iter().any(|p| p.model == j)
        })
        .collect();
    let model_hz: Vec<f64> = columns.iter().map(|&j| c.model[j].frequency_hz).collect();
    let column_of = |j: usize| columns.iter().position(|&k| k == j);
    let pairs: Vec<(usize, usize)> =
        c.pairing.pairs.iter().filter_map(|p| Some((p.measured, column_of(p.model)?))).collect();
    let mac: Vec<Vec<f64>> = c.pairing.mac.iter().map(|row| columns.iter().map(|&j| row[j]).collect()).collect();
    if !meas_hz.is_empty() && !model_hz.is_empty() {
        let svg = plot::modes::mac_matrix("MAC of measured against model modes", &meas_hz, &model_hz, &mac, &pairs)?;
        blocks.push(out.figure(
            "mac-matrix",
            svg,
            format!(
                "The modal assurance criterion of every measured mode (rows) with every model mode in the band (and any paired from above it) \
                 (columns), over the {} measured responses: 1 for the same shape, 0 for orthogonal ones. Outlined: \
                 the one-to-one pairing (greedy by MAC, at least {MIN_MAC}). A clear diagonal says the modes \
                 correspond; a pair off the diagonal, that the model orders its modes differently; a row without an \
                 outline, a measured mode the model lacks.",
                c.estimate.responses.len()
            ),
        )?);
    }

    let rec = measured.to_receptance();
    let (lo, hi) = c.estimate.band_hz;
    let lines: Vec<usize> =
        (0..rec.n_freq()).filter(|&k| rec.frequencies_hz()[k] >= lo && rec.frequencies_hz()[k] <= hi).collect();
    let lines_hz: Vec<f64> = lines.iter().map(|&k| rec.frequencies_hz()[k]).collect();
    let magnitude: Vec<f64> =
        lines.iter().map(|&k| (0..rec.channels().len()).map(|ch| rec.get(ch, k).norm()).sum()).collect();
    let points: Vec<StabilisationPoint> = c
        .estimate
        .stabilisation
        .iter()
        .flat_map(|o| {
            o.poles.iter().map(move |p| StabilisationPoint {
                frequency_hz: p.frequency_hz,
                order: o.order,
                status: p.status,
            })
        })
        .collect();
    let svg = plot::modes::stabilisation(&points, &meas_hz, &lines_hz, &magnitude, opts.frequency_scale)?;
    blocks.push(out.figure(
        "stabilisation",
        svg,
        format!(
            "The poles of the least-squares complex frequency estimate at every model order from {} to {}, marked by \
             how each compares with the nearest pole of the order below (frequency within 1 %, damping within 5 %, \
             participation MAC above 0.98). A mode is a column of stable poles; the dashed lines are the {} modes \
             identified, numbered as in the table. Behind them, the measured receptances' summed magnitude shows \
             where the peaks are.",
            c.estimate.stabilisation.first().map_or(0, |o| o.order),
            c.estimate.stabilisation.last().map_or(0, |o| o.order),
            meas_hz.len()
        ),
    )?);

    let mut panels = Vec::new();
    for (k, p) in c.pairing.pairs.iter().enumerate() {
        let (x, m) = (&c.model[p.model], &c.measured[p.measured]);
        let (theta, real) = real_shape(&x.dofs, &x.shape);
        let mut per_node: HashMap<u32, PerDof> = HashMap::new();
        for (d, v) in x.dofs.iter().zip(&real) {
            per_node.entry(d.node.0).or_default()[d.dof] = *v;
        }
        // nodes without a free DOF (a clamped support) stay where they are
        for r in model.nodes().iter().map(|n| n.id.0) {
            per_node.entry(r).or_default();
        }
        panels.push(ShapePanel {
            title: format!("Mode {}: MAC {:.3}", k + 1, p.mac),
            subtitle: format!("measured {} Hz, model {} Hz", short_hz(m.frequency_hz), short_hz(x.frequency_hz)),
            model: per_node,
            measured: measured_on_model(m, x, theta),
        });
    }
    if !panels.is_empty() {
        let svg = plot::structure::mode_shapes("Paired mode shapes on the structure", model, &panels)?;
        blocks.push(out.figure(
            "mode-shapes",
            svg,
            "Each paired mode drawn on the structure: the model's shape (blue, interpolated along each beam with \
             its end rotations) over the undeformed structure (grey), and the measured shape at the measured \
             responses (black dots: the measured value in the measured direction, the model's in the directions \
             not measured). The measured shape is scaled and turned onto the model's by the least-squares modal \
             scale factor, and both are shown at the phase that makes them most nearly real. Where the shapes \
             agree the dots sit on the blue line; a dot off it shows where they differ.",
        )?);
    }
    Ok(blocks)
}

fn short_hz(f: f64) -> String {
    format!("{f:.1}")
}

/// The mode section: what was compared, the mode table, then the figures.
/// `against` names the model (`the model`, `the updated model`).
pub(crate) fn section(
    comparison: std::result::Result<&ModalComparison, &String>,
    against: &str,
    model: &Model,
    measured: &FrfSet,
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<Section> {
    let mut s = Section::new("Modes");
    let c = match comparison {
        Err(e) => {
            s.push(Block::Text(format!("The modes could not be compared: {e}.")));
            return Ok(s);
        }
        Ok(c) => c,
    };
    let m = rows(c);
    s.push(Block::Text(format!(
        "Measured modes estimated from the FRFs (least-squares complex frequency method, stable poles over model \
         orders, {} to {} Hz), paired with {against}'s complex modes by MAC at the measured responses. A resonance \
         moved by more than its peak is wide points at stiffness or mass; a peak of the right frequency but the \
         wrong height and width points at damping.",
        short(m.band_hz.0),
        short(m.band_hz.1)
    )));
    let (header, rows) = mode_table_rows(&m);
    let mut t = Table::new(&header);
    for r in rows {
        let bad = !r[7].starts_with("matches");
        let cells =
            r.into_iter().enumerate().map(|(i, c)| (c, if bad && i == 7 { Tone::Bad } else { Tone::Plain })).collect();
        t.row_toned(cells);
    }
    s.push(Block::Table(t));
    for b in figures(c, model, measured, opts, out)? {
        s.push(b);
    }
    Ok(s)
}

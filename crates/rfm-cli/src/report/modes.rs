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
    /// The measured mode's number: its place in frequency order among the
    /// measured modes, as the MAC matrix's rows, the stabilisation diagram
    /// and the shape panels number it.
    measured_mode: Option<usize>,
    /// The model mode's number: its place in frequency order among the
    /// model modes in the band (and those paired from above it), as the MAC
    /// matrix's columns and the shape panels number it.
    model_mode: Option<usize>,
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

/// The model modes a comparison shows, in frequency order: those in the
/// band and those paired from above it. A model mode's number everywhere
/// is its place here plus one.
pub(crate) fn model_columns(c: &ModalComparison) -> Vec<usize> {
    let (lo, hi) = c.band_hz;
    let mut columns: Vec<usize> = (0..c.model.len())
        .filter(|&j| {
            let f = c.model[j].frequency_hz;
            (lo..=hi).contains(&f) || c.pairing.pairs.iter().any(|p| p.model == j)
        })
        .collect();
    columns.sort_by(|&a, &b| c.model[a].frequency_hz.total_cmp(&c.model[b].frequency_hz));
    columns
}

/// The measured modes in frequency order; a measured mode's number
/// everywhere is its place here plus one.
pub(crate) fn measured_order(c: &ModalComparison) -> Vec<usize> {
    let mut order: Vec<usize> = (0..c.measured.len()).collect();
    order.sort_by(|&a, &b| c.measured[a].frequency_hz.total_cmp(&c.measured[b].frequency_hz));
    order
}

/// What a pair's symptom says when the model's misfit is within the noise:
/// the FRFs agree as well as the data allow, so a difference of the modal
/// estimates is the estimate's (a weakly excited or observed mode, few
/// sensors), not the model's.
const WITHIN_NOISE: &str = "within the noise: the FRFs agree to the data's noise, so this difference is the modal \
                            estimate's, not the model's";

/// The mode table: each measured mode with its partner and what the
/// pair suggests, then the model modes nothing was paired with, by
/// frequency. `within_noise`: the model's misfit is within
/// [`rfm_update::quantities::CONSISTENT`] times the noise, and a symptom
/// other than "matches" is read as the estimate's (see [`WITHIN_NOISE`]).
pub(crate) fn rows(c: &ModalComparison, within_noise: bool) -> ModesJson {
    let outside = |hz: f64| hz < c.band_hz.0 || hz > c.band_hz.1;
    let columns = model_columns(c);
    let measured_number: Vec<usize> = {
        let order = measured_order(c);
        (0..c.measured.len()).map(|i| order.iter().position(|&k| k == i).map_or(0, |p| p + 1)).collect()
    };
    let model_number = |j: usize| columns.iter().position(|&k| k == j).map(|p| p + 1);
    let mut rows = Vec::new();
    for (i, m) in c.measured.iter().enumerate() {
        let row = match c.pairing.pairs.iter().find(|p| p.measured == i) {
            Some(p) => {
                let x = &c.model[p.model];
                let symptom = frf::symptom(x, m, p.mac);
                ModeRow {
                    measured_mode: Some(measured_number[i]),
                    model_mode: model_number(p.model),
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
                    } else if within_noise && symptom != frf::Symptom::Matches {
                        format!("{} ({WITHIN_NOISE})", symptom.reading())
                    } else {
                        symptom.reading().to_string()
                    },
                }
            }
            None => ModeRow {
                measured_mode: Some(measured_number[i]),
                model_mode: None,
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
            measured_mode: None,
            model_mode: model_number(j),
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
    let header = vec![
        "measured mode",
        "model mode",
        "measured Hz",
        "model Hz",
        "error %",
        "zeta meas. %",
        "zeta model %",
        "MAC",
        "reading",
    ];
    let number = |n: Option<usize>| n.map_or("-".to_string(), |n| n.to_string());
    let rows = m
        .rows
        .iter()
        .map(|r| {
            vec![
                number(r.measured_mode),
                number(r.model_mode),
                opt(r.measured_hz, |f| format!("{f:.2}")),
                opt(r.model_hz, |f| format!("{f:.2}")),
                opt(r.frequency_error_pct, |e| crate::table::fixed(e, 2, true)),
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
    // one numbering of the measured and the model modes for the table and
    // every figure: frequency order
    let order = measured_order(c);
    let row_of = |i: usize| order.iter().position(|&k| k == i);
    let meas_hz: Vec<f64> = order.iter().map(|&i| c.measured[i].frequency_hz).collect();
    let columns = model_columns(c);
    let model_hz: Vec<f64> = columns.iter().map(|&j| c.model[j].frequency_hz).collect();
    let column_of = |j: usize| columns.iter().position(|&k| k == j);
    let pairs: Vec<(usize, usize)> =
        c.pairing.pairs.iter().filter_map(|p| Some((row_of(p.measured)?, column_of(p.model)?))).collect();
    let mac: Vec<Vec<f64>> = order.iter().map(|&i| columns.iter().map(|&j| c.pairing.mac[i][j]).collect()).collect();
    if !meas_hz.is_empty() && !model_hz.is_empty() {
        let svg = plot::modes::mac_matrix("MAC of measured against model modes", &meas_hz, &model_hz, &mac, &pairs)?;
        blocks.push(out.figure(
            "mac-matrix",
            svg,
            format!(
                "The modal assurance criterion of every measured mode (rows) with every model mode in the band (and \
                 any paired from above it) (columns), over the {} measured responses, both numbered as in the mode \
                 table: 1 for the same shape, 0 for orthogonal ones. Outlined: the one-to-one pairing (greedy by \
                 MAC, at least {MIN_MAC}). A clear diagonal says the modes correspond; a pair off the diagonal, that \
                 the model orders its modes differently; a row without an outline, a measured mode the model lacks.",
                c.estimate.responses.len()
            ),
        )?);
    }

    // the data's own kind, as every figure of the report draws them
    let rec = measured;
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
             identified, numbered as the measured modes of the mode table. Behind them, the measured FRFs' \
             summed magnitude shows where the peaks are.",
            c.estimate.stabilisation.first().map_or(0, |o| o.order),
            c.estimate.stabilisation.last().map_or(0, |o| o.order),
            meas_hz.len()
        ),
    )?);

    let mut panels = Vec::new();
    let mut paired: Vec<&frf::ModePair> = c.pairing.pairs.iter().collect();
    paired.sort_by_key(|p| row_of(p.measured));
    for p in paired {
        let (x, m) = (&c.model[p.model], &c.measured[p.measured]);
        let number = |n: Option<usize>| n.map_or("-".to_string(), |n| (n + 1).to_string());
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
            title: format!(
                "Measured mode {}, model mode {}: MAC {:.3}",
                number(row_of(p.measured)),
                number(column_of(p.model)),
                p.mac
            ),
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
            "Each paired mode drawn on the structure, numbered as in the mode table: the model's shape (blue, \
             interpolated along each beam with \
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

/// The mode section: what was compared, the mode table (also as CSV),
/// then the figures. `against` names the model (`the model`, `the updated
/// model`); `within_noise`: its misfit is within the noise (see [`rows`]).
pub(crate) fn section(
    comparison: std::result::Result<&ModalComparison, &String>,
    against: &str,
    model: &Model,
    measured: &FrfSet,
    within_noise: bool,
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
    let m = rows(c, within_noise);
    s.push(Block::Text(format!(
        "Measured modes estimated from the FRFs (least-squares complex frequency method, stable poles over model \
         orders, {} to {} Hz), paired with {against}'s complex modes by MAC at the measured responses. A resonance \
         moved by more than its peak is wide points at stiffness or mass; a peak of the right frequency but the \
         wrong height and width points at damping. Measured and model modes are numbered in frequency order, \
         here and in every figure below.{}",
        short(m.band_hz.0),
        short(m.band_hz.1),
        if within_noise {
            " The model's misfit is within the noise: a reading that points at the model is marked as the modal \
             estimate's."
        } else {
            ""
        }
    )));
    let (header, rows) = mode_table_rows(&m);
    let reading = header.len() - 1;
    let mut t = Table::new(&header);
    for r in rows {
        let bad = !r[reading].starts_with("matches") && !r[reading].contains(WITHIN_NOISE);
        let cells = r
            .into_iter()
            .enumerate()
            .map(|(i, c)| (c, if bad && i == reading { Tone::Bad } else { Tone::Plain }))
            .collect();
        t.row_toned(cells);
    }
    s.push(out.table("modes", t)?);
    for b in figures(c, model, measured, opts, out)? {
        s.push(b);
    }
    Ok(s)
}

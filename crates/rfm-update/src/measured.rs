//! A case's measured data, read as the case says: the file (through the
//! case's map, or its test nodes paired with the model's by coordinates),
//! the channels checked against the model, force-gauge calibrations applied,
//! and the lines cut to the case's band and exclusions. Every command that
//! reads measured data for a case goes through [`read_measured_for`], so
//! that `data =` and `--measured` give the same set.

use std::path::Path;

use damping::DampedSystem;
use fe_model::case::{CalibrationTarget, MeasurementSpec, PairingSpec};
use frf::io::uff::{self, Direction, PairingOptions};
use frf::io::{Measured, MeasuredFormat, ReadOptions};
use frf::{FileError, FrfError};

use crate::error::UpdateError;

/// Reads a measured FRF file for a model with the case's `[measurement]`
/// (none: the file as it is): the channel map or the pairing by coordinates,
/// the mask rules, the calibrations, the band and the exclusions; checks
/// that every channel is at a free DOF of the model (or leaves it out where
/// the mask allows). The set keeps the file's kind. What was changed is in
/// [`Measured::notes`], what was left out in [`Measured::masked`].
pub fn read_measured_for(
    system: &DampedSystem,
    path: &Path,
    spec: Option<&MeasurementSpec>,
) -> Result<Measured, UpdateError> {
    let (map, mask) = spec.map_or((&[][..], &[][..]), |s| (&s.map[..], &s.mask[..]));
    // a CSV file of one unnamed channel (`freq,re,im`) is the case's one channel
    let channel = spec
        .filter(|s| s.references.len() == 1 && s.responses.len() == 1)
        .map(|s| frf::Channel::new(s.responses[0], s.references[0]));
    let measured = match spec.and_then(|s| s.pairing.map(|p| (s, p))) {
        Some((s, p)) => read_paired(system, path, s, &p)?,
        None => {
            let dimension = system.model().dimension();
            frf::io::load_measured_opts(path, &ReadOptions { map, mask, channel, dimension })?
        }
    };
    let mut measured = match spec {
        Some(s) if !s.corrections.is_empty() => correct(measured, path, s)?,
        _ => measured,
    };
    measured = measured.check_channels(path, system.assembly().dofs(), mask)?;
    if let Some(s) = spec {
        calibrate(&mut measured, path, s)?;
        measured = restrict(measured, path, s)?;
    }
    Ok(measured)
}

/// Reads a universal file whose test nodes are paired with the model's by
/// coordinates (`[measurement] pair = "coordinates"`).
fn read_paired(
    system: &DampedSystem,
    path: &Path,
    spec: &MeasurementSpec,
    p: &PairingSpec,
) -> Result<Measured, UpdateError> {
    if frf::io::detect_format(path)? != MeasuredFormat::Uff {
        return Err(UpdateError::Data(format!(
            "{}: `pair = \"coordinates\"` pairs the test nodes of a universal file; a CSV file names model DOFs \
             already",
            path.display()
        )));
    }
    let file = uff::read_uff(path)?;
    let other = spec.geometry.as_deref().map(|g| uff::read_uff(g).map(|f| (g, f))).transpose()?;
    let (geo_path, geo_file) = match &other {
        Some((g, f)) => (*g, f),
        None => (path, &file),
    };
    let geometry = geo_file
        .geometry()
        .map_err(|(line, message)| FrfError::File(FileError::Parse { path: geo_path.to_path_buf(), line, message }))?;
    if geometry.nodes.is_empty() {
        return Err(UpdateError::Frf(FrfError::File(FileError::Parse {
            path: geo_path.to_path_buf(),
            line: 1,
            message: "`pair = \"coordinates\"`, but the file holds no node coordinates (datasets 15 or 2411); \
                      export the geometry with the FRFs, name a `geometry` file, or map the test points with \
                      [[measurement.map]]"
                .into(),
        })));
    }
    let mut used: Vec<i64> = Vec::new();
    for r in &file.records {
        for d in [r.function.header.response, r.function.header.reference] {
            if !used.contains(&d.node) {
                used.push(d.node);
            }
        }
    }
    let model: Vec<(u32, [f64; 3])> = system.model().nodes().iter().map(|n| (n.id.0, n.position())).collect();
    let axis = |c: i8| Direction::from_code(i64::from(c)).unwrap_or(Direction::X);
    let opts = PairingOptions {
        tolerance_m: p.tolerance_m,
        axes: [axis(p.axes[0]), axis(p.axes[1])],
        dimension: system.model().dimension(),
    };
    let (pairing, paired, notes) = uff::pair_by_coordinates(&geometry, &used, &model, &opts, &spec.map);
    let frfs = uff::frfs_from_uff_mapped(path, &file, &spec.mask, &|d| pairing.map(d))?;
    let mut measured = frfs.into_measured();
    let from = if other.is_some() { format!(" (geometry from {})", geo_path.display()) } else { String::new() };
    measured.notes.extend(geometry.notes.iter().map(|n| format!("geometry: {n}")));
    measured.notes.extend(notes);
    measured.notes.push(format!(
        "paired {} test node(s) with model nodes by coordinates within {} mm{from}: {}",
        paired.len(),
        p.tolerance_m * 1e3,
        paired.iter().map(|n| format!("{} -> {}", n.test_node, n.model_node)).collect::<Vec<_>>().join(", ")
    ));
    measured.pairing = paired;
    Ok(frf::io::check_not_empty(path, measured)?)
}

/// Applies the case's corrections of set-up errors
/// (`[[measurement.corrections]]`): each matched channel multiplied by its
/// sign and scale, and moved to the DOF its sensor measured. A correction
/// that matches no channel, or moves one onto a channel the data hold
/// already, is refused where it is written.
fn correct(mut measured: Measured, path: &Path, spec: &MeasurementSpec) -> Result<Measured, UpdateError> {
    // matched by the names the data give them, whatever an earlier
    // correction renamed (two swapped channels name each other)
    let original: Vec<frf::Channel> = measured.set.channels().to_vec();
    let mut names = original.clone();
    for fix in &spec.corrections {
        let hits: Vec<usize> =
            (0..original.len()).filter(|&c| fix.applies_to(original[c].response, original[c].reference)).collect();
        if hits.is_empty() {
            return Err(UpdateError::Case(fix.place.with_message(format!(
                "the correction of `{}` applies to no channel of {}",
                fix.response,
                path.display()
            ))));
        }
        for &c in &hits {
            for v in measured.set.channel_mut(c) {
                *v *= fix.sign * fix.scale;
            }
            names[c].response = fix.corrected_response();
        }
        let what: Vec<String> = [
            (fix.sign < 0.0).then(|| "sign inverted".to_string()),
            (fix.scale != 1.0).then(|| format!("scaled by {}", fix.scale)),
            fix.measured_at.map(|d| format!("moved to {d}, where its sensor was")),
        ]
        .into_iter()
        .flatten()
        .collect();
        measured.notes.push(format!(
            "{} channel(s) at {} corrected as the case says: {}",
            hits.len(),
            fix.response,
            what.join(", ")
        ));
    }
    measured.set.rename_channels(names).map_err(|e| {
        let first = spec.corrections.iter().find(|c| c.measured_at.is_some()).unwrap_or(&spec.corrections[0]);
        UpdateError::Case(first.place.with_message(format!("after the corrections, {}: {e}", path.display())))
    })?;
    Ok(measured)
}

/// Multiplies per-volt channels by the sensitivity of the force gauge the
/// case gives for their reference (`H_N = H_V s`, `s` in V/N). A
/// calibration that matches no channel, or one whose channels are per
/// newton already, is refused where it is written.
fn calibrate(measured: &mut Measured, path: &Path, spec: &MeasurementSpec) -> Result<(), UpdateError> {
    for cal in &spec.calibration {
        let matches = |c: usize| {
            let ch = measured.set.channels()[c];
            match cal.target {
                CalibrationTarget::Model(d) => ch.reference == d,
                CalibrationTarget::Test(node, axis) => {
                    measured.units[c].test_reference.is_some_and(|t| t.node == node && t.direction.code().abs() == axis)
                }
            }
        };
        let hits: Vec<usize> = (0..measured.set.channels().len()).filter(|&c| matches(c)).collect();
        if hits.is_empty() {
            return Err(UpdateError::Case(cal.place.with_message(format!(
                "calibration of `{}` applies to no channel of {} (its references: {})",
                cal.target,
                path.display(),
                measured.set.references().iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
            ))));
        }
        if let Some(&c) = hits.iter().find(|&&c| !measured.units[c].per_volt) {
            return Err(UpdateError::Case(cal.place.with_message(format!(
                "calibration of `{}`: the FRF {} of {} is per newton already ({}); a calibration would scale it a \
                 second time",
                cal.target,
                measured.set.channels()[c],
                path.display(),
                measured.units[c].basis
            ))));
        }
        for &c in &hits {
            for v in measured.set.channel_mut(c) {
                *v *= cal.volts_per_newton;
            }
            measured.units[c].per_volt = false;
        }
        measured.notes.push(format!(
            "{} channel(s) of reference {} multiplied by the force gauge's {} ({} V/N, calibration of `{}`): per \
             volt to per newton",
            hits.len(),
            measured.set.channels()[hits[0]].reference,
            cal.text,
            cal.volts_per_newton,
            cal.target
        ));
    }
    Ok(())
}

/// Keeps the lines the case uses: its `frequencies` (each must be a line of
/// the data), within its `band`, outside its `exclude` bands.
fn restrict(measured: Measured, path: &Path, spec: &MeasurementSpec) -> Result<Measured, UpdateError> {
    let f = measured.set.frequencies_hz().to_vec();
    let n = f.len();
    let span = |f: &[f64]| match (f.first(), f.last()) {
        (Some(a), Some(b)) => format!("{a} to {b} Hz"),
        _ => "none".into(),
    };
    let mut keep: Vec<usize> = (0..n).collect();
    let mut notes = Vec::new();
    if !spec.frequencies_hz.is_empty() {
        let mut idx = Vec::with_capacity(spec.frequencies_hz.len());
        let mut masked_out = Vec::new();
        for &x in &spec.frequencies_hz {
            // a line the case's mask left out is not used, as the mask says, and listed
            if measured.set.line_of(x).is_none()
                && measured.masked.iter().any(|m| m.freq_hz.is_some_and(|f| (f - x).abs() <= 1e-9 * x.abs().max(1.0)))
            {
                masked_out.push(x);
                continue;
            }
            let k = measured.set.line_of(x).ok_or_else(|| {
                let nearest = f.iter().copied().min_by(|a, b| (a - x).abs().total_cmp(&(b - x).abs()));
                let msg = format!(
                    "{x} Hz is not a line of {} (nearest {} Hz); with a data file, `frequencies` chooses lines of \
                     the data: leave it out to use them all, or restrict them with `band`",
                    path.display(),
                    nearest.map_or("-".to_string(), |v| v.to_string())
                );
                match &spec.frequencies_place {
                    Some(p) => UpdateError::Case(p.with_message(msg)),
                    None => UpdateError::Data(msg),
                }
            })?;
            idx.push(k);
        }
        if !masked_out.is_empty() {
            let list: Vec<String> = masked_out.iter().map(|x| format!("{x}")).collect();
            notes.push(format!("`frequencies` names {} Hz, which the mask left out", list.join(", ")));
        }
        if idx.len() < n {
            notes.push(format!("used the {} lines the case's `frequencies` name, of the data's {n}", idx.len()));
        }
        keep = idx;
    }
    if let Some((lo, hi)) = spec.band {
        let before = keep.len();
        keep.retain(|&k| lo <= f[k] && f[k] <= hi);
        if keep.is_empty() {
            let msg = format!("the band {lo} to {hi} Hz holds none of the data's lines ({})", span(&f));
            return Err(match &spec.band_place {
                Some(p) => UpdateError::Case(p.with_message(msg)),
                None => UpdateError::Data(msg),
            });
        }
        if keep.len() < before {
            notes.push(format!(
                "kept the {} lines within the case's band {lo} to {hi} Hz, of {before} ({})",
                keep.len(),
                span(&f)
            ));
        }
    }
    for &(lo, hi) in &spec.exclude {
        let before = keep.len();
        keep.retain(|&k| !(lo <= f[k] && f[k] <= hi));
        if keep.len() < before {
            notes.push(format!("left out {} line(s) in the excluded band {lo} to {hi} Hz", before - keep.len()));
        }
    }
    if keep.is_empty() {
        return Err(UpdateError::Data(format!(
            "{}: the case's band and exclusions leave no line of the data ({})",
            path.display(),
            span(&f)
        )));
    }
    if keep.len() == n {
        return Ok(measured);
    }
    let set = measured.set.select_lines(&keep)?;
    let mut out = Measured { set, ..measured };
    out.notes.extend(notes);
    Ok(out)
}

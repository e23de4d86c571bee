//! Writing dataset 58 (ASCII and binary 58b) in the fixed-width layout of
//! the format: records 1-11 exactly as test systems and pyuff read them
//! (column positions of every field), the data in 13- and 20-column fields.
//!
//! Every `E` field keeps its width and at least one leading blank, and holds
//! as many digits as fit (`E13.6`/`E20.13` for non-negative numbers,
//! `E13.5`/`E20.12` for negative ones), so that readers that split at blanks
//! and readers that cut columns both work, and frequencies keep 7
//! significant digits.

use std::path::{Path, PathBuf};

use super::read::values_per_point;
use super::{
    Abscissa, DataAxis, Encoding, FUNCTION_COHERENCE, FUNCTION_FRF, Function58, Header58, OrdinateType, Ordinates,
    model_to_test_dof,
};
use crate::error::{FileError, FrfError};
use crate::set::{FrfKind, FrfSet};

const FORMAT: &str = "UFF dataset 58";

/// How the writer lays out the frequency lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Spacing {
    /// Even (start and increment in record 7) when the lines are evenly
    /// spaced and record 7's 7 significant digits reproduce every line to
    /// 1e-9; uneven otherwise.
    #[default]
    Auto,
    /// Even; an error if the lines are not evenly spaced.
    Even,
    /// Uneven: every line written beside its value.
    Uneven,
}

/// Options of [`write_uff`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UffWriteOptions {
    /// ASCII (default) or binary 58b.
    pub encoding: Encoding,
    /// Complex double (default) or complex single. FRFs are complex: real
    /// types are refused. Coherence is written real with the same precision.
    pub ordinate_type: OrdinateType,
    /// Even or uneven abscissa.
    pub spacing: Spacing,
}

impl Default for UffWriteOptions {
    fn default() -> Self {
        UffWriteOptions {
            encoding: Encoding::Ascii,
            ordinate_type: OrdinateType::ComplexDouble,
            spacing: Spacing::Auto,
        }
    }
}

/// Writes a set as dataset 58 records (one per channel, each followed by its
/// coherence when the set has it), atomically; refuses to replace any of
/// `inputs`.
pub fn write_uff(set: &FrfSet, path: &Path, options: &UffWriteOptions, inputs: &[PathBuf]) -> Result<(), FrfError> {
    let bytes = to_uff_bytes(set, options)?;
    crate::io::atomic_write(path, &bytes, inputs)
}

/// The bytes [`write_uff`] writes.
pub fn to_uff_bytes(set: &FrfSet, options: &UffWriteOptions) -> Result<Vec<u8>, FrfError> {
    encode(&frf_set_to_functions(set, options)?, options.encoding)
}

/// The dataset 58 functions of a set: an FRF record (function type 4) per
/// channel, response and reference as `+X`, `+Y`, `+RZ` of the model node
/// (the inverse of the default channel mapping), units in SI by kind; and a
/// coherence record (type 6) after each when the set has coherence.
pub fn frf_set_to_functions(set: &FrfSet, options: &UffWriteOptions) -> Result<Vec<Function58>, FrfError> {
    let unwritable = |message: String| FrfError::File(FileError::Unwritable { format: FORMAT, message });
    if !options.ordinate_type.is_complex() {
        return Err(unwritable(format!(
            "FRFs are complex; ordinate type {} would drop their imaginary parts (use complex single (5) or \
             complex double (6))",
            options.ordinate_type
        )));
    }
    let f = set.frequencies_hz();
    let abscissa = match (options.spacing, even_spacing(f)) {
        (Spacing::Uneven, _) => Abscissa::Uneven(f.to_vec()),
        (Spacing::Even, Some((min, step))) => Abscissa::Even { min, step },
        (Spacing::Even, None) => {
            return Err(unwritable("the frequency lines are not evenly spaced; write them uneven".into()));
        }
        (Spacing::Auto, Some((min, step))) if reproduces(f, min, step) => Abscissa::Even { min, step },
        (Spacing::Auto, _) => Abscissa::Uneven(f.to_vec()),
    };
    let real_type = if options.ordinate_type.is_double() { OrdinateType::RealDouble } else { OrdinateType::RealSingle };
    let kind = set.kind();
    let (numerator_type, label, per_time) = match kind {
        FrfKind::Receptance => (8, "Displacement", ""),
        FrfKind::Mobility => (11, "Velocity", "/s"),
        FrfKind::Accelerance => (12, "Acceleration", "/s^2"),
    };
    let mut out = Vec::new();
    for (c, ch) in set.channels().iter().enumerate() {
        let response = model_to_test_dof(ch.response);
        let reference = model_to_test_dof(ch.reference);
        let (num_label, num_units) = if ch.response.dof.is_translation() {
            (label.to_string(), format!("m{per_time}"))
        } else {
            (format!("Angular {}", label.to_ascii_lowercase()), format!("rad{per_time}"))
        };
        let denominator = if ch.reference.dof.is_translation() {
            DataAxis::new(13, "Force", "N")
        } else {
            DataAxis::new(13, "Moment", "N*m")
        };
        let header = Header58 {
            ids: [format!("{ch} {kind}"), "written by rfm".into(), "NONE".into(), "NONE".into(), "NONE".into()],
            function_type: FUNCTION_FRF,
            function_id: i64::try_from(c + 1).unwrap_or(0),
            version: 0,
            load_case: 0,
            response_entity: "NONE".into(),
            response,
            reference_entity: "NONE".into(),
            reference,
            ordinate_type: options.ordinate_type,
            z_value: 0.0,
            abscissa_axis: DataAxis::new(18, "Frequency", "Hz"),
            numerator: DataAxis::new(numerator_type, &num_label, &num_units),
            denominator,
            z_axis: DataAxis::none(),
        };
        out.push(Function58 {
            header: header.clone(),
            abscissa: abscissa.clone(),
            ordinates: Ordinates::Complex(set.channel(c).to_vec()),
        });
        if let Some(coh) = set.coherence(c) {
            out.push(Function58 {
                header: Header58 {
                    ids: [
                        format!("{ch} coherence"),
                        header.ids[1].clone(),
                        "NONE".into(),
                        "NONE".into(),
                        "NONE".into(),
                    ],
                    function_type: FUNCTION_COHERENCE,
                    ordinate_type: real_type,
                    numerator: DataAxis::new(0, "Coherence", "NONE"),
                    denominator: DataAxis::none(),
                    ..header
                },
                abscissa: abscissa.clone(),
                ordinates: Ordinates::Real(coh.to_vec()),
            });
        }
    }
    Ok(out)
}

/// Start and increment when the lines are evenly spaced (to 1e-9 of the
/// largest), with at least two lines.
fn even_spacing(f: &[f64]) -> Option<(f64, f64)> {
    let (&first, &last) = (f.first()?, f.last()?);
    if f.len() < 2 {
        return None;
    }
    let step = (last - first) / (f.len() - 1) as f64;
    let tol = 1e-9 * first.abs().max(last.abs());
    f.iter().enumerate().all(|(k, &x)| (first + k as f64 * step - x).abs() <= tol).then_some((first, step))
}

/// Whether start and increment, as written in record 7, give back every line to 1e-9.
fn reproduces(f: &[f64], min: f64, step: f64) -> bool {
    let back = |x: f64| fmt_e(x, 13).trim().parse::<f64>().unwrap_or(f64::NAN);
    let (min, step) = (back(min), back(step));
    let tol = 1e-9 * f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    f.iter().enumerate().all(|(k, &x)| (min + k as f64 * step - x).abs() <= tol)
}

/// Encodes functions as dataset 58 records, all in one encoding.
pub fn encode(functions: &[Function58], encoding: Encoding) -> Result<Vec<u8>, FrfError> {
    let mut out = Vec::new();
    for (i, f) in functions.iter().enumerate() {
        encode_one(&mut out, f, encoding).map_err(|m| {
            FrfError::File(FileError::Unwritable { format: FORMAT, message: format!("function {}: {m}", i + 1) })
        })?;
    }
    Ok(out)
}

fn encode_one(out: &mut Vec<u8>, f: &Function58, encoding: Encoding) -> Result<(), String> {
    let h = &f.header;
    let t = h.ordinate_type;
    let n = f.len();
    match (&f.ordinates, t.is_complex()) {
        (Ordinates::Complex(_), true) | (Ordinates::Real(_), false) => {}
        _ => {
            return Err(format!(
                "ordinate type {t} does not match the {} values",
                if t.is_complex() { "real" } else { "complex" }
            ));
        }
    }
    let (even, min, step) = match &f.abscissa {
        Abscissa::Even { min, step } => (true, *min, *step),
        Abscissa::Uneven(x) if x.len() == n => (false, 0.0, 0.0),
        Abscissa::Uneven(x) => return Err(format!("{} abscissa values for {n} ordinates", x.len())),
    };
    let mut numbers: Vec<f64> = Vec::with_capacity(n * values_per_point(t, !even));
    for k in 0..n {
        if let Abscissa::Uneven(x) = &f.abscissa {
            numbers.extend(x.get(k));
        }
        match &f.ordinates {
            Ordinates::Complex(v) => numbers.extend(v.get(k).iter().flat_map(|z| [z.re, z.im])),
            Ordinates::Real(v) => numbers.extend(v.get(k)),
        }
    }
    if !t.is_double() {
        for x in &mut numbers {
            *x = f64::from(*x as f32);
        }
    }
    let per = values_per_point(t, !even);
    if let Some(i) = numbers.iter().position(|x| !x.is_finite()) {
        let precision = if t.is_double() { "" } else { " in single precision" };
        return Err(format!("value {} of the data is not finite{precision} ({})", i / per + 1, numbers[i]));
    }
    for (x, what) in [(min, "abscissa start"), (step, "abscissa increment"), (h.z_value, "z-axis value")] {
        if !x.is_finite() {
            return Err(format!("{what} {x} is not finite"));
        }
    }

    let mut text = String::new();
    text.push_str("    -1\n");
    let size = t.number_size();
    match encoding {
        Encoding::Ascii => text.push_str(&format!("{:>6}{:74}\n", 58, "")),
        Encoding::Binary { big_endian } => text.push_str(&format!(
            "{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}\n",
            58,
            if big_endian { 2 } else { 1 },
            2,
            11,
            numbers.len() * size,
            0,
            0,
            0,
            0
        )),
    }
    for id in &h.ids {
        text.push_str(&alpha(id, 80));
        text.push('\n');
    }
    text.push_str(&format!(
        "{}{}{}{} {}{}{} {}{}{}\n",
        int(h.function_type, 5, "function type")?,
        int(h.function_id, 10, "function id")?,
        int(h.version, 5, "version number")?,
        int(h.load_case, 10, "load case")?,
        alpha(&h.response_entity, 10),
        int(h.response.node, 10, "response node")?,
        int(i64::from(h.response.direction.code()), 4, "response direction")?,
        alpha(&h.reference_entity, 10),
        int(h.reference.node, 10, "reference node")?,
        int(i64::from(h.reference.direction.code()), 4, "reference direction")?,
    ));
    text.push_str(&format!(
        "{}{}{}{}{}{}\n",
        int(t.code(), 10, "ordinate data type")?,
        int(i64::try_from(n).unwrap_or(i64::MAX), 10, "number of values")?,
        int(i64::from(even), 10, "spacing")?,
        fmt_e(min, 13),
        fmt_e(step, 13),
        fmt_e(h.z_value, 13)
    ));
    for (axis, record) in [(&h.abscissa_axis, 8), (&h.numerator, 9), (&h.denominator, 10), (&h.z_axis, 11)] {
        let what = |s: &str| format!("record {record}: {s}");
        text.push_str(&format!(
            "{}{}{}{} {} {}\n",
            int(axis.specific_type, 10, &what("specific data type"))?,
            int(axis.length_exp, 5, &what("length exponent"))?,
            int(axis.force_exp, 5, &what("force exponent"))?,
            int(axis.temperature_exp, 5, &what("temperature exponent"))?,
            alpha(&axis.label, 20),
            alpha(&axis.units, 20),
        ));
    }
    match encoding {
        Encoding::Ascii => {
            let widths = field_widths(t, even);
            for (i, &x) in numbers.iter().enumerate() {
                let w = widths.get(i % widths.len()).copied().unwrap_or(20);
                text.push_str(&fmt_e(x, w));
                if (i + 1).is_multiple_of(widths.len()) {
                    text.push('\n');
                }
            }
            if !numbers.len().is_multiple_of(widths.len()) {
                text.push('\n');
            }
            text.push_str("    -1\n");
            out.extend_from_slice(text.as_bytes());
        }
        Encoding::Binary { big_endian } => {
            out.extend_from_slice(text.as_bytes());
            for &x in &numbers {
                match (size, big_endian) {
                    (4, false) => out.extend_from_slice(&(x as f32).to_le_bytes()),
                    (4, true) => out.extend_from_slice(&(x as f32).to_be_bytes()),
                    (_, false) => out.extend_from_slice(&x.to_le_bytes()),
                    (_, true) => out.extend_from_slice(&x.to_be_bytes()),
                }
            }
            // no line break before the closing -1: pyuff reads everything up to it as data
            out.extend_from_slice(b"    -1\n");
        }
    }
    Ok(())
}

/// Column widths of one data line (record 12) by type and spacing.
fn field_widths(t: OrdinateType, even: bool) -> &'static [usize] {
    match (t, even) {
        (OrdinateType::RealSingle | OrdinateType::ComplexSingle, _) => &[13; 6],
        (OrdinateType::RealDouble | OrdinateType::ComplexDouble, true) => &[20; 4],
        (OrdinateType::RealDouble, false) => &[13, 20, 13, 20],
        (OrdinateType::ComplexDouble, false) => &[13, 20, 20],
    }
}

/// An integer right-aligned in `width` columns, or an error if it does not fit.
fn int(v: i64, width: usize, what: &str) -> Result<String, String> {
    let s = format!("{v:>width$}");
    if s.len() > width { Err(format!("{what} {v} does not fit in {width} columns")) } else { Ok(s) }
}

/// Text left-aligned in `width` columns: non-ASCII and control characters
/// become `?` (the format is ASCII), longer text is cut.
fn alpha(s: &str, width: usize) -> String {
    let clean: String =
        s.chars().map(|c| if c.is_ascii() && !c.is_ascii_control() { c } else { '?' }).take(width).collect();
    format!("{clean:<width$}")
}

/// `x` in `width` columns in Fortran `E` form (`1.234567E+01`) with as many
/// digits as fit beside one leading blank.
pub(super) fn fmt_e(x: f64, width: usize) -> String {
    let mut p = width.saturating_sub(7);
    loop {
        let s = sci(x, p);
        if s.len() < width || p == 0 {
            return format!("{s:>width$}");
        }
        p -= 1;
    }
}

fn sci(x: f64, p: usize) -> String {
    let s = format!("{x:.p$E}");
    match s.split_once('E') {
        Some((m, e)) => {
            let e: i32 = e.parse().unwrap_or(0);
            format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
        }
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn e_fields_keep_width_and_a_leading_blank() {
        assert_eq!(fmt_e(1.0, 13), " 1.000000E+00");
        assert_eq!(fmt_e(-1.0, 13), " -1.00000E+00");
        assert_eq!(fmt_e(0.1953125, 13), " 1.953125E-01");
        assert_eq!(fmt_e(0.0, 13), " 0.000000E+00");
        assert_eq!(fmt_e(-2.5e-7, 20), " -2.500000000000E-07");
        assert_eq!(fmt_e(123.456, 20), " 1.2345600000000E+02");
        assert_eq!(fmt_e(1e-300, 13), " 1.00000E-300");
        assert_eq!(fmt_e(-1e-300, 20), " -1.00000000000E-300");
        for w in [13, 20] {
            for x in [1.0, -1.0, 1e-300, -1e300, 0.0] {
                let s = fmt_e(x, w);
                assert_eq!(s.len(), w, "{s}");
                assert!(s.starts_with(' '), "{s}");
            }
        }
    }

    #[test]
    fn even_spacing_needs_uniform_lines_that_record_7_reproduces() {
        assert_eq!(even_spacing(&[1.0, 1.5, 2.0]), Some((1.0, 0.5)));
        assert_eq!(even_spacing(&[1.0, 1.5, 2.1]), None);
        assert_eq!(even_spacing(&[1.0]), None);
        let f: Vec<f64> = (1..=2000).map(|k| 0.1953125 * f64::from(k)).collect();
        assert!(reproduces(&f, f[0], 0.1953125));
        let f: Vec<f64> = (1..=2000).map(|k| f64::from(k) / 3.0).collect();
        assert!(!reproduces(&f, f[0], 1.0 / 3.0));
    }
}

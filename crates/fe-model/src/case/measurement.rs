//! The `[measurement]` table of a case file: which channels are measured,
//! where the data come from, and how to read them (the map of test points,
//! masks, the band and excluded lines, gains, calibrations, pairing by
//! coordinates). See `docs/case-files.md` and `docs/measured-data.md`.
//!
//! The value types with their syntaxes have a file each: `gains.rs`,
//! `calibration.rs` (with the units of a sensitivity), `mask.rs` and
//! `channel_map.rs`.

mod calibration;
mod channel_map;
mod correction;
mod gains;
mod mask;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use super::{Ctx, hint, parse_dof_refs, parse_frequencies};
use crate::dof::DofRef;
use crate::error::CaseError;
use crate::model::Model;

pub use calibration::{Calibration, CalibrationTarget};
pub use channel_map::ChannelMap;
pub use correction::ChannelCorrection;
pub use gains::{FittedGain, GainKey, Gains};
pub use mask::MaskRule;

use calibration::{calibration_target, sensitivity};
use correction::{RawCorrection, parse_corrections};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMeasurement {
    frequencies: Option<Spanned<toml::Value>>,
    references: Vec<Spanned<String>>,
    responses: Vec<Spanned<String>>,
    data: Option<Spanned<String>>,
    #[serde(default)]
    map: Vec<Spanned<RawChannelMap>>,
    #[serde(default)]
    mask: Vec<Spanned<String>>,
    band: Option<Spanned<Vec<f64>>>,
    #[serde(default)]
    exclude: Vec<Spanned<Vec<f64>>>,
    gains: Option<Spanned<String>>,
    #[serde(default)]
    calibration: BTreeMap<String, Spanned<String>>,
    pair: Option<Spanned<String>>,
    tolerance: Option<Spanned<f64>>,
    axes: Option<Spanned<Vec<String>>>,
    geometry: Option<Spanned<String>>,
    coherence_threshold: Option<Spanned<f64>>,
    #[serde(default)]
    fitted_gains: BTreeMap<String, Spanned<Vec<f64>>>,
    #[serde(default)]
    corrections: Vec<Spanned<RawCorrection>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawChannelMap {
    test: Spanned<String>,
    model: Spanned<String>,
    #[serde(default = "super::one")]
    sign: f64,
}

/// Where the measured FRFs come from and which channels they hold.
#[derive(Clone, Debug)]
pub struct MeasurementSpec {
    /// Frequency lines (Hz): those synthesised from a truth, or, with a
    /// data file, the measured lines to use (each must be one). Empty when
    /// the case gives none (allowed with a data file: every line is used).
    pub frequencies_hz: Vec<f64>,
    /// Where `frequencies` is written, for messages about it
    /// ([`CaseError::with_message`]).
    pub frequencies_place: Option<CaseError>,
    /// Excitation DOFs (columns of the FRF matrix).
    pub references: Vec<DofRef>,
    /// Response DOFs (rows).
    pub responses: Vec<DofRef>,
    /// Measured data file (resolved relative to the case file), if any.
    pub data: Option<PathBuf>,
    /// Where the `[measurement]` table starts, for messages about it (a
    /// measurement without `data` in a case without `[truth]`: the lines
    /// and channels `rfm simulate` writes, which no command comparing with
    /// a test can read; see [`crate::CaseFile::measured_source`]).
    pub place: Option<CaseError>,
    /// Test (node, direction) to model DOF mapping for measured files.
    pub map: Vec<ChannelMap>,
    /// What to leave out of the measured data instead of refusing it
    /// (`mask = ["non-finite", ...]`); empty: refuse every defect.
    pub mask: Vec<MaskRule>,
    /// The band every command uses (`band = [from, to]`, Hz); lines outside
    /// it are left out, with a note.
    pub band: Option<(f64, f64)>,
    /// Where `band` is written, for messages about it.
    pub band_place: Option<CaseError>,
    /// Bands left out (`exclude = [[48, 52], ...]`, Hz, edges included).
    pub exclude: Vec<(f64, f64)>,
    /// Unknown complex gains to fit (`gains = "per-reference"`); `None`:
    /// decided by the data (per reference when a reference is a voltage).
    pub gains: Option<Gains>,
    /// Where `gains` is written, for messages about it.
    pub gains_place: Option<CaseError>,
    /// Force-gauge sensitivities that turn per-volt FRFs into per-newton ones.
    pub calibration: Vec<Calibration>,
    /// Pairing of test nodes with model nodes by coordinates (`pair =
    /// "coordinates"`); `None`: by node numbers and the map.
    pub pairing: Option<PairingSpec>,
    /// The file with the test geometry (datasets 15/2411), resolved; `None`:
    /// the data file itself.
    pub geometry: Option<PathBuf>,
    /// Coherence below which a line counts as poor (shaded in the overlays).
    pub coherence_threshold: f64,
    /// Gains an earlier update fitted (written by rfm, read for reports).
    pub fitted_gains: Vec<FittedGain>,
    /// Set-up errors of the test corrected after reading
    /// (`[[measurement.corrections]]`: an inverted sensor, a wrong
    /// sensitivity, a sensor at another DOF).
    pub corrections: Vec<ChannelCorrection>,
}

impl MeasurementSpec {
    /// The channels the case's data hold once corrected: every reference
    /// with every response, a response moved to the DOF a correction says
    /// its sensor measured.
    pub fn channels(&self) -> Vec<(DofRef, DofRef)> {
        self.references
            .iter()
            .flat_map(|&r| {
                self.responses.iter().map(move |&resp| {
                    let at = self
                        .corrections
                        .iter()
                        .find(|c| c.applies_to(resp, r))
                        .map_or(resp, |c| c.corrected_response());
                    (at, r)
                })
            })
            .collect()
    }
}

/// Coherence below which a line counts as poor, unless the case says.
pub const DEFAULT_COHERENCE_THRESHOLD: f64 = 0.8;

/// Pairing of test nodes with model nodes by position (`pair = "coordinates"`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairingSpec {
    /// Largest distance (m) in the model's plane (`tolerance`).
    pub tolerance_m: f64,
    /// The signed test axes (1 X, 2 Y, 3 Z; negative for -) along the
    /// model's x and y (`axes = ["+X", "+Y"]`, the default).
    pub axes: [i8; 2],
}

pub(super) fn parse_measurement(
    ctx: &Ctx<'_>,
    m: &Spanned<RawMeasurement>,
    model: &Model,
) -> Result<MeasurementSpec, CaseError> {
    let r = m.get_ref();
    let frequencies_hz = match &r.frequencies {
        Some(f) => parse_frequencies(ctx, f)?,
        None if r.data.is_some() => Vec::new(),
        None => {
            return Err(ctx.err(
                m.span(),
                "the measurement needs `frequencies` (the lines to synthesise) when it has no `data` file",
            ));
        }
    };
    let references = parse_dof_refs(ctx, &r.references, model)?;
    let responses = parse_dof_refs(ctx, &r.responses, model)?;
    if references.is_empty() || responses.is_empty() {
        return Err(ctx.err(m.span(), "the measurement needs at least one reference and one response"));
    }
    let data = r.data.as_ref().map(|d| resolve(ctx, d.get_ref()));
    let mut map: Vec<ChannelMap> = Vec::new();
    for entry in &r.map {
        let c = entry.get_ref();
        let (node, dir) = ChannelMap::parse_test_point(c.test.get_ref()).map_err(|e| ctx.err(c.test.span(), e))?;
        // One entry per test node and axis: `101:+Z` and `101:-Z` describe the same sensor axis.
        if let Some(prev) = map.iter().find(|m| m.test_point().is_ok_and(|(n, d)| n == node && d.abs() == dir.abs())) {
            return Err(ctx.err(
                c.test.span(),
                format!("test point `{}` is already mapped by `{}`", c.test.get_ref(), prev.test),
            ));
        }
        let model_dof: DofRef = c.model.get_ref().parse().map_err(|e: String| ctx.err(c.model.span(), e))?;
        model.dimension().check(model_dof.dof).map_err(|e| ctx.err(c.model.span(), e))?;
        if model.node(model_dof.node).is_none() {
            return Err(ctx.err(c.model.span(), format!("node {} does not exist in the model", model_dof.node)));
        }
        if c.sign != 1.0 && c.sign != -1.0 {
            return Err(ctx.err(entry.span(), "sign must be 1 or -1"));
        }
        map.push(ChannelMap { test: c.test.get_ref().clone(), model: model_dof, sign: c.sign });
    }
    let mut mask: Vec<MaskRule> = Vec::new();
    for m in &r.mask {
        let rule = MaskRule::parse(m.get_ref()).ok_or_else(|| {
            let hint = hint(m.get_ref(), &MaskRule::ALL.map(MaskRule::name), "available");
            ctx.err(m.span(), format!("unknown mask `{}`{hint}", m.get_ref()))
        })?;
        if mask.contains(&rule) {
            return Err(ctx.err(m.span(), format!("mask `{rule}` is listed twice")));
        }
        mask.push(rule);
    }
    if !mask.is_empty() && r.data.is_none() {
        return Err(
            ctx.err(r.mask[0].span(), "`mask` applies to a measured `data` file, and this measurement has none")
        );
    }
    let band = r.band.as_ref().map(|b| parse_band(ctx, b)).transpose()?;
    let exclude = r.exclude.iter().map(|b| parse_band(ctx, b)).collect::<Result<Vec<_>, _>>()?;
    let gains = r
        .gains
        .as_ref()
        .map(|g| {
            Gains::parse(g.get_ref()).ok_or_else(|| {
                let hint = hint(g.get_ref(), &Gains::ALL.map(Gains::name), "available");
                ctx.err(g.span(), format!("unknown gains `{}`{hint}", g.get_ref()))
            })
        })
        .transpose()?;
    let mut calibration = Vec::new();
    for (key, v) in &r.calibration {
        let target = calibration_target(key).map_err(|e| ctx.err(v.span(), e))?;
        if let CalibrationTarget::Model(d) = target
            && !references.contains(&d)
        {
            return Err(ctx.err(v.span(), format!("calibration of `{key}`, which is not one of the references")));
        }
        let volts_per_newton = sensitivity(v.get_ref()).map_err(|e| ctx.err(v.span(), e))?;
        let place = ctx.err(v.span(), "");
        calibration.push(Calibration { target, volts_per_newton, text: v.get_ref().trim().to_string(), place });
    }
    let pairing = match r.pair.as_ref().map(|p| (p.get_ref().trim(), p.span())) {
        None | Some(("numbers", _)) => {
            if let Some(t) = &r.tolerance {
                return Err(ctx.err(t.span(), "`tolerance` applies to `pair = \"coordinates\"`"));
            }
            if let Some(a) = &r.axes {
                return Err(ctx.err(a.span(), "`axes` applies to `pair = \"coordinates\"`"));
            }
            None
        }
        Some(("coordinates", span)) => {
            let t = r.tolerance.as_ref().ok_or_else(|| {
                ctx.err(span.clone(), "`pair = \"coordinates\"` needs a `tolerance` (m), e.g. `tolerance = 0.005`")
            })?;
            if !(*t.get_ref() > 0.0 && t.get_ref().is_finite()) {
                return Err(
                    ctx.err(t.span(), format!("tolerance must be positive and finite (m), got {}", t.get_ref()))
                );
            }
            let axes = match &r.axes {
                None => [1, 2],
                Some(a) => parse_axes(a.get_ref()).map_err(|e| ctx.err(a.span(), e))?,
            };
            Some(PairingSpec { tolerance_m: *t.get_ref(), axes })
        }
        Some((other, span)) => {
            return Err(ctx.err(span, format!("unknown pairing `{other}` (available: numbers, coordinates)")));
        }
    };
    let geometry = r.geometry.as_ref().map(|g| {
        if pairing.is_none() {
            return Err(
                ctx.err(g.span(), "`geometry` is read to pair nodes by coordinates: add `pair = \"coordinates\"`")
            );
        }
        Ok(resolve(ctx, g.get_ref()))
    });
    let geometry = geometry.transpose()?;
    let coherence_threshold = match &r.coherence_threshold {
        None => DEFAULT_COHERENCE_THRESHOLD,
        Some(c) if (0.0..=1.0).contains(c.get_ref()) => *c.get_ref(),
        Some(c) => return Err(ctx.err(c.span(), format!("coherence_threshold must lie in 0..1, got {}", c.get_ref()))),
    };
    let mut fitted_gains = Vec::new();
    for (key, v) in &r.fitted_gains {
        let key: GainKey = key.parse().map_err(|e: String| ctx.err(v.span(), e))?;
        match v.get_ref()[..] {
            [magnitude, phase_deg] if magnitude > 0.0 && magnitude.is_finite() && phase_deg.is_finite() => {
                fitted_gains.push(FittedGain { key, magnitude, phase_deg });
            }
            _ => {
                return Err(ctx.err(
                    v.span(),
                    "a fitted gain is [magnitude, phase in degrees] with a positive, finite magnitude",
                ));
            }
        }
    }
    let corrections =
        parse_corrections(&|span, message| ctx.err(span, message), &r.corrections, model, &responses, &references)?;
    if r.data.is_none() {
        let data_only: [(&str, Option<Range<usize>>); 5] = [
            ("band", r.band.as_ref().map(Spanned::span)),
            ("exclude", r.exclude.first().map(Spanned::span)),
            ("calibration", r.calibration.values().next().map(Spanned::span)),
            ("pair", r.pair.as_ref().map(Spanned::span)),
            ("corrections", r.corrections.first().map(Spanned::span)),
        ];
        if let Some((key, Some(span))) = data_only.into_iter().find(|(_, s)| s.is_some()) {
            return Err(
                ctx.err(span, format!("`{key}` applies to a measured `data` file, and this measurement has none"))
            );
        }
    }
    Ok(MeasurementSpec {
        frequencies_hz,
        frequencies_place: r.frequencies.as_ref().map(|f| ctx.err(f.span(), "")),
        references,
        responses,
        data,
        place: Some(ctx.err(m.span(), "")),
        map,
        mask,
        band,
        band_place: r.band.as_ref().map(|b| ctx.err(b.span(), "")),
        exclude,
        gains,
        gains_place: r.gains.as_ref().map(|g| ctx.err(g.span(), "")),
        calibration,
        pairing,
        geometry,
        coherence_threshold,
        fitted_gains,
        corrections,
    })
}

/// A path relative to the case file's folder.
fn resolve(ctx: &Ctx<'_>, p: &str) -> PathBuf {
    let p = Path::new(p);
    if p.is_absolute() { p.to_path_buf() } else { ctx.path.parent().unwrap_or(Path::new(".")).join(p) }
}

/// `[from, to]` in Hz, `0 <= from < to`, finite.
fn parse_band(ctx: &Ctx<'_>, b: &Spanned<Vec<f64>>) -> Result<(f64, f64), CaseError> {
    match b.get_ref()[..] {
        [lo, hi] if lo >= 0.0 && hi > lo && hi.is_finite() => Ok((lo, hi)),
        [lo, hi] => Err(ctx.err(b.span(), format!("a band needs 0 <= from < to (Hz), finite; got [{lo}, {hi}]"))),
        _ => Err(ctx.err(b.span(), format!("a band is [from, to] in Hz, got {} numbers", b.get_ref().len()))),
    }
}

/// `["+X", "-Z"]`: two perpendicular test axes (X, Y or Z, optional sign).
fn parse_axes(list: &[String]) -> Result<[i8; 2], String> {
    let one = |s: &str| -> Result<i8, String> {
        let u = s.trim().to_ascii_uppercase();
        let (sign, axis) = match u.strip_prefix('-') {
            Some(a) => (-1, a.to_string()),
            None => (1, u.strip_prefix('+').unwrap_or(&u).to_string()),
        };
        match axis.as_str() {
            "X" => Ok(sign),
            "Y" => Ok(2 * sign),
            "Z" => Ok(3 * sign),
            _ => Err(format!("`{s}` is not a test axis (+X, -X, +Y, -Y, +Z or -Z)")),
        }
    };
    match list {
        [a, b] => {
            let (a, b) = (one(a)?, one(b)?);
            if a.abs() == b.abs() {
                return Err("the model's x and y must lie along two different test axes".into());
            }
            Ok([a, b])
        }
        _ => Err(format!("`axes` names the test axes along the model's x and y: two of them, got {}", list.len())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CaseFile;
    use crate::dof::Dof;

    /// The tests' beam, measured at its tip.
    const MEASUREMENT: &str = r#"[measurement]
references = ["5:uy"]
responses = ["2..5:uy"]
"#;

    fn parse(extra: &str) -> Result<MeasurementSpec, CaseError> {
        let text = format!("{}{MEASUREMENT}{extra}", crate::case::tests::BEAM);
        CaseFile::parse(Path::new("/lab/case.toml"), &text).map(|c| c.measurement.unwrap())
    }

    fn err(extra: &str) -> String {
        parse(extra).unwrap_err().to_string()
    }

    #[test]
    fn with_data_the_frequencies_may_be_left_out_and_band_and_exclusions_read() {
        let m = parse("data = \"m.uff\"\nband = [5, 400.5]\nexclude = [[49.0, 51.0], [99, 101]]\n").unwrap();
        assert!(m.frequencies_hz.is_empty() && m.frequencies_place.is_none());
        assert_eq!(m.band, Some((5.0, 400.5)));
        assert_eq!(m.exclude, vec![(49.0, 51.0), (99.0, 101.0)]);
        assert_eq!(m.data, Some(PathBuf::from("/lab/m.uff")));
        assert_eq!((m.gains, m.coherence_threshold), (None, DEFAULT_COHERENCE_THRESHOLD));
        // without data they are needed, and data-only keys are refused at their place
        let e = err("");
        assert!(e.contains("case.toml:") && e.contains("needs `frequencies`"), "{e}");
        let e = err("frequencies = [10.0]\nband = [1, 2]\n[truth]\n");
        assert!(e.contains(":24:8:") && e.contains("`band` applies to a measured `data` file"), "{e}");
        let e = err("data = \"m.uff\"\nband = [400, 5]\n");
        assert!(e.contains(":24:8:") && e.contains("0 <= from < to"), "{e}");
        let e = err("data = \"m.uff\"\nexclude = [[1, 2, 3]]\n");
        assert!(e.contains("a band is [from, to] in Hz, got 3 numbers"), "{e}");
    }

    #[test]
    fn gains_are_named_and_misspellings_get_a_suggestion() {
        let m = parse("data = \"m.uff\"\ngains = \"per-channel\"\n").unwrap();
        assert_eq!(m.gains, Some(Gains::PerChannel));
        let place = m.gains_place.unwrap().with_message("refused here");
        assert_eq!(place.to_string(), "/lab/case.toml:24:9: refused here");
        let e = err("data = \"m.uff\"\ngains = \"per-refrence\"\n");
        assert!(e.contains(":24:9:") && e.contains("did you mean `per-reference`?"), "{e}");
    }

    #[test]
    fn calibrations_need_units_and_convert_to_volts_per_newton() {
        for (text, want) in [
            ("10.2 mV/N", 0.0102),
            ("0.0102 V/N", 0.0102),
            ("98.0392156862745 N/V", 0.0102),
            ("45.37 mV/lbf", 45.37e-3 / 4.448_221_615_260_5),
            ("10.2mV / kN", 10.2e-6),
        ] {
            let got = sensitivity(text).unwrap();
            assert!((got - want).abs() <= 1e-12 * want, "{text}: {got} vs {want}");
        }
        for (text, why) in
            [("0.0102", "no units"), ("10.2 mV", "quotient"), ("10 m/s", "not volts per force"), ("-1 V/N", "positive")]
        {
            let e = sensitivity(text).unwrap_err();
            assert!(e.contains(why) && e.contains("10.2 mV/N"), "{text}: {e}");
        }
        let m = parse("data = \"m.uff\"\ncalibration = { \"5:uy\" = \"10 mV/N\", \"1:+Z\" = \"2 V/N\" }\n").unwrap();
        let targets: Vec<CalibrationTarget> = m.calibration.iter().map(|c| c.target).collect();
        assert_eq!(targets, vec![CalibrationTarget::Test(1, 3), CalibrationTarget::Model(DofRef::new(5, Dof::Uy))]);
        let e = err("data = \"m.uff\"\ncalibration = { \"5:uy\" = \"0.01\" }\n");
        assert!(e.contains(":24:26:") && e.contains("no units"), "{e}");
        let e = err("data = \"m.uff\"\ncalibration = { \"3:uy\" = \"1 V/N\" }\n");
        assert!(e.contains("not one of the references"), "{e}");
    }

    #[test]
    fn pairing_by_coordinates_needs_a_tolerance_and_two_axes() {
        let m =
            parse("data = \"m.uff\"\npair = \"coordinates\"\ntolerance = 0.005\naxes = [\"+X\", \"-Z\"]\n").unwrap();
        assert_eq!(m.pairing, Some(PairingSpec { tolerance_m: 0.005, axes: [1, -3] }));
        let m = parse("data = \"m.uff\"\npair = \"coordinates\"\ntolerance = 0.005\ngeometry = \"geo/test.unv\"\n")
            .unwrap();
        assert_eq!(m.pairing.unwrap().axes, [1, 2]);
        assert_eq!(m.geometry, Some(PathBuf::from("/lab/geo/test.unv")));
        let e = err("data = \"m.uff\"\npair = \"coordinates\"\n");
        assert!(e.contains("needs a `tolerance`"), "{e}");
        let e = err("data = \"m.uff\"\npair = \"coordinates\"\ntolerance = 0.005\naxes = [\"X\", \"-X\"]\n");
        assert!(e.contains("two different test axes"), "{e}");
        let e = err("data = \"m.uff\"\ntolerance = 0.005\n");
        assert!(e.contains("`tolerance` applies to `pair = \"coordinates\"`"), "{e}");
        let e = err("data = \"m.uff\"\npair = \"positions\"\n");
        assert!(e.contains("unknown pairing `positions`"), "{e}");
    }

    #[test]
    fn corrections_of_set_up_errors_are_read_and_move_the_case_channels() {
        let m = parse(
            "data = \"m.csv\"\n[[measurement.corrections]]\nresponse = \"3:uy\"\nsign = -1\nwhy = \"upside down\"\n\
             [[measurement.corrections]]\nresponse = \"4:uy\"\nreference = \"5:uy\"\nmeasured_at = \"4:ux\"\nscale = 1.25\n",
        )
        .unwrap();
        let c = &m.corrections;
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].response, c[0].reference, c[0].sign, c[0].scale), (DofRef::new(3, Dof::Uy), None, -1.0, 1.0));
        assert_eq!(c[0].why.as_deref(), Some("upside down"));
        assert_eq!((c[1].sign, c[1].scale, c[1].measured_at), (1.0, 1.25, Some(DofRef::new(4, Dof::Ux))));
        assert!(c[1].applies_to(DofRef::new(4, Dof::Uy), DofRef::new(5, Dof::Uy)));
        assert!(!c[1].applies_to(DofRef::new(4, Dof::Uy), DofRef::new(2, Dof::Uy)));
        // the case's channels: the moved one at the DOF its sensor measured
        let uy = |n| DofRef::new(n, Dof::Uy);
        let want = vec![(uy(2), uy(5)), (uy(3), uy(5)), (DofRef::new(4, Dof::Ux), uy(5)), (uy(5), uy(5))];
        assert_eq!(m.channels(), want);

        let bad = |entry: &str| err(&format!("data = \"m.csv\"\n[[measurement.corrections]]\n{entry}"));
        let e = bad("response = \"1:uy\"\nsign = -1\n");
        assert!(e.contains(":25:12:") && e.contains("not one of the measurement's responses"), "{e}");
        let e = bad("response = \"3:uy\"\nreference = \"2:uy\"\nsign = -1\n");
        assert!(e.contains("`2:uy` is not one of the measurement's references"), "{e}");
        let e = bad("response = \"3:uy\"\nsign = 2\n");
        assert!(e.contains(":26:8:") && e.contains("sign must be 1 or -1"), "{e}");
        let e = bad("response = \"3:uy\"\nscale = 0\n");
        assert!(e.contains("scale must be positive and finite"), "{e}");
        let e = bad("response = \"3:uy\"\n");
        assert!(e.contains("needs `sign`, `scale` or `measured_at`"), "{e}");
        let e = bad("response = \"3:uy\"\nmeasured_at = \"9:uy\"\n");
        assert!(e.contains("node 9 does not exist"), "{e}");
        let e = bad("response = \"3:uy\"\nsign = -1\n[[measurement.corrections]]\nresponse = \"3:uy\"\nscale = 2\n");
        assert!(e.contains("corrected twice"), "{e}");
        // only with a data file
        let e = err("frequencies = [10.0]\n[[measurement.corrections]]\nresponse = \"3:uy\"\nsign = -1\n[truth]\n");
        assert!(e.contains("`corrections` applies to a measured `data` file"), "{e}");
    }

    #[test]
    fn fitted_gains_read_back_by_reference_or_channel() {
        let m = parse("data = \"m.uff\"\nfitted_gains = { \"5:uy\" = [12.5, -3.0], \"H(2:uy,5:uy)\" = [1.0, 0.0] }\n")
            .unwrap();
        let keys: Vec<String> = m.fitted_gains.iter().map(|g| g.key.to_string()).collect();
        assert_eq!(keys, vec!["5:uy", "H(2:uy,5:uy)"]);
        assert_eq!((m.fitted_gains[0].magnitude, m.fitted_gains[0].phase_deg), (12.5, -3.0));
        let e = err("data = \"m.uff\"\nfitted_gains = { \"5:uy\" = [0.0, 1.0] }\n");
        assert!(e.contains("positive, finite magnitude"), "{e}");
    }
}

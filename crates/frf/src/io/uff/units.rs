//! What an FRF record relates, from its units labels (records 9 and 10) or,
//! when those are absent, from its specific data types; and the factor to SI.
//!
//! Units labels are parsed as products and quotients of known units with
//! integer powers (`m/s^2`, `(1/N)*(m/s²)`, `g/lbf`, `m s-2 N-1`, `1/kg`,
//! `(m/s^2)/V`) into exponents of length, force, time and voltage plus a
//! scale to metres, newtons, seconds and volts. The time exponent decides
//! the kind: 0 receptance, -1 mobility, -2 accelerance. `g` is the standard
//! gravity (9.80665 m/s^2), as in accelerometer units, never the gram.
//!
//! An FRF per volt (`(m/s^2)/V`: referenced to a shaker amplifier's drive
//! signal or an uncalibrated force gauge) is read as such and marked
//! [`FrfUnits::per_volt`]: its level is the structure's times an unknown
//! gain, which a case either fits or removes with a calibration.

use std::f64::consts::PI;

use super::{Direction, Header58, specific_data_type_name};
use crate::set::FrfKind;

/// The kind of an FRF record and the factor that brings its values to SI.
#[derive(Clone, Debug, PartialEq)]
pub struct FrfUnits {
    /// Receptance, mobility or accelerance.
    pub kind: FrfKind,
    /// Multiply the file's values by this to get m, m/s or m/s^2 per N (rad for rotations, N m for moments).
    pub scale: f64,
    /// How it was decided, for messages (`units "g" / "N"`, or the data types).
    pub basis: String,
    /// Whether SI units were assumed because the file states none.
    pub assumed_si: bool,
    /// Whether the reference is a voltage (`V`, `mV`), not a force: the
    /// values are response per volt, scaled to per volt.
    pub per_volt: bool,
}

/// Decides what an FRF record relates from its header. Units labels win;
/// without them the specific data types decide (SI assumed). When both are
/// given and disagree, or neither is usable, it is an error (returned as a
/// message to be prefixed with the record).
pub fn frf_units(h: &Header58) -> Result<FrfUnits, String> {
    let by_units = units_kind(h)?;
    let by_types = types_kind(h)?;
    match (by_units, by_types) {
        (Some(u), Some((k, names))) if u.kind != k => Err(format!(
            "the units {} say {}, but the data types ({names}) say {k}; correct one of them in the file",
            u.basis, u.kind
        )),
        (Some(u), _) => Ok(u),
        (None, Some((kind, names))) => Ok(FrfUnits {
            kind,
            scale: 1.0,
            basis: format!("data types {names}, SI assumed"),
            assumed_si: true,
            per_volt: false,
        }),
        (None, None) => Err(format!(
            "cannot tell whether the FRF is a receptance, mobility or accelerance: the ordinate units are `{}` over \
             `{}` and the data types {} over {}; the file should give units such as `m/s^2` over `N` (records 9 and \
             10)",
            h.numerator.units, h.denominator.units, h.numerator.specific_type, h.denominator.specific_type
        )),
    }
}

/// The factor from the abscissa's units to hertz, and whether Hz was assumed
/// because the file does not say.
pub(super) fn abscissa_to_hz(h: &Header58) -> Result<(f64, bool), String> {
    let units = h.abscissa_axis.units.trim();
    let t = h.abscissa_axis.specific_type;
    match units.to_ascii_lowercase().replace(' ', "").as_str() {
        "hz" | "1/s" | "cycles/s" => Ok((1.0, false)),
        "khz" => Ok((1e3, false)),
        "rad/s" | "rad/sec" => Ok((1.0 / (2.0 * PI), false)),
        "" | "none" if t == 0 || t == 18 => Ok((1.0, true)),
        _ if t == 17 => Err(format!("the abscissa is time (`{units}`), not frequency")),
        "s" | "sec" | "ms" => Err(format!("the abscissa is time (`{units}`), not frequency")),
        _ => Err(format!(
            "the abscissa units `{units}` (data type {t}, {}) are not a frequency (Hz, kHz or rad/s)",
            specific_data_type_name(t)
        )),
    }
}

fn is_none(s: &str) -> bool {
    let s = s.trim();
    s.is_empty() || s.eq_ignore_ascii_case("none")
}

fn units_kind(h: &Header58) -> Result<Option<FrfUnits>, String> {
    let (num, den) = (h.numerator.units.trim(), h.denominator.units.trim());
    if is_none(num) {
        return Ok(None);
    }
    // A label rfm cannot read is refused rather than passed over: the data
    // types would then decide with SI assumed, and a file in mm or lbf
    // would be read a thousand or four times off without a word.
    let unknown = |which: &str, label: &str| {
        format!(
            "the {which} units `{label}` are not units rfm can read (such as m, mm, m/s, m/s^2, g, in, N, lbf, V); \
             correct them in the file, or write NONE to let the data types decide (SI is then assumed)"
        )
    };
    let Some(n) = parse_units(num) else { return Err(unknown("ordinate", num)) };
    // numerator units of a response alone (`m/s^2`) with no denominator units: per newton
    // (per newton metre for a moment), stated by a force data type or else assumed
    let per_force_assumed = is_none(den) && n.f == 0 && n.v == 0;
    let assumed_si = per_force_assumed && !matches!(h.denominator.specific_type, 9 | 13);
    let d = if per_force_assumed {
        Some(Dim {
            l: i32::from(matches!(h.reference.direction.axis_name(), "RX" | "RY" | "RZ")),
            f: 1,
            t: 0,
            v: 0,
            scale: 1.0,
        })
    } else if is_none(den) {
        Some(Dim::ONE)
    } else {
        parse_units(den)
    };
    let Some(d) = d else { return Err(unknown("denominator", den)) };
    let dim = n.div(d);
    if n.v != 0 {
        return Err(format!(
            "the ordinate units `{num}` measure the response in volts: calibrate the sensor in the test system so \
             that the FRF is a displacement, velocity or acceleration (per force or per volt)"
        ));
    }
    let basis = match (is_none(den), assumed_si) {
        (true, true) => format!("`{num}` (per N assumed)"),
        (true, false) if per_force_assumed => {
            format!("`{num}` / {}", specific_data_type_name(h.denominator.specific_type))
        }
        (true, false) => format!("`{num}`"),
        _ => format!("`{num}` / `{den}`"),
    };
    // a rotation in the response has no length; a moment as reference has one more
    let rot = |dir: Direction| matches!(dir.axis_name(), "RX" | "RY" | "RZ");
    // per volt: the reference is a voltage, which has no length whatever the direction
    let per_volt = dim.v == -1 && dim.f == 0;
    let want_l = i32::from(!rot(h.response.direction)) - i32::from(rot(h.reference.direction) && !per_volt);
    let kind = match dim.t {
        0 => FrfKind::Receptance,
        -1 => FrfKind::Mobility,
        -2 => FrfKind::Accelerance,
        _ => {
            return Err(format!(
                "the units {basis} are not those of an FRF (displacement, velocity or acceleration per force)"
            ));
        }
    };
    if !(per_volt || (dim.f == -1 && dim.v == 0)) || dim.l != want_l {
        return Err(format!(
            "the units {basis} are not those of an FRF from {} to {} (expected displacement, velocity or \
             acceleration per {}, or per volt)",
            h.reference.direction,
            h.response.direction,
            if rot(h.reference.direction) { "moment" } else { "force" }
        ));
    }
    Ok(Some(FrfUnits { kind, scale: dim.scale, basis, assumed_si, per_volt }))
}

fn types_kind(h: &Header58) -> Result<Option<(FrfKind, String)>, String> {
    let (n, d) = (h.numerator.specific_type, h.denominator.specific_type);
    let kind = match n {
        8 => FrfKind::Receptance,
        11 => FrfKind::Mobility,
        12 => FrfKind::Accelerance,
        _ => return Ok(None),
    };
    let names = format!("{} / {}", specific_data_type_name(n), specific_data_type_name(d));
    match d {
        0 | 1 | 9 | 13 => Ok(Some((kind, names))),
        _ => Err(format!("the data types ({names}) are not a response over a force")),
    }
}

/// What a whole units label of translational FRFs says (`g/N`,
/// `(m/s^2)/V`, `mm/N`, `in/s/lbf`): the kind, the factor to SI, and
/// whether the values are per volt. Used for a CSV file's `# units = ...`
/// line, which speaks of every channel at once.
pub(crate) fn label_units(label: &str) -> Result<(FrfKind, f64, bool), String> {
    let d = parse_units(label).ok_or_else(|| {
        format!(
            "`{label}` is not a units label rfm can read; write the response over the reference, such as m/N, \
             mm/N, m/s/N, m/s^2/N, g/N, in/s/lbf or (m/s^2)/V"
        )
    })?;
    let per_volt = d.v == -1 && d.f == 0;
    let kind = match d.t {
        0 => Some(FrfKind::Receptance),
        -1 => Some(FrfKind::Mobility),
        -2 => Some(FrfKind::Accelerance),
        _ => None,
    };
    match kind {
        Some(kind) if d.l == 1 && (per_volt || (d.f == -1 && d.v == 0)) && d.scale.is_finite() && d.scale > 0.0 => {
            Ok((kind, d.scale, per_volt))
        }
        _ => Err(format!(
            "`{label}` are not the units of an FRF: expected a displacement, velocity or acceleration per force \
             (m/N, m/s/N, m/s^2/N, g/N, ...) or per volt ((m/s^2)/V)"
        )),
    }
}

/// Exponents of length, force, time and voltage, and the factor to SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dim {
    l: i32,
    f: i32,
    t: i32,
    v: i32,
    scale: f64,
}

impl Dim {
    const ONE: Dim = Dim { l: 0, f: 0, t: 0, v: 0, scale: 1.0 };

    // saturating: a label like `((m^99)^99)^99` must not overflow
    fn mul(self, o: Dim) -> Dim {
        Dim {
            l: self.l.saturating_add(o.l),
            f: self.f.saturating_add(o.f),
            t: self.t.saturating_add(o.t),
            v: self.v.saturating_add(o.v),
            scale: self.scale * o.scale,
        }
    }

    fn div(self, o: Dim) -> Dim {
        self.mul(o.pow(-1))
    }

    fn pow(self, p: i32) -> Dim {
        Dim {
            l: self.l.saturating_mul(p),
            f: self.f.saturating_mul(p),
            t: self.t.saturating_mul(p),
            v: self.v.saturating_mul(p),
            scale: self.scale.powi(p),
        }
    }
}

const G0: f64 = 9.80665;
const LBF: f64 = 4.448_221_615_260_5;

fn unit(name: &str) -> Option<Dim> {
    let d = |l, f, t, scale| Some(Dim { l, f, t, v: 0, scale });
    let volt = |scale| Some(Dim { l: 0, f: 0, t: 0, v: 1, scale });
    match name.to_lowercase().as_str() {
        "m" => d(1, 0, 0, 1.0),
        "mm" => d(1, 0, 0, 1e-3),
        "cm" => d(1, 0, 0, 1e-2),
        "um" | "µm" | "μm" | "micron" => d(1, 0, 0, 1e-6),
        "in" | "inch" => d(1, 0, 0, 0.0254),
        "ft" => d(1, 0, 0, 0.3048),
        "s" | "sec" => d(0, 0, 1, 1.0),
        "ms" => d(0, 0, 1, 1e-3),
        "n" => d(0, 1, 0, 1.0),
        "kn" => d(0, 1, 0, 1e3),
        "mn" => d(0, 1, 0, 1e-3),
        "lbf" | "lb" | "lbs" => d(0, 1, 0, LBF),
        "kgf" => d(0, 1, 0, G0),
        "kg" => d(-1, 1, 2, 1.0),
        "g" | "gn" => d(1, 0, -2, G0),
        "rad" => d(0, 0, 0, 1.0),
        "deg" => d(0, 0, 0, PI / 180.0),
        "hz" => d(0, 0, -1, 1.0),
        // volts: `mv` cannot be confused with another unit here (no `mv` of length or force)
        "v" => volt(1.0),
        "mv" => volt(1e-3),
        "uv" | "µv" | "μv" => volt(1e-6),
        _ => None,
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Unit(String, i32),
    One,
    Mul,
    Div,
    Pow(i32),
    Open,
    Close,
}

fn lex(s: &str) -> Option<Vec<Tok>> {
    let s = s
        .replace("**", "^")
        .replace('²', "^2")
        .replace('³', "^3")
        .replace("⁻¹", "^-1")
        .replace("⁻²", "^-2")
        .replace(['·', '×'], "*")
        .replace('[', "(")
        .replace(']', ")");
    let c: Vec<char> = s.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let int_at = |i: &mut usize| -> Option<i32> {
        let start = *i;
        if matches!(c.get(*i), Some('-' | '+')) {
            *i += 1;
        }
        let digits = *i;
        while c.get(*i).is_some_and(|d| d.is_ascii_digit()) {
            *i += 1;
        }
        if *i == digits || *i - digits > 2 {
            return None;
        }
        c.get(start..*i)?.iter().collect::<String>().parse().ok()
    };
    while let Some(&ch) = c.get(i) {
        match ch {
            ' ' | '\t' => i += 1,
            '*' | '.' => {
                out.push(Tok::Mul);
                i += 1;
            }
            '/' => {
                out.push(Tok::Div);
                i += 1;
            }
            '(' => {
                out.push(Tok::Open);
                i += 1;
            }
            ')' => {
                out.push(Tok::Close);
                i += 1;
            }
            '^' => {
                i += 1;
                out.push(Tok::Pow(int_at(&mut i)?));
            }
            '1' if !c.get(i + 1).is_some_and(|d| d.is_ascii_digit()) => {
                out.push(Tok::One);
                i += 1;
            }
            ch if ch.is_alphabetic() => {
                let start = i;
                while c.get(i).is_some_and(|d| d.is_alphabetic()) {
                    i += 1;
                }
                let name: String = c.get(start..i)?.iter().collect();
                // `s2`, `s-2`: an exponent written right after the unit
                let p = if c.get(i).is_some_and(|d| d.is_ascii_digit() || *d == '-') { int_at(&mut i)? } else { 1 };
                out.push(Tok::Unit(name, p));
            }
            _ => return None,
        }
    }
    Some(out)
}

/// Parses a units label into dimensions, or `None` when it is not understood.
fn parse_units(s: &str) -> Option<Dim> {
    let toks = lex(s)?;
    let mut pos = 0;
    let d = expr(&toks, &mut pos, 0)?;
    (pos == toks.len()).then_some(d)
}

fn expr(t: &[Tok], pos: &mut usize, depth: usize) -> Option<Dim> {
    if depth > 16 {
        return None;
    }
    let mut acc = term(t, pos, depth)?;
    loop {
        match t.get(*pos) {
            Some(Tok::Mul) => {
                *pos += 1;
                acc = acc.mul(term(t, pos, depth)?);
            }
            Some(Tok::Div) => {
                *pos += 1;
                acc = acc.div(term(t, pos, depth)?);
            }
            // implicit product: `N m`, `m s-2`
            Some(Tok::Unit(..) | Tok::Open | Tok::One) => acc = acc.mul(term(t, pos, depth)?),
            _ => return Some(acc),
        }
    }
}

fn term(t: &[Tok], pos: &mut usize, depth: usize) -> Option<Dim> {
    let base = match t.get(*pos)? {
        Tok::Unit(name, p) => {
            *pos += 1;
            unit(name)?.pow(*p)
        }
        Tok::One => {
            *pos += 1;
            Dim::ONE
        }
        Tok::Open => {
            *pos += 1;
            let d = expr(t, pos, depth + 1)?;
            if t.get(*pos) != Some(&Tok::Close) {
                return None;
            }
            *pos += 1;
            d
        }
        _ => return None,
    };
    if let Some(Tok::Pow(p)) = t.get(*pos) {
        *pos += 1;
        return Some(base.pow(*p));
    }
    Some(base)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_labels_give_kind_scale_and_whether_per_volt() {
        assert_eq!(label_units("g/N"), Ok((FrfKind::Accelerance, G0, false)));
        assert_eq!(label_units("mm/N"), Ok((FrfKind::Receptance, 1e-3, false)));
        assert_eq!(label_units("m/s/N"), Ok((FrfKind::Mobility, 1.0, false)));
        assert_eq!(label_units("(m/s^2)/V"), Ok((FrfKind::Accelerance, 1.0, true)));
        let (k, s, v) = label_units("in/s/lbf").unwrap();
        assert_eq!((k, v), (FrfKind::Mobility, false));
        assert!((s - 0.0254 / LBF).abs() < 1e-15);
        // labels that parse but are no FRF, and labels that do not parse
        for bad in ["m/s^2", "N/m", "V/N", "m/s^3/N"] {
            let e = label_units(bad).unwrap_err();
            assert!(e.contains(&format!("`{bad}` are not the units of an FRF")), "{e}");
        }
        let e = label_units("furlong/N").unwrap_err();
        assert!(e.contains("`furlong/N` is not a units label rfm can read"), "{e}");
    }

    fn dims(s: &str) -> Option<(i32, i32, i32, f64)> {
        parse_units(s).map(|d| (d.l, d.f, d.t, d.scale))
    }

    #[test]
    fn units_labels_parse_to_dimensions_and_scales() {
        assert_eq!(dims("m/s^2"), Some((1, 0, -2, 1.0)));
        assert_eq!(dims("m/s2"), Some((1, 0, -2, 1.0)));
        assert_eq!(dims("m/s²"), Some((1, 0, -2, 1.0)));
        assert_eq!(dims("(1/N)*(m/s²)"), Some((1, -1, -2, 1.0)));
        assert_eq!(dims("[m/s^2]/[N]"), Some((1, -1, -2, 1.0)));
        assert_eq!(dims("m s-2 N-1"), Some((1, -1, -2, 1.0)));
        assert_eq!(dims("m/s/N"), Some((1, -1, -1, 1.0)));
        assert_eq!(dims("mm/N"), Some((1, -1, 0, 1e-3)));
        assert_eq!(dims("g/N"), Some((1, -1, -2, G0)));
        assert_eq!(dims("1/kg"), Some((1, -1, -2, 1.0)));
        assert_eq!(dims("N*m"), Some((1, 1, 0, 1.0)));
        let (l, f, t, s) = dims("in/s/lbf").unwrap();
        assert_eq!((l, f, t), (1, -1, -1));
        assert!((s - 0.0254 / LBF).abs() < 1e-15);
        for bad in ["Pa", "m/", "(m/s", "m^", "NONE", "m/s^999", "m))"] {
            assert_eq!(dims(bad), None, "{bad}");
        }
        assert_eq!(dims("(m/s^2)/V").map(|d| (d.0, d.1, d.2)), Some((1, 0, -2)));
        let volts = |s: &str| parse_units(s).map(|d| (d.v, d.scale));
        assert_eq!(volts("m/s^2/V"), Some((-1, 1.0)));
        assert_eq!(volts("g/mV"), Some((-1, G0 * 1e3)));
        assert_eq!(volts("m/N"), Some((0, 1.0)));
        let deep = format!("{}m{}", "(".repeat(16), "^99)".repeat(16));
        assert_eq!(dims(&deep).map(|d| d.0), Some(i32::MAX));
    }

    use super::super::{DataAxis, OrdinateType, TestDof};

    /// An FRF header: response over reference, abscissa, numerator and
    /// denominator axes as given.
    fn header(response: Direction, reference: Direction, abscissa: DataAxis, num: DataAxis, den: DataAxis) -> Header58 {
        Header58 {
            ids: Default::default(),
            function_type: 4,
            function_id: 1,
            version: 0,
            load_case: 0,
            response_entity: "NONE".into(),
            response: TestDof::new(5, response),
            reference_entity: "NONE".into(),
            reference: TestDof::new(9, reference),
            ordinate_type: OrdinateType::ComplexDouble,
            z_value: 0.0,
            abscissa_axis: abscissa,
            numerator: num,
            denominator: den,
            z_axis: DataAxis::none(),
        }
    }

    fn with_abscissa(t: i64, units: &str) -> Header58 {
        header(
            Direction::Y,
            Direction::Y,
            DataAxis::new(t, "x", units),
            DataAxis::new(12, "a", "m/s^2"),
            DataAxis::new(13, "f", "N"),
        )
    }

    #[test]
    fn every_known_unit_has_its_si_scale() {
        let length = [
            ("m", 1.0),
            ("mm", 1e-3),
            ("cm", 1e-2),
            ("um", 1e-6),
            ("µm", 1e-6),
            ("micron", 1e-6),
            ("in", 0.0254),
            ("ft", 0.3048),
        ];
        for (name, scale) in length {
            assert_eq!(unit(name), Some(Dim { l: 1, f: 0, t: 0, v: 0, scale }), "{name}");
        }
        for (name, scale) in [("s", 1.0), ("sec", 1.0), ("ms", 1e-3)] {
            assert_eq!(unit(name), Some(Dim { l: 0, f: 0, t: 1, v: 0, scale }), "{name}");
        }
        for (name, scale) in [("N", 1.0), ("kN", 1e3), ("mN", 1e-3), ("lbf", LBF), ("lb", LBF), ("kgf", G0)] {
            assert_eq!(unit(name), Some(Dim { l: 0, f: 1, t: 0, v: 0, scale }), "{name}");
        }
        // a kilogram is a newton per (m/s^2); g is the standard gravity
        assert_eq!(unit("kg"), Some(Dim { l: -1, f: 1, t: 2, v: 0, scale: 1.0 }));
        assert_eq!(unit("g"), Some(Dim { l: 1, f: 0, t: -2, v: 0, scale: G0 }));
        assert_eq!(unit("deg"), Some(Dim { l: 0, f: 0, t: 0, v: 0, scale: PI / 180.0 }));
        assert_eq!(unit("Hz"), Some(Dim { l: 0, f: 0, t: -1, v: 0, scale: 1.0 }));
        for (name, scale) in [("V", 1.0), ("mV", 1e-3), ("uV", 1e-6), ("µV", 1e-6), ("μV", 1e-6)] {
            assert_eq!(unit(name), Some(Dim { l: 0, f: 0, t: 0, v: 1, scale }), "{name}");
        }
        assert_eq!(unit("furlong"), None);
    }

    #[test]
    fn the_abscissa_becomes_hertz_or_is_refused_as_time() {
        assert_eq!(abscissa_to_hz(&with_abscissa(18, "Hz")), Ok((1.0, false)));
        assert_eq!(abscissa_to_hz(&with_abscissa(18, "kHz")), Ok((1e3, false)));
        assert_eq!(abscissa_to_hz(&with_abscissa(18, "rad/s")), Ok((1.0 / (2.0 * PI), false)));
        assert_eq!(abscissa_to_hz(&with_abscissa(18, "rad / sec")), Ok((1.0 / (2.0 * PI), false)));
        // no units: hertz is assumed for a frequency or an unknown type only
        assert_eq!(abscissa_to_hz(&with_abscissa(18, "NONE")), Ok((1.0, true)));
        assert_eq!(abscissa_to_hz(&with_abscissa(0, "")), Ok((1.0, true)));
        let e = abscissa_to_hz(&with_abscissa(17, "NONE")).unwrap_err();
        assert!(e.contains("the abscissa is time (`NONE`)"), "{e}");
        for time in ["s", "ms", "sec"] {
            let e = abscissa_to_hz(&with_abscissa(0, time)).unwrap_err();
            assert!(e.contains(&format!("the abscissa is time (`{time}`)")), "{e}");
        }
        let e = abscissa_to_hz(&with_abscissa(1, "NONE")).unwrap_err();
        assert!(e.contains("are not a frequency"), "{e}");
    }

    #[test]
    fn units_labels_decide_the_kind_and_the_scale() {
        let y = Direction::Y;
        let kind = |num: &str, den: &str| {
            frf_units(&header(
                y,
                y,
                DataAxis::new(18, "f", "Hz"),
                DataAxis::new(0, "r", num),
                DataAxis::new(0, "e", den),
            ))
        };
        let u = kind("g", "lbf").unwrap();
        assert_eq!((u.kind, u.assumed_si), (FrfKind::Accelerance, false));
        assert!((u.scale - G0 / LBF).abs() < 1e-15);
        assert_eq!(kind("mm/s", "N").unwrap().kind, FrfKind::Mobility);
        let u = kind("m/N", "NONE").unwrap();
        assert_eq!((u.kind, u.basis.as_str()), (FrfKind::Receptance, "`m/N`"));
        // a response with no denominator units is per newton, assumed unless a force type says so
        let u = kind("m/s^2", "NONE").unwrap();
        assert_eq!((u.kind, u.scale, u.assumed_si), (FrfKind::Accelerance, 1.0, true));
        assert!(u.basis.contains("per N assumed"), "{}", u.basis);
        let stated = frf_units(&header(
            y,
            y,
            DataAxis::new(18, "f", "Hz"),
            DataAxis::new(0, "r", "m/s^2"),
            DataAxis::new(13, "F", "NONE"),
        ))
        .unwrap();
        assert!(!stated.assumed_si, "{stated:?}");
        assert_eq!(stated.basis, format!("`m/s^2` / {}", specific_data_type_name(13)));
        // a moment as reference takes one more length: rotation over moment is rad/(N m)
        let rz = Direction::RZ;
        let u = frf_units(&header(
            rz,
            rz,
            DataAxis::new(18, "f", "Hz"),
            DataAxis::new(0, "r", "rad"),
            DataAxis::new(0, "M", "N*m"),
        ))
        .unwrap();
        assert_eq!(u.kind, FrfKind::Receptance);
        let e = frf_units(&header(
            y,
            rz,
            DataAxis::new(18, "f", "Hz"),
            DataAxis::new(0, "r", "m"),
            DataAxis::new(0, "F", "N"),
        ))
        .unwrap_err();
        assert!(e.contains("expected displacement, velocity or acceleration per moment"), "{e}");
        let e = kind("m*s", "N").unwrap_err();
        assert!(e.contains("are not those of an FRF"), "{e}");
        // per volt (the reference a drive signal, not a force): any length
        // over V or mV, with no force in it; a volt has no length, so a
        // rotational reference takes none
        let u = kind("m/s^2", "mV").unwrap();
        assert_eq!((u.kind, u.per_volt, u.assumed_si), (FrfKind::Accelerance, true, false));
        assert!((u.scale - 1e3).abs() < 1e-12, "{}", u.scale);
        let u = kind("mm", "V").unwrap();
        assert_eq!((u.kind, u.per_volt), (FrfKind::Receptance, true));
        assert!(!kind("m/s^2", "N").unwrap().per_volt);
        let u = frf_units(&header(
            y,
            rz,
            DataAxis::new(18, "f", "Hz"),
            DataAxis::new(0, "r", "m/s"),
            DataAxis::new(0, "e", "V"),
        ))
        .unwrap();
        assert_eq!((u.kind, u.per_volt), (FrfKind::Mobility, true));
        // a response over neither a force nor a volt, or over a force squared
        for (num, den) in [("m", "s"), ("m/s", "N^2")] {
            let e = kind(num, den).unwrap_err();
            assert!(e.contains("are not those of an FRF"), "{num} / {den}: {e}");
        }
        // a force and a volt together, or a volt squared, are no FRF
        for den in ["N*V", "V^2"] {
            let e = kind("m/s^2", den).unwrap_err();
            assert!(e.contains("are not those of an FRF"), "{den}: {e}");
        }
    }

    #[test]
    fn data_types_decide_the_kind_when_there_are_no_units() {
        let y = Direction::Y;
        let by_types = |num: i64, den: i64| {
            frf_units(&header(
                y,
                y,
                DataAxis::new(18, "f", "Hz"),
                DataAxis::new(num, "r", "NONE"),
                DataAxis::new(den, "e", "NONE"),
            ))
        };
        for (num, kind) in [(8, FrfKind::Receptance), (11, FrfKind::Mobility), (12, FrfKind::Accelerance)] {
            for den in [0, 1, 9, 13] {
                let u = by_types(num, den).unwrap();
                assert_eq!((u.kind, u.scale, u.assumed_si), (kind, 1.0, true), "types {num}/{den}");
            }
        }
        let e = by_types(12, 8).unwrap_err();
        assert!(e.contains("are not a response over a force"), "{e}");
        assert!(by_types(3, 13).unwrap_err().contains("cannot tell whether the FRF is a receptance"));
        // units and types that disagree are refused
        let e = frf_units(&header(
            y,
            y,
            DataAxis::new(18, "f", "Hz"),
            DataAxis::new(11, "v", "m/s^2"),
            DataAxis::new(13, "F", "N"),
        ))
        .unwrap_err();
        assert!(e.contains("but the data types"), "{e}");
    }
}

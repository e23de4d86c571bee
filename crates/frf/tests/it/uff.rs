//! UFF dataset 58: round trips of every data type and encoding, the exact
//! header text, real files from test systems, truncated and corrupted input,
//! kind and unit conversions, channel mapping with signs, coherence.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use fe_model::case::ChannelMap;
use fe_model::{Dof, DofRef};
use frf::io::uff::{
    self, Abscissa, DataAxis, Direction, Encoding, Function58, Header58, OrdinateType, Ordinates, Spacing, TestDof,
    UffWriteOptions,
};
use frf::{C64, Channel, FileError, FrfError, FrfKind, FrfSet};

const ENCODINGS: [Encoding; 3] =
    [Encoding::Ascii, Encoding::Binary { big_endian: false }, Encoding::Binary { big_endian: true }];

fn header(function_type: i64, t: OrdinateType, response: &str, reference: &str, units: (&str, &str)) -> Header58 {
    Header58 {
        ids: ["a test record".into(), "NONE".into(), "01-Jan-25 00:00:00".into(), "NONE".into(), "NONE".into()],
        function_type,
        function_id: 7,
        version: 1,
        load_case: 0,
        response_entity: "acc 1".into(),
        response: response.parse().unwrap(),
        reference_entity: "NONE".into(),
        reference: reference.parse().unwrap(),
        ordinate_type: t,
        z_value: 0.0,
        abscissa_axis: DataAxis::new(18, "Frequency", "Hz"),
        numerator: DataAxis::new(0, "Response", units.0),
        denominator: DataAxis::new(0, "Force", units.1),
        z_axis: DataAxis::none(),
    }
}

/// Values that exercise signs, magnitudes and exponents of three digits (in double precision).
fn values(n: usize, complex: bool, double: bool) -> Ordinates {
    let tiny = if double { 1e-120 } else { 1e-30 };
    let x = |k: usize| {
        let k = k as f64;
        match k as usize % 4 {
            0 => (1.0 + k).sqrt() * 1.234_567_890_123_456_7e-3,
            1 => -(k + 0.5).ln() * 98.765_432_1,
            2 => tiny * (k + 1.0),
            _ => -1.0 / (k + 3.0),
        }
    };
    if complex {
        Ordinates::Complex((0..n).map(|k| C64::new(x(k), x(k + 3) * 0.5)).collect())
    } else {
        Ordinates::Real((0..n).map(x).collect())
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

fn read(bytes: &[u8]) -> Result<uff::UffFile, FrfError> {
    uff::parse_uff(Path::new("mem.uff"), bytes)
}

#[test]
fn every_data_type_and_spacing_round_trips_in_ascii_and_binary() {
    let n = 7; // not a multiple of any line length, so the last data line is partial
    let uneven: Vec<f64> = vec![1.5, 2.25, 10.125, 33.0, 100.5, 101.75, 4096.0]; // exact in 7 digits and in f32
    for encoding in ENCODINGS {
        for t in OrdinateType::ALL {
            for even in [true, false] {
                let f = Function58 {
                    header: header(4, t, "101:+Z", "3:-Y", ("m/s^2", "N")),
                    abscissa: if even {
                        Abscissa::Even { min: 0.5, step: 0.25 }
                    } else {
                        Abscissa::Uneven(uneven.clone())
                    },
                    ordinates: values(n, t.is_complex(), t.is_double()),
                };
                let bytes = uff::encode(std::slice::from_ref(&f), encoding).unwrap();
                let file = read(&bytes).unwrap_or_else(|e| panic!("{t:?} {encoding:?} even={even}: {e}"));
                assert_eq!(file.records.len(), 1);
                let r = &file.records[0];
                assert_eq!((r.index, r.line, r.encoding), (1, 2, encoding));
                assert_eq!(r.function.header, f.header, "{t:?} {encoding:?}");
                assert_eq!(r.function.abscissa_values(), f.abscissa_values(), "{t:?} {encoding:?}");
                assert_eq!(r.function.is_even(), even);
                // precision of what is stored: exact in binary (after rounding to f32 for single
                // precision), 13 significant digits in ASCII double, 6 in ASCII single
                let rel = match (encoding, t.is_double()) {
                    (Encoding::Binary { .. }, _) => 0.0,
                    (Encoding::Ascii, true) => 1e-12,
                    (Encoding::Ascii, false) => 1e-5,
                };
                for k in 0..n {
                    let (a, b) = (r.function.ordinates.get(k).unwrap(), f.ordinates.get(k).unwrap());
                    let b = if t.is_double() { b } else { C64::new(f64::from(b.re as f32), f64::from(b.im as f32)) };
                    assert!(close(a.re, b.re, rel) && close(a.im, b.im, rel), "{t:?} {encoding:?} k={k}: {a} vs {b}");
                }
                assert!(matches!(
                    (&r.function.ordinates, t.is_complex()),
                    (Ordinates::Complex(_), true) | (Ordinates::Real(_), false)
                ));
            }
        }
    }
}

fn small_set() -> FrfSet {
    let ch = vec![Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(1, Dof::Ux))];
    let mut s = FrfSet::zeros(vec![10.0, 12.5, 15.0], ch, FrfKind::Mobility).unwrap();
    s.set(0, 0, C64::new(1.0, 2.0));
    s.set(0, 1, C64::new(-0.5, 0.25));
    s.set(0, 2, C64::new(3.0e-5, -4.0e-7));
    s
}

#[test]
fn header_lines_have_the_exact_fixed_width_text() {
    let bytes = uff::to_uff_bytes(&small_set(), &UffWriteOptions::default()).unwrap();
    let text = String::from_utf8(bytes).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // hand-computed: I6 dataset markers, records 1-5 as A80, record 6 as
    // 2(I5,I10),2(1X,A10,I10,I4), record 7 as 3I10,3E13, records 8-11 as I10,3I5,2(1X,A20)
    let expected = [
        "    -1".to_string(),
        format!("    58{}", " ".repeat(74)),
        format!("{:<80}", "H(2:uy,1:ux) mobility"),
        format!("{:<80}", "written by rfm"),
        format!("{:<80}", "NONE"),
        format!("{:<80}", "NONE"),
        format!("{:<80}", "NONE"),
        "    4         1    0         0 NONE               2   2 NONE               1   1".to_string(),
        "         6         3         1 1.000000E+01 2.500000E+00 0.000000E+00".to_string(),
        "        18    0    0    0 Frequency            Hz                  ".to_string(),
        "        11    0    0    0 Velocity             m/s                 ".to_string(),
        "        13    0    0    0 Force                N                   ".to_string(),
        "         0    0    0    0 NONE                 NONE                ".to_string(),
        " 1.0000000000000E+00 2.0000000000000E+00 -5.000000000000E-01 2.5000000000000E-01".to_string(),
        " 3.0000000000000E-05 -4.000000000000E-07".to_string(),
        "    -1".to_string(),
    ];
    assert_eq!(lines.len(), expected.len(), "{text}");
    for (i, (got, want)) in lines.iter().zip(&expected).enumerate() {
        assert_eq!(got, want, "line {}", i + 1);
    }
    // record 6 columns as a reader that cuts fields sees them
    let r6 = lines[7];
    assert_eq!(
        (&r6[0..5], &r6[41..51], &r6[51..55], &r6[66..76], &r6[76..80]),
        ("    4", "         2", "   2", "         1", "   1")
    );

    // binary: the 58b line gives byte order, IEEE format, 11 lines and 3 x 2 x 8 bytes
    let opts = UffWriteOptions { encoding: Encoding::BINARY, ..Default::default() };
    let bytes = uff::to_uff_bytes(&small_set(), &opts).unwrap();
    let second = bytes.split(|&b| b == b'\n').nth(1).unwrap();
    assert_eq!(second, b"    58b     1     2          11          48     0     0           0           0");
    assert!(bytes.ends_with(b"    -1\n"));
    // the same 13 lines, but the `58b` line has 79 columns where the ASCII `58` line has 80;
    // then 48 bytes of data and the closing line
    let header_len: usize = text.lines().take(13).map(|l| l.len() + 1).sum();
    assert_eq!(bytes.len(), header_len - 1 + 48 + "    -1\n".len());
}

#[test]
fn frf_sets_round_trip_through_write_uff_and_read_measured() {
    let dofs = [DofRef::new(3, Dof::Ux), DofRef::new(3, Dof::Uy), DofRef::new(4, Dof::Rz)];
    let channels: Vec<Channel> = dofs.iter().flat_map(|&r| dofs.iter().map(move |&m| Channel::new(m, r))).collect();
    let freqs: Vec<f64> = (1..=50).map(|k| 0.5 * f64::from(k)).collect();
    for kind in [FrfKind::Receptance, FrfKind::Mobility, FrfKind::Accelerance] {
        let mut s = FrfSet::zeros(freqs.clone(), channels.clone(), kind).unwrap();
        for c in 0..channels.len() {
            for k in 0..freqs.len() {
                s.set(c, k, C64::new((c as f64 + 1.0) / (k as f64 + 1.0), -((c * k) as f64).sin() * 1e-3));
            }
        }
        let coh: Vec<f64> = (0..channels.len() * freqs.len()).map(|i| (i % 101) as f64 / 100.0).collect();
        s.set_coherence(coh).unwrap();
        for encoding in ENCODINGS {
            for spacing in [Spacing::Auto, Spacing::Uneven] {
                for ordinate_type in [OrdinateType::ComplexDouble, OrdinateType::ComplexSingle] {
                    let dir = tempfile::tempdir().unwrap();
                    let path = dir.path().join("h.uff");
                    let opts = UffWriteOptions { encoding, ordinate_type, spacing };
                    uff::write_uff(&s, &path, &opts, &[]).unwrap();
                    let back = frf::io::load_measured(&path, &[]).unwrap();
                    let got = &back.set;
                    assert_eq!((got.kind(), got.channels()), (kind, s.channels()));
                    assert_eq!(got.frequencies_hz(), s.frequencies_hz(), "{opts:?}");
                    let rel = match (encoding, ordinate_type) {
                        (Encoding::Binary { .. }, OrdinateType::ComplexDouble) => 0.0,
                        (Encoding::Ascii, OrdinateType::ComplexDouble) => 1e-12,
                        _ => 1e-5,
                    };
                    for c in 0..channels.len() {
                        for k in 0..freqs.len() {
                            let (a, b) = (got.get(c, k), s.get(c, k));
                            assert!(close(a.re, b.re, rel) && close(a.im, b.im, rel), "{opts:?}: {a} vs {b}");
                            let (ga, gb) = (got.coherence(c).unwrap()[k], s.coherence(c).unwrap()[k]);
                            assert!((ga - gb).abs() <= rel.max(1e-15), "{ga} vs {gb}");
                        }
                    }
                    assert!(back.notes.is_empty(), "{:?}", back.notes);
                }
            }
        }
    }
    // real types would drop imaginary parts: refused
    let e = uff::to_uff_bytes(
        &small_set(),
        &UffWriteOptions { ordinate_type: OrdinateType::RealDouble, ..Default::default() },
    )
    .unwrap_err();
    assert!(e.to_string().contains("FRFs are complex"), "{e}");
}

#[test]
fn writing_never_replaces_an_input_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("in.uff");
    std::fs::write(&path, b"keep").unwrap();
    let e = uff::write_uff(&small_set(), &path, &UffWriteOptions::default(), std::slice::from_ref(&path)).unwrap_err();
    assert!(e.to_string().contains("refusing to overwrite an input"), "{e}");
    assert_eq!(std::fs::read(&path).unwrap(), b"keep");
}

fn samples_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/uff-samples");
    if d.is_dir() {
        Some(d)
    } else {
        eprintln!("skipping: no UFF samples at {}", d.display());
        None
    }
}

fn measured_err(path: &Path, map: &[ChannelMap]) -> String {
    match frf::io::read_measured(path, map) {
        Ok(s) => panic!("{} was read ({} channels), expected a refusal", path.display(), s.channels().len()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_sample_file_is_read_or_refused_with_a_clear_message() {
    let Some(dir) = samples_dir() else { return };
    let p = |name: &str| dir.join(name);
    let mut seen = Vec::new();
    let mut check = |name: &str| {
        seen.push(name.to_string());
        p(name)
    };

    // time responses from test systems: read as records, refused as FRFs by type
    let time_files: [(&str, usize, OrdinateType, Encoding, usize); 5] = [
        ("MPSTD_Set001_time_58b.uff", 4, OrdinateType::RealSingle, Encoding::BINARY, 222_400),
        ("Sample_UFF58_ascii.uff", 1, OrdinateType::RealSingle, Encoding::Ascii, 79_292),
        ("Sample_UFF58b_bin.uff", 1, OrdinateType::RealSingle, Encoding::BINARY, 79_292),
        ("binary8byte.uff", 1, OrdinateType::RealDouble, Encoding::BINARY, 250),
        ("time-history-not-all-columns-filled.uff", 1, OrdinateType::RealSingle, Encoding::Ascii, 13),
    ];
    for (name, count, t, encoding, n) in time_files {
        let path = check(name);
        let file = uff::read_uff(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(file.records.len(), count, "{name}");
        for r in &file.records {
            let h = &r.function.header;
            assert_eq!((h.function_type, h.ordinate_type, r.encoding, r.function.len()), (1, t, encoding, n), "{name}");
        }
        let e = measured_err(&path, &[]);
        assert!(
            e.contains("record 1 (line 2): function type 1 (time response) is not a frequency response function"),
            "{name}: {e}"
        );
    }
    // the ASCII and binary versions of the same recording agree to single precision
    let a = uff::read_uff(&p("Sample_UFF58_ascii.uff")).unwrap();
    let b = uff::read_uff(&p("Sample_UFF58b_bin.uff")).unwrap();
    let (fa, fb) = (&a.records[0].function, &b.records[0].function);
    assert_eq!(fa.header, fb.header);
    for k in (0..fa.len()).step_by(997) {
        let (x, y) = (fa.ordinates.get(k).unwrap().re, fb.ordinates.get(k).unwrap().re);
        assert!((x - y).abs() <= 5e-6 * x.abs().max(1e-12), "k={k}: {x} vs {y}");
    }
    assert!(close(fa.abscissa_at(79_291).unwrap(), 79_291.0 * 1.52588e-5, 1e-12));

    // a header from an unknown system with a data block cut short: the time type is refused
    // first; read as records, the short data is reported with its line
    let path = check("dataset_milestone_in_header.uff");
    let e = measured_err(&path, &[]);
    assert!(e.contains("function type 1 (time response)"), "{e}");
    let e = uff::read_uff(&path).unwrap_err().to_string();
    assert!(
        e.contains("record 7 declares 2508876 values") && e.contains("the data holds 42 numbers (lines 14-20)"),
        "{e}"
    );

    // a power spectral density (uneven, complex single): refused by name
    let path = check("sample_dataset58_psd.uff");
    let file = uff::read_uff(&path).unwrap();
    let f = &file.records[0].function;
    assert_eq!(
        (f.header.function_type, f.header.ordinate_type, f.is_even(), f.len()),
        (9, OrdinateType::ComplexSingle, false, 3201)
    );
    assert_eq!((f.abscissa_at(0), f.abscissa_at(3200)), (Some(0.0), Some(3200.0)));
    let e = measured_err(&path, &[]);
    assert!(
        e.contains("record 1 (line 2): function type 9 (power spectral density) is not a frequency response function"),
        "{e}"
    );

    // files without dataset 58: their datasets are listed, nothing is read
    for (name, numbers) in [
        ("TestLab_161_164_18_15_82.uff", vec![151, 164, 18, 15, 82, 82, 82]),
        ("heat_engine_housing.uff", vec![151, 164, 2411, 2412, 2414]),
        ("uff55_sample_record10.uff", vec![55]),
    ] {
        let path = check(name);
        let file = uff::read_uff(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(file.records.is_empty());
        assert_eq!(file.skipped.iter().map(|d| d.number).collect::<Vec<_>>(), numbers, "{name}");
        let e = measured_err(&path, &[]);
        assert!(e.contains("no frequency response function (dataset 58, function type 4)"), "{name}: {e}");
        assert!(e.contains(&format!("it holds no dataset 58, only datasets {} (", numbers[0])), "{name}: {e}");
    }

    // an FRF (accelerance in Latin-1 `(1/N)*(m/s²)`) at a scalar test point: needs a map entry
    let path = check("non_ascii_header.uff");
    let e = measured_err(&path, &[]);
    assert!(e.contains("response 0:S") && e.contains("scalar") && e.contains("test = \"0:S\""), "{e}");
    let map = [ChannelMap { test: "0:S".into(), model: "1:uy".parse().unwrap(), sign: 1.0 }];
    let m = frf::io::load_measured(&path, &map).unwrap();
    let file = uff::read_uff(&path).unwrap();
    let f = &file.records[0].function;
    assert_eq!(f.header.numerator.units, "(1/N)*(m/s²)");
    assert_eq!(m.set.kind(), FrfKind::Accelerance);
    assert_eq!(m.set.channels(), &[Channel::new(DofRef::new(1, Dof::Uy), DofRef::new(1, Dof::Uy))]);
    assert_eq!(m.set.n_freq(), 5, "the 0 Hz line is dropped");
    assert!(m.notes.iter().any(|n| n.contains("0 Hz")), "{:?}", m.notes);
    for k in 0..5 {
        assert_eq!(m.set.frequencies_hz()[k], f.abscissa_at(k + 1).unwrap());
        assert_eq!(m.set.get(0, k), f.ordinates.get(k + 1).unwrap());
    }

    // not a UFF and not the project's CSV layout
    let path = check("meas_point_1.txt");
    let e = measured_err(&path, &[]);
    assert!(e.contains("meas_point_1.txt:1:") && e.contains("frequency"), "{e}");

    // every file of the folder is covered here (README.md aside)
    let mut all: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "README.md")
        .collect();
    all.sort();
    seen.sort();
    assert_eq!(all, seen);
}

/// A small valid file: two FRFs and a coherence, in the given encoding.
fn sample_bytes(encoding: Encoding) -> Vec<u8> {
    let mut s = FrfSet::zeros(
        vec![1.0, 2.0, 3.0, 4.5],
        vec![
            Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy)),
            Channel::new(DofRef::new(3, Dof::Rz), DofRef::new(2, Dof::Uy)),
        ],
        FrfKind::Accelerance,
    )
    .unwrap();
    for k in 0..4 {
        s.set(0, k, C64::new(k as f64 - 1.5, 0.25));
        s.set(1, k, C64::new(-2.0, k as f64));
    }
    s.set_coherence(vec![0.9; 8]).unwrap();
    uff::to_uff_bytes(&s, &UffWriteOptions { encoding, spacing: Spacing::Uneven, ..Default::default() }).unwrap()
}

#[test]
fn truncated_and_corrupted_files_give_errors_never_panics() {
    let path = Path::new("cut.uff");
    for encoding in [Encoding::Ascii, Encoding::BINARY] {
        let bytes = sample_bytes(encoding);
        let full = read(&bytes).unwrap();
        assert_eq!(full.records.len(), 4);
        let frfs = |b: &[u8]| read(b).and_then(|f| uff::frfs_from_uff(path, &f, &[]));
        assert!(frfs(&bytes).is_ok());
        for cut in 0..bytes.len() {
            let r = read(&bytes[..cut]);
            // a cut file is an error, or a shorter file that ends between two datasets
            match &r {
                Ok(f) => {
                    assert!(f.records.len() < 4 || cut + 1 >= bytes.len(), "{encoding:?}: cut at {cut} read whole")
                }
                Err(FrfError::File(FileError::Parse { message, .. })) => assert!(!message.is_empty()),
                Err(e) => panic!("unexpected error kind {e:?}"),
            }
            let _ = frfs(&bytes[..cut]);
        }
        for pos in 0..bytes.len() {
            for replacement in [0xFFu8, b'-', b'9', b' ', b'\n', b'b', 0] {
                let mut b = bytes.clone();
                b[pos] = replacement;
                let _ = frfs(&b);
            }
            let mut b = bytes.clone();
            b[pos] ^= 0x5A;
            let _ = frfs(&b);
        }
    }
    // the messages say where: a line for ASCII, a byte offset for binary
    let ascii = sample_bytes(Encoding::Ascii);
    let e = read(&ascii[..ascii.len() - 20]).unwrap_err().to_string();
    assert!(e.contains("record 4 (line") && e.contains("truncated"), "{e}");
    let bin = sample_bytes(Encoding::BINARY);
    let data_start = bin.iter().enumerate().filter(|(_, b)| **b == b'\n').nth(12).unwrap().0 + 1;
    let e = read(&bin[..data_start + 10]).unwrap_err();
    let FrfError::File(FileError::Parse { line, message, .. }) = &e else { panic!("{e:?}") };
    assert_eq!(*line, data_start);
    assert!(
        message.starts_with(&format!("byte offset {data_start}: record 1 (line 2)")) && message.contains("truncated"),
        "{message}"
    );
    let mut bad = ascii.clone();
    let data_start = ascii.iter().enumerate().filter(|(_, b)| **b == b'\n').nth(12).unwrap().0 + 1;
    let at = data_start + String::from_utf8_lossy(&ascii[data_start..]).find("E+00").unwrap();
    bad[at + 1] = b'x';
    let e = read(&bad).unwrap_err().to_string();
    let line = ascii[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    assert!(e.starts_with(&format!("mem.uff:{line}: record 1 (line 2): data: `")), "{e}");
}

/// One FRF record of `set`'s shape with chosen units and test DOFs.
fn frf_record(units: (&str, &str), response: &str, reference: &str, freqs: &[f64], v: &[C64]) -> Function58 {
    Function58 {
        header: header(4, OrdinateType::ComplexDouble, response, reference, units),
        abscissa: Abscissa::Uneven(freqs.to_vec()),
        ordinates: Ordinates::Complex(v.to_vec()),
    }
}

fn write_records(dir: &Path, name: &str, records: &[Function58]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, uff::encode(records, Encoding::BINARY).unwrap()).unwrap();
    path
}

#[test]
fn mobility_and_accelerance_become_receptance_by_powers_of_jw() {
    let dir = tempfile::tempdir().unwrap();
    let freqs = [2.0, 5.0, 11.0, 40.0];
    // a receptance with structure: one damped mode at 9 Hz
    let h: Vec<C64> = freqs
        .iter()
        .map(|&f| {
            let (w, wn) = (2.0 * PI * f, 2.0 * PI * 9.0);
            C64::new(1.0, 0.0) / C64::new(wn * wn - w * w, 0.04 * wn * w)
        })
        .collect();
    let jw = |f: f64| C64::new(0.0, 2.0 * PI * f);
    let cases: [(&str, &str, Vec<C64>, FrfKind); 6] = [
        ("m/N", "NONE", h.clone(), FrfKind::Receptance),
        // numerator units alone: per newton assumed (the record's denominator type is 0)
        ("m/s^2", "NONE", freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * jw(f) * x).collect(), FrfKind::Accelerance),
        ("m/s", "N", freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * x).collect(), FrfKind::Mobility),
        ("m/s^2", "N", freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * jw(f) * x).collect(), FrfKind::Accelerance),
        // units other than SI: scaled on reading
        ("g", "N", freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * jw(f) * x / 9.80665).collect(), FrfKind::Accelerance),
        ("mm/N", "NONE", h.iter().map(|&x| x * 1e3).collect(), FrfKind::Receptance),
    ];
    for (num, den, v, kind) in cases {
        let path = write_records(dir.path(), "k.uff", &[frf_record((num, den), "4:+Y", "4:+Y", &freqs, &v)]);
        let m = frf::io::load_measured(&path, &[]).unwrap();
        assert_eq!(m.set.kind(), kind, "{num}/{den}");
        let assumed = m.notes.iter().any(|n| n.contains("(per N assumed)"));
        assert_eq!(assumed, den == "NONE" && num == "m/s^2", "{:?}", m.notes);
        let r = m.set.to_receptance();
        for k in 0..freqs.len() {
            assert!((r.get(0, k) - h[k]).norm() <= 1e-12 * h[k].norm(), "{num}/{den} at {} Hz", freqs[k]);
        }
    }
    // two kinds in one file: the second is converted to the first's kind
    let mob: Vec<C64> = freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * x).collect();
    let acc: Vec<C64> = freqs.iter().zip(&h).map(|(&f, &x)| jw(f) * jw(f) * x).collect();
    let path = write_records(
        dir.path(),
        "mixed.uff",
        &[
            frf_record(("m/s^2", "N"), "4:+Y", "4:+Y", &freqs, &acc),
            frf_record(("m/s", "N"), "5:+Y", "4:+Y", &freqs, &mob),
        ],
    );
    let m = frf::io::load_measured(&path, &[]).unwrap();
    assert_eq!(m.set.kind(), FrfKind::Accelerance);
    for k in 0..freqs.len() {
        assert!((m.set.get(1, k) - acc[k]).norm() <= 1e-12 * acc[k].norm());
    }
    assert!(m.notes.iter().any(|n| n.contains("converted record(s) 2 to accelerance")), "{:?}", m.notes);
    // units that are not an FRF's, or that contradict the data types, are refused
    let mut bad = frf_record(("N", "N"), "4:+Y", "4:+Y", &freqs, &acc);
    let path = write_records(dir.path(), "bad.uff", std::slice::from_ref(&bad));
    let e = measured_err(&path, &[]);
    assert!(e.contains("record 1 (line 2): the units `N` / `N` are not those of an FRF from +Y to +Y"), "{e}");
    bad.header.numerator = DataAxis::new(8, "Displacement", "m/s^2");
    bad.header.denominator = DataAxis::new(13, "Force", "N");
    let path = write_records(dir.path(), "bad.uff", &[bad]);
    let e = measured_err(&path, &[]);
    assert!(e.contains("say accelerance, but the data types (displacement / excitation force) say receptance"), "{e}");
}

#[test]
fn channels_map_to_model_dofs_with_direction_and_map_signs() {
    let dir = tempfile::tempdir().unwrap();
    let freqs = [10.0, 20.0];
    let v = [C64::new(1.0, -2.0), C64::new(0.5, 0.25)];
    let map = |entries: &[(&str, &str, f64)]| -> Vec<ChannelMap> {
        entries.iter().map(|&(t, m, s)| ChannelMap { test: t.into(), model: m.parse().unwrap(), sign: s }).collect()
    };
    // response, reference, map, expected channel, expected factor
    type Case = (&'static str, &'static str, Vec<ChannelMap>, (DofRef, DofRef), f64);
    let m1 = map(&[("101:+Z", "2:uy", 1.0), ("1:+Z", "5:uy", -1.0)]);
    let m2 = map(&[("101:-Z", "2:uy", 1.0)]);
    let cases: Vec<Case> = vec![
        ("7:+Y", "7:+Y", vec![], (DofRef::new(7, Dof::Uy), DofRef::new(7, Dof::Uy)), 1.0),
        ("7:-Y", "8:+X", vec![], (DofRef::new(7, Dof::Uy), DofRef::new(8, Dof::Ux)), -1.0),
        ("7:-Y", "8:-X", vec![], (DofRef::new(7, Dof::Uy), DofRef::new(8, Dof::Ux)), 1.0),
        ("7:-RZ", "8:+Y", vec![], (DofRef::new(7, Dof::Rz), DofRef::new(8, Dof::Uy)), -1.0),
        ("101:+Z", "1:+Z", m1.clone(), (DofRef::new(2, Dof::Uy), DofRef::new(5, Dof::Uy)), -1.0),
        ("101:+Z", "1:-Z", m1.clone(), (DofRef::new(2, Dof::Uy), DofRef::new(5, Dof::Uy)), 1.0),
        ("101:-Z", "1:-Z", m1, (DofRef::new(2, Dof::Uy), DofRef::new(5, Dof::Uy)), -1.0),
        // an entry written for -Z: the file's -Z is +uy, its +Z is -uy
        ("101:-Z", "3:+Y", m2.clone(), (DofRef::new(2, Dof::Uy), DofRef::new(3, Dof::Uy)), 1.0),
        ("101:+Z", "3:+Y", m2, (DofRef::new(2, Dof::Uy), DofRef::new(3, Dof::Uy)), -1.0),
    ];
    for (resp, refr, map, (r, e), factor) in cases {
        let units = if resp.ends_with("RZ") { ("rad/N", "NONE") } else { ("m/N", "NONE") };
        let path = write_records(dir.path(), "m.uff", &[frf_record(units, resp, refr, &freqs, &v)]);
        let m = frf::io::load_measured(&path, &map).unwrap_or_else(|e| panic!("{resp} {refr}: {e}"));
        assert_eq!(m.set.channels(), &[Channel::new(r, e)], "{resp} / {refr}");
        for k in 0..2 {
            assert_eq!(m.set.get(0, k), v[k] * factor, "{resp} / {refr}");
        }
    }
    // out of plane without a map entry: the record, the DOF and the line to add
    let path = write_records(
        dir.path(),
        "z.uff",
        &[
            frf_record(("m/N", "NONE"), "7:+Y", "7:+Y", &freqs, &v),
            frf_record(("m/N", "NONE"), "101:-Z", "7:+Y", &freqs, &v),
        ],
    );
    let e = measured_err(&path, &[]);
    assert!(e.contains("record 2 (line") && e.contains("response 101:-Z: test DOF 101:-Z is along Z"), "{e}");
    assert!(
        e.contains("[[measurement.map]]") && e.contains("test = \"101:+Z\"") && e.contains("model = \"101:uy\""),
        "{e}"
    );
    // two records on the same model channel are refused, naming both
    let path = write_records(
        dir.path(),
        "dup.uff",
        &[
            frf_record(("m/N", "NONE"), "7:+Y", "7:+Y", &freqs, &v),
            frf_record(("m/N", "NONE"), "7:-Y", "7:-Y", &freqs, &v),
        ],
    );
    let e = measured_err(&path, &[]);
    assert!(e.contains("record 2 (line") && e.contains("and record 1 (line 2) both give H(7:uy,7:uy)"), "{e}");
}

#[test]
fn coherence_records_attach_to_their_frfs_and_other_types_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let freqs = [10.0, 20.0, 30.0];
    let v = [C64::new(1.0, -2.0), C64::new(0.5, 0.25), C64::new(-1.0, 0.0)];
    let coherence = |resp: &str, refr: &str, g: Vec<f64>| Function58 {
        header: header(6, OrdinateType::RealSingle, resp, refr, ("NONE", "NONE")),
        abscissa: Abscissa::Uneven(freqs.to_vec()),
        ordinates: Ordinates::Real(g),
    };
    let path = write_records(
        dir.path(),
        "c.uff",
        &[
            frf_record(("m/N", "NONE"), "7:+Y", "7:+Y", &freqs, &v),
            frf_record(("m/N", "NONE"), "8:+Y", "7:+Y", &freqs, &v),
            coherence("7:-Y", "7:+Y", vec![0.5, 0.75, 1.0]),
        ],
    );
    let m = frf::io::load_measured(&path, &[]).unwrap();
    assert_eq!(m.set.coherence(0), Some(&[0.5, 0.75, 1.0][..]));
    assert_eq!(m.set.coherence(1), Some(&[1.0, 1.0, 1.0][..]));
    assert!(m.notes.iter().any(|n| n.contains("no coherence for H(8:uy,7:uy); taken as 1")), "{:?}", m.notes);

    // a PSD among FRFs: refused, naming its record and line
    let mut psd = frf_record(("m/N", "NONE"), "8:+Y", "7:+Y", &freqs, &v);
    psd.header.function_type = 9;
    let records = [frf_record(("m/N", "NONE"), "7:+Y", "7:+Y", &freqs, &v), psd];
    let path = dir.path().join("psd.uff");
    let bytes = uff::encode(&records, Encoding::Ascii).unwrap();
    std::fs::write(&path, &bytes).unwrap();
    let line =
        String::from_utf8(bytes).unwrap().lines().enumerate().filter(|(_, l)| l.trim() == "58").nth(1).unwrap().0 + 1;
    let e = measured_err(&path, &[]);
    assert!(
        e.contains(&format!(":{line}: record 2 (line {line}): function type 9 (power spectral density) is not a frequency response function")),
        "{e}"
    );
    // coherence alone is not enough
    let path = write_records(dir.path(), "conly.uff", &[coherence("7:+Y", "7:+Y", vec![1.0; 3])]);
    let e = measured_err(&path, &[]);
    assert!(e.contains("no frequency response function") && e.contains("coherence only"), "{e}");
}

#[test]
fn extension_or_content_chooses_the_format() {
    let dir = tempfile::tempdir().unwrap();
    let s = small_set();
    let bytes = uff::to_uff_bytes(&s, &UffWriteOptions::default()).unwrap();
    for name in ["a.uff", "a.unv", "a.58", "a.UFF58", "a.dat", "noextension"] {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(frf::io::detect_format(&path).unwrap(), frf::io::MeasuredFormat::Uff, "{name}");
        assert_eq!(frf::io::read_measured(&path, &[]).unwrap(), s, "{name}");
    }
    let path = dir.path().join("b.data");
    std::fs::write(&path, frf::io::csv::to_csv_string(&s)).unwrap();
    assert_eq!(frf::io::detect_format(&path).unwrap(), frf::io::MeasuredFormat::Csv);
    assert_eq!(frf::io::read_measured(&path, &[]).unwrap().channels(), s.channels());
    let path = dir.path().join("c.bin");
    std::fs::write(&path, b"\x00\x01garbage").unwrap();
    let e = frf::io::read_measured(&path, &[]).unwrap_err().to_string();
    assert!(e.contains("cannot tell the format") && e.contains(".uff"), "{e}");
    // the mapping is used for UFF and the direction letters parse like case files
    let t: TestDof = "12:-rx".parse().unwrap();
    assert_eq!((t.node, t.direction, t.direction.negated()), (12, Direction::RX.negated(), Direction::RX));
}

/// The fixture's FRF: accelerance of a single DOF oscillator, `-w^2 / (k - w^2 m + j w c)`.
fn fixture_accelerance(f: f64) -> C64 {
    let (k, m, c) = (1.0e4, 1.0, 2.0);
    let w = 2.0 * PI * f;
    C64::new(-w * w, 0.0) / C64::new(k - w * w * m, w * c)
}

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)).unwrap()
}

/// `tests/data/oscillator_z_*.uff` were written by this crate's writer (and checked with
/// pyuff 2.5.8): an accelerance from 101:+Z to 1:-Z at 2.5..20 Hz and its coherence
/// `1 - 0.5 / f` (real single).
#[test]
fn committed_fixtures_read_as_the_oscillator_and_rewrite_byte_for_byte() {
    let map = [
        ChannelMap { test: "101:+Z".into(), model: "2:uy".parse().unwrap(), sign: 1.0 },
        ChannelMap { test: "1:+Z".into(), model: "1:uy".parse().unwrap(), sign: 1.0 },
    ];
    for (name, rel) in [("oscillator_z_ascii.uff", 1e-12), ("oscillator_z_binary.uff", 0.0)] {
        let bytes = fixture(name);
        let file = read(&bytes).unwrap();
        let m = uff::frfs_from_uff(Path::new(name), &file, &map).unwrap();
        assert_eq!(m.set.channels(), &[Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(1, Dof::Uy))]);
        assert_eq!(m.set.kind(), FrfKind::Accelerance);
        assert_eq!(m.sources[0].factor, -1.0, "the reference is along -Z, mapped from +Z");
        for (k, &f) in m.set.frequencies_hz().iter().enumerate() {
            assert_eq!(f, 2.5 * (k as f64 + 1.0));
            let want = -fixture_accelerance(f);
            assert!((m.set.get(0, k) - want).norm() <= rel * want.norm(), "{name} at {f} Hz");
            assert!((m.set.coherence(0).unwrap()[k] - (1.0 - 0.5 / f)).abs() < 1e-7);
        }
        assert!(m.notes.is_empty(), "{:?}", m.notes);
        // the writer reproduces the file exactly from what the reader made of it
        let functions: Vec<Function58> = file.records.iter().map(|r| r.function.clone()).collect();
        assert_eq!(uff::encode(&functions, file.records[0].encoding).unwrap(), bytes, "{name}");
    }
}

/// Replaces the byte count of the first `58b` line (columns 32-43).
fn with_byte_count(bytes: &[u8], count: usize) -> Vec<u8> {
    let at = bytes.windows(4).position(|w| w == b"58b ").unwrap() - 4;
    let mut b = bytes.to_vec();
    b[at + 31..at + 43].copy_from_slice(format!("{count:>12}").as_bytes());
    b
}

#[test]
fn pyuff_byte_counts_and_empty_datasets_are_worked_around_with_notes() {
    let bytes = fixture("oscillator_z_binary.uff");
    assert!(String::from_utf8_lossy(&bytes).contains("          11         128     0"));
    // pyuff writes 8 bytes per abscissa point whatever the type: 64 for 8 complex doubles
    let file = read(&with_byte_count(&bytes, 64)).unwrap();
    assert_eq!(file.records.len(), 2);
    assert_eq!(file.records[0].function, read(&bytes).unwrap().records[0].function);
    assert!(file.notes[0].contains("declares 64 bytes of data, but record 7 needs 128 bytes"), "{:?}", file.notes);
    // when record 7 (9 values here) does not end where the data does either, it is an error
    // at the data's first byte
    let mut b = bytes.clone();
    let r7 = b.windows(30).position(|w| w == b"         6         8         1").unwrap();
    b[r7 + 19] = b'9';
    let e = read(&b).unwrap_err();
    let FrfError::File(FileError::Parse { line, message, .. }) = &e else { panic!("{e:?}") };
    let start = bytes.iter().enumerate().filter(|(_, b)| **b == b'\n').nth(12).unwrap().0 + 1;
    assert_eq!(*line, start);
    assert!(message.contains("declares 128 bytes of data, but record 7's 9 values of type complex double (6) with even spacing need 144 bytes"), "{message}");
    // an empty dataset (`-1` twice), as pyuff leaves when it rewrites a binary file
    let mut b = b"    -1\n".to_vec();
    b.extend(&bytes);
    let file = read(&b).unwrap();
    assert_eq!((file.records.len(), file.records[0].line), (2, 3));
    assert!(file.notes[0].contains("line 2: an empty dataset"), "{:?}", file.notes);
}

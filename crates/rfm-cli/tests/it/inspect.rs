//! `rfm inspect`: the listing of measurement files, as a table and as JSON.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use frf::io::uff::{self, Abscissa, DataAxis, Encoding, Function58, Header58, OrdinateType, Ordinates};
use frf::{C64, Channel, FrfKind, FrfSet};

fn rfm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// An accelerance from 101:+Z to 1:-Z (800 even lines, ASCII), its coherence, and a
/// time response in binary.
fn write_file(dir: &Path) -> PathBuf {
    let header = |function_type, t, units: (&str, &str)| Header58 {
        ids: ["tap test".into(), "NONE".into(), "NONE".into(), "NONE".into(), "NONE".into()],
        function_type,
        function_id: 1,
        version: 0,
        load_case: 0,
        response_entity: "tip".into(),
        response: "101:+Z".parse().unwrap(),
        reference_entity: "NONE".into(),
        reference: "1:-Z".parse().unwrap(),
        ordinate_type: t,
        z_value: 0.0,
        abscissa_axis: DataAxis::new(18, "Frequency", "Hz"),
        numerator: DataAxis::new(12, "Acceleration", units.0),
        denominator: DataAxis::new(13, "Force", units.1),
        z_axis: DataAxis::none(),
    };
    let n = 800;
    let frf = Function58 {
        header: header(4, OrdinateType::ComplexDouble, ("m/s^2", "N")),
        abscissa: Abscissa::Even { min: 0.5, step: 0.5 },
        ordinates: Ordinates::Complex((0..n).map(|k| C64::new(1.0, k as f64)).collect()),
    };
    let coherence = Function58 {
        header: header(6, OrdinateType::RealSingle, ("NONE", "NONE")),
        abscissa: Abscissa::Even { min: 0.5, step: 0.5 },
        ordinates: Ordinates::Real(vec![0.99; n]),
    };
    let mut bytes = uff::encode(&[frf, coherence], Encoding::Ascii).unwrap();
    let time = Function58 {
        header: Header58 {
            abscissa_axis: DataAxis::new(17, "Time", "s"),
            ..header(1, OrdinateType::RealDouble, ("m/s^2", "NONE"))
        },
        abscissa: Abscissa::Uneven(vec![0.0, 0.001, 0.003]),
        ordinates: Ordinates::Real(vec![1.0, -1.0, 0.5]),
    };
    bytes.extend(uff::encode(&[time], Encoding::BINARY).unwrap());
    // a dataset that is not 58, skipped
    bytes.extend(b"    -1\n   164\n         1SI\n    -1\n");
    let path = dir.join("tap.uff");
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn inspect_lists_records_units_lines_and_skipped_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path());
    let out = rfm(&["inspect", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("universal file, 3 datasets 58, 1 other dataset skipped"), "{stdout}");
    let row = |needle: &str| stdout.lines().find(|l| l.starts_with(needle)).unwrap_or_else(|| panic!("{stdout}"));
    let frf = row("1 ");
    for cell in [
        "101:+Z (tip)",
        "1:-Z",
        "4 FRF (accelerance)",
        "m/s^2 / N",
        "0.5 .. 400 Hz (even)",
        "800",
        "complex double",
        "ASCII",
    ] {
        assert!(frf.contains(cell), "`{cell}` missing from `{frf}`");
    }
    let coh = row("2 ");
    assert!(coh.contains("6 coherence") && coh.contains("real single"), "{coh}");
    let time = row("3 ");
    assert!(
        time.contains("1 time response") && time.contains("0 .. 0.003 s (uneven)") && time.contains("binary"),
        "{time}"
    );
    assert!(stdout.contains("skipped dataset 164 (units) at line"), "{stdout}");

    let out = rfm(&["inspect", path.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["format"], "uff");
    let r = &json["records"][0];
    assert_eq!((r["response"]["node"].as_i64(), r["response"]["direction"].as_str()), (Some(101), Some("+Z")));
    assert_eq!((r["reference"]["node"].as_i64(), r["reference"]["direction"].as_str()), (Some(1), Some("-Z")));
    assert_eq!((r["function_type"].as_i64(), r["kind"].as_str()), (Some(4), Some("accelerance")));
    assert_eq!((r["abscissa"]["min"].as_f64(), r["abscissa"]["max"].as_f64()), (Some(0.5), Some(400.0)));
    assert_eq!((r["abscissa"]["count"].as_u64(), r["data_type"]["code"].as_i64()), (Some(800), Some(6)));
    assert_eq!(r["encoding"], "ASCII");
    assert_eq!(json["records"][2]["encoding"], "binary");
    assert_eq!(json["skipped"][0]["dataset"], 164);
}

#[test]
fn inspect_reads_csv_too() {
    let dir = tempfile::tempdir().unwrap();
    let ch = vec![Channel::new("2:uy".parse().unwrap(), "5:uy".parse().unwrap())];
    let mut s = FrfSet::zeros(vec![1.0, 2.0, 4.0], ch, FrfKind::Mobility).unwrap();
    s.set(0, 1, C64::new(1.0, 1.0));
    let path = dir.path().join("h.csv");
    frf::io::csv::write_csv(&s, &path).unwrap();
    let out = rfm(&["inspect", path.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["format"], "csv");
    let r = &json["records"][0];
    assert_eq!((r["response"]["dof"].as_str(), r["reference"]["dof"].as_str()), (Some("2:uy"), Some("5:uy")));
    assert_eq!(
        (r["kind"].as_str(), r["abscissa"]["count"].as_u64(), r["abscissa"]["max"].as_f64()),
        (Some("mobility"), Some(3), Some(4.0))
    );
    let out = rfm(&["inspect", path.to_str().unwrap()]);
    assert!(text(&out.stdout).contains("CSV (channels name model DOFs), 1 channel"), "{}", text(&out.stdout));
}

#[test]
fn inspect_fails_on_a_truncated_file_with_the_location() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path());
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.uff");
    std::fs::write(&cut, &bytes[..2000]).unwrap();
    let out = rfm(&["inspect", cut.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    // record 1's 13 header lines take 916 bytes (7 + 81 + 5 x 81 + 81 + 70 + 4 x 68); its data
    // lines of 81 bytes start at line 14, so byte 2000 is in line 14 + (2000 - 916) / 81 = 27
    assert!(err.contains("cut.uff:27: record 1 (line 2): the file ends inside the data"), "{err}");
    let out = rfm(&["inspect", dir.path().join("missing.uff").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("missing.uff: cannot read"), "{}", text(&out.stderr));
}

#[test]
fn inspect_lists_the_sample_files_it_can_read() {
    let samples = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/uff-samples");
    if !samples.is_dir() {
        eprintln!("skipping: no UFF samples at {}", samples.display());
        return;
    }
    let out = rfm(&["inspect", samples.join("sample_dataset58_psd.uff").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("9 power spectral density") && stdout.contains("3201"), "{stdout}");
    let out = rfm(&["inspect", samples.join("TestLab_161_164_18_15_82.uff").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("0 datasets 58, 7 other datasets skipped"), "{}", text(&out.stdout));
}

/// Nothing is taken as per newton or as SI in silence: a per-volt record
/// and one whose units are NONE each get a note, and the test geometry of
/// dataset 15 is listed.
#[test]
fn inspect_says_per_volt_and_si_assumed_and_lists_the_test_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let header = |units: (&str, &str), den_type| Header58 {
        ids: ["shaker test".into(), "NONE".into(), "NONE".into(), "NONE".into(), "NONE".into()],
        function_type: 4,
        function_id: 1,
        version: 0,
        load_case: 0,
        response_entity: "NONE".into(),
        response: "7:+Z".parse().unwrap(),
        reference_entity: "NONE".into(),
        reference: "1:+Z".parse().unwrap(),
        ordinate_type: OrdinateType::ComplexDouble,
        z_value: 0.0,
        abscissa_axis: DataAxis::new(18, "Frequency", "Hz"),
        numerator: DataAxis::new(12, "Acceleration", units.0),
        denominator: DataAxis::new(den_type, "Voltage", units.1),
        z_axis: DataAxis::none(),
    };
    let record = |h| Function58 {
        header: h,
        abscissa: Abscissa::Even { min: 1.0, step: 1.0 },
        ordinates: Ordinates::Complex((0..4).map(|k| C64::new(1.0, k as f64)).collect()),
    };
    let mut bytes =
        uff::encode(&[record(header(("m/s^2", "V"), 0)), record(header(("NONE", "NONE"), 13))], Encoding::Ascii)
            .unwrap();
    bytes.extend(b"    -1\n    15\n");
    bytes.extend(b"         7         0         0         1  2.50000E-01  0.00000E+00  1.00000E-02\n");
    bytes.extend(b"    -1\n");
    let path = dir.path().join("volts.uff");
    std::fs::write(&path, bytes).unwrap();
    let out = rfm(&["inspect", path.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let notes: Vec<&str> = json["notes"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect();
    assert!(notes.iter().any(|n| n.starts_with("record 1") && n.contains("per volt")), "{notes:?}");
    assert!(notes.iter().any(|n| n.starts_with("record 2") && n.contains("SI assumed")), "{notes:?}");
    assert!(notes.iter().any(|n| n.contains("no dataset 164")), "{notes:?}");
    assert_eq!(
        (json["records"][0]["per_volt"].as_bool(), json["records"][1]["per_volt"].as_bool()),
        (Some(true), Some(false))
    );
    assert_eq!((json["nodes"][0]["node"].as_i64(), json["nodes"][0]["x_m"].as_f64()), (Some(7), Some(0.25)));
    let out = rfm(&["inspect", path.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("test geometry: 1 nodes") && stdout.contains("note: record 1"), "{stdout}");

    // a CSV without units says what it assumed
    let csv = dir.path().join("h.csv");
    std::fs::write(&csv, "frequency_hz,\"H(2:uy,5:uy).re\",\"H(2:uy,5:uy).im\"\n1,1,0\n").unwrap();
    let out = rfm(&["inspect", csv.to_str().unwrap(), "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["notes"][0].as_str().unwrap().contains("receptance in SI (m/N) assumed"), "{json}");
}

/// The listing of a CSV file, as text and as JSON, is the one the tool
/// wrote before the text was streamed (`expected/`, written by `rfm
/// inspect` at commit b95b216): the same bytes.
#[test]
fn inspect_of_a_small_csv_prints_the_same_text_and_json_as_before() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/it/expected");
    for (args, expected) in [(&[][..], "inspect-small.txt"), (&["--json"][..], "inspect-small.json")] {
        let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
            .current_dir(&dir)
            .args(["inspect", "inspect-small.csv"])
            .args(args)
            .output()
            .expect("rfm runs");
        assert!(out.status.success(), "{}", text(&out.stderr));
        let expected = std::fs::read_to_string(dir.join(expected)).unwrap();
        assert_eq!(text(&out.stdout), expected, "rfm inspect {args:?}");
    }
}

/// A CSV file of many channels is listed as text line by line, not built
/// whole: 50,000 channels (a file of 3.5 MB) are listed within 128 MiB of
/// address space, where a listing built whole took some 400 MB.
#[cfg(target_os = "linux")]
#[test]
fn inspect_lists_many_csv_channels_in_bounded_memory() {
    use std::fmt::Write as _;

    let n = 50_000;
    let mut csv = String::from("# kind = receptance\n# units = SI\nfrequency_hz");
    for i in 0..n {
        let _ = write!(csv, ",H({}:uy,1:uy).re,H({}:uy,1:uy).im", i + 2, i + 2);
    }
    csv.push('\n');
    for k in 1..=3 {
        let _ = write!(csv, "{}", 10 * k);
        csv.push_str(&",1e-6,2e-7".repeat(n));
        csv.push('\n');
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("channels.csv");
    std::fs::write(&path, csv).unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {}; exec \"$0\" inspect \"$1\"", 128 * 1024))
        .arg(env!("CARGO_BIN_EXE_rfm"))
        .arg(&path)
        .output()
        .expect("sh runs");
    assert!(out.status.success(), "{:?}: {}", out.status, text(&out.stderr));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines[0].ends_with("CSV (channels name model DOFs), 50000 channels"), "{}", lines[0]);
    // the heading, the table's header and rule, a row per channel, the note on the units
    assert_eq!(lines.len(), 3 + n + 1);
    assert!(lines[3].starts_with("1 ") && lines[3].contains("2:uy"), "{}", lines[3]);
    assert!(lines[2 + n].starts_with("50000 ") && lines[2 + n].contains("50001:uy"), "{}", lines[2 + n]);
}

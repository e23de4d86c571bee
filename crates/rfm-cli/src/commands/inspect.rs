//! `rfm inspect`: what a measurement file holds, before any case uses it.

use std::path::Path;

use frf::io::MeasuredFormat;
use frf::io::uff::{self, Record58};
use serde_json::{Value, json};

use super::Result;
use crate::exit::Exit;
use crate::table::{Table, num};

/// `rfm inspect`: lists what a measurement file holds.
pub fn inspect(file: &Path, json: bool) -> Result<Exit> {
    let report = match frf::io::detect_format(file)? {
        MeasuredFormat::Uff => uff_report(file)?,
        MeasuredFormat::Csv if json => return csv_json(file),
        MeasuredFormat::Csv => return csv_text(file),
    };
    if json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report)?;
    }
    Ok(Exit::Success)
}

fn uff_report(file: &Path) -> Result<Value> {
    let u = uff::read_uff(file)?;
    let records: Vec<Value> = u.records.iter().map(record_json).collect();
    // what the units say, record by record: nothing is taken as SI or per newton in silence
    let mut notes = u.notes.clone();
    for r in u.records.iter().filter(|r| r.function.header.function_type == uff::FUNCTION_FRF) {
        match uff::frf_units(&r.function.header) {
            Ok(k) if k.per_volt => notes.push(format!(
                "{}: per volt ({}): the reference is a voltage, not a force; a case must fit a gain (the \
                 default) or give a calibration",
                r.label(),
                k.basis
            )),
            Ok(k) if k.assumed_si => notes.push(format!("{}: units not stated ({}); SI assumed", r.label(), k.basis)),
            Ok(k) if k.scale != 1.0 => {
                notes.push(format!("{}: values in {} scaled by {} to SI", r.label(), k.basis, k.scale))
            }
            Ok(_) => {}
            Err(e) => notes.push(format!("{}: {e}", r.label())),
        }
    }
    // the test geometry, which `[measurement] pair = "coordinates"` uses
    let nodes: Vec<Value> = match u.geometry() {
        Ok(g) => {
            notes.extend(g.notes.iter().map(|n| format!("geometry: {n}")));
            g.nodes
                .iter()
                .map(|n| {
                    json!({
                        "node": n.id,
                        "x_m": n.position[0],
                        "y_m": n.position[1],
                        "z_m": n.position[2],
                        "displacement_cs": n.displacement_cs,
                        "dataset": n.dataset,
                        "line": n.line,
                    })
                })
                .collect()
        }
        Err((line, message)) => {
            notes.push(format!("geometry (line {line}): {message}"));
            Vec::new()
        }
    };
    let skipped: Vec<Value> = u
        .skipped
        .iter()
        .map(|d| json!({ "dataset": d.number, "line": d.line, "description": d.description() }))
        .collect();
    Ok(json!({
        "file": file.display().to_string(),
        "format": "uff",
        "records": records,
        "skipped": skipped,
        "nodes": nodes,
        "notes": notes,
    }))
}

fn record_json(r: &Record58) -> Value {
    let f = &r.function;
    let h = &f.header;
    let x = f.abscissa_values();
    let kind = (h.function_type == uff::FUNCTION_FRF).then(|| uff::frf_units(h).ok()).flatten();
    let dof = |d: uff::TestDof, entity: &str| json!({ "node": d.node, "direction": d.direction.to_string(), "entity": entity });
    json!({
        "record": r.index,
        "line": r.line,
        "response": dof(h.response, &h.response_entity),
        "reference": dof(h.reference, &h.reference_entity),
        "function_type": h.function_type,
        "function": uff::function_type_name(h.function_type),
        "kind": kind.as_ref().map(|k| k.kind.name()),
        "per_volt": kind.as_ref().map(|k| k.per_volt),
        "scale_to_si": kind.as_ref().map(|k| k.scale),
        "units": { "numerator": h.numerator.units, "denominator": h.denominator.units },
        "abscissa": {
            "units": h.abscissa_axis.units,
            "min": x.first(),
            "max": x.last(),
            "count": f.len(),
            "spacing": if f.is_even() { "even" } else { "uneven" },
        },
        "data_type": { "code": h.ordinate_type.code(), "name": h.ordinate_type.name() },
        "encoding": r.encoding.name(),
    })
}

/// The record of channel `c` of a CSV file: what `inspect` shows of a UFF
/// record, for a file that has no records.
fn csv_record(set: &frf::FrfSet, c: usize) -> Value {
    let f = set.frequencies_hz();
    let ch = set.channels()[c];
    json!({
        "record": c + 1,
        "line": Value::Null,
        "response": { "dof": ch.response.to_string() },
        "reference": { "dof": ch.reference.to_string() },
        "function_type": uff::FUNCTION_FRF,
        "function": uff::function_type_name(uff::FUNCTION_FRF),
        "kind": set.kind().name(),
        "units": Value::Null,
        "abscissa": {
            "units": "Hz",
            "min": f.first(),
            "max": f.last(),
            "count": f.len(),
            "spacing": "listed",
        },
        "data_type": { "code": Value::Null, "name": "complex (decimal text)" },
        "encoding": "CSV",
    })
}

/// The notes of a CSV file: what reading it assumed or scaled, and the units.
fn csv_notes(notes: &[String], per_volt: bool, units: &str) -> Vec<String> {
    let mut out = notes.to_vec();
    if !per_volt && !notes.iter().any(|n| n.contains("assumed")) {
        out.push(format!("units {units}"));
    }
    out
}

/// The JSON report of a CSV file (the shape of a UFF file's), written
/// record by record: a file of 500,000 channels would otherwise hold a
/// JSON tree of several gigabytes.
fn csv_json(file: &Path) -> Result<Exit> {
    use serde::ser::SerializeSeq as _;
    use std::io::Write as _;

    /// The records, serialised one at a time from the set.
    struct Records<'a>(&'a frf::FrfSet);

    impl serde::Serialize for Records<'_> {
        fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
            let set = self.0;
            let mut seq = s.serialize_seq(Some(set.channels().len()))?;
            for c in 0..set.channels().len() {
                seq.serialize_element(&csv_record(set, c))?;
            }
            seq.end()
        }
    }

    #[derive(serde::Serialize)]
    struct Report<'a> {
        file: String,
        format: &'static str,
        records: Records<'a>,
        skipped: [(); 0],
        notes: Vec<String>,
    }

    let read = frf::io::csv::read_csv_with(file, &[])?;
    let notes = csv_notes(&read.notes, read.per_volt, &read.units);
    let set = read.set;
    let report = Report { file: file.display().to_string(), format: "csv", records: Records(&set), skipped: [], notes };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let written = serde_json::to_writer_pretty(&mut out, &report)
        .map_err(std::io::Error::from)
        .and_then(|()| writeln!(out))
        .and_then(|()| out.flush());
    finished(written)
}

/// The text report of a CSV file, written line by line: the table of its
/// channels is laid out in one pass over the set and written in a second,
/// each record made when it is needed, so that a file of 500,000 channels
/// is listed in the memory its set takes.
fn csv_text(file: &Path) -> Result<Exit> {
    use std::io::Write as _;

    let read = frf::io::csv::read_csv_with(file, &[])?;
    let notes = csv_notes(&read.notes, read.per_volt, &read.units);
    let set = &read.set;
    let n = set.channels().len();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut write = || -> std::io::Result<()> {
        writeln!(out, "{}", heading(&file.display().to_string(), true, n, 0))?;
        if n > 0 {
            let rows = || (0..n).map(|c| record_row(&csv_record(set, c)));
            crate::table::write_streamed(&RECORD_COLUMNS, rows, &mut out)?;
        }
        for note in &notes {
            writeln!(out, "note: {note}")?;
        }
        out.flush()
    };
    finished(write())
}

/// The end of a report written through a buffer.
fn finished(written: std::io::Result<()>) -> Result<Exit> {
    match written {
        // the reader has gone (`rfm inspect big.csv | head`): nothing is lost
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(Exit::Success),
        other => other.map(|()| Exit::Success).map_err(Into::into),
    }
}

/// The columns of the table of records.
const RECORD_COLUMNS: [&str; 10] =
    ["record", "line", "response", "reference", "function", "units", "abscissa", "values", "data type", "encoding"];

/// The first line of a report: the file, its format and what it holds.
fn heading(file: &str, csv: bool, records: usize, skipped: usize) -> String {
    let count = |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    format!(
        "{file}: {}, {}{}",
        if csv { "CSV (channels name model DOFs)" } else { "universal file" },
        if csv { count(records, "channel", "channels") } else { count(records, "dataset 58", "datasets 58") },
        if skipped == 0 {
            String::new()
        } else {
            format!(", {} skipped", count(skipped, "other dataset", "other datasets"))
        }
    )
}

/// The row of a record (UFF or CSV) in the table of records.
fn record_row(r: &Value) -> Vec<String> {
    vec![
        r["record"].to_string(),
        r["line"].as_u64().map_or("-".into(), |l| l.to_string()),
        dof_text(&r["response"]),
        dof_text(&r["reference"]),
        function_text(r),
        units_text(&r["units"]),
        abscissa_text(&r["abscissa"]),
        r["abscissa"]["count"].to_string(),
        r["data_type"]["name"].as_str().unwrap_or_default().to_string(),
        r["encoding"].as_str().unwrap_or_default().to_string(),
    ]
}

/// The text report of a UFF file, from its JSON.
fn print_report(report: &Value) -> Result<()> {
    let records = report["records"].as_array().map(Vec::as_slice).unwrap_or_default();
    let skipped = report["skipped"].as_array().map(Vec::as_slice).unwrap_or_default();
    let file = report["file"].as_str().unwrap_or_default();
    outln!("{}", heading(file, report["format"] == "csv", records.len(), skipped.len()));
    if !records.is_empty() {
        let mut t = Table::new(&RECORD_COLUMNS);
        for r in records {
            t.row(record_row(r));
        }
        outln!("{}", t.render());
    }
    for n in report["notes"].as_array().map(Vec::as_slice).unwrap_or_default() {
        outln!("note: {}", n.as_str().unwrap_or_default());
    }
    let nodes = report["nodes"].as_array().map(Vec::as_slice).unwrap_or_default();
    if !nodes.is_empty() {
        let mut t = Table::new(&["node", "x (m)", "y (m)", "z (m)", "directions in", "line"]);
        for n in nodes {
            t.row(vec![
                n["node"].to_string(),
                num(n["x_m"].as_f64().unwrap_or(f64::NAN)),
                num(n["y_m"].as_f64().unwrap_or(f64::NAN)),
                num(n["z_m"].as_f64().unwrap_or(f64::NAN)),
                match n["displacement_cs"].as_i64() {
                    Some(0) | None => "global".into(),
                    Some(cs) => format!("system {cs}"),
                },
                n["line"].to_string(),
            ]);
        }
        outln!("test geometry: {} nodes\n{}", nodes.len(), t.render());
    }
    for d in skipped {
        outln!(
            "skipped dataset {} ({}) at line {}",
            d["dataset"],
            d["description"].as_str().unwrap_or_default(),
            d["line"]
        );
    }
    Ok(())
}

fn dof_text(v: &Value) -> String {
    if let Some(d) = v["dof"].as_str() {
        return d.to_string();
    }
    let entity = v["entity"].as_str().unwrap_or_default();
    let base = format!("{}:{}", v["node"], v["direction"].as_str().unwrap_or_default());
    if entity.is_empty() || entity.eq_ignore_ascii_case("none") { base } else { format!("{base} ({entity})") }
}

fn function_text(r: &Value) -> String {
    let name = match r["function_type"].as_i64() {
        Some(4) => "FRF".to_string(),
        _ => r["function"].as_str().unwrap_or_default().to_string(),
    };
    match r["kind"].as_str() {
        Some(k) => format!("{} {name} ({k})", r["function_type"]),
        None => format!("{} {name}", r["function_type"]),
    }
}

fn units_text(u: &Value) -> String {
    let (n, d) = (u["numerator"].as_str().unwrap_or("-"), u["denominator"].as_str().unwrap_or("NONE"));
    if d.is_empty() || d.eq_ignore_ascii_case("none") { n.to_string() } else { format!("{n} / {d}") }
}

fn abscissa_text(a: &Value) -> String {
    match (a["min"].as_f64(), a["max"].as_f64()) {
        (Some(lo), Some(hi)) => {
            let units = a["units"].as_str().unwrap_or_default();
            let units = if units.eq_ignore_ascii_case("none") { "" } else { units };
            format!("{} .. {} {units} ({})", num(lo), num(hi), a["spacing"].as_str().unwrap_or_default())
        }
        _ => "-".into(),
    }
}

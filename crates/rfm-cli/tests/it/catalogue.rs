//! A catalogue of malformed inputs: case files and measured files written to
//! a temporary folder, each run through `rfm`, which must exit non-zero with
//! a message that names the file and line, or the node, element, group or
//! frequency at fault.

use std::path::Path;
use std::process::Command;

use damping::DampedSystem;
use fe_model::{CaseFile, Dof, DofRef};
use frf::Channel;

/// A 4-element steel cantilever along x, nodes 1-5, clamped at node 1.
const BEAM: &str = include_str!("cases/catalogue-beam.toml");

/// One malformed input.
struct Entry {
    /// What is wrong.
    what: &'static str,
    /// Files to write (name, contents).
    files: Vec<(&'static str, Vec<u8>)>,
    /// The command, `{dir}` standing for the folder of the files.
    args: Vec<&'static str>,
    /// Words the error must contain; `@file:text` stands for
    /// `file:LINE:` with the line of the first occurrence of `text` in
    /// that file.
    expect: Vec<&'static str>,
    /// The exit code (see `rfm --help`): 3 for invalid input, 4 for failed
    /// numerics.
    code: i32,
}

/// Exit code of invalid input.
const INVALID_INPUT: i32 = 3;
/// Exit code of failed numerics.
const NUMERICS: i32 = 4;

fn replaced(from: &str, to: &str) -> String {
    assert!(BEAM.contains(from), "{from}");
    BEAM.replacen(from, to, 1)
}

fn case(text: String) -> Vec<(&'static str, Vec<u8>)> {
    vec![("cat.toml", text.into_bytes())]
}

/// A case file entry run with `rfm simulate`.
fn bad_case(what: &'static str, text: String, expect: Vec<&'static str>) -> Entry {
    Entry {
        what,
        files: case(text),
        args: vec!["simulate", "{dir}/cat.toml", "--out", "{dir}/h.csv"],
        expect,
        code: INVALID_INPUT,
    }
}

/// Measured receptances of the beam at 10, 20, ... 100 Hz, for the 3:uy
/// and 5:uy responses to 5:uy.
fn measured() -> frf::FrfSet {
    let model = CaseFile::parse(Path::new("cat.toml"), BEAM).unwrap().model;
    let tip = DofRef::new(5, Dof::Uy);
    let channels = [Channel::new(DofRef::new(3, Dof::Uy), tip), Channel::new(tip, tip)];
    let freqs: Vec<f64> = (1..=10).map(|k| 10.0 * f64::from(k)).collect();
    frf::synthesize(&DampedSystem::new(model).unwrap(), &channels, &freqs).unwrap()
}

fn csv() -> String {
    frf::io::csv::to_csv_string(&measured())
}

fn uff() -> String {
    String::from_utf8(frf::io::uff::to_uff_bytes(&measured(), &Default::default()).unwrap()).unwrap()
}

/// The beam case reading `data`, with extra `[measurement]` lines, and the
/// data file; run with `rfm compare`.
fn bad_data(what: &'static str, name: &'static str, data: String, extra: &str, expect: Vec<&'static str>) -> Entry {
    let text = format!("{BEAM}data = \"{name}\"\n{extra}");
    let mut files = case(text);
    files.push((name, data.into_bytes()));
    Entry { what, files, args: vec!["compare", "{dir}/cat.toml"], expect, code: INVALID_INPUT }
}

/// Line `n` (1-based) of `text` replaced by `f(line)`.
fn edit_line(text: &str, n: usize, f: impl Fn(&str) -> String) -> String {
    text.lines().enumerate().map(|(i, l)| if i + 1 == n { f(l) } else { l.to_string() } + "\n").collect()
}

/// The first line of `text` containing `pat` (1-based).
fn line_of(text: &str, pat: &str) -> usize {
    text.lines().position(|l| l.contains(pat)).unwrap_or_else(|| panic!("`{pat}` not found")) + 1
}

/// The single-DOF oscillators of an undamped 1 kg mass (1 kg m^2) on
/// springs of 1e4 to ground in x, y and rotation: all three at
/// sqrt(1e4) / (2 pi) = 15.915494309189533 Hz.
const OSCILLATOR: &str = r#"title = "undamped oscillator"
nodes = [[1, 0.0, 0.0]]

[groups.g]
"#;

/// The universal-file fixture of the frf tests: an accelerance from test
/// point 101:+Z to 1:-Z at 2.5, 5, ... 20 Hz (record 1, lines 1-18) and its
/// coherence (record 2, lines 19-34).
const OSC_UFF: &str = include_str!("../../../frf/tests/data/oscillator_z_ascii.uff");

/// The fixture with line `n` (1-based) replaced, and only lines
/// `..=last` kept (then closed with `-1`).
fn osc_uff(edits: &[(usize, &str)], last: usize) -> Vec<u8> {
    let mut lines: Vec<String> = OSC_UFF.lines().take(last).map(str::to_string).collect();
    for &(n, text) in edits {
        lines[n - 1] = text.to_string();
    }
    if lines.last().is_none_or(|l| l.trim() != "-1") {
        lines.push("    -1".into());
    }
    (lines.join("\n") + "\n").into_bytes()
}

/// The beam case reading the fixture as `m.uff`, its test points mapped to
/// the tip (5:uy) and node 4; with `extra` appended, run with `args`.
fn osc_entry(
    what: &'static str,
    uff: Vec<u8>,
    extra: &str,
    args: &[&'static str],
    expect: Vec<&'static str>,
    code: i32,
) -> Entry {
    // the data give the lines: a case with a data file needs no `frequencies`
    let text = BEAM
        .replace("responses = [\"3:uy\", \"5:uy\"]", "responses = [\"4:uy\"]")
        .replace("[truth]\n", "")
        .replace("frequencies = { from = 10.0, to = 100.0, step = 10.0 }\n", "")
        + "data = \"m.uff\"\n[[measurement.map]]\ntest = \"101:+Z\"\nmodel = \"4:uy\"\n[[measurement.map]]\ntest = \"1:+Z\"\nmodel = \"5:uy\"\nsign = -1\n"
        + extra;
    let mut files = case(text);
    files.push(("m.uff", uff));
    Entry { what, files, args: args.to_vec(), expect, code }
}

/// The beam case (truth data) with an `[update]` of its damping.
fn beam_update(replace: (&str, &str)) -> String {
    replaced(replace.0, replace.1) + "\n[update]\nparameters = [\"group.beam.alpha\", \"group.beam.beta\"]\n"
}

/// Exit code of a wrong command line.
const USAGE: i32 = 2;

fn catalogue() -> Vec<Entry> {
    let csv = csv();
    let uff = uff();
    // CSV: line 1 is a comment (kind), line 2 the header, data from line 3
    let csv_header = line_of(&csv, "frequency_hz");
    let first_row = csv_header + 1;
    let uff_line = |pat: &str| line_of(&uff, pat);
    vec![
        // ------------------------------------------------------------ case files
        bad_case("TOML syntax", replaced("elements = 4", "elements = "), vec!["@cat.toml:elements = ", "expected"]),
        bad_case(
            "unknown top-level key",
            replaced("title =", "titel ="),
            vec!["@cat.toml:titel", "unknown field `titel`", "did you mean `title`?"],
        ),
        bad_case(
            "a history entry naming an effect there is no such kind of",
            format!("{BEAM}\n[[history]]\nstep = \"+ a joint\"\nmisfit = 0.1\neffect = \"flexible-joint\"\n"),
            vec!["@cat.toml:[[history]]", "unknown effect `flexible-joint`", "did you mean `flexible_joint`?"],
        ),
        bad_case(
            "unknown key in a group",
            replaced("alpha = 1e-5", "alpah = 1e-5"),
            vec!["@cat.toml:alpah", "did you mean `alpha`?"],
        ),
        bad_case(
            "unknown key in a line",
            replaced("elements = 4", "elemnts = 4"),
            vec!["@cat.toml:elemnts", "did you mean `elements`?"],
        ),
        bad_case(
            "unknown key in a material",
            replaced("rho = 7800", "rh0 = 7800"),
            vec!["@cat.toml:rh0", "did you mean `rho`?"],
        ),
        bad_case(
            "unknown key in [measurement]",
            replaced("references =", "referencs ="),
            vec!["@cat.toml:referencs", "did you mean `references`?"],
        ),
        bad_case(
            "unknown key in [truth]",
            replaced("[truth]\n", "[truth]\nnoize = 0.01\n"),
            vec!["@cat.toml:noize", "did you mean `noise`?"],
        ),
        bad_case(
            "unknown key in [update]",
            format!("{BEAM}\n[update]\nparameters = [\"group.beam.alpha\"]\nmax_iteration = 3\n"),
            vec!["@cat.toml:max_iteration", "did you mean `max_iterations`?"],
        ),
        bad_case(
            "unknown key in [[joints]]",
            format!("{BEAM}\n[[joints]]\nname = \"j\"\nnode = 3\nelemets = [3]\ngroup = \"beam\"\n"),
            vec!["@cat.toml:elemets", "did you mean `elements`?"],
        ),
        bad_case(
            "unknown key in a frequency range",
            replaced("step = 10.0", "stpe = 10.0"),
            vec!["@cat.toml:stpe", "unknown key `stpe`", "did you mean `step`?"],
        ),
        bad_case(
            "missing field",
            replaced("material = \"steel\"\n", ""),
            vec!["@cat.toml:[[lines]]", "missing field `material`"],
        ),
        bad_case(
            "mistyped field",
            replaced("elements = 4", "elements = \"four\""),
            vec!["@cat.toml:\"four\"", "invalid type"],
        ),
        bad_case(
            "E <= 0",
            replaced("E = 2.0e11", "E = -2.0e11"),
            vec!["@cat.toml:E = -2.0e11", "material `steel`: E", "positive"],
        ),
        bad_case(
            "rho = 0",
            replaced("rho = 7800", "rho = 0"),
            vec!["@cat.toml:rho = 0", "material `steel`: rho", "positive"],
        ),
        bad_case(
            "mu <= 0",
            replaced("beta = 0.5", "beta = 0.5\nmu = -3.0"),
            vec!["@cat.toml:[groups.beam]", "group `beam`: mu", "positive"],
        ),
        bad_case(
            "negative spring stiffness",
            format!("{BEAM}\n[[springs]]\nname = \"s\"\nnode = 5\nky = -1e3\ngroup = \"beam\"\n"),
            vec!["@cat.toml:[[springs]]", "spring `s`: ky", "zero or positive"],
        ),
        bad_case(
            "zero-length element",
            format!(
                "{BEAM}\n[[beams]]\nid = 9\nnodes = [5, 5]\nmaterial = \"steel\"\nsection = \"bar\"\ngroup = \"beam\"\n"
            ),
            vec!["@cat.toml:[[beams]]", "element 9", "zero length"],
        ),
        bad_case(
            "duplicate node id",
            replaced(
                "title = \"catalogue beam\"\n",
                "title = \"catalogue beam\"\nnodes = [[1, 0.0, 0.0], [1, 0.5, 0.0]]\n",
            ),
            vec!["@cat.toml:[1, 0.5, 0.0]", "node 1"],
        ),
        bad_case(
            "support at an unknown node",
            replaced("node = 1", "node = 71"),
            vec!["@cat.toml:[[supports]]", "node 71", "does not exist"],
        ),
        bad_case(
            "unknown group",
            replaced("group = \"beam\"", "group = \"bean\""),
            vec!["@cat.toml:group = \"bean\"", "unknown group `bean`", "did you mean `beam`?"],
        ),
        bad_case(
            "unknown material",
            replaced("material = \"steel\"", "material = \"steal\""),
            vec!["@cat.toml:material = \"steal\"", "unknown material `steal`", "did you mean `steel`?"],
        ),
        bad_case(
            "measured DOF at an unknown node",
            replaced("\"3:uy\", \"5:uy\"]", "\"3:uy\", \"50:uy\"]"),
            vec!["@cat.toml:50:uy", "50"],
        ),
        bad_case(
            "frequencies that go backwards",
            replaced("frequencies = { from = 10.0, to = 100.0, step = 10.0 }", "frequencies = [10.0, 30.0, 20.0]"),
            vec!["@cat.toml:[10.0, 30.0, 20.0]", "increase"],
        ),
        bad_case(
            "unknown [update] parameter",
            format!("{BEAM}\n[update]\nparameters = [\"group.beam.alpah\"]\n"),
            vec!["@cat.toml:group.beam.alpah", "alpha"],
        ),
        bad_case(
            "unknown mask rule",
            format!("{BEAM}data = \"m.csv\"\nmask = [\"non-finit\"]\n"),
            vec!["@cat.toml:non-finit", "did you mean `non-finite`?"],
        ),
        bad_case(
            "a pin instead of a clamp: mechanism",
            replaced("node = 1\n", "node = 1\ndofs = [\"ux\", \"uy\"]\n"),
            vec!["cat.toml: ", "zero-energy motion", "largest at 5:uy", "nodes 1-5"],
        ),
        bad_case(
            "no support: free body",
            replaced("[[supports]]\nnode = 1\n", ""),
            vec!["cat.toml: ", "3 independent zero-energy motions", "nodes 1-5"],
        ),
        bad_case(
            "a sensor mass on a pin: its rotation is free",
            format!(
                "{}\n[[springs]]\nname = \"pin\"\nnodes = [5, 6]\nkx = 1e6\nky = 1e6\ngroup = \"beam\"\n\n[[masses]]\nname = \"sensor\"\nnode = 6\nm = 0.05\nj = 1e-5\ngroup = \"beam\"\n",
                replaced("title = \"catalogue beam\"\n", "title = \"catalogue beam\"\nnodes = [[6, 1.0, 0.0]]\n")
                    .replace("elements = 4\n", "elements = 4\nfirst_node = 1\n")
            ),
            vec!["cat.toml: ", "a zero-energy motion", "largest at 6:rz (node 6)"],
        ),
        Entry {
            what: "undamped model on its resonance",
            files: case(format!(
                "{OSCILLATOR}\n[[springs]]\nname = \"k\"\nnode = 1\nkx = 1e4\nky = 1e4\nkr = 1e4\ngroup = \"g\"\n\n[[masses]]\nname = \"m\"\nnode = 1\nm = 1.0\nj = 1.0\ngroup = \"g\"\n\n[truth]\n\n[measurement]\nfrequencies = [10.0, 15.915494309189533]\nreferences = [\"1:uy\"]\nresponses = [\"1:uy\"]\n"
            )),
            args: vec!["simulate", "{dir}/cat.toml", "--out", "{dir}/h.csv"],
            expect: vec!["singular at 15.915494309189533 Hz"],
            code: NUMERICS,
        },
        // ------------------------------------------------------------ measured data
        bad_data(
            "CSV row cut short",
            "m.csv",
            edit_line(&csv, first_row + 2, |l| l.rsplit_once(',').unwrap().0.to_string()),
            "",
            vec!["m.csv:", "4 fields, but the header has 5"],
        ),
        bad_data(
            "CSV NaN",
            "m.csv",
            edit_line(&csv, first_row + 4, |l| {
                let mut f: Vec<&str> = l.split(',').collect();
                f[2] = "NaN";
                f.join(",")
            }),
            "",
            vec!["m.csv:", "50 Hz is NaN", "mask = [\"non-finite\"]"],
        ),
        bad_data(
            "CSV frequencies going backwards",
            "m.csv",
            edit_line(&csv, first_row + 3, |l| format!("5{}", &l[l.find(',').unwrap()..])),
            "",
            vec!["m.csv:", "below the one before it"],
        ),
        bad_data(
            "CSV repeated frequency",
            "m.csv",
            edit_line(&csv, first_row + 3, |l| format!("30{}", &l[l.find(',').unwrap()..])),
            "",
            vec!["m.csv:", "repeats 30 Hz", "duplicate-lines"],
        ),
        bad_data(
            "CSV duplicate channel",
            "m.csv",
            edit_line(&csv, csv_header, |l| l.replace("H(3:uy,5:uy)", "H(5:uy,5:uy)")),
            "",
            vec!["m.csv:", "appears twice"],
        ),
        bad_data(
            "CSV channel at a node the model lacks",
            "m.csv",
            edit_line(&csv, csv_header, |l| l.replace("H(3:uy,5:uy)", "H(99:uy,5:uy)")),
            "",
            vec!["m.csv:", "the model has no node 99", "unmodelled-channels"],
        ),
        bad_data(
            "CSV channel at a supported DOF",
            "m.csv",
            edit_line(&csv, csv_header, |l| l.replace("H(3:uy,5:uy)", "H(1:uy,5:uy)")),
            "",
            vec!["m.csv:", "1:uy is held fixed"],
        ),
        bad_data(
            "CSV text in a number",
            "m.csv",
            edit_line(&csv, first_row + 1, |l| l.replacen(',', ",x", 1)),
            "",
            vec!["m.csv:", "is not a number"],
        ),
        bad_data(
            "CSV channels the case lists are missing",
            "m.csv",
            edit_line(&csv, csv_header, |l| l.replace("H(3:uy,5:uy)", "H(4:uy,5:uy)")),
            "",
            vec!["m.csv", "no channel H(3:uy,5:uy)"],
        ),
        bad_data("UFF cut short", "m.uff", uff[..uff.len() / 3].to_string(), "", vec!["m.uff:", "record 1"]),
        bad_data(
            "UFF NaN in the data",
            "m.uff",
            {
                let line = uff_line("    -1") + 13;
                edit_line(&uff, line, |l| format!("{:>20}{}", "NaN", &l[20..]))
            },
            "",
            vec!["m.uff:", "record 1", "NaN", "non-finite"],
        ),
        bad_data(
            "UFF units that contradict the data types",
            "m.uff",
            uff.replacen("Displacement         m   ", "Displacement         m/s ", 1),
            "",
            vec!["m.uff:", "record 1", "say mobility", "say receptance"],
        ),
        bad_data(
            "UFF abscissa in seconds",
            "m.uff",
            uff.replacen("Hz", "s ", 1),
            "",
            vec!["m.uff:", "record 1", "not frequency"],
        ),
        bad_data(
            "UFF response at a node the model lacks",
            "m.uff",
            uff.replacen("NONE               3   2", "NONE              93   2", 1),
            "",
            vec!["m.uff:", "record 1", "no node 93"],
        ),
        // ------------------------------------------------ issue 14: empty, huge and degenerate inputs
        osc_entry(
            "UFF whose record declares 0 values",
            osc_uff(&[(9, "         6         0         1 2.500000E+00 2.500000E+00 0.000000E+00")], 13),
            "",
            &["compare", "{dir}/cat.toml"],
            vec!["m.uff:2:", "record 1 (line 2)", "no frequency line to compare", "declares no values"],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF whose only line is at 0 Hz (update)",
            osc_uff(
                &[
                    (9, "         6         1         1 0.000000E+00 2.500000E+00 0.000000E+00"),
                    (14, " 1.0E+00 0.0E+00"),
                ],
                14,
            ),
            "\n[update]\nparameters = [\"group.beam.alpha\"]\n",
            &["update", "{dir}/cat.toml"],
            vec!["m.uff:2:", "no frequency line to compare", "all at 0 Hz or below"],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF whose only line is at 0 Hz (diagnose)",
            osc_uff(
                &[
                    (9, "         6         1         1 0.000000E+00 2.500000E+00 0.000000E+00"),
                    (14, " 1.0E+00 0.0E+00"),
                ],
                14,
            ),
            "",
            &["diagnose", "{dir}/cat.toml"],
            vec!["m.uff:2:", "no frequency line to compare", "all at 0 Hz or below"],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF abscissa going backwards",
            osc_uff(&[(9, "         6         8         1 2.000000E+01-2.500000E+00 0.000000E+00")], 34),
            "",
            &["compare", "{dir}/cat.toml"],
            vec!["m.uff:", "record 1", "below the one before it", "must increase"],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF coherence of 7",
            osc_uff(&[(32, " 7.000000E+00 9.000000E-01 9.333333E-01 9.500000E-01 9.600000E-01 9.666666E-01")], 34),
            "",
            &["compare", "{dir}/cat.toml"],
            vec![
                "m.uff:20:",
                "record 2 (line 20)",
                "coherence of H(4:uy,5:uy) at 2.5 Hz is 7, outside 0..1",
                "bad-coherence",
            ],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF coherence NaN",
            osc_uff(&[(33, "          NaN 9.750000E-01")], 34),
            "",
            &["compare", "{dir}/cat.toml"],
            vec!["m.uff:20:", "coherence of H(4:uy,5:uy) at 17.5 Hz is NaN", "bad-coherence"],
            INVALID_INPUT,
        ),
        osc_entry(
            "UFF units rfm cannot read",
            osc_uff(&[(11, "        12    0    0    0 Acceleration         furlong             ")], 34),
            "",
            &["compare", "{dir}/cat.toml"],
            vec!["m.uff:2:", "record 1", "the ordinate units `furlong` are not units rfm can read", "NONE"],
            INVALID_INPUT,
        ),
        Entry {
            what: "update --lines 0",
            files: case(beam_update(("alpha = 1e-5", "alpha = 1e-5"))),
            args: vec!["update", "{dir}/cat.toml", "--lines", "0"],
            expect: vec!["--lines 0", "at least one measured line"],
            code: USAGE,
        },
        bad_case(
            "a response range of four billion nodes (checked before it is allocated)",
            replaced("\"3:uy\", \"5:uy\"]", "\"2..4000000000:uy\"]"),
            vec!["@cat.toml:2..4000000000", "node 6 does not exist in the model"],
        ),
        bad_case(
            "E = -1e300 printed as a number, not 301 digits",
            replaced("E = 2.0e11", "E = -1e300"),
            vec!["@cat.toml:E = -1e300", "material `steel`: E must be positive and finite, got -1e300"],
        ),
        bad_case(
            "a tie between distant nodes",
            format!("{BEAM}\n[[ties]]\nnodes = [2, 4]\ndofs = [\"uy\"]\n"),
            vec!["cat.toml", "tie 2-4", "joins nodes 5.000000e-1 m apart", "coincident"],
        ),
        Entry {
            what: "alpha = 1e300: the dynamic stiffness overflows (not a bad frequency)",
            files: case(replaced("alpha = 1e-5", "alpha = 1e300")),
            args: vec!["simulate", "{dir}/cat.toml", "--out", "{dir}/h.csv"],
            expect: vec![
                "dynamic stiffness at 10 Hz has an entry that is not a finite number",
                "check the case's values",
            ],
            code: NUMERICS,
        },
        Entry {
            what: "E = 1e300 against measured data: no NaN 'converged'",
            files: {
                let text = beam_update(("E = 2.0e11", "E = 1e300"))
                    .replace("[truth]\n", "")
                    .replace("responses = [\"3:uy\", \"5:uy\"]", "responses = [\"3:uy\", \"5:uy\"]\ndata = \"m.csv\"");
                vec![("cat.toml", text.into_bytes()), ("m.csv", csv.clone().into_bytes())]
            },
            args: vec!["update", "{dir}/cat.toml"],
            expect: vec!["receptances are zero at every updating line", "out of the range double precision holds"],
            code: NUMERICS,
        },
        Entry {
            what: "an update whose initial model is singular at a line",
            files: case(format!(
                "{OSCILLATOR}\n[[springs]]\nname = \"k\"\nnode = 1\nkx = 1e4\nky = 1e4\nkr = 1e4\ngroup = \"g\"\n\n[[masses]]\nname = \"m\"\nnode = 1\nm = 1.0\nj = 1.0\ngroup = \"g\"\n\n[truth]\n[truth.set]\n\"spring.k.ky\" = 2e4\n\n[measurement]\nfrequencies = [10.0, 15.915494309189533]\nreferences = [\"1:uy\"]\nresponses = [\"1:uy\"]\n\n[update]\nparameters = [\"spring.k.ky\"]\nfrequencies = \"all\"\n"
            )),
            args: vec!["update", "{dir}/cat.toml"],
            expect: vec!["singular at 15.915494309189533 Hz"],
            code: NUMERICS,
        },
        {
            let mut e = bad_data(
                "CSV bytes that are not UTF-8",
                "m.csv",
                String::new(),
                "",
                vec!["m.csv:4:", "column 4: byte 0xff is not UTF-8 text"],
            );
            let mut bytes = csv.clone().into_bytes();
            let line4 = csv.match_indices('\n').nth(2).unwrap().0 + 1;
            bytes[line4 + 3] = 0xff;
            e.files[1].1 = bytes;
            e
        },
        Entry {
            what: "case file bytes that are not UTF-8",
            files: vec![("cat.toml", {
                let mut b = BEAM.as_bytes().to_vec();
                let at = BEAM.find("steel = ").unwrap();
                b[at + 2] = 0xe9;
                b
            })],
            args: vec!["simulate", "{dir}/cat.toml", "--out", "{dir}/h.csv"],
            expect: vec!["cat.toml:4:3:", "byte 0xe9 is not UTF-8 text"],
            code: INVALID_INPUT,
        },
        Entry {
            what: "measured file missing",
            files: case(format!("{BEAM}data = \"absent.uff\"\n")),
            args: vec!["compare", "{dir}/cat.toml"],
            expect: vec!["absent.uff", "cannot read"],
            code: INVALID_INPUT,
        },
    ]
}

fn run(entry: &Entry, dir: &Path) -> Result<(), String> {
    for (name, bytes) in &entry.files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let d = dir.to_str().unwrap();
    let args: Vec<String> = entry.args.iter().map(|a| a.replace("{dir}", d)).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_rfm")).args(&args).output().expect("rfm runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        return Err(format!("succeeded; stderr: {stderr}"));
    }
    if out.status.code() != Some(entry.code) {
        return Err(format!("exit code {:?}: {stderr}", out.status.code()));
    }
    for e in &entry.expect {
        let want = match e.strip_prefix('@') {
            Some(spec) => {
                let (file, pat) = spec.split_once(':').unwrap();
                let text = &entry.files.iter().find(|(n, _)| *n == file).unwrap().1;
                format!("{file}:{}:", line_of(&String::from_utf8_lossy(text), pat))
            }
            None => e.to_string(),
        };
        if !stderr.contains(&want) {
            return Err(format!("lacks `{want}`: {stderr}"));
        }
    }
    Ok(())
}

/// At least 30 malformed inputs, each refused with a located message.
#[test]
fn every_malformed_input_of_the_catalogue_is_refused_with_a_located_message() {
    let entries = catalogue();
    assert!(entries.len() >= 30, "{} entries", entries.len());
    let root = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for (i, e) in entries.iter().enumerate() {
        let dir = root.path().join(format!("{i:02}"));
        std::fs::create_dir(&dir).unwrap();
        if let Err(why) = run(e, &dir) {
            failures.push(format!("{i:02} {}: {why}", e.what));
        }
    }
    assert!(failures.is_empty(), "{} of {} entries failed:\n{}", failures.len(), entries.len(), failures.join("\n"));
}

/// The same defects with the case's mask: the run succeeds and says what
/// it left out.
#[test]
fn masked_defects_are_left_out_and_reported() {
    let csv = csv();
    let row = line_of(&csv, "frequency_hz") + 5;
    let nan = edit_line(&csv, row, |l| {
        let mut f: Vec<&str> = l.split(',').collect();
        f[2] = "NaN";
        f.join(",")
    });
    let data = edit_line(&nan, line_of(&nan, "frequency_hz"), |l| format!("{l},H(99:uy,5:uy).re,H(99:uy,5:uy).im"));
    let data: String = data
        .lines()
        .enumerate()
        .map(|(i, l)| if i + 1 > line_of(&nan, "frequency_hz") { format!("{l},1.0,0.0\n") } else { format!("{l}\n") })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{BEAM}data = \"m.csv\"\nmask = [\"non-finite\", \"unmodelled-channels\"]\n");
    std::fs::write(dir.path().join("cat.toml"), text).unwrap();
    std::fs::write(dir.path().join("m.csv"), data).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["compare", dir.path().join("cat.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("left out of the measured data, as the case's [measurement] mask allows (2)"), "{stdout}");
    assert!(stdout.contains(&format!("non-finite: line {row}, columns 2-3: H(3:uy,5:uy) at 50 Hz is NaN")), "{stdout}");
    assert!(
        stdout.contains("unmodelled-channels: columns 6-7: H(99:uy,5:uy): its response the model has no node 99"),
        "{stdout}"
    );
}

/// Lines dropped while reading (here a line at 0 Hz) are said on the
/// terminal and kept in results.json, not passed over in silence.
#[test]
fn lines_dropped_while_reading_are_printed_and_stored() {
    let uff = osc_uff(&[(9, "         6         8         1 0.000000E+00 2.500000E+00 0.000000E+00")], 34);
    let e = osc_entry("0 Hz line", uff, "\n[update]\nparameters = [\"group.beam.alpha\"]\n", &[], vec![], 0);
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in &e.files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let out_dir = dir.path().join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["update", dir.path().join("cat.toml").to_str().unwrap(), "--out", out_dir.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    // the fit of a beam to an oscillator's data need not converge; its outputs are written either way
    assert!(matches!(out.status.code(), Some(0 | 5)), "{}", String::from_utf8_lossy(&out.stderr));
    let note = "record 1 (line 2): dropped 1 line(s) at 0 Hz or below";
    assert!(stdout.contains("read from the measured data") && stdout.contains(note), "{stdout}");
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap()).unwrap();
    let notes = results["notes"].as_array().unwrap();
    assert!(notes.iter().any(|n| n.as_str().unwrap().contains(note)), "{notes:?}");
    // compare --json keeps them in its document, and says them on standard error
    let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["compare", dir.path().join("cat.toml").to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(doc["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains(note)), "{doc}");
    assert!(String::from_utf8_lossy(&out.stderr).contains(note));
}

/// A byte-order mark (as Excel's "CSV UTF-8" and Windows editors write) is
/// not part of the first field or key: the files read as without it.
#[test]
fn a_byte_order_mark_is_read_as_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("\u{feff}{BEAM}data = \"m.csv\"\n");
    std::fs::write(dir.path().join("cat.toml"), text).unwrap();
    std::fs::write(dir.path().join("m.csv"), format!("\u{feff}{}", csv())).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["compare", dir.path().join("cat.toml").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// A full standard output is named as such, with the output error code.
#[test]
fn a_full_standard_output_is_named() {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cat.toml"), BEAM).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["compare", dir.path().join("cat.toml").to_str().unwrap()])
        .stdout(full)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(6), "{stderr}");
    assert!(stderr.contains("standard output: cannot write") && stderr.contains("No space left"), "{stderr}");
}

/// A measured file of a single line goes through every command without a
/// panic: each either works or says why it cannot (diagnosis needs more
/// lines).
#[test]
fn a_single_measured_line_never_panics_any_command() {
    let dir = tempfile::tempdir().unwrap();
    let csv = csv();
    let one_line: String = csv.lines().take(line_of(&csv, "frequency_hz") + 1).map(|l| format!("{l}\n")).collect();
    std::fs::write(dir.path().join("m.csv"), one_line).unwrap();
    let text = format!("{BEAM}data = \"m.csv\"\n\n[update]\nparameters = [\"group.beam.alpha\"]\n");
    let text = text.replace("[truth]\n", "").replace("frequencies = { from = 10.0, to = 100.0, step = 10.0 }\n", "");
    std::fs::write(dir.path().join("cat.toml"), text).unwrap();
    let case = dir.path().join("cat.toml");
    let out = dir.path().join("out");
    let runs: [(&[&str], i32); 5] = [
        (&["compare"], 0),
        (&["compare", "--out", out.to_str().unwrap()], 0),
        (&["update"], 0),
        (&["update", "--method", "output-error"], 0),
        (&["diagnose"], INVALID_INPUT),
    ];
    for (args, code) in runs {
        let result = Command::new(env!("CARGO_BIN_EXE_rfm")).arg(args[0]).arg(&case).args(&args[1..]).output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(code), "{args:?}: {stderr}");
        if code == INVALID_INPUT {
            assert!(stderr.contains("diagnosis needs at least 10 measured lines"), "{stderr}");
        }
    }
}

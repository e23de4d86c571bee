//! The damping form of a leading effect: a portal frame whose right foot
//! is a flexible clamp with a relaxing (exponential-kernel) loss, written
//! as a case file by hand (a ground spring and a group with alpha and mu;
//! no candidate code makes it).
//!
//! The viscous support screens far better than the non-viscous one, whose
//! screening fit stops in a local minimum of its relaxation parameter; the
//! diagnosis must still name the clamp in its own form, with its
//! stiffness, alpha and mu, and the loop must add that clamp alone (before
//! the diagnosis fitted each leader's other form from the leader's fit, it
//! added a joint and a damping window beside the viscous clamp and stopped
//! at 1.03 times the noise after five steps, exit 5). A viscous clamp keeps
//! its viscous form: the other form's extra parameter buys nothing. With a
//! motor on the beam as well and a sensor reading 20 % low, the loop finds
//! the sensor against the model its revisions mended.

use std::path::Path;

use fe_model::CaseFile;
use rfm_update::Study;
use rfm_update::checks::FindingKind;
use rfm_update::diagnose::{DiagnoseOptions, Diagnosis, Ranked, diagnose};
use rfm_update::fix::{FixOptions, FixOutcome, fix};

const FRAME: &str = include_str!("cases/portal-frame.toml");

const MEASUREMENT: &str = "[measurement]\nfrequencies = { from = 5.0, to = 400.0, step = 0.5 }\n\
     references = [\"12:uy\"]\n\
     responses = [\"5:ux\", \"9:ux\", \"11:uy\", \"12:uy\", \"14:uy\", \"16:uy\", \"19:ux\", \"23:ux\"]\n";

/// The true clamp: kr to ground at node 27 (fixed in ux, uy), damped by
/// `alpha` and, when non-viscous, relaxing at `mu`; with a motor of
/// `motor` kg at node 14 (in the frame's damping group) where given; the
/// data with `noise` relative noise.
struct Clamp {
    kr: f64,
    alpha: f64,
    mu: Option<f64>,
    motor: Option<f64>,
    noise: f64,
}

const RELAXING: Clamp = Clamp { kr: 2.0e4, alpha: 4.0e-4, mu: Some(300.0), motor: None, noise: 0.01 };

impl Clamp {
    fn truth_text(&self) -> String {
        let mu = self.mu.map_or(String::new(), |m| format!("mu = {m:e}\n"));
        let motor = self.motor.map_or(String::new(), |m| {
            format!("[[masses]]\nname = \"motor\"\nnode = 14\nm = {m:e}\ngroup = \"frame\"\n\n")
        });
        format!(
            "title = \"portal frame on a lossy clamp (truth)\"\n{FRAME}\n[[supports]]\nnode = 27\ndofs = [\"ux\", \"uy\"]\n\
             [groups.base]\nalpha = {:e}\n{mu}\n[[springs]]\nname = \"base\"\nnode = 27\nkr = {:e}\ngroup = \"base\"\n\n\
             {motor}{MEASUREMENT}\n[truth]\nnoise = {}\nseed = 9\n",
            self.alpha, self.kr, self.noise
        )
    }
}

/// The nominal case (both feet clamped) written into `dir` with the
/// truth's FRFs as its data, the channel at response `wrong` (if any)
/// scaled by its factor: -1 as a sensor mounted upside down makes it, or a
/// sensitivity entered wrong.
fn nominal_case(clamp: &Clamp, wrong: Option<(&str, f64)>, dir: &Path) -> CaseFile {
    let truth = CaseFile::parse(&dir.join("truth.toml"), &clamp.truth_text()).expect("the truth case loads");
    let mut measured = Study::from_case(truth).expect("the truth synthesises").measured().clone();
    if let Some((response, factor)) = wrong {
        let c = measured.channels().iter().position(|c| c.response.to_string() == response).expect("a channel");
        measured.channel_mut(c).iter_mut().for_each(|v| *v *= factor);
    }
    std::fs::write(dir.join("measured.csv"), frf::io::csv::to_csv_string(&measured)).unwrap();
    let text = format!(
        "title = \"portal frame, clamped (nominal)\"\n{FRAME}\n[[supports]]\nnode = 27\n\n{MEASUREMENT}data = \"measured.csv\"\n"
    );
    let path = dir.join("nominal.toml");
    std::fs::write(&path, &text).unwrap();
    CaseFile::load(&path).expect("the nominal case loads")
}

fn diagnosis(clamp: &Clamp) -> Diagnosis {
    let tmp = tempfile::tempdir().unwrap();
    let study = Study::from_case(nominal_case(clamp, None, tmp.path())).unwrap();
    let d = diagnose(&study.case().model, study.measured(), &DiagnoseOptions::default()).unwrap();
    for r in d.ranking.iter().take(4) {
        println!("{:>16.1}  {} (misfit {:.4e}, noise {:.4e})", r.delta_bic, r.description, r.misfit, d.noise);
    }
    d
}

/// `rfm fix`'s loop on the nominal case with the truth's data, one channel
/// scaled (see [`nominal_case`]), with the options `rfm fix` uses.
fn fixed(clamp: &Clamp, wrong: (&str, f64)) -> FixOutcome {
    let tmp = tempfile::tempdir().unwrap();
    let case = nominal_case(clamp, Some(wrong), tmp.path());
    let study = Study::from_case(case.clone()).unwrap();
    let out = fix(&case, study.measured(), &FixOptions::default(), |_| {}).unwrap();
    println!(
        "findings {:?}; effects {:?}; {:.2} x the noise",
        out.findings.iter().map(|f| &f.summary).collect::<Vec<_>>(),
        out.effects.iter().map(|e| &e.description).collect::<Vec<_>>(),
        out.final_misfit() / out.noise
    );
    out
}

/// The best ranked support at node 27 in the damping form `form`.
fn support<'a>(d: &'a Diagnosis, form: &str) -> (usize, &'a Ranked) {
    d.ranking
        .iter()
        .enumerate()
        .find(|(_, r)| r.description.starts_with("flexible, lossy support at node 27") && r.damping == Some(form))
        .unwrap_or_else(|| panic!("no {form} support at node 27 was ranked"))
}

/// How many reported standard deviations (of the log) the fitted value of
/// the parameter ending in `suffix` lies from `truth`.
fn z(r: &Ranked, suffix: &str, truth: f64) -> f64 {
    let p = r.parameters.iter().find(|p| p.name.ends_with(suffix)).unwrap_or_else(|| panic!("no {suffix}"));
    assert!(p.determined, "{} not determined", p.name);
    (p.value / truth).ln().abs() / p.relative_std
}

#[test]
fn a_clamp_with_a_relaxing_loss_is_named_in_its_own_form() {
    let d = diagnosis(&RELAXING);
    let (rank_nv, nv) = support(&d, "non-viscous");
    let (rank_v, _) = support(&d, "viscous");
    assert_eq!(
        d.recommended,
        Some(rank_nv + 1),
        "recommended {:?}, the non-viscous clamp ranks {}",
        d.recommended,
        rank_nv + 1
    );
    assert!(rank_nv < rank_v);
    assert!(nv.misfit <= 1.5 * d.noise, "the clamp leaves {:.2} times the noise", nv.misfit / d.noise);
    let zs = [z(nv, ".kr", RELAXING.kr), z(nv, ".alpha", RELAXING.alpha), z(nv, ".mu", RELAXING.mu.unwrap())];
    println!("z of kr, alpha, mu: {zs:?}");
    assert!(zs.iter().all(|&z| z <= 3.0), "{zs:?}");
}

#[test]
fn a_viscous_clamp_keeps_its_viscous_form() {
    let viscous = Clamp { mu: None, ..RELAXING };
    let d = diagnosis(&viscous);
    let (rank_v, v) = support(&d, "viscous");
    assert_eq!(
        d.recommended,
        Some(rank_v + 1),
        "recommended {:?}, the viscous clamp ranks {}",
        d.recommended,
        rank_v + 1
    );
    assert!(z(v, ".kr", viscous.kr) <= 3.0 && z(v, ".alpha", viscous.alpha) <= 3.0);
}

#[test]
fn the_loop_adds_the_relaxing_clamp_alone_beside_an_inverted_channel() {
    let out = fixed(&RELAXING, ("19:ux", -1.0));
    let effects: Vec<&str> = out.effects.iter().map(|e| e.description.as_str()).collect();
    assert_eq!(out.findings.len(), 1);
    assert_eq!(out.findings[0].kind, FindingKind::InvertedPolarity);
    assert_eq!(out.findings[0].channels, ["H(19:ux,12:uy)"]);
    assert_eq!(effects.len(), 1, "{effects:?}");
    assert!(
        effects[0].starts_with("flexible, lossy support at node 27") && out.effects[0].damping == Some("non-viscous")
    );
    assert!(out.final_misfit() <= 1.5 * out.noise);
}

/// Two effects and a sensor 20 % low, 2 % noise: the clamp screens far
/// above the motor, the loop reaches both only through its revisions (at
/// 3.9 times the noise), and the miscalibrated channel, hidden by the model
/// error when the data were first checked, is found against the revised
/// model (it then held 95 % of the misfit, and the loop stopped there).
#[test]
fn a_low_sensor_is_found_once_the_revisions_mend_the_model() {
    let truth = Clamp { motor: Some(0.25), noise: 0.02, ..RELAXING };
    let out = fixed(&truth, ("9:ux", 0.8));
    let effects: Vec<&str> = out.effects.iter().map(|e| e.description.as_str()).collect();
    assert_eq!(out.findings.len(), 1);
    assert_eq!(out.findings[0].kind, FindingKind::Calibration);
    assert_eq!(out.findings[0].channels, ["H(9:ux,12:uy)"]);
    assert_eq!(effects.len(), 2, "{effects:?}");
    assert!(effects.iter().any(|e| e.starts_with("flexible, lossy support at node 27")));
    assert!(effects.contains(&"lumped mass at node 14"));
    assert!(out.final_misfit() <= 1.5 * out.noise);
}

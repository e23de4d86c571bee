//! The CSV reader on arbitrary text, with and without every mask rule:
//! every input must give FRFs or a located error, never a panic, a hang or
//! memory out of proportion to the text.
#![no_main]

use std::path::Path;

use fe_model::case::MaskRule;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    let path = Path::new("fuzz.csv");
    for rules in [&[][..], &MaskRule::ALL[..]] {
        if let Ok(read) = frf::io::csv::parse_csv_with(path, text, rules) {
            // what a command does next with a measured set
            let set = read.set.to_receptance();
            let _ = frf::io::csv::to_csv_string(&set);
            let _ = rfm_update::diagnose::estimate_noise(&set);
        }
    }
});

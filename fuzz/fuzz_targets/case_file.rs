//! The case-file loader on arbitrary text: TOML parsing, model building,
//! assembly and the mechanism check must give a case or a located error,
//! never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(text) = std::str::from_utf8(bytes) {
        let _ = fe_model::CaseFile::parse(Path::new("fuzz.toml"), text);
    }
});

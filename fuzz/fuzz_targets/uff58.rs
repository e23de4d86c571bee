//! The universal-file reader on arbitrary bytes (ASCII and binary 58b
//! records), then the conversion to FRFs with and without mask rules: every
//! input must give a value or an error, never a panic.
#![no_main]

use std::path::Path;

use fe_model::case::MaskRule;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let path = Path::new("fuzz.uff");
    if let Ok(file) = frf::io::uff::parse_uff(path, bytes) {
        let _ = frf::io::uff::frfs_from_uff(path, &file, &[]);
        let _ = frf::io::uff::frfs_from_uff_with(path, &file, &[], &MaskRule::ALL);
    }
});

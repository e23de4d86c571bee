//! Text files as people and test systems write them: a UTF-8 byte-order
//! mark (Windows editors, Excel's "CSV UTF-8") is dropped, and bytes that
//! are not UTF-8 are reported at their line and column instead of as a
//! bare "stream did not contain valid UTF-8".

/// Bytes that are not UTF-8 text, located for the message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NotUtf8 {
    /// 1-based line of the first bad byte.
    pub line: usize,
    /// 1-based column (in bytes) of the first bad byte.
    pub column: usize,
    /// The bad byte.
    pub byte: u8,
}

impl std::fmt::Display for NotUtf8 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "column {}: byte 0x{:02x} is not UTF-8 text; save the file as UTF-8 (or plain ASCII)",
            self.column, self.byte
        )
    }
}

/// The text of a file's bytes without a leading byte-order mark.
pub fn decode(bytes: &[u8]) -> Result<&str, NotUtf8> {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = good.len() - good.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1) + 1;
        NotUtf8 { line, column, byte: bytes[e.valid_up_to()] }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_byte_order_mark_is_dropped_and_bad_bytes_are_located() {
        assert_eq!(decode(b"\xef\xbb\xbffreq,a\n"), Ok("freq,a\n"));
        let e = decode(b"one\ntwo \xff\n").unwrap_err();
        assert_eq!(e, NotUtf8 { line: 2, column: 5, byte: 0xff });
        assert!(e.to_string().starts_with("column 5: byte 0xff is not UTF-8"), "{e}");
    }
}

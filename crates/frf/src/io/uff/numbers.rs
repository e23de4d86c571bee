//! The numbers of a text line of a universal file, as the writers in the
//! wild put them: shared by the dataset 58 reader and the geometry
//! datasets, in a file of its own so that neither imports the other.

/// The numbers of a line: whitespace-separated, Fortran `D` exponents
/// accepted, and fields that touch (`1.0E+00-2.0E+00`, as some writers
/// produce when a value fills its column) split at the sign. `NaN` and
/// infinities (`nan`, `inf`, or an exponent too large) are kept: the FRF
/// conversion refuses or masks them with the record and frequency.
pub(super) fn numbers(text: &[u8]) -> Result<Vec<f64>, String> {
    let s = std::str::from_utf8(text).map_err(|_| "the line is not text (non-ASCII bytes)".to_string())?;
    let mut out = Vec::new();
    for token in s.split_whitespace() {
        match parse_number(token) {
            Some(x) => out.push(x),
            None => {
                let pieces = split_touching(token);
                if pieces.len() < 2 {
                    return Err(format!("`{token}` is not a number"));
                }
                for p in pieces {
                    out.push(parse_number(p).ok_or_else(|| format!("`{token}` is not a number"))?);
                }
            }
        }
    }
    Ok(out)
}

fn parse_number(token: &str) -> Option<f64> {
    if let Some(x) = crate::io::non_finite_word(token) {
        return Some(x);
    }
    // only digits, signs, a point and an exponent letter: refuses `infinite`, `1.#QNAN` and the like
    if !token.bytes().all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E' | b'd' | b'D')) {
        return None;
    }
    if token.bytes().any(|b| matches!(b, b'd' | b'D')) {
        token.replace(['d', 'D'], "E").parse().ok()
    } else {
        token.parse().ok()
    }
}

/// Splits `1.0E+00-2.0E+00` into `1.0E+00` and `-2.0E+00`: at a sign that
/// follows a digit or a point (not an exponent letter).
fn split_touching(token: &str) -> Vec<&str> {
    let b = token.as_bytes();
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..b.len() {
        if matches!(b[i], b'+' | b'-') && (b[i - 1].is_ascii_digit() || b[i - 1] == b'.') {
            out.push(&token[start..i]);
            start = i;
        }
    }
    out.push(&token[start..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_accept_fortran_forms_and_touching_fields() {
        assert_eq!(numbers(b" 1.5E+00 -2.0D-01  3").unwrap(), vec![1.5, -0.2, 3.0]);
        assert_eq!(numbers(b"4.111111E+03-3.111111E+03").unwrap(), vec![4111.111, -3111.111]);
        assert_eq!(numbers(b"1.0E-100-2.5E+00").unwrap(), vec![1e-100, -2.5]);
        assert!(numbers(b"1.0 x").unwrap_err().contains("`x` is not a number"));
        let v = numbers(b"1.0 NaN -inf 1e999").unwrap();
        assert!(v[1].is_nan() && v[2] == f64::NEG_INFINITY && v[3] == f64::INFINITY, "{v:?}");
        assert!(numbers(b"1.#QNAN").unwrap_err().contains("`1.#QNAN` is not a number"));
        assert!(numbers(b"infinite").unwrap_err().contains("`infinite` is not a number"));
    }
}

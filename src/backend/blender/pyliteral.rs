//! Python string literals for data: every character outside printable ASCII is escaped, so
//! the generated script is pure ASCII and no user string can end the literal or inject code.

/// A double-quoted Python `str` literal whose value is exactly `s`.
///
/// Printable ASCII other than `\` and `"` is kept; everything else becomes `\xNN`, `\uNNNN`
/// or `\UNNNNNNNN`. The result contains no newline, no quote that closes it and no
/// non-ASCII byte, whatever `s` holds.
pub fn py_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for ch in s.chars() {
        match ch {
            '\\' => out.push_str("\\\\"),
            '"' => out.push_str("\\\""),
            ' '..='~' => out.push(ch),
            c if (c as u32) < 0x100 => out.push_str(&format!("\\x{:02x}", c as u32)),
            c if (c as u32) < 0x10000 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push_str(&format!("\\U{:08x}", c as u32)),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::py_str;

    #[test]
    fn escapes_everything_that_could_break_out() {
        let s = "a\"b\\c\nd\r'''\"\"\"\u{0}é\u{2028}😀";
        let lit = py_str(s);
        assert!(lit.is_ascii());
        assert!(!lit.contains('\n') && !lit.contains('\r'));
        assert_eq!(
            lit,
            r#""a\"b\\c\x0ad\x0d'''\"\"\"\x00\xe9\u2028\U0001f600""#
        );
    }
}

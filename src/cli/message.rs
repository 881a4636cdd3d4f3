//! The one shape of every message the CLI prints on stderr (errors and notices): one line, control
//! characters escaped (`\n`, `\t`, `\x1b`, …, so a file name or a file's contents cannot move the
//! terminal's cursor or colour it), long decimal numbers shortened to 6 significant digits, and
//! at most [`MAX_CHARS`] characters (the end cut with `…`).

/// The longest message printed, in characters.
pub const MAX_CHARS: usize = 300;

/// Significant digits kept of a decimal number with more.
const DIGITS: usize = 6;

/// An error and its causes as one printable line, leaving out a cause whose text the message
/// already carries (the library's I/O errors print their OS error themselves).
pub fn error_line(e: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !message.contains(&text) {
            if !message.is_empty() {
                message.push_str(": ");
            }
            message.push_str(&text);
        }
    }
    clean(&message)
}

/// A command-line usage error of clap as one printable line: its text up to the usage part,
/// without clap's own `error:` prefix.
pub fn usage_error_line(e: &clap::Error) -> String {
    let rendered = e.render().to_string();
    let text: Vec<&str> = rendered
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
        .collect();
    let text = text.join(" ");
    clean(text.strip_prefix("error: ").unwrap_or(&text))
}

/// `text` as one printable line (see the module documentation).
pub fn clean(text: &str) -> String {
    let short = shorten_numbers(text);
    let mut out = String::with_capacity(short.len());
    for c in short.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push(c),
        }
    }
    if out.chars().count() > MAX_CHARS {
        out = out.chars().take(MAX_CHARS - 1).collect();
        out.push('…');
    }
    out
}

/// Rewrites every decimal number with a fraction or exponent and more than [`DIGITS`]
/// significant digits (e.g. `0.30000000000000004`, `1.2345678901234567e300`), and every integer
/// of more than 20 digits (`1e300` printed in full), with 6 significant digits. A number
/// that is part of a word or a file name (next to a letter, `_`, `/` or another `.`) is left
/// as it is.
fn shorten_numbers(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut copied = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit()
            && (i == 0 || !is_word_byte(bytes[i - 1]) && bytes[i - 1] != b'.');
        if !starts {
            i += 1;
            continue;
        }
        let end = number_end(bytes, i);
        let token = &text[i..end];
        let attached = bytes
            .get(end)
            .is_some_and(|&b| is_word_byte(b) || b == b'.');
        // An integer of more than 20 digits is no count or index (u64 has 20): a float's digits.
        let long = if token.contains(['.', 'e', 'E']) {
            significant_digits(token) > DIGITS
        } else {
            token.len() > 20
        };
        if !attached && long {
            if let Ok(v) = token.parse::<f64>() {
                out.push_str(&text[copied..i]);
                out.push_str(&short_number(v));
                copied = end;
            }
        }
        i = end.max(i + 1);
    }
    out.push_str(&text[copied..]);
    out
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'/' || b == b'\\'
}

/// The end of the number starting at `start`: digits, one fraction, one exponent.
fn number_end(bytes: &[u8], start: usize) -> usize {
    let digits = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = digits(start);
    if bytes.get(i) == Some(&b'.') && bytes.get(i + 1).is_some_and(u8::is_ascii_digit) {
        i = digits(i + 1);
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
        if bytes.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
            i = digits(i + 1 + sign);
        }
    }
    i
}

fn significant_digits(token: &str) -> usize {
    let mantissa = token.split(['e', 'E']).next().unwrap_or(token);
    mantissa
        .chars()
        .filter(char::is_ascii_digit)
        .skip_while(|&c| c == '0')
        .count()
}

/// `v` with 6 significant digits (the library's, so its messages shorten numbers alike).
pub use crate::error::short_number;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_shortened_and_words_kept() {
        assert_eq!(
            clean("voxel 0.30000000000000004 too small"),
            "voxel 0.3 too small"
        );
        assert_eq!(
            clean("radius 1.2345678901234567e300, centre (1.5, 2.25)"),
            "radius 1.23457e300, centre (1.5, 2.25)"
        );
        assert_eq!(clean("-12.3456789 mm"), "-12.3457 mm");
        // File names and words keep their digits.
        assert_eq!(
            clean("/tmp/run1.23456789/level_1.234567890.ply"),
            "/tmp/run1.23456789/level_1.234567890.ply"
        );
        assert_eq!(clean("v1.2345678901.stl: bad"), "v1.2345678901.stl: bad");
        assert_eq!(clean("12345678901 bytes"), "12345678901 bytes");
        assert_eq!(
            clean("18446744073709551615 samples"),
            "18446744073709551615 samples"
        );
        assert_eq!(clean(&format!("got {}", 1e300)), "got 1.00000e300");
    }

    #[test]
    fn control_characters_are_escaped_and_length_capped() {
        assert_eq!(clean("a\x1b[31mb\nc\td\u{7f}"), "a\\x1b[31mb\\nc\\td\\x7f");
        let long = "x".repeat(2000);
        let c = clean(&long);
        assert_eq!(c.chars().count(), MAX_CHARS);
        assert!(c.ends_with('…'));
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short_number(1.0 / 3.0), "0.333333");
        assert_eq!(short_number(123456.789), "123457");
        assert_eq!(short_number(2.5), "2.5");
        assert_eq!(short_number(1e300), "1.00000e300");
        assert_eq!(short_number(-1.5e-7), "-1.50000e-7");
    }
}

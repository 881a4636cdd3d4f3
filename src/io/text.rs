//! Whitespace tokenizer over raw bytes with line numbers, shared by the ASCII readers (ASCII STL and
//! the body of ASCII PLY). It works on bytes so that a stray non-UTF-8 byte in a name or comment
//! cannot stop a read; numbers are parsed from the token's text.

/// Tokens separated by ASCII whitespace, with the 1-based line of the last token returned.
pub(crate) struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Line at `pos`.
    at_line: usize,
    /// Line of the last token returned.
    line: usize,
}

impl<'a> Tokens<'a> {
    /// Tokens of `bytes`, whose first byte lies on line `first_line`.
    pub(crate) fn new(bytes: &'a [u8], first_line: usize) -> Self {
        Tokens {
            bytes,
            pos: 0,
            at_line: first_line,
            line: first_line,
        }
    }

    /// The line of the last token returned (at the end of the input: of the last token).
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// The next token, or `None` at the end of the input.
    pub(crate) fn next_token(&mut self) -> Option<&'a [u8]> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.at_line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        self.line = self.at_line;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some(&self.bytes[start..self.pos])
    }

    /// Skips the rest of the current line (used for names after `solid` / `endsolid`).
    pub(crate) fn skip_line(&mut self) {
        match self.bytes[self.pos..].iter().position(|&b| b == b'\n') {
            Some(k) => {
                self.pos += k + 1;
                self.at_line += 1;
            }
            None => self.pos = self.bytes.len(),
        }
    }
}

/// A token parsed as a float (`inf` and `nan` are accepted here and rejected by validation).
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A token parsed as a signed integer.
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A token for an error message: lossy UTF-8, cut to a reasonable length.
pub(crate) fn show(token: &[u8]) -> String {
    const MAX: usize = 40;
    let text = String::from_utf8_lossy(&token[..token.len().min(MAX)]);
    if token.len() > MAX {
        format!("{text}…")
    } else {
        text.into_owned()
    }
}

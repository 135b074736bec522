//! Line numbers of JSON paths.
//!
//! `serde_json` reports line and column for syntax and type errors, but once a
//! document has parsed, the values carry no positions. Validation problems
//! found afterwards (a negative thickness, an unknown material) still have to
//! name the line, so this module re-scans the text and maps every JSON path
//! (`objects[2].parts[0].material`) to the 1-based line where its value (or,
//! for object members, its key) starts. It is only run when there is an error
//! to report.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Location};

/// A `serde_json` error as an irsig error naming the file, line and column.
pub fn serde_error(path: &Path, e: &serde_json::Error) -> Error {
    let msg = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let msg = msg.strip_suffix(&suffix).unwrap_or(&msg);
    Error::parse(
        Location::file(path).at(e.line(), e.column()),
        crate::suggest::with_suggestion(msg),
    )
}

/// Path → 1-based line of every member and element in a JSON text.
///
/// Paths are written `a.b[2].c`; the root is `""`. Malformed text yields the
/// paths found before the problem.
#[derive(Debug, Default, Clone)]
pub struct JsonLines {
    /// Path → (1-based line, 1-based column in characters).
    lines: HashMap<String, (usize, usize)>,
}

impl JsonLines {
    /// Scan `text`.
    pub fn new(text: &str) -> Self {
        let mut s = Scanner {
            b: text.as_bytes(),
            pos: 0,
            line: 1,
            line_start: 0,
            out: HashMap::new(),
        };
        s.out.insert(String::new(), (1, 1));
        s.value("", 0);
        JsonLines { lines: s.out }
    }

    /// The line of `path`, or of its nearest ancestor that was found.
    pub fn line(&self, path: &str) -> Option<usize> {
        self.position(path).map(|(l, _)| l)
    }

    /// The 1-based (line, column) of `path` (where its key, or for array
    /// elements its value, starts), or of its nearest ancestor that was
    /// found. Columns count characters, as `serde_json`'s do.
    pub fn position(&self, path: &str) -> Option<(usize, usize)> {
        let mut p = path;
        loop {
            if let Some(&l) = self.lines.get(p) {
                return Some(l);
            }
            // Strip the last component: `.name` or `[i]`.
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
        }
    }
}

struct Scanner<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
    /// Byte offset where the current line starts.
    line_start: usize,
    out: HashMap<String, (usize, usize)>,
}

impl Scanner<'_> {
    fn peek(&self) -> Option<u8> {
        self.b.get(self.pos).copied()
    }
    fn bump(&mut self) {
        if self.peek() == Some(b'\n') {
            self.line += 1;
            self.line_start = self.pos + 1;
        }
        self.pos += 1;
    }
    /// The current (line, column); the column counts UTF-8 characters.
    fn here(&self) -> (usize, usize) {
        let end = self.pos.min(self.b.len());
        let start = self.line_start.min(end);
        let chars = self.b[start..end]
            .iter()
            .filter(|&&c| (c & 0xC0) != 0x80)
            .count();
        (self.line, chars + 1)
    }
    fn ws(&mut self) {
        while let Some(c) = self.peek() {
            if c.is_ascii_whitespace() {
                self.bump();
            } else {
                break;
            }
        }
    }
    fn string(&mut self) -> String {
        // At the opening quote.
        self.bump();
        let start = self.pos;
        while let Some(c) = self.peek() {
            match c {
                b'\\' => {
                    self.bump();
                    self.bump();
                }
                b'"' => {
                    let s = String::from_utf8_lossy(&self.b[start..self.pos]).into_owned();
                    self.bump();
                    return s;
                }
                _ => self.bump(),
            }
        }
        String::from_utf8_lossy(&self.b[start..]).into_owned()
    }
    fn value(&mut self, path: &str, depth: usize) {
        if depth > 256 {
            self.pos = self.b.len();
            return;
        }
        self.ws();
        match self.peek() {
            Some(b'{') => {
                self.bump();
                loop {
                    self.ws();
                    match self.peek() {
                        Some(b'"') => {}
                        Some(b'}') => {
                            self.bump();
                            return;
                        }
                        _ => {
                            self.pos = self.b.len();
                            return;
                        }
                    }
                    let at = self.here();
                    let key = self.string();
                    let child = if path.is_empty() {
                        key
                    } else {
                        format!("{path}.{key}")
                    };
                    self.out.insert(child.clone(), at);
                    self.ws();
                    if self.peek() == Some(b':') {
                        self.bump();
                    }
                    self.value(&child, depth + 1);
                    self.ws();
                    match self.peek() {
                        Some(b',') => self.bump(),
                        Some(b'}') => {
                            self.bump();
                            return;
                        }
                        _ => {
                            self.pos = self.b.len();
                            return;
                        }
                    }
                }
            }
            Some(b'[') => {
                self.bump();
                let mut i = 0;
                loop {
                    self.ws();
                    if self.peek() == Some(b']') {
                        self.bump();
                        return;
                    }
                    if self.peek().is_none() {
                        return;
                    }
                    let child = format!("{path}[{i}]");
                    let at = self.here();
                    self.out.insert(child.clone(), at);
                    self.value(&child, depth + 1);
                    i += 1;
                    self.ws();
                    match self.peek() {
                        Some(b',') => self.bump(),
                        Some(b']') => {
                            self.bump();
                            return;
                        }
                        _ => {
                            self.pos = self.b.len();
                            return;
                        }
                    }
                }
            }
            Some(b'"') => {
                self.string();
            }
            Some(_) => {
                while let Some(c) = self.peek() {
                    if matches!(c, b',' | b']' | b'}') || c.is_ascii_whitespace() {
                        break;
                    }
                    self.bump();
                }
            }
            None => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_map_to_lines() {
        let t = "{\n \"a\": 1,\n \"b\": [\n  {\"c\": \"x\\\"y\"},\n  {\n   \"c\": 2\n  }\n ]\n}";
        let j = JsonLines::new(t);
        assert_eq!(j.line("a"), Some(2));
        assert_eq!(j.line("b"), Some(3));
        assert_eq!(j.line("b[0].c"), Some(4));
        assert_eq!(j.line("b[1]"), Some(5));
        assert_eq!(j.line("b[1].c"), Some(6));
        // Unknown leaf: nearest ancestor.
        assert_eq!(j.line("b[1].zzz"), Some(5));
        assert_eq!(j.position("a"), Some((2, 2)));
        assert_eq!(j.position("b[0].c"), Some((4, 4)));
        assert_eq!(j.position("b[1].c"), Some((6, 4)));
        // Columns count characters, not bytes (`é` is two bytes).
        let j = JsonLines::new("{\"é\": {\"x\": 1}}");
        assert_eq!(j.position("é.x"), Some((1, 8)));
    }
}

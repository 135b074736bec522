//! Line-oriented delimited text: the one CSV reader behind irsig's input
//! tables (analysis points and series, spectral responses, emissivity
//! curves, terrain height grids, irsig/EPW/TMY3 weather).
//!
//! Owns: numbering lines (1-based, as editors do), stripping a UTF-8 byte
//! order mark, skipping blank and comment lines where a format allows
//! comments, and splitting one line into fields with the `csv` crate's
//! parser (`csv-core`; RFC 4180 quoting: `"a,b"` is one field, `""` inside
//! quotes is a quote). Fields come back trimmed of surrounding whitespace;
//! [`tokens`] splits them further for the loose numeric-column dialect.
//!
//! Takes text already read by the caller (who owns I/O errors and the path
//! for messages); gives [`Row`]s, or numbered lines and a [`Splitter`] for
//! formats with fixed header lines (EPW, TMY3) or meaningful comments
//! (irsig weather's `# site:`).
//!
//! Each line is parsed on its own, so a quoted field cannot span lines and a
//! stray quote cannot swallow the rest of a file; line numbers in errors are
//! therefore exact. Must not know: any format's columns, units or error
//! wording.

use csv_core::ReadFieldResult;

/// Which comments a format allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Comments {
    /// A line whose first non-blank character is `#` is a comment.
    WholeLine,
    /// `#` starts a comment anywhere on a line (also inside quotes).
    Trailing,
}

/// One data line of a table.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Row<'a> {
    /// 1-based line number in the text.
    pub line: usize,
    /// The line without its comment, trimmed.
    pub text: &'a str,
    /// The comma-separated fields, trimmed.
    pub fields: Vec<String>,
}

/// The lines of `text` with their 1-based numbers; a UTF-8 byte order mark
/// before the first line is dropped, and `\r\n` ends a line like `\n`.
pub(crate) fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.trim_start_matches('\u{feff}')
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
}

/// The non-blank, non-comment lines of `text`, split into fields.
pub(crate) fn rows(text: &str, comments: Comments) -> impl Iterator<Item = Row<'_>> {
    let mut splitter = Splitter::new();
    lines(text).filter_map(move |(line, raw)| {
        let t = match comments {
            Comments::WholeLine => raw.trim(),
            Comments::Trailing => raw.split('#').next().unwrap_or("").trim(),
        };
        if t.is_empty() || (comments == Comments::WholeLine && t.starts_with('#')) {
            return None;
        }
        Some(Row {
            line,
            text: t,
            fields: splitter.split(t),
        })
    })
}

/// Splits lines into comma-separated fields (RFC 4180 quoting), each
/// trimmed of surrounding whitespace. Blanks before an opening quote are
/// skipped (Python's `skipinitialspace`), so `a, "b,c"` is two fields. An
/// empty line gives no fields. One splitter serves a whole file (building
/// the parser's tables costs more than splitting a line).
pub(crate) struct Splitter {
    reader: csv_core::Reader,
    out: Vec<u8>,
}

impl Splitter {
    pub(crate) fn new() -> Self {
        Splitter {
            reader: csv_core::ReaderBuilder::new()
                // One line in: `\r` is data, not a record end.
                .terminator(csv_core::Terminator::Any(b'\n'))
                .build(),
            out: Vec::new(),
        }
    }

    /// The fields of `line`.
    pub(crate) fn split(&mut self, line: &str) -> Vec<String> {
        // csv-core is the csv crate's parser; its field-at-a-time interface
        // lets the blanks at each field's start be skipped before it decides
        // whether the field is quoted.
        self.reader.reset();
        let mut input = line.as_bytes();
        self.out.resize(input.len().max(1), 0);
        let mut field = Vec::new();
        let mut fields = Vec::new();
        let mut at_field_start = true;
        loop {
            if at_field_start {
                let blanks = input
                    .iter()
                    .take_while(|b| matches!(b, b' ' | b'\t'))
                    .count();
                input = &input[blanks..];
            }
            let (result, nin, nout) = self.reader.read_field(input, &mut self.out);
            input = &input[nin..];
            field.extend_from_slice(&self.out[..nout]);
            match result {
                ReadFieldResult::InputEmpty | ReadFieldResult::OutputFull => at_field_start = false,
                ReadFieldResult::Field { record_end } => {
                    // Fields end at ASCII bytes, so they stay valid UTF-8.
                    fields.push(String::from_utf8_lossy(&field).trim().to_string());
                    field.clear();
                    at_field_start = true;
                    if record_end {
                        return fields;
                    }
                }
                ReadFieldResult::End => return fields,
            }
        }
    }
}

/// Split `fields` further at whitespace and `;`, dropping empty pieces: the
/// loose numeric-column dialect of spectral files (`1.0, 0.5`, `1.0 0.5`,
/// `1.0;0.5` and `1.0\t0.5` all give two tokens).
pub(crate) fn tokens(fields: &[String]) -> Vec<&str> {
    fields
        .iter()
        .flat_map(|f| f.split(|c: char| c == ';' || c.is_whitespace()))
        .filter(|s| !s.is_empty())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(line: &str) -> Vec<String> {
        Splitter::new().split(line)
    }

    #[test]
    fn quoted_fields_keep_commas_and_quotes() {
        assert_eq!(
            split(r#"a, "b,c" ,"say ""hi""",,"#),
            ["a", "b,c", r#"say "hi""#, "", ""]
        );
        assert_eq!(split(r#""x",  "y, z" , w"#), ["x", "y, z", "w"]);
        assert_eq!(split(r#""unterminated, quote"#), ["unterminated, quote"]);
        assert_eq!(split(","), ["", ""]);
        assert_eq!(split("é, ü ,"), ["é", "ü", ""]);
        assert_eq!(split(""), Vec::<String>::new());
        assert_eq!(split("a\rb"), ["a\rb"]);
    }

    #[test]
    fn rows_number_lines_and_skip_comments() {
        let text = "\u{feff}# c\r\nx,y\r\n\r\n  # indented\n1, 2 \n";
        let r: Vec<_> = rows(text, Comments::WholeLine).collect();
        assert_eq!(r.len(), 2);
        assert_eq!(
            (r[0].line, r[0].fields.clone()),
            (2, vec!["x".into(), "y".into()])
        );
        assert_eq!(
            (r[1].line, r[1].fields.clone()),
            (5, vec!["1".into(), "2".into()])
        );
        let mut s = Splitter::new();
        assert_eq!(s.split(r#""a,"#), ["a,"]);
        assert_eq!(s.split("b,c"), ["b", "c"]);
        let r: Vec<_> = rows("8.0 0.5 # peak\n# all\n9,0.6", Comments::Trailing).collect();
        assert_eq!(r.iter().map(|r| r.line).collect::<Vec<_>>(), [1, 3]);
        assert_eq!(tokens(&r[0].fields), ["8.0", "0.5"]);
        assert_eq!(tokens(&r[1].fields), ["9", "0.6"]);
    }

    #[test]
    fn tokens_accept_every_separator() {
        for l in [
            "1.0, 0.5",
            "1.0 0.5",
            "1.0;0.5",
            "1.0\t0.5",
            "1.0,,0.5",
            "\"1.0\",0.5",
        ] {
            assert_eq!(tokens(&split(l)), ["1.0", "0.5"], "{l:?}");
        }
    }
}

//! Line-oriented delimited text: the one CSV reader behind irsig's input
//! tables (analysis points and series, spectral responses, emissivity
//! curves, irsig/EPW/TMY3 weather).
//!
//! Owns: numbering lines (1-based, as editors do), stripping a UTF-8 byte
//! order mark, skipping blank and comment lines where a format allows
//! comments, and splitting one line into fields with the `csv` crate
//! (RFC 4180 quoting: `"a,b"` is one field, `""` inside quotes is a quote).
//! Fields come back trimmed of surrounding whitespace.
//!
//! Takes text already read by the caller (who owns I/O errors and the path
//! for messages); gives [`Row`]s, or numbered lines and [`split`] for
//! formats with fixed header lines (EPW, TMY3) or meaningful comments
//! (irsig weather's `# site:`).
//!
//! Each line is parsed on its own, so a quoted field cannot span lines and a
//! stray quote cannot swallow the rest of a file; line numbers in errors are
//! therefore exact. Must not know: any format's columns, units or error
//! wording.

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
            fields: split(t),
        })
    })
}

/// Split one line into comma-separated fields (RFC 4180 quoting), each
/// trimmed of surrounding whitespace. An empty line gives no fields.
pub(crate) fn split(line: &str) -> Vec<String> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        // The caller hands one line: `\r` is data, not a record end.
        .terminator(csv::Terminator::Any(b'\n'))
        .buffer_capacity(line.len().max(64))
        .from_reader(line.as_bytes());
    let mut record = csv::StringRecord::new();
    match reader.read_record(&mut record) {
        Ok(true) => record.iter().map(|f| f.trim().to_string()).collect(),
        // Valid UTF-8 in, ASCII delimiters: reading cannot fail, but never panic.
        Ok(false) | Err(_) => Vec::new(),
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

    #[test]
    fn quoted_fields_keep_commas_and_quotes() {
        assert_eq!(
            split(r#"a, "b,c" ,"say ""hi""",,"#),
            ["a", "b,c", r#"say "hi""#, "", ""]
        );
        assert_eq!(split(""), Vec::<String>::new());
        assert_eq!(split("   "), [""]);
        assert_eq!(split("a\rb"), ["a\rb"]);
    }

    #[test]
    fn rows_number_lines_and_skip_comments() {
        let text = "\u{feff}# c\r\nx,y\r\n\r\n  # indented\n1, 2 \n";
        let r: Vec<_> = rows(text, Comments::WholeLine).collect();
        assert_eq!(r.len(), 2);
        assert_eq!((r[0].line, r[0].fields.clone()), (2, vec!["x".into(), "y".into()]));
        assert_eq!((r[1].line, r[1].fields.clone()), (5, vec!["1".into(), "2".into()]));
        let r: Vec<_> = rows("8.0 0.5 # peak\n# all\n9,0.6", Comments::Trailing).collect();
        assert_eq!(r.iter().map(|r| r.line).collect::<Vec<_>>(), [1, 3]);
        assert_eq!(tokens(&r[0].fields), ["8.0", "0.5"]);
        assert_eq!(tokens(&r[1].fields), ["9", "0.6"]);
    }

    #[test]
    fn tokens_accept_every_separator() {
        for l in ["1.0, 0.5", "1.0 0.5", "1.0;0.5", "1.0\t0.5", "1.0,,0.5", "\"1.0\",0.5"] {
            assert_eq!(tokens(&split(l)), ["1.0", "0.5"], "{l:?}");
        }
    }
}

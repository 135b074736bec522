//! "Did you mean …?" hints for misspelt keys and names.
//!
//! Owns the one rule for how close a misspelling must be to a known name to
//! be suggested, and the rewriting of `serde` messages (`unknown field
//! `x`, expected one of …`) into messages with a hint. Takes words and
//! candidate lists; knows nothing of files or the command line.

/// The candidate closest to `word`, when it is close enough to be a likely
/// misspelling: equal ignoring case, `-`/`_` and spaces; one a prefix of the
/// other at a word boundary (`latitude` → `latitude_deg`), or anywhere when
/// the shorter has four characters or more (`latitud`); or an optimal
/// string alignment (Damerau–Levenshtein) distance of at most one edit per
/// three characters of the longer, at least one. Ties go to the first
/// candidate.
pub fn closest<'a, I>(word: &str, candidates: I) -> Option<&'a str>
where
    I: IntoIterator<Item = &'a str>,
{
    let norm = |s: &str| -> String {
        s.chars()
            .filter(|c| !matches!(c, '_' | '-' | ' '))
            .flat_map(char::to_lowercase)
            .collect()
    };
    let w = norm(word);
    if w.is_empty() {
        return None;
    }
    let mut best: Option<(usize, &'a str)> = None;
    for c in candidates {
        if c == word {
            continue;
        }
        let n = norm(c);
        let score = if n == w {
            0
        } else if boundary_prefix(word, c) || boundary_prefix(c, word) {
            1
        } else if w.chars().count() >= 4 && (n.starts_with(&w) || w.starts_with(&n)) {
            2
        } else {
            let d = strsim::osa_distance(&w, &n);
            let limit = (w.chars().count().max(n.chars().count()) / 3).max(1);
            if d > limit {
                continue;
            }
            2 + d
        };
        if best.is_none_or(|(s, _)| score < s) {
            best = Some((score, c));
        }
    }
    best.map(|(_, c)| c)
}

/// Whether `short` is `long` cut at a word boundary (`_`, `-`, space),
/// ignoring case, and at least three characters long.
fn boundary_prefix(short: &str, long: &str) -> bool {
    let (s, l) = (short.to_lowercase(), long.to_lowercase());
    s.len() >= 3
        && l.len() > s.len()
        && l.starts_with(&s)
        && matches!(l.as_bytes()[s.len()], b'_' | b'-' | b' ')
}

/// `" (did you mean `x`?)"` for the closest of `candidates`, or `""`.
pub fn hint<'a, I>(word: &str, candidates: I) -> String
where
    I: IntoIterator<Item = &'a str>,
{
    closest(word, candidates)
        .map(|c| format!(" (did you mean `{c}`?)"))
        .unwrap_or_default()
}

/// A `serde` message with a "did you mean" hint appended where it names an
/// unknown field or variant and lists what was expected (`unknown field
/// `focal_lenght_m`, expected one of `name`, …, `focal_length_m`, …`).
/// Other messages are returned unchanged.
pub fn with_suggestion(message: &str) -> String {
    let hint = serde_unknown(message)
        .map(|(word, expected)| hint(word, expected.iter().copied()))
        .unwrap_or_default();
    format!("{message}{hint}")
}

/// The unknown word and the expected names of a `serde` "unknown field" /
/// "unknown variant" message.
fn serde_unknown(message: &str) -> Option<(&str, Vec<&str>)> {
    let rest = message
        .find("unknown field `")
        .map(|i| &message[i + "unknown field `".len()..])
        .or_else(|| {
            message
                .find("unknown variant `")
                .map(|i| &message[i + "unknown variant `".len()..])
        })?;
    let end = rest.find('`')?;
    let word = &rest[..end];
    let tail = &rest[end + 1..];
    let list = tail.strip_prefix(", expected ")?;
    let list = list.strip_prefix("one of ").unwrap_or(list);
    // Backquoted names up to the end of the list.
    let mut names = Vec::new();
    let mut s = list;
    while let Some(a) = s.find('`') {
        let after = &s[a + 1..];
        let Some(b) = after.find('`') else { break };
        names.push(&after[..b]);
        s = &after[b + 1..];
        if !(s.starts_with(", ") || s.starts_with(" or ")) {
            break;
        }
    }
    (!names.is_empty()).then_some((word, names))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_names_are_suggested_and_far_ones_not() {
        let keys = ["name", "width", "focal_length_m", "pixel_pitch_m"];
        assert_eq!(closest("focal_lenght_m", keys), Some("focal_length_m"));
        assert_eq!(closest("Focal-Length-M", keys), Some("focal_length_m"));
        assert_eq!(closest("focal_length", keys), Some("focal_length_m"));
        assert_eq!(closest("wdth", keys), Some("width"));
        assert_eq!(closest("altitude", keys), None);
        assert_eq!(closest("", keys), None);
        // A word equal to a candidate is not "misspelt" as itself.
        assert_eq!(closest("name", ["name"]), None);
    }

    #[test]
    fn serde_messages_get_a_hint() {
        let m = "unknown field `max_bounce`, expected one of `max_bounces`, `spectral_step_um`";
        assert_eq!(
            with_suggestion(m),
            format!("{m} (did you mean `max_bounces`?)")
        );
        let m = "unknown variant `fram`, expected `frame` or `line_scanner`";
        assert!(with_suggestion(m).ends_with("(did you mean `frame`?)"));
        let m = "unknown field `latitud`, expected one of `latitude_deg`, `longitude_deg`";
        assert!(with_suggestion(m).ends_with("(did you mean `latitude_deg`?)"));
        let m = "unknown field `zzzzzz`, expected one of `max_bounces`";
        assert_eq!(with_suggestion(m), m);
        let m = "invalid type: string \"x\", expected f64";
        assert_eq!(with_suggestion(m), m);
    }
}

//! Small text helpers shared by the weather readers.

use crate::error::{Error, Location, Result};

/// Split one CSV line into fields, honouring double quotes (`"a,b"` and `""`).
pub(crate) fn split_csv(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Parse a finite number; `what` names the field and its unit in messages.
pub(crate) fn number(s: &str, loc: &Location, what: &str) -> Result<f64> {
    let t = s.trim();
    let v: f64 = t.parse().map_err(|_| {
        Error::parse(
            loc.clone(),
            format!("expected a number for {what}, found `{t}`"),
        )
    })?;
    if !v.is_finite() {
        return Err(Error::parse(
            loc.clone(),
            format!("{what} is `{t}`; expected a finite number"),
        ));
    }
    Ok(v)
}

/// Parse an optional number: empty → `None`.
pub(crate) fn opt_number(s: &str, loc: &Location, what: &str) -> Result<Option<f64>> {
    if s.trim().is_empty() {
        Ok(None)
    } else {
        number(s, loc, what).map(Some)
    }
}

//! Number parsing shared by the weather readers, with messages naming the
//! field and its unit. Field splitting is `crate::textio`'s.

use crate::error::{Error, Location, Result};

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

//! Small helpers over `roxmltree` for DIRSIG's XML files (`.scene`, `.glist`, `.atm`,
//! `.sim`, `.platform`, `.ppd`, `.tasks`): element lookup by name (case-insensitive,
//! as DIRSIG's own files vary), numbers with the file and line in errors.
//!
//! Takes XML text and its path; gives nodes and values. Must not know what the
//! elements mean.

use std::path::Path;

use roxmltree::{Document, Node};

use crate::error::{Error, Location, Result};

/// Parse `text` (from `path`) as XML; the error names the file and line.
pub fn parse<'a>(text: &'a str, path: &Path) -> Result<Document<'a>> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    Document::parse_with_options(text, opts).map_err(|e| {
        let pos = e.pos();
        Error::parse(
            Location::file(path).at_line(pos.row as usize),
            format!("not well-formed XML: {e}"),
        )
    })
}

/// The root element of `doc` (read from `path`), which must be `<name>`
/// (case-insensitive); otherwise an error naming it and what was expected,
/// followed by `note`.
pub fn root<'a, 'i>(
    doc: &'a Document<'i>,
    path: &Path,
    name: &str,
    note: &str,
) -> Result<Node<'a, 'i>> {
    let root = doc.root_element();
    if !root.tag_name().name().eq_ignore_ascii_case(name) {
        return Err(Error::parse(
            loc(path, root),
            format!(
                "root `<{}>`: expected `<{name}>`{note}",
                root.tag_name().name()
            ),
        ));
    }
    Ok(root)
}

/// The 1-based line of `n`.
pub fn line(n: Node) -> usize {
    n.document().text_pos_at(n.range().start).row as usize
}

/// A location at `n` in `path`, with the element name as the field.
pub fn loc(path: &Path, n: Node) -> Location {
    Location::file(path)
        .at_line(line(n))
        .with_field(format!("<{}>", n.tag_name().name()))
}

/// The element children of `n`.
pub fn elements<'a, 'i>(n: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    n.children().filter(Node::is_element)
}

/// The first child element named `name` (ASCII case-insensitive).
pub fn child<'a, 'i>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    elements(n).find(|c| c.tag_name().name().eq_ignore_ascii_case(name))
}

/// Every child element named `name`.
pub fn children<'a, 'i>(n: Node<'a, 'i>, name: &'a str) -> impl Iterator<Item = Node<'a, 'i>> {
    elements(n).filter(move |c| c.tag_name().name().eq_ignore_ascii_case(name))
}

/// The element at a path of names below `n` (`child(child(n, a), b)`…).
pub fn path<'a, 'i>(n: Node<'a, 'i>, names: &[&str]) -> Option<Node<'a, 'i>> {
    names.iter().try_fold(n, |n, name| child(n, name))
}

/// The trimmed text of `n` (CDATA included).
pub fn text(n: Node) -> String {
    n.descendants()
        .filter(Node::is_text)
        .filter_map(|t| t.text())
        .collect::<String>()
        .trim()
        .to_string()
}

/// An attribute, ASCII case-insensitive.
pub fn attr<'a>(n: Node<'a, '_>, name: &str) -> Option<&'a str> {
    n.attributes()
        .find(|a| a.name().eq_ignore_ascii_case(name))
        .map(|a| a.value())
}

/// `enabled="false"` (or `0`, `no`) on `n`.
pub fn disabled(n: Node) -> bool {
    attr(n, "enabled").is_some_and(|v| {
        matches!(
            v.trim().to_ascii_lowercase().as_str(),
            "false" | "0" | "no" | "off"
        )
    })
}

/// The text of `n` as a finite number.
pub fn number(path: &Path, n: Node) -> Result<f64> {
    let t = text(n);
    t.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| Error::parse(loc(path, n), format!("expected a number, found `{t}`")))
}

/// The number in child `name` of `n`, if present.
pub fn opt_number(path: &Path, n: Node, name: &str) -> Result<Option<f64>> {
    child(n, name).map(|c| number(path, c)).transpose()
}

/// The number in child `name` of `n`, required.
pub fn req_number(path: &Path, n: Node, name: &str) -> Result<f64> {
    let c = child(n, name).ok_or_else(|| {
        Error::parse(
            loc(path, n),
            format!("`<{}>` needs a `<{name}>`", n.tag_name().name()),
        )
    })?;
    number(path, c)
}

/// `<x>`, `<y>`, `<z>` children of `n` (each defaulting to `default`), or the
/// text `x, y, z` / `x y z`.
pub fn triple(path: &Path, n: Node, default: f64) -> Result<[f64; 3]> {
    if elements(n).next().is_none() {
        let t = text(n);
        let v: Vec<f64> = t
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or(()))
            .collect::<std::result::Result<_, _>>()
            .map_err(|()| {
                Error::parse(
                    loc(path, n),
                    format!("expected three finite numbers, found `{t}`"),
                )
            })?;
        return match v.len() {
            0 => Ok([default; 3]),
            3 => Ok([v[0], v[1], v[2]]),
            k => Err(Error::parse(
                loc(path, n),
                format!("expected three numbers, found {k}"),
            )),
        };
    }
    // A wrapper such as `<point>` or `<cartesiantriple>`.
    let inner = if child(n, "x").is_none() {
        elements(n).next().unwrap_or(n)
    } else {
        n
    };
    let mut out = [default; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        if let Some(v) = opt_number(path, inner, name)? {
            out[k] = v;
        }
    }
    Ok(out)
}

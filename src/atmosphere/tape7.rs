//! MODTRAN `tape7` reader.
//!
//! A tape7 file echoes the input cards, then a column header (one line of
//! names, and in transmittance mode a second line of units), then one row
//! per spectral point, ending with a line `-9999.`. Columns are fixed-width
//! Fortran fields and may be blank (e.g. `THRML_SCT` in some runs), so rows
//! are cut at the column boundaries given by the header (each header token is
//! right-aligned on its column's last character), never split on spaces.
//! Blank fields read as NaN.
//!
//! Units (MODTRAN 4/5 user's manual, "tape7" output): `FREQ` in cm⁻¹;
//! radiances in W·cm⁻²·sr⁻¹·(cm⁻¹)⁻¹; transmittances dimensionless. Converted
//! to the wavelength domain, λ [µm] = 10⁴/ν [cm⁻¹] and |dν/dλ| = 10⁴/λ², so
//!
//! ```text
//! L_λ [W m⁻² sr⁻¹ µm⁻¹] = L_ν [W cm⁻² sr⁻¹ (cm⁻¹)⁻¹] · 10⁴ [cm²/m²] · 10⁴/λ² = L_ν · ν²
//! ```
//!
//! In radiance mode the path (atmospheric) radiance is `PTH_THRML + SOL_SCAT`
//! (`THRML_SCT` is already part of `PTH_THRML`: `TOTAL_RAD = PTH_THRML +
//! SURF_EMIS + SOL_SCAT + GRND_RFLT`, which the files here satisfy), and the
//! path transmittance is `TOT_TRANS`. In transmittance mode the total is the
//! `COMBIN TRANS` column.

use std::path::Path;

use crate::{Error, Location, Result};

/// What a tape7 file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tape7Mode {
    /// Radiance mode (IEMSCT = 1 or 2): TOT_TRANS, PTH_THRML, … columns.
    Radiance,
    /// Transmittance mode (IEMSCT = 0): COMBIN and per-species TRANS columns.
    Transmittance,
}

/// One column of a tape7 table.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape7Column {
    /// Name from the first header line (`TOT_TRANS`, `H2O`, …).
    pub name: String,
    /// Second header line's entry (`TRANS`, `CONT`, …), empty when absent.
    pub unit: String,
    /// Values, one per row, in the file's units; blank fields are NaN.
    pub values: Vec<f64>,
}

/// A parsed tape7 file.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape7 {
    /// The echoed input cards (the lines before the column header).
    pub cards: Vec<String>,
    /// Radiance or transmittance mode.
    pub mode: Tape7Mode,
    /// Wavenumbers of the rows, cm⁻¹, in file order (strictly monotonic).
    pub wavenumber_cm: Vec<f64>,
    /// The other columns, in file order.
    pub columns: Vec<Tape7Column>,
}

fn token_spans(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        out.push((s, i));
    }
    out
}

fn slice(line: &str, a: usize, b: usize) -> &str {
    let n = line.len();
    line.get(a.min(n)..b.min(n)).unwrap_or("").trim()
}

impl Tape7 {
    /// Read and parse a tape7 file.
    pub fn read(path: impl AsRef<Path>) -> Result<Tape7> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Tape7::parse(&text, path)
    }

    /// Parse tape7 text; `path` names the file in error messages.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Tape7> {
        let path = path.as_ref();
        let loc = |line: usize| Location::file(path).at_line(line);
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            if !l.is_ascii() {
                return Err(Error::parse(
                    loc(i + 1),
                    "expected ASCII text (is this a MODTRAN tape7 file?)",
                ));
            }
        }
        let h = lines
            .iter()
            .position(|l| l.split_whitespace().next() == Some("FREQ"))
            .ok_or_else(|| {
                Error::parse(
                    Location::file(path),
                    "no column header line starting with `FREQ` (expected a MODTRAN tape7 \
                     file with spectral output in wavenumbers)",
                )
            })?;
        let is_numeric_line = |l: &str| {
            l.split_whitespace()
                .next()
                .is_some_and(|t| t.parse::<f64>().is_ok())
        };
        // An optional second header line (units) that is not numeric.
        let mut first_data = h + 1;
        let unit_line = match lines.get(h + 1) {
            Some(l) if !is_numeric_line(l) && !l.trim().is_empty() => {
                first_data = h + 2;
                Some(*l)
            }
            _ => None,
        };
        let name_spans = token_spans(lines[h]);
        let unit_spans = unit_line.map(token_spans).unwrap_or_default();
        // Column boundaries from the header line with the most tokens (the
        // units line: names can run together, `H2-CH4CH4-CH4`).
        let ends: Vec<usize> = if unit_spans.len() >= name_spans.len() {
            unit_spans.iter().map(|s| s.1).collect()
        } else {
            name_spans.iter().map(|s| s.1).collect()
        };
        let bounds: Vec<(usize, usize)> = ends
            .iter()
            .enumerate()
            .map(|(i, &e)| (if i == 0 { 0 } else { ends[i - 1] }, e))
            .collect();
        let ncol = bounds.len();
        if ncol < 2 {
            return Err(Error::parse(
                loc(h + 1),
                "expected FREQ followed by at least one data column",
            ));
        }
        let names: Vec<String> = bounds
            .iter()
            .map(|&(a, b)| slice(lines[h], a, b).to_string())
            .collect();
        let units: Vec<String> = bounds
            .iter()
            .map(|&(a, b)| unit_line.map(|u| slice(u, a, b)).unwrap_or("").to_string())
            .collect();

        let mut values: Vec<Vec<f64>> = vec![Vec::new(); ncol];
        let mut terminated = false;
        for (i, line) in lines.iter().enumerate().skip(first_data) {
            let lineno = i + 1;
            let t = line.trim();
            if t.starts_with("-9999") {
                terminated = true;
                break;
            }
            if t.is_empty() {
                return Err(Error::parse(
                    loc(lineno),
                    "blank line inside the data block (expected a data row or `-9999.`)",
                ));
            }
            let last = bounds[ncol - 1].1;
            if line.len() > last && !line[last..].trim().is_empty() {
                return Err(Error::parse(
                    loc(lineno),
                    format!(
                        "text beyond the last column (character {}): `{}`",
                        last + 1,
                        line[last..].trim()
                    ),
                ));
            }
            for (c, &(a, b)) in bounds.iter().enumerate() {
                let f = slice(line, a, b);
                let v = if f.is_empty() {
                    f64::NAN
                } else {
                    f.replace(['D', 'd'], "E").parse::<f64>().map_err(|_| {
                        Error::parse(
                            loc(lineno).with_field(names[c].clone()),
                            format!("expected a number in columns {}–{}, found `{f}`", a + 1, b),
                        )
                    })?
                };
                if c == 0 && !v.is_finite() {
                    return Err(Error::parse(
                        loc(lineno).with_field("FREQ"),
                        "the wavenumber (FREQ) field is blank",
                    ));
                }
                values[c].push(v);
            }
        }
        if !terminated {
            return Err(Error::parse(
                Location::file(path).at_line(lines.len()),
                "the data block does not end with a `-9999.` line (truncated file?)",
            ));
        }
        let wavenumber_cm = std::mem::take(&mut values[0]);
        if wavenumber_cm.len() < 2 {
            return Err(Error::parse(
                loc(first_data + 1),
                format!(
                    "expected at least two spectral rows, found {}",
                    wavenumber_cm.len()
                ),
            ));
        }
        if wavenumber_cm[0] <= 0.0 {
            return Err(Error::parse(
                loc(first_data + 1).with_field("FREQ"),
                format!(
                    "wavenumbers must be positive: the first is {}",
                    wavenumber_cm[0]
                ),
            ));
        }
        let increasing = wavenumber_cm[1] > wavenumber_cm[0];
        for k in 1..wavenumber_cm.len() {
            let (p, q) = (wavenumber_cm[k - 1], wavenumber_cm[k]);
            if (increasing && q <= p) || (!increasing && q >= p) || q <= 0.0 {
                return Err(Error::parse(
                    loc(first_data + k + 1).with_field("FREQ"),
                    format!("wavenumbers must be positive and monotonic: {q} follows {p}"),
                ));
            }
        }
        let columns: Vec<Tape7Column> = names
            .into_iter()
            .zip(units)
            .zip(values)
            .skip(1)
            .map(|((name, unit), values)| Tape7Column { name, unit, values })
            .collect();
        let has = |n: &str| columns.iter().any(|c| c.name == n);
        let mode = if has("TOT_TRANS") && has("PTH_THRML") {
            Tape7Mode::Radiance
        } else if has("COMBIN") {
            Tape7Mode::Transmittance
        } else {
            return Err(Error::parse(
                loc(h + 1),
                "unsupported tape7 layout: expected radiance-mode columns (TOT_TRANS, \
                 PTH_THRML, …) or transmittance-mode columns (COMBIN, …)",
            ));
        };
        let t7 = Tape7 {
            cards: lines[..h].iter().map(|s| s.to_string()).collect(),
            mode,
            wavenumber_cm,
            columns,
        };
        // The columns the atmosphere uses must be complete.
        let mut needed = vec![t7.transmittance_column_name()];
        if mode == Tape7Mode::Radiance {
            needed.extend(["PTH_THRML", "SOL_SCAT"]);
        }
        for n in needed {
            let Some(col) = t7.column(n) else {
                return Err(Error::parse(
                    loc(h + 1).with_field(n),
                    format!("radiance-mode tape7 without a {n} column; irsig needs it"),
                ));
            };
            if let Some(k) = col.iter().position(|v| !v.is_finite()) {
                return Err(Error::parse(
                    loc(first_data + k + 1).with_field(n),
                    format!("column {n} is blank; irsig needs it"),
                ));
            }
        }
        Ok(t7)
    }

    fn transmittance_column_name(&self) -> &'static str {
        match self.mode {
            Tape7Mode::Radiance => "TOT_TRANS",
            Tape7Mode::Transmittance => "COMBIN",
        }
    }

    /// A column by name (`TOT_TRANS`) or by name and unit (`H2O CONT`); the
    /// first match.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|c| c.name == name || format!("{} {}", c.name, c.unit) == name)
            .map(|c| c.values.as_slice())
    }

    /// Number of spectral rows.
    pub fn len(&self) -> usize {
        self.wavenumber_cm.len()
    }
    /// Whether there are no rows (never true for a parsed file).
    pub fn is_empty(&self) -> bool {
        self.wavenumber_cm.is_empty()
    }

    /// The rows' wavelengths, µm, increasing, and the row index of each.
    fn order_um(&self) -> (Vec<f64>, Vec<usize>) {
        let mut idx: Vec<usize> = (0..self.len()).collect();
        if self.wavenumber_cm[1] > self.wavenumber_cm[0] {
            idx.reverse();
        }
        (
            idx.iter().map(|&i| 1e4 / self.wavenumber_cm[i]).collect(),
            idx,
        )
    }

    /// The spectral range covered, µm (min, max).
    pub fn range_um(&self) -> (f64, f64) {
        let (a, b) = (
            1e4 / self.wavenumber_cm[0],
            1e4 / self.wavenumber_cm[self.len() - 1],
        );
        (a.min(b), a.max(b))
    }

    /// A dimensionless column (a transmittance) against increasing
    /// wavelength: (λ µm, values).
    pub fn column_um(&self, name: &str) -> Option<(Vec<f64>, Vec<f64>)> {
        let col = self.column(name)?;
        let (wl, idx) = self.order_um();
        Some((wl, idx.iter().map(|&i| col[i]).collect()))
    }

    /// A radiance column converted to W·m⁻²·sr⁻¹·µm⁻¹ against increasing
    /// wavelength (L_λ = L_ν · ν², see the module docs).
    pub fn radiance_column_um(&self, name: &str) -> Option<(Vec<f64>, Vec<f64>)> {
        let col = self.column(name)?;
        let (wl, idx) = self.order_um();
        let v = idx
            .iter()
            .map(|&i| col[i] * self.wavenumber_cm[i] * self.wavenumber_cm[i])
            .collect();
        Some((wl, v))
    }

    /// Total path transmittance against increasing wavelength (µm).
    pub fn transmittance_um(&self) -> (Vec<f64>, Vec<f64>) {
        self.column_um(self.transmittance_column_name())
            .expect("checked when parsed")
    }

    /// Path radiance `PTH_THRML + SOL_SCAT` in W·m⁻²·sr⁻¹·µm⁻¹ against
    /// increasing wavelength; `None` in transmittance mode.
    pub fn path_radiance_um(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        if self.mode != Tape7Mode::Radiance {
            return None;
        }
        let (wl, th) = self.radiance_column_um("PTH_THRML")?;
        let (_, ss) = self.radiance_column_um("SOL_SCAT")?;
        Some((wl, th.iter().zip(&ss).map(|(a, b)| a + b).collect()))
    }
}

//! Calendar placement of EPW/TMY3 rows: each row's stamp (year, month, day, minutes after
//! local midnight) → a time, with typical-year files recognised and given one year.
//!
//! A typical meteorological year (TMY2/TMY3, the EPW files built from them, IWEC, …) is
//! twelve months picked from different years (Wilcox & Marion 2008, NREL/TP-581-43156,
//! §1.2): its rows keep each month's source year, so read as written they are not in time
//! order. A file is taken for a typical year when the year changes between two consecutive
//! rows where the month changes, other than at a 31 December → 1 January turn of the year. Such a file gets one
//! year for all rows: [`LoadOptions::year`] when given, else [`LoadOptions::typical_year`]
//! (a scene gives its image time's year), else it is an error saying so.
//!
//! When one year is applied (either option), 29 February follows that year: a file's
//! 29 February rows are dropped in a common year, and in a leap year a file without them
//! (TMY files have 8760 hours) repeats its 28 February rows as 29 February (EnergyPlus
//! does the same for a leap-year run period).
//!
//! Takes stamps with their records; gives the records with their times. Must not know the
//! formats' columns (the readers) or gap filling ([`super::fill`]).

use chrono::{FixedOffset, NaiveDate, TimeDelta, TimeZone};

use super::LoadOptions;
use super::fill::RawRecord;
use crate::error::{Error, Result};

/// A row's calendar stamp as written in the file (local standard time).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Stamp {
    pub year: i32,
    pub month: u32,
    pub day: u32,
    /// Minutes after local midnight (an hour-ending `24:00` is 1440).
    pub minutes: i64,
}

fn is_leap(y: i32) -> bool {
    (y % 4 == 0 && y % 100 != 0) || y % 400 == 0
}

/// The first row (index) where the year changes at a change of month other than the
/// turn of the year. (A year that changes inside a month is a damaged file, not a typical
/// year: it stays as written and fails the time-order check.)
fn mixed_year_row(rows: &[(Stamp, RawRecord)]) -> Option<usize> {
    (1..rows.len()).find(|&i| {
        let (a, b) = (&rows[i - 1].0, &rows[i].0);
        a.year != b.year
            && a.month != b.month
            && !(a.month == 12 && b.month == 1 && b.year == a.year + 1)
    })
}

/// Give each row its time (see the module docs).
///
/// # Errors
/// A typical-year file without a year to apply; a stamp that is not a date in the
/// year used; each naming the file and line.
pub(crate) fn place(
    mut rows: Vec<(Stamp, RawRecord)>,
    offset: FixedOffset,
    options: &LoadOptions,
) -> Result<Vec<RawRecord>> {
    let year = match (options.year, mixed_year_row(&rows)) {
        (Some(y), _) => Some(y),
        (None, None) => None,
        (None, Some(i)) => match options.typical_year {
            Some(y) => Some(y),
            None => {
                return Err(Error::parse(
                    rows[i].1.loc.clone().with_field("year"),
                    format!(
                        "the year changes from {} to {} between {:02}-{:02} and {:02}-{:02}: \
                         this is a typical-year file (months from different years), and the \
                         year to apply must be given (a scene applies its image time's year)",
                        rows[i - 1].0.year,
                        rows[i].0.year,
                        rows[i - 1].0.month,
                        rows[i - 1].0.day,
                        rows[i].0.month,
                        rows[i].0.day,
                    ),
                ));
            }
        },
    };
    if let Some(y) = year {
        // A typical year's rows (and a forced year's) all take year `y`, except that a
        // Dec → Jan turn inside the file moves on to the next year.
        let mut add = 0;
        for i in 0..rows.len() {
            if i > 0 && rows[i - 1].0.month == 12 && rows[i].0.month == 1 {
                add += 1;
            }
            rows[i].0.year = y + add;
        }
        rows.retain(|(s, _)| !(s.month == 2 && s.day == 29 && !is_leap(s.year)));
        let has_feb29 = rows.iter().any(|(s, _)| s.month == 2 && s.day == 29);
        if !has_feb29 {
            let feb28: Vec<usize> = (0..rows.len())
                .filter(|&i| {
                    let s = &rows[i].0;
                    s.month == 2 && s.day == 28 && is_leap(s.year)
                })
                .collect();
            let followed_by_march = feb28
                .last()
                .and_then(|&i| rows.get(i + 1))
                .is_some_and(|(s, _)| s.month == 3 && s.day == 1);
            if followed_by_march {
                let at = feb28[feb28.len() - 1] + 1;
                let copies: Vec<(Stamp, RawRecord)> = feb28
                    .iter()
                    .map(|&i| {
                        let (mut s, r) = rows[i].clone();
                        s.day = 29;
                        (s, r)
                    })
                    .collect();
                rows.splice(at..at, copies);
            }
        }
    }
    rows.into_iter()
        .map(|(s, mut r)| {
            let date = NaiveDate::from_ymd_opt(s.year, s.month, s.day).ok_or_else(|| {
                Error::parse(
                    r.loc.clone().with_field("day"),
                    format!(
                        "{}-{:02}-{:02} is not a date{}",
                        s.year,
                        s.month,
                        s.day,
                        if year.is_some() {
                            " in the year applied"
                        } else {
                            ""
                        }
                    ),
                )
            })?;
            let midnight = offset
                .from_local_datetime(&date.and_hms_opt(0, 0, 0).unwrap_or_default())
                .single()
                .ok_or_else(|| {
                    Error::parse(r.loc.clone(), "local midnight is not representable")
                })?;
            r.time = midnight + TimeDelta::minutes(s.minutes);
            Ok(r)
        })
        .collect()
}

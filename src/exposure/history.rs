//! The history window of the thermal model and the sun over it.

use chrono::{DateTime, FixedOffset, TimeDelta};
use glam::Vec3;

use crate::sun::{self, Site};
use crate::weather::WeatherHistory;
use crate::{Error, Result};
/// The stretch of weather the thermal model is run over, ending at the last
/// image time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HistoryWindow {
    /// How far before the first image time the history starts (default
    /// 24 h; the slab solver spins up by repeating its first day).
    pub length: TimeDelta,
    /// Largest time step (default 15 min): the step is the weather's own
    /// step, or this when the weather is coarser (hourly files) — the
    /// weather is then interpolated linearly in time, and the sun traced at
    /// every step.
    pub max_step: TimeDelta,
}

impl Default for HistoryWindow {
    fn default() -> Self {
        HistoryWindow {
            length: TimeDelta::hours(24),
            max_step: TimeDelta::minutes(15),
        }
    }
}

/// Record times of the history: the grid of multiples of the step (counted
/// from the Unix epoch, so that it does not depend on the image times) from
/// `first image − length` up to the last image time, with every image time
/// inserted exactly. Each image time's own window ([`image_window`]) is
/// then the same whether it is rendered alone or in a series.
///
/// # Errors
/// [`Error::Invalid`] when there is no image time, the window is not
/// positive, or the weather does not cover the window.
pub fn history_times(
    weather: &WeatherHistory,
    image_times: &[DateTime<FixedOffset>],
    window: &HistoryWindow,
) -> Result<Vec<DateTime<FixedOffset>>> {
    let (Some(&first), Some(&last)) = (image_times.iter().min(), image_times.iter().max()) else {
        return Err(Error::invalid(
            "image_times",
            "expected at least one image time",
        ));
    };
    if window.length <= TimeDelta::zero() || window.max_step <= TimeDelta::zero() {
        return Err(Error::invalid(
            "history window",
            format!(
                "expected a positive length and step, got {} s and {} s",
                window.length.num_seconds(),
                window.max_step.num_seconds()
            ),
        ));
    }
    let start = first - window.length;
    if start < weather.start() || last > weather.end() {
        return Err(Error::invalid(
            "image time",
            format!(
                "the thermal history from {} (a {} h window before the first image time) to {} \
                 needs weather over that span, but the weather history covers {} to {}",
                start.to_rfc3339(),
                window.length.num_minutes() as f64 / 60.0,
                last.to_rfc3339(),
                weather.start().to_rfc3339(),
                weather.end().to_rfc3339()
            ),
        ));
    }
    let step = history_step(weather, window);
    let mut times = Vec::new();
    let mut t = align_up(start, step);
    while t < last {
        times.push(t);
        t += step;
    }
    times.extend(image_times.iter().copied());
    times.sort();
    // Merge times closer than a second (an image time on the grid).
    times.dedup_by(|b, a| (*b - *a).abs() < TimeDelta::seconds(1));
    Ok(times)
}

/// The step of the history grid: the weather's own step, capped at
/// `window.max_step`, at least a second.
pub fn history_step(weather: &WeatherHistory, window: &HistoryWindow) -> TimeDelta {
    weather
        .step()
        .min(window.max_step)
        .max(TimeDelta::seconds(1))
}

/// The first multiple of `step` since the Unix epoch at or after `t` (in
/// `t`'s offset).
fn align_up(t: DateTime<FixedOffset>, step: TimeDelta) -> DateTime<FixedOffset> {
    let (ms, step_ms) = (t.timestamp_millis(), step.num_milliseconds().max(1));
    let up = ms.div_euclid(step_ms) * step_ms
        + if ms.rem_euclid(step_ms) > 0 {
            step_ms
        } else {
            0
        };
    t + TimeDelta::milliseconds(up - ms)
}

/// The records (indices into `times`, from [`history_times`] with grid
/// step `step`, [`history_step`]) of the window of image time `image`: the
/// grid times within `length` before it, and `image` itself last. Other image times that fall between
/// grid times are left out, so the window — and with it the thermal
/// solution at `image` — does not depend on which other times share the
/// history.
pub fn image_window(
    times: &[DateTime<FixedOffset>],
    image: DateTime<FixedOffset>,
    images: &[DateTime<FixedOffset>],
    length: TimeDelta,
    step: TimeDelta,
) -> Vec<usize> {
    let start = image - length;
    let close =
        |a: DateTime<FixedOffset>, b: DateTime<FixedOffset>| (a - b).abs() < TimeDelta::seconds(1);
    // A grid time is one that is not an inserted image time, or an image
    // time that lies on the grid.
    let step_ms = step.num_milliseconds().max(1);
    let on_grid = |t: DateTime<FixedOffset>| t.timestamp_millis().rem_euclid(step_ms) == 0;
    times
        .iter()
        .enumerate()
        .filter(|&(_, &t)| {
            if close(t, image) {
                return true;
            }
            t >= start && t < image && (on_grid(t) || !images.iter().any(|&i| close(i, t)))
        })
        .map(|(i, _)| i)
        .collect()
}

/// Unit east-north-up vectors toward the sun's apparent position at each
/// time (NREL SPA, [`sun::positions_standard`]), computed once for the
/// scene; `z ≤ 0` when the sun is down.
///
/// # Errors
/// As [`sun::position`] (bad site or time).
pub fn sun_directions(site: &Site, times: &[DateTime<FixedOffset>]) -> Result<Vec<Vec3>> {
    Ok(sun::positions_standard(site, times.iter().copied())?
        .iter()
        .map(|p| {
            let d = p.direction_enu().as_vec3().normalize();
            if p.is_up() {
                d
            } else {
                Vec3::new(d.x, d.y, d.z.min(0.0))
            }
        })
        .collect())
}

//! Plots of the analysis commands, drawn with `plotters` into an RGB buffer
//! and written as PNG atomically. Text uses a font embedded in the binary
//! (Hack, from `epaint_default_fonts`), so no system font or fontconfig is
//! needed.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::stats::Histogram;
use crate::{Error, Result};

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is a valid TrueType file; a failure would leave
        // plotters without text, which `draw` reports as an error.
        let _ = plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            epaint_default_fonts::HACK_REGULAR,
        );
    });
}

/// Colours of successive series.
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Draw into a `width × height` RGB canvas with `draw` and write it as a
/// PNG file at `path`, atomically.
pub fn render_png(
    path: &Path,
    width: u32,
    height: u32,
    draw: impl FnOnce(&Area) -> DrawResult,
) -> Result<()> {
    register_font();
    let mut buf = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| Error::Other(format!("plot {}: {e}", path.display())))?;
        draw(&root).map_err(|e| Error::Other(format!("plot {}: {e}", path.display())))?;
        root.present()
            .map_err(|e| Error::Other(format!("plot {}: {e}", path.display())))?;
    }
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| Error::Other(format!("PNG {}: {e}", path.display())))?;
        w.write_image_data(&buf)
            .map_err(|e| Error::Other(format!("PNG {}: {e}", path.display())))?;
    }
    super::write_file_atomic(path, &png_bytes)
}

/// Overlaid histograms (step outlines) of several samples on one axis.
pub fn histograms(
    path: &Path,
    title: &str,
    x_label: &str,
    series: &[(&str, &Histogram)],
) -> Result<()> {
    let (xmin, xmax) = series
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (_, h)| {
            (a.min(h.min), b.max(h.max))
        });
    let ymax = series
        .iter()
        .flat_map(|(_, h)| h.counts.iter().copied())
        .max()
        .unwrap_or(1)
        .max(1) as f64
        * 1.08;
    render_png(path, 900, 560, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT, 22))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(xmin..xmax, 0.0..ymax)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("pixels")
            .label_style((FONT, 14))
            .draw()?;
        for (k, (name, h)) in series.iter().enumerate() {
            let c = PALETTE[k % PALETTE.len()];
            let w = h.bin_width();
            let mut pts = Vec::with_capacity(2 * h.counts.len() + 2);
            pts.push((h.min, 0.0));
            for (i, &n) in h.counts.iter().enumerate() {
                let x0 = h.min + i as f64 * w;
                pts.push((x0, n as f64));
                pts.push((x0 + w, n as f64));
            }
            pts.push((h.max, 0.0));
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    })
}

/// One bar of a tornado plot: output change at the low and at the high
/// bound of a parameter, relative to the nominal output.
#[derive(Debug, Clone)]
pub struct TornadoBar {
    /// Parameter name.
    pub name: String,
    /// Output change with the parameter at its low bound.
    pub at_low: f64,
    /// Output change with the parameter at its high bound.
    pub at_high: f64,
}

/// A tornado plot: horizontal bars, largest swing at the top; `legend`
/// names the two bar colours (e.g. `["low bound", "high bound"]`).
pub fn tornado(
    path: &Path,
    title: &str,
    x_label: &str,
    legend: [&str; 2],
    bars: &[TornadoBar],
) -> Result<()> {
    let mut bars: Vec<TornadoBar> = bars.to_vec();
    bars.sort_by(|a, b| {
        let sa = (a.at_high - a.at_low).abs();
        let sb = (b.at_high - b.at_low).abs();
        sb.total_cmp(&sa)
    });
    let m = bars
        .iter()
        .flat_map(|b| [b.at_low.abs(), b.at_high.abs()])
        .fold(0.0f64, f64::max)
        .max(1e-12)
        * 1.1;
    let n = bars.len().max(1);
    let height = (120 + 36 * n) as u32;
    render_png(path, 900, height, |root| {
        let label_w = bars
            .iter()
            .map(|b| b.name.chars().count())
            .max()
            .unwrap_or(4) as u32
            * 9
            + 16;
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT, 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(label_w.min(380))
            .build_cartesian_2d(-m..m, 0.0..n as f64)?;
        let names: Vec<String> = bars.iter().map(|b| b.name.clone()).collect();
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_labels(n * 2 + 1)
            .y_label_formatter(&|y: &f64| {
                let k = (y - 0.5).round();
                if (y - 0.5 - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < names.len() {
                    names[n - 1 - k as usize].clone()
                } else {
                    String::new()
                }
            })
            .disable_y_mesh()
            .label_style((FONT, 14))
            .draw()?;
        for (i, b) in bars.iter().enumerate() {
            let y0 = (n - 1 - i) as f64 + 0.15;
            let y1 = y0 + 0.7;
            chart.draw_series([
                Rectangle::new([(0.0, y0), (b.at_low, y1)], PALETTE[0].filled()),
                Rectangle::new([(0.0, y0), (b.at_high, y1)], PALETTE[1].filled()),
            ])?;
        }
        chart.draw_series(LineSeries::new([(0.0, 0.0), (0.0, n as f64)], BLACK))?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(0.0, 0.0), (0.0, 0.0)],
                PALETTE[0].filled(),
            )))?
            .label(legend[0])
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], PALETTE[0].filled()));
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(0.0, 0.0), (0.0, 0.0)],
                PALETTE[1].filled(),
            )))?
            .label(legend[1])
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], PALETTE[1].filled()));
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()?;
        Ok(())
    })
}

/// A set of curves over a shared x axis (e.g. hours), with optional vertical
/// marker lines (label, x).
pub fn curves(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    x: &[f64],
    series: &[(&str, &[f64])],
    markers: &[(String, f64)],
) -> Result<()> {
    if x.is_empty() {
        return Err(Error::invalid("plot", "no points to plot"));
    }
    let (xmin, xmax) = (x[0], x[x.len() - 1].max(x[0] + 1e-9));
    let (mut ymin, mut ymax) = series
        .iter()
        .flat_map(|(_, s)| s.iter().copied().filter(|v| v.is_finite()))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if ymin > ymax {
        return Err(Error::invalid("plot", "no finite value to plot"));
    }
    let pad = ((ymax - ymin) * 0.06).max(1e-9);
    ymin -= pad;
    ymax += pad;
    render_png(path, 960, 560, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT, 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(xmin..xmax, ymin..ymax)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .label_style((FONT, 14))
            .draw()?;
        for (k, (name, s)) in series.iter().enumerate() {
            let c = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    x.iter()
                        .copied()
                        .zip(s.iter().copied())
                        .filter(|(_, v)| v.is_finite()),
                    c.stroke_width(2),
                ))?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        for (label, xm) in markers {
            chart.draw_series(LineSeries::new(
                [(*xm, ymin), (*xm, ymax)],
                BLACK.mix(0.5).stroke_width(1),
            ))?;
            chart.draw_series(std::iter::once(Text::new(
                label.clone(),
                (*xm, ymax - pad * 0.5),
                (FONT, 13),
            )))?;
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    })
}

/// Scatter of predicted against truth values with the 1:1 line.
pub fn scatter(
    path: &Path,
    title: &str,
    unit: &str,
    truth: &[f64],
    predicted: &[f64],
) -> Result<()> {
    let range = super::stats::common_range([truth, predicted])
        .ok_or_else(|| Error::invalid("plot", "no finite value to plot"))?;
    let pad = (range.1 - range.0) * 0.05;
    let (lo, hi) = (range.0 - pad, range.1 + pad);
    render_png(path, 640, 640, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT, 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(lo..hi, lo..hi)?;
        chart
            .configure_mesh()
            .x_desc(format!("truth ({unit})"))
            .y_desc(format!("synthetic ({unit})"))
            .label_style((FONT, 14))
            .draw()?;
        chart.draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK.mix(0.5)))?;
        chart.draw_series(
            truth
                .iter()
                .zip(predicted)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(&a, &b)| Circle::new((a, b), 3, PALETTE[0].filled())),
        )?;
        Ok(())
    })
}

//! `irsig info FILE [--json]`: size and per-layer statistics of an image.

use std::io::Write;
use std::path::PathBuf;

use irsig::output::{LayerStats, read_image};

/// Arguments of `irsig info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Image file: `.exr` (OpenEXR) or `.hdr`/`.img` (ENVI).
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Print JSON: `{"width", "height", "layers": [{"name", "min", "max",
    /// "mean", "nan_count"}]}` (min/max/mean over non-NaN values; `null`
    /// when a layer is all NaN).
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Info {
    width: usize,
    height: usize,
    layers: Vec<LayerStats>,
}

/// Run `irsig info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let image = read_image(&args.file)?;
    let info = Info {
        width: image.width,
        height: image.height,
        layers: image.stats(),
    };
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string(&info)?)?;
        return Ok(());
    }
    writeln!(out, "{}", args.file.display())?;
    writeln!(out, "width  {}", info.width)?;
    writeln!(out, "height {}", info.height)?;
    let w = info
        .layers
        .iter()
        .map(|l| l.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    writeln!(
        out,
        "{:<w$}  {:>14}  {:>14}  {:>14}  {:>9}",
        "layer", "min", "max", "mean", "NaN count"
    )?;
    let num = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.6}"));
    for l in &info.layers {
        writeln!(
            out,
            "{:<w$}  {:>14}  {:>14}  {:>14}  {:>9}",
            l.name,
            num(l.min),
            num(l.max),
            num(l.mean),
            l.nan_count
        )?;
    }
    Ok(())
}

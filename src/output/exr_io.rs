//! OpenEXR writer and reader for an [`ImageStack`] (crate `exr`): one `f32`
//! channel per layer, in a single EXR part, lossless ZIP compression.
//!
//! EXR stores channels sorted by name; the layer order is kept in the custom
//! part attribute `irsigLayerOrder` (a text vector) and restored on reading.
//! Files written by other tools (without that attribute) read back with
//! channels in name order; `f16` and `u32` channels are converted to `f32`.

use std::path::Path;

use exr::prelude::traits::*;
use exr::prelude::{self as x};

use super::atomic::write_atomic;
use super::{ImageStack, Layer};
use crate::{Error, Location, Result};

/// Name of the custom attribute that records the layer order.
const ORDER_ATTRIBUTE: &str = "irsigLayerOrder";

/// Write `stack` to `path` as OpenEXR, atomically. Layer names must be
/// non-empty, unique and free of `.` (EXR's layer separator).
pub fn write_exr(path: impl AsRef<Path>, stack: &ImageStack) -> Result<()> {
    let path = path.as_ref();
    stack.validate()?;
    if stack.width == 0 || stack.height == 0 || stack.layers.is_empty() {
        return Err(Error::invalid(
            "image",
            format!(
                "cannot write an empty image ({}×{}, {} layers) to {}",
                stack.width,
                stack.height,
                stack.layers.len(),
                path.display()
            ),
        ));
    }
    for l in &stack.layers {
        if l.name.contains('.') || l.name.is_empty() {
            return Err(Error::invalid(
                "layer name",
                format!("`{}`: expected a non-empty name without `.`", l.name),
            ));
        }
    }
    let mut attributes = x::LayerAttributes::named("irsig");
    attributes.other.insert(
        x::Text::from(ORDER_ATTRIBUTE),
        x::AttributeValue::TextVector(
            stack
                .layers
                .iter()
                .map(|l| x::Text::from(l.name.as_str()))
                .collect(),
        ),
    );
    let layer = flat_exr_layer(
        (stack.width, stack.height),
        attributes,
        stack.layers.iter().map(|l| (l.name.as_str(), &l.data)),
    );
    write_flat_exr(path, layer, "OpenEXR")
}

/// A single flat EXR part with all its channels and attributes.
pub type FlatExrLayer = x::Layer<x::AnyChannels<x::FlatSamples>>;

/// One flat EXR part of `f32` channels `(name, data)` of `size`, with
/// `attributes`, lossless ZIP compression.
pub fn flat_exr_layer<'a>(
    size: (usize, usize),
    attributes: x::LayerAttributes,
    channels: impl IntoIterator<Item = (&'a str, &'a Vec<f32>)>,
) -> FlatExrLayer {
    let channels: x::SmallVec<[x::AnyChannel<x::FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(n, d)| x::AnyChannel::new(n, x::FlatSamples::F32(d.clone())))
        .collect();
    x::Layer::new(
        size,
        attributes,
        x::Encoding::SMALL_LOSSLESS,
        x::AnyChannels::sort(channels),
    )
}

/// Write one flat EXR part to `path`, atomically; `what` names the file kind
/// in errors ("OpenEXR", "tile").
///
/// The blocks (16 scan lines each) are ZIP-compressed in parallel on a pool
/// of as many threads as the caller's rayon pool has (exr's
/// own parallel writer would take every core), and written in increasing
/// line order, so the file is the same for any thread count.
pub fn write_flat_exr(path: &Path, layer: FlatExrLayer, what: &str) -> Result<()> {
    use exr::block::writer::{ChunksWriter, ParallelBlocksCompressor};
    use exr::image::write::layers::{LayersWriter, WritableLayers};
    let image = x::Image::from_layer(layer);
    let err = |e: x::Error| Error::Other(format!("{}: writing {what}: {e}", path.display()));
    let threads = rayon::current_num_threads();
    write_atomic(path, |w| {
        let headers = image.layer_data.infer_headers(&image.attributes);
        let layers = image.layer_data.create_writer(&headers);
        exr::block::write(w, headers, true, |meta, chunks| {
            let blocks = meta.collect_ordered_block_data(|block| {
                layers.extract_uncompressed_block(&meta.headers, block)
            });
            let mut chunks = chunks.on_progress(|_| ());
            let pool = || {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("irsig-exr-{i}"))
                    .build()
            };
            let parallel = if threads > 1 {
                ParallelBlocksCompressor::new_with_thread_pool(&meta, &mut chunks, pool)
            } else {
                None
            };
            match parallel {
                Some(mut p) => {
                    for (index, block) in blocks {
                        p.add_block_to_compression_queue(index, block)?;
                    }
                    Ok(())
                }
                None => chunks.compress_all_blocks_sequential(&meta, blocks),
            }
        })
        .map_err(err)
    })
}

/// Read the first flat part of an EXR file, all channels and attributes;
/// `what` names the expected kind in errors ("OpenEXR image", "OpenEXR tile").
pub fn read_flat_exr(path: &Path, what: &str) -> Result<FlatExrLayer> {
    if !path.exists() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    let image = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_file(path)
        .map_err(|e| Error::parse(Location::file(path), format!("not a readable {what}: {e}")))?;
    Ok(image.layer_data)
}

/// Read an OpenEXR file written by [`write_exr`] (or any flat, single-part
/// EXR) into an [`ImageStack`].
pub fn read_exr(path: impl AsRef<Path>) -> Result<ImageStack> {
    let path = path.as_ref();
    let bad = |m: String| Error::parse(Location::file(path), m);
    let layer = read_flat_exr(path, "OpenEXR image")?;
    let (width, height) = (layer.size.width(), layer.size.height());
    let mut layers: Vec<Layer> = layer
        .channel_data
        .list
        .iter()
        .map(|c| Layer {
            name: c.name.to_string(),
            data: match &c.sample_data {
                x::FlatSamples::F32(v) => v.clone(),
                x::FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
                x::FlatSamples::U32(v) => v.iter().map(|&u| u as f32).collect(),
            },
        })
        .collect();
    if let Some(x::AttributeValue::TextVector(order)) =
        layer.attributes.other.get(&x::Text::from(ORDER_ATTRIBUTE))
    {
        let order: Vec<String> = order.iter().map(|t| t.to_string()).collect();
        if order.len() == layers.len() && layers.iter().all(|l| order.contains(&l.name)) {
            layers.sort_by_key(|l| order.iter().position(|n| *n == l.name));
        }
    }
    let stack = ImageStack {
        width,
        height,
        layers,
    };
    stack
        .validate()
        .map_err(|e| bad(format!("inconsistent image: {e}")))?;
    Ok(stack)
}

//! Image outputs: a stack of named float layers and its writers/readers
//! (OpenEXR, ENVI, PNG quick-look), all written atomically.

/// One named float layer, row-major, `width × height` values.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Layer name (`apparent_temperature`, `band0_radiance`, ...).
    pub name: String,
    /// Row-major values, row 0 at the top.
    pub data: Vec<f32>,
}

/// A multi-layer float image.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImageStack {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// The layers, each `width * height` long.
    pub layers: Vec<Layer>,
}

impl ImageStack {
    /// The layer called `name`, if present.
    pub fn layer(&self, name: &str) -> Option<&Layer> {
        self.layers.iter().find(|l| l.name == name)
    }
}

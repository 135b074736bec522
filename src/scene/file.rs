//! The scene file format (JSON): serde types with a JSON Schema
//! (`irsig scene schema`, `scenes/scene.schema.json`).
//!
//! ```json
//! {
//!   "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
//!   "time": "2025-06-21T14:00:00-04:00",
//!   "weather": {"file": "weather.csv"},
//!   "materials": ["../materials.json"],
//!   "objects": [
//!     {"name": "house",
//!      "shapes": [
//!        {"box": {"size": [10, 8, 5]}, "part": "walls"},
//!        {"gable_roof": {"width": 10, "depth": 8, "height": 3}, "part": "roof",
//!         "transform": {"translate": [0, 0, 5]}}],
//!      "parts": [{"name": "walls", "material": "brick"},
//!                {"name": "roof", "material": "asphalt_shingle_roof"}],
//!      "instances": [{"translate": [20, 0, 0]}, {"translate": [40, 0, 0], "rotate_deg": [0, 0, 90]}]}
//!   ],
//!   "sensors": [{"type": "frame", "...": "..."}]
//! }
//! ```
//!
//! - **Objects → shapes → groups → parts → facets.** An object's shapes are
//!   merged into one mesh (stored once) and placed by each of its instances.
//!   Each shape yields triangles in face groups (`top`/`sides`/`bottom` of a
//!   box, OBJ `usemtl` names, glTF material names, heightmap classes); a shape's `part` puts all
//!   of its faces in one group of that name. A group maps to the object's
//!   part of the same name; else to an implicit part with the object's
//!   `material`; else to the database material of the same name.
//! - **Transforms**: `scale`, then `rotate_deg` (about x, then y, then z,
//!   degrees, right-handed), then `translate` (m); or a 4×4 `matrix`. A shape's transform places
//!   it in its object; an instance's transform places the object in the
//!   world, after the object's own `transform` (world = instance ∘ object).
//!   No `instances` = one instance at the object's `transform`.
//! - **Paths** are relative to the scene file.
//! - `sensors`, `atmosphere` and `render` are passed through as JSON objects
//!   for the stages that read them.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The top level of a scene file.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// JSON Schema reference for editors (ignored).
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Where the scene is.
    pub site: SiteSpec,
    /// Image time, RFC 3339 with offset (`2025-06-21T14:00:00-04:00`).
    pub time: String,
    /// Weather history.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weather: Option<WeatherSpec>,
    /// Material databases: irsig JSON or DIRSIG `.mat` files, merged in order
    /// (names must be unique across them).
    pub materials: Vec<String>,
    /// The objects.
    pub objects: Vec<ObjectSpec>,
    /// Sensors (frame cameras, line scanners), read by the sensor stage.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensors: Vec<Map<String, Value>>,
    /// Atmosphere settings, read by the atmosphere stage (an object, or a
    /// name such as `"none"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atmosphere: Option<Value>,
    /// Render settings, read by the renderer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub render: Option<Map<String, Value>>,
}

/// The site: geodetic position and the local time zone.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SiteSpec {
    /// Latitude, degrees north (−90..=90).
    pub latitude_deg: f64,
    /// Longitude, degrees east (−180..=180).
    pub longitude_deg: f64,
    /// Altitude above mean sea level, m.
    #[serde(default)]
    pub altitude_m: f64,
    /// Local standard/daylight time offset from UTC, hours (−12..=14).
    pub utc_offset_hours: f64,
}

/// A weather history reference.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WeatherSpec {
    /// The file (irsig CSV/JSON, EPW, TMY3, DIRSIG `.wth`), relative to the
    /// scene file; the format is recognised from its extension and content.
    pub file: String,
    /// Local date and time of the first row of a DIRSIG `.wth` file (which
    /// carries no date), RFC 3339.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<String>,
    /// Replace the year of every row of an EPW/TMY3 typical-year file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub year: Option<i32>,
}

/// An affine transform: scale, then rotate (x, y, z), then translate; or a 4×4 `matrix`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Translation, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
    /// Rotations about x, y, z, degrees, applied in that order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate_deg: Option<[f64; 3]>,
    /// Scale: one factor or one per axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Scale>,
    /// A 4×4 affine matrix instead of the three keys above: 16 numbers, row by row,
    /// last row `0, 0, 0, 1`; a point moves to M·[x, y, z, 1]ᵀ (translation in the
    /// fourth column, m), as DIRSIG's `.glist` `<matrix>` and `.odb` `INFO` give it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<Vec<f64>>,
}

/// Uniform or per-axis scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum Scale {
    /// The same factor on every axis.
    Uniform(f64),
    /// One factor per axis.
    PerAxis([f64; 3]),
}

/// An object: shapes merged into one mesh, parts, and placements.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Name (unique within the scene).
    pub name: String,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The shapes making up the object (object space).
    pub shapes: Vec<ShapeSpec>,
    /// Parts: material and overrides per face group.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<PartSpec>,
    /// Material for face groups without a part.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Object → world (before each instance's transform).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<TransformSpec>,
    /// Placements; absent = one, at `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instances: Option<Vec<TransformSpec>>,
    /// What the back faces of the object's parts touch (a building's
    /// interior), over their materials' own; a part's `back` or
    /// `exposed_area` overrides it ([`crate::material::BackSpec`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back: Option<crate::material::BackSpec>,
}

/// A part: a material and per-part overrides of its thermal inputs.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Face group name this part applies to.
    pub name: String,
    /// Material name (from the scene's material databases).
    pub material: String,
    /// Slab thickness override, m (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_m: Option<f64>,
    /// Self-generated power override, W/m² (e.g. a running engine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_power_w_m2: Option<f64>,
    /// Exposed-area override (−1..=1, see `irsig::material`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposed_area: Option<f64>,
    /// What the part's back face touches, over the object's and the
    /// material's ([`crate::material::BackSpec`]; not with `exposed_area`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back: Option<crate::material::BackSpec>,
    /// Fixed temperature, K: bypasses the thermal model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_temperature_k: Option<f64>,
    /// Default sky-view shape factor (0..=1) when not ray traced.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape_factor: Option<f64>,
}

/// One shape of an object: exactly one of the geometry keys (`obj`, `gltf`,
/// `box`, `plane`, `heightmap`, `cylinder`, `cone`, `sphere`, `gable_roof`).
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// Put every face of this shape in the group of this name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
    /// Shape → object space.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<TransformSpec>,
    /// A Wavefront OBJ file (relative to the scene file); groups are the
    /// `usemtl` names, else the `o`/`g` names.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obj: Option<String>,
    /// The up axis of the `obj` file: `"z"` (the default; irsig's east-north-up) or
    /// `"y"` (what most modelling tools export), turned to Z-up as glTF is:
    /// (x, y, z) → (x, −z, y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up_axis: Option<UpAxis>,
    /// The length unit of the `obj` file's coordinates: `"m"` (the default), `"cm"`,
    /// `"mm"`, `"ft"` or `"in"` (international foot and inch); applied before the
    /// shape's `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<LengthUnit>,
    /// Reverse the winding of every face of the `obj` or `gltf` file (its
    /// normals then face the other way): for a closed mesh exported with its
    /// normals facing inward, which `irsig scene check` warns about.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub flip_normals: bool,
    /// A glTF 2.0 file, `.gltf` or `.glb` (relative to the scene file): the
    /// triangles of the default scene's meshes placed by their nodes, Y-up
    /// turned to Z-up; groups are the glTF material names, else the mesh
    /// names.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gltf: Option<String>,
    /// A box standing on the origin.
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub box_: Option<BoxSpec>,
    /// A horizontal rectangle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<PlaneSpec>,
    /// A terrain grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heightmap: Option<HeightmapSpec>,
    /// A cylinder along z.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<CylinderSpec>,
    /// A cone along z.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cone: Option<ConeSpec>,
    /// A sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereSpec>,
    /// A gable roof.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gable_roof: Option<GableRoofSpec>,
}

/// The up axis of a mesh file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// Y up (turned to irsig's Z up).
    Y,
    /// Z up (as irsig).
    Z,
}

/// A length unit of mesh coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub enum LengthUnit {
    /// Metre.
    #[serde(rename = "m")]
    Metre,
    /// Centimetre.
    #[serde(rename = "cm")]
    Centimetre,
    /// Millimetre.
    #[serde(rename = "mm")]
    Millimetre,
    /// International foot, 0.3048 m.
    #[serde(rename = "ft")]
    Foot,
    /// International inch, 0.0254 m.
    #[serde(rename = "in")]
    Inch,
}

impl LengthUnit {
    /// Metres per unit (exact by definition).
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Metre => 1.0,
            LengthUnit::Centimetre => 0.01,
            LengthUnit::Millimetre => 0.001,
            LengthUnit::Foot => 0.3048,
            LengthUnit::Inch => 0.0254,
        }
    }
}

fn yes() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}

/// A box: x, y centred on the origin, z from 0 to `size[2]`. Groups `top`,
/// `sides`, `bottom`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Size along x, y, z, m.
    pub size: [f64; 3],
    /// Subdivide faces so no cell edge exceeds this, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_edge_m: Option<f64>,
    /// Include the bottom face (default true).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub bottom: bool,
}

/// A horizontal rectangle centred on the origin, facing +z. Group `surface`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    /// Size along x, y, m.
    pub size: [f64; 2],
    /// Subdivide so no cell edge exceeds this, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_edge_m: Option<f64>,
}

/// A cylinder of `radius` from z = 0 to `height`. Groups `side`, `top`,
/// `bottom`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    /// Radius, m.
    pub radius: f64,
    /// Height, m.
    pub height: f64,
    /// Segments around (default 16).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    /// Include the end caps (default true).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub caps: bool,
}

/// A cone: base `radius` at z = 0, apex at `height`. Groups `side`, `bottom`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConeSpec {
    /// Base radius, m.
    pub radius: f64,
    /// Height, m.
    pub height: f64,
    /// Segments around (default 16).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    /// Include the base (default true).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub cap: bool,
}

/// A UV sphere centred on the origin. Group `surface`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Radius, m.
    pub radius: f64,
    /// Segments around (default 16).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    /// Rings pole to pole (default 8).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rings: Option<usize>,
}

/// A gable roof over `width` (x) × `depth` (y) at z = 0, ridge along y.
/// Groups `roof`, `gables`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GableRoofSpec {
    /// Footprint width across the ridge, m.
    pub width: f64,
    /// Footprint depth along the ridge, m.
    pub depth: f64,
    /// Ridge height above the eaves, m.
    pub height: f64,
    /// Eave overhang, m (default 0).
    #[serde(default)]
    pub overhang: f64,
}

/// A terrain grid of `cells[0] × cells[1]` over `size` m, centred on the
/// origin. Heights (m) come from `heights` (rows of `cells[0] + 1` vertex
/// heights, first row = north edge), a `heights_csv` file in the same
/// layout, or the `function`; absent = flat. `classes` assigns each cell a
/// face group; default group `surface`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HeightmapSpec {
    /// Extent along x (east) and y (north), m.
    pub size: [f64; 2],
    /// Number of cells along x and y.
    pub cells: [usize; 2],
    /// Vertex heights, `cells[1] + 1` rows (north first) of `cells[0] + 1`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heights: Option<Vec<Vec<f64>>>,
    /// CSV file of vertex heights, same layout as `heights`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heights_csv: Option<String>,
    /// Height as a function of position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function: Option<HeightFunction>,
    /// Per-cell classes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub classes: Option<ClassMap>,
}

/// z(x, y) = base + Σ waves + Σ bowls, with world-space x, y of the grid.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HeightFunction {
    /// Constant height, m.
    #[serde(default)]
    pub base_m: f64,
    /// Linear slope: dz/dx, dz/dy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slope: Option<[f64; 2]>,
    /// Sinusoidal undulations.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub waves: Vec<Wave>,
    /// Smooth depressions (negative depth = mound).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bowls: Vec<Bowl>,
    /// Rectangles levelled to a fixed height (building pads), applied last.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flats: Vec<Flat>,
}

/// `amplitude · sin(2π (x cos d + y sin d) / wavelength + phase)`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Wave {
    /// Amplitude, m.
    pub amplitude_m: f64,
    /// Wavelength, m.
    pub wavelength_m: f64,
    /// Direction of travel, degrees counter-clockwise from +x (east).
    #[serde(default)]
    pub direction_deg: f64,
    /// Phase, radians.
    #[serde(default)]
    pub phase_rad: f64,
}

/// `−depth · (1 − (r/radius)²)²` inside `radius` of `center`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Bowl {
    /// Centre x, y, m.
    pub center: [f64; 2],
    /// Radius, m.
    pub radius_m: f64,
    /// Depth at the centre, m.
    pub depth_m: f64,
}

/// An axis-aligned rectangle set to `height_m`, blending over `blend_m`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Flat {
    /// Minimum x, y, m.
    pub min: [f64; 2],
    /// Maximum x, y, m.
    pub max: [f64; 2],
    /// Height, m.
    pub height_m: f64,
    /// Width of the transition to the surrounding terrain, m.
    #[serde(default)]
    pub blend_m: f64,
}

/// Per-cell classes: `rows` of one character per cell (first row = north),
/// each character a key of `legend` giving the face group.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ClassMap {
    /// Character → face group name.
    pub legend: std::collections::BTreeMap<String, String>,
    /// `cells[1]` strings of `cells[0]` characters.
    pub rows: Vec<String>,
}

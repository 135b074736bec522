//! Procedural test scenes: a terrain height-field grid with box buildings on
//! it, sized by a triangle-count knob (10 k … 10 M) and fully determined by a
//! seed. Used by `irsig bench trace` and the backend tests.
//!
//! The terrain is one mesh (two triangles per grid cell) over a square of
//! [`TerrainParams::size_m`] metres centred on the origin, with gentle hills
//! (a few random sinusoids, amplitude ≈ 2 % of the size). Buildings are
//! closed-top boxes (10 triangles, no floor) of random footprint, height and
//! heading, sunk 1 m into the ground. With [`TerrainParams::instanced`] the
//! box is stored once and placed by one instance per building (exercising
//! instancing); otherwise each building is its own mesh placed once.

use glam::{Affine3A, Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Instance, SceneGeometry, TriangleMesh};

/// Parameters of [`generate`].
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainParams {
    /// Target total triangle (facet) count; the result is within about 1 %
    /// of it (at least 2 terrain triangles are always produced).
    pub triangles: usize,
    /// Random seed: the same parameters give the same scene.
    pub seed: u64,
    /// Side of the square terrain, metres.
    pub size_m: f32,
    /// Number of buildings.
    pub buildings: usize,
    /// Place all buildings as instances of one stored box mesh.
    pub instanced: bool,
}

impl TerrainParams {
    /// About `triangles` facets: a 1 km terrain with one building per
    /// thousand triangles (10 … 3000), instanced.
    pub fn with_triangles(triangles: usize, seed: u64) -> Self {
        TerrainParams {
            triangles,
            seed,
            size_m: 1000.0,
            buildings: (triangles / 1000).clamp(10, 3000),
            instanced: true,
        }
    }

    /// Terrain height (metres) at world `(x, y)` for this seed.
    pub fn height_at(&self, x: f32, y: f32) -> f32 {
        Hills::new(self).height(x, y)
    }
}

/// Sum of a few random sinusoids.
struct Hills {
    waves: Vec<(f32, f32, f32, f32)>, // (kx, ky, phase, amplitude)
}

impl Hills {
    fn new(p: &TerrainParams) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(p.seed ^ 0x9E37_79B9_7F4A_7C15);
        let base = std::f32::consts::TAU / p.size_m.max(1e-3);
        let waves = (0..6)
            .map(|i| {
                let f = base * (1.0 + i as f32 * 1.7);
                let a: f32 = rng.random_range(0.0..std::f32::consts::TAU);
                (
                    f * a.cos(),
                    f * a.sin(),
                    rng.random_range(0.0..std::f32::consts::TAU),
                    0.02 * p.size_m / (1.0 + i as f32),
                )
            })
            .collect();
        Hills { waves }
    }

    fn height(&self, x: f32, y: f32) -> f32 {
        self.waves
            .iter()
            .map(|&(kx, ky, ph, a)| a * (kx * x + ky * y + ph).sin())
            .sum()
    }
}

/// A unit box `[-½, ½]² × [0, 1]` without its floor: 10 triangles, faces
/// counter-clockwise seen from outside (normals point out).
pub fn box_mesh() -> TriangleMesh {
    let positions = vec![
        Vec3::new(-0.5, -0.5, 0.0),
        Vec3::new(0.5, -0.5, 0.0),
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(-0.5, 0.5, 0.0),
        Vec3::new(-0.5, -0.5, 1.0),
        Vec3::new(0.5, -0.5, 1.0),
        Vec3::new(0.5, 0.5, 1.0),
        Vec3::new(-0.5, 0.5, 1.0),
    ];
    let indices = vec![
        [4, 5, 6],
        [4, 6, 7], // top (+z)
        [0, 1, 5],
        [0, 5, 4], // south (-y)
        [1, 2, 6],
        [1, 6, 5], // east (+x)
        [2, 3, 7],
        [2, 7, 6], // north (+y)
        [3, 0, 4],
        [3, 4, 7], // west (-x)
    ];
    TriangleMesh {
        name: "box".into(),
        positions,
        indices,
    }
}

/// Generates the scene. Instance 0 is the terrain (identity transform);
/// instances `1..=buildings` are the buildings.
pub fn generate(p: &TerrainParams) -> SceneGeometry {
    let hills = Hills::new(p);
    let box_tris = 10 * p.buildings;
    let terrain_tris = p.triangles.saturating_sub(box_tris).max(2);
    let n = ((terrain_tris as f64 / 2.0).sqrt().floor() as usize).max(1);
    let half = 0.5 * p.size_m;
    let step = p.size_m / n as f32;

    let mut terrain = TriangleMesh {
        name: "terrain".into(),
        positions: Vec::with_capacity((n + 1) * (n + 1)),
        indices: Vec::with_capacity(2 * n * n),
    };
    for j in 0..=n {
        for i in 0..=n {
            let x = -half + i as f32 * step;
            let y = -half + j as f32 * step;
            terrain.positions.push(Vec3::new(x, y, hills.height(x, y)));
        }
    }
    let row = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + row + 1, a + row);
            terrain.indices.push([a, b, c]);
            terrain.indices.push([a, c, d]);
        }
    }

    let mut geom = SceneGeometry::single(terrain);
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    let unit = box_mesh();
    if p.instanced && p.buildings > 0 {
        geom.meshes.push(unit.clone());
    }
    for _ in 0..p.buildings {
        let x = rng.random_range(-0.45..0.45) * p.size_m;
        let y = rng.random_range(-0.45..0.45) * p.size_m;
        let scale = Vec3::new(
            rng.random_range(8.0..30.0),
            rng.random_range(8.0..30.0),
            rng.random_range(5.0..40.0),
        );
        let heading = rng.random_range(0.0..std::f32::consts::TAU);
        let xf = Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_rotation_z(heading),
            Vec3::new(x, y, hills.height(x, y) - 1.0),
        );
        if p.instanced {
            geom.instances.push(Instance {
                mesh: 1,
                world_from_object: xf,
            });
        } else {
            geom.meshes.push(unit.clone());
            geom.instances.push(Instance {
                mesh: geom.meshes.len() - 1,
                world_from_object: xf,
            });
        }
    }
    geom
}

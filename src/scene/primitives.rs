//! Built-in primitives, triangulated in object space (metres, z up), each
//! triangle tagged with a face group (`"top"`, `"sides"`, …) that a scene
//! maps to a part. Front faces are counter-clockwise seen from outside.

use glam::Vec3;

/// Triangles with a face group per triangle.
#[derive(Debug, Clone, Default)]
pub struct GroupedMesh {
    /// Vertex positions, m.
    pub positions: Vec<Vec3>,
    /// Triangles (counter-clockwise from the front).
    pub indices: Vec<[u32; 3]>,
    /// Face group of each triangle: index into `groups`.
    pub group_of: Vec<u32>,
    /// Group names.
    pub groups: Vec<String>,
}

impl GroupedMesh {
    /// The index of group `name`, added if new.
    pub fn group(&mut self, name: &str) -> u32 {
        match self.groups.iter().position(|g| g == name) {
            Some(i) => i as u32,
            None => {
                self.groups.push(name.to_string());
                (self.groups.len() - 1) as u32
            }
        }
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    fn tri(&mut self, t: [u32; 3], g: u32) {
        self.indices.push(t);
        self.group_of.push(g);
    }

    /// A planar quad `o + s·u + t·v`, s,t ∈ [0,1], subdivided into
    /// `nu × nv` cells; front side along `u × v`.
    pub fn quad(&mut self, o: Vec3, u: Vec3, v: Vec3, nu: usize, nv: usize, group: &str) {
        let g = self.group(group);
        let (nu, nv) = (nu.max(1), nv.max(1));
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                self.vertex(o + u * (i as f32 / nu as f32) + v * (j as f32 / nv as f32));
            }
        }
        let w = (nu + 1) as u32;
        for j in 0..nv as u32 {
            for i in 0..nu as u32 {
                let a = base + j * w + i;
                self.tri([a, a + 1, a + w + 1], g);
                self.tri([a, a + w + 1, a + w], g);
            }
        }
    }

    /// Append another mesh.
    pub fn append(&mut self, other: &GroupedMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        let remap: Vec<u32> = other.groups.iter().map(|g| self.group(g)).collect();
        for (t, g) in other.indices.iter().zip(&other.group_of) {
            self.indices.push(t.map(|i| i + base));
            self.group_of.push(remap[*g as usize]);
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
}

fn cells(len: f32, max_edge: Option<f64>) -> usize {
    match max_edge {
        Some(e) if e > 0.0 => ((len as f64 / e).ceil() as usize).max(1),
        _ => 1,
    }
}

/// A box `size = [x, y, z]` standing on the origin: x, y centred, z from 0
/// to `size.z`. Groups `top`, `sides`, `bottom` (omitted when `!bottom`).
/// Faces are subdivided so no cell edge exceeds `max_edge_m`.
pub fn box_mesh(size: Vec3, max_edge_m: Option<f64>, bottom: bool) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let h = size * 0.5;
    let (x, y, z) = (Vec3::X * size.x, Vec3::Y * size.y, Vec3::Z * size.z);
    let (nx, ny, nz) = (
        cells(size.x, max_edge_m),
        cells(size.y, max_edge_m),
        cells(size.z, max_edge_m),
    );
    let c0 = Vec3::new(-h.x, -h.y, 0.0);
    m.quad(c0 + z, x, y, nx, ny, "top");
    // South (−y), east (+x), north (+y), west (−x): outward normals.
    m.quad(c0, x, z, nx, nz, "sides");
    m.quad(c0 + x, y, z, ny, nz, "sides");
    m.quad(c0 + x + y, -x, z, nx, nz, "sides");
    m.quad(c0 + y, -y, z, ny, nz, "sides");
    if bottom {
        m.quad(c0 + y, x, -y, nx, ny, "bottom");
    }
    m
}

/// A horizontal rectangle `size = [x, y]` centred on the origin at z = 0,
/// facing +z. Group `surface`.
pub fn plane_mesh(size: [f32; 2], max_edge_m: Option<f64>) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    m.quad(
        Vec3::new(-size[0] / 2.0, -size[1] / 2.0, 0.0),
        Vec3::X * size[0],
        Vec3::Y * size[1],
        cells(size[0], max_edge_m),
        cells(size[1], max_edge_m),
        "surface",
    );
    m
}

/// A cylinder of `radius` along z from 0 to `height`, `segments` around.
/// Groups `side`, `top`, `bottom` (caps only when `caps`).
pub fn cylinder_mesh(radius: f32, height: f32, segments: usize, caps: bool) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let n = segments.max(3);
    let g = m.group("side");
    let ring = |k: usize| {
        let a = std::f32::consts::TAU * k as f32 / n as f32;
        Vec3::new(radius * a.cos(), radius * a.sin(), 0.0)
    };
    let base = m.positions.len() as u32;
    for k in 0..n {
        m.vertex(ring(k));
        m.vertex(ring(k) + Vec3::Z * height);
    }
    for k in 0..n as u32 {
        let a = base + 2 * k;
        let b = base + 2 * ((k + 1) % n as u32);
        m.tri([a, b, b + 1], g);
        m.tri([a, b + 1, a + 1], g);
    }
    if caps {
        let gt = m.group("top");
        let c = m.vertex(Vec3::Z * height);
        for k in 0..n as u32 {
            m.tri(
                [c, base + 2 * k + 1, base + 2 * ((k + 1) % n as u32) + 1],
                gt,
            );
        }
        let gb = m.group("bottom");
        let c = m.vertex(Vec3::ZERO);
        for k in 0..n as u32 {
            m.tri([c, base + 2 * ((k + 1) % n as u32), base + 2 * k], gb);
        }
    }
    m
}

/// A cone of base `radius` at z = 0, apex at `height`. Groups `side`,
/// `bottom` (when `cap`).
pub fn cone_mesh(radius: f32, height: f32, segments: usize, cap: bool) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let n = segments.max(3) as u32;
    let g = m.group("side");
    let base = m.positions.len() as u32;
    for k in 0..n {
        let a = std::f32::consts::TAU * k as f32 / n as f32;
        m.vertex(Vec3::new(radius * a.cos(), radius * a.sin(), 0.0));
    }
    let apex = m.vertex(Vec3::Z * height);
    for k in 0..n {
        m.tri([base + k, base + (k + 1) % n, apex], g);
    }
    if cap {
        let gb = m.group("bottom");
        let c = m.vertex(Vec3::ZERO);
        for k in 0..n {
            m.tri([c, base + (k + 1) % n, base + k], gb);
        }
    }
    m
}

/// A UV sphere of `radius` centred on the origin: `segments` around,
/// `rings` from pole to pole. Group `surface`.
pub fn sphere_mesh(radius: f32, segments: usize, rings: usize) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let g = m.group("surface");
    let (n, r) = (segments.max(3) as u32, rings.max(2) as u32);
    let south = m.vertex(-Vec3::Z * radius);
    let base = m.positions.len() as u32;
    for j in 1..r {
        let th = std::f32::consts::PI * j as f32 / r as f32;
        for k in 0..n {
            let ph = std::f32::consts::TAU * k as f32 / n as f32;
            m.vertex(radius * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos()));
        }
    }
    let north = m.vertex(Vec3::Z * radius);
    let at = |j: u32, k: u32| base + (j - 1) * n + k % n;
    for k in 0..n {
        m.tri([south, at(1, k + 1), at(1, k)], g);
        m.tri([north, at(r - 1, k), at(r - 1, k + 1)], g);
    }
    for j in 1..r - 1 {
        for k in 0..n {
            m.tri([at(j, k), at(j, k + 1), at(j + 1, k + 1)], g);
            m.tri([at(j, k), at(j + 1, k + 1), at(j + 1, k)], g);
        }
    }
    m
}

/// A gable roof over a `width` (x) × `depth` (y) footprint at z = 0, ridge
/// along y at height `height`, eaves overhanging by `overhang`. Groups
/// `roof` (two slopes) and `gables` (two end triangles).
pub fn gable_roof_mesh(width: f32, depth: f32, height: f32, overhang: f32) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let (hw, hd) = (width / 2.0, depth / 2.0 + overhang);
    // Extend the slope outward by the overhang, dropping accordingly.
    let drop = height * overhang / hw.max(1e-6);
    let ew = hw + overhang;
    let ridge0 = Vec3::new(0.0, -hd, height);
    let ridge = Vec3::Y * 2.0 * hd;
    // East slope: eave (x = +ew) to ridge; normal points +x,+z.
    m.quad(
        Vec3::new(ew, -hd, -drop),
        ridge,
        ridge0 - Vec3::new(ew, -hd, -drop),
        1,
        1,
        "roof",
    );
    // West slope.
    m.quad(
        Vec3::new(-ew, -hd, -drop),
        ridge0 - Vec3::new(-ew, -hd, -drop),
        ridge,
        1,
        1,
        "roof",
    );
    let gg = m.group("gables");
    let (yd, yn) = (-depth / 2.0, depth / 2.0);
    let a = m.vertex(Vec3::new(-hw, yd, 0.0));
    let b = m.vertex(Vec3::new(hw, yd, 0.0));
    let c = m.vertex(Vec3::new(0.0, yd, height));
    m.tri([a, b, c], gg);
    let a = m.vertex(Vec3::new(hw, yn, 0.0));
    let b = m.vertex(Vec3::new(-hw, yn, 0.0));
    let c = m.vertex(Vec3::new(0.0, yn, height));
    m.tri([a, b, c], gg);
    m
}

/// A terrain grid of `nx × ny` cells over `size = [x, y]` m centred on the
/// origin, with vertex heights `z(i, j)` (i east, j north, vertex indices),
/// and each cell's group from `cell_group(i, j)` (a group name).
pub fn heightmap_mesh(
    size: [f32; 2],
    nx: usize,
    ny: usize,
    z: impl Fn(usize, usize) -> f32,
    mut cell_group: impl FnMut(usize, usize) -> String,
) -> GroupedMesh {
    let mut m = GroupedMesh::default();
    let (dx, dy) = (size[0] / nx as f32, size[1] / ny as f32);
    let (x0, y0) = (-size[0] / 2.0, -size[1] / 2.0);
    for j in 0..=ny {
        for i in 0..=nx {
            m.vertex(Vec3::new(x0 + i as f32 * dx, y0 + j as f32 * dy, z(i, j)));
        }
    }
    let w = (nx + 1) as u32;
    m.indices.reserve(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let g = m.group(&cell_group(i, j));
            let a = j as u32 * w + i as u32;
            // Split along the diagonal that alternates, to avoid a bias.
            if (i + j) % 2 == 0 {
                m.tri([a, a + 1, a + w + 1], g);
                m.tri([a, a + w + 1, a + w], g);
            } else {
                m.tri([a, a + 1, a + w], g);
                m.tri([a + 1, a + w + 1, a + w], g);
            }
        }
    }
    m
}

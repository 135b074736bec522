//! Deterministic sample patterns: points on a facet, directions over its
//! hemisphere, and the per-facet pseudo-random stream that jitters them.
//!
//! Owns the patterns (in a facet's local frame, `z` along the normal) and
//! their weights. Takes sample counts, grid steps and a jitter source; gives
//! barycentric points and [`HemiSample`]s. Must not know the scene, the
//! tracer or what the directions are used for (that is `exposure::sky`).

use glam::Vec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Barycentric coordinates `(b1, b2)` (weights of vertices 1 and 2) of the
/// `n²` stratified sample points of a triangle: the centroids of the `n²`
/// congruent sub-triangles obtained by cutting every edge into `n` equal
/// parts. Each point stands for the same area `A/n²`; all lie strictly
/// inside the triangle. `n = 1` gives the centroid.
pub fn triangle_strata(n: u32) -> Vec<(f32, f32)> {
    let n = n.max(1);
    let nf = n as f32;
    let mut out = Vec::with_capacity((n * n) as usize);
    for i in 0..n {
        for j in 0..n - i {
            // "Upward" sub-triangle (i,j),(i+1,j),(i,j+1).
            out.push(((i as f32 + 1.0 / 3.0) / nf, (j as f32 + 1.0 / 3.0) / nf));
            // "Downward" sub-triangle (i+1,j),(i,j+1),(i+1,j+1), where it exists.
            if i + j + 1 < n {
                out.push(((i as f32 + 2.0 / 3.0) / nf, (j as f32 + 2.0 / 3.0) / nf));
            }
        }
    }
    out
}

/// An orthonormal basis `(t, b)` completing the unit vector `n` to a
/// right-handed frame `(t, b, n)`; continuous except at `n.z = -1`.
/// Duff et al. (2017), "Building an Orthonormal Basis, Revisited",
/// JCGT 6(1), Listing 3.
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// One hemisphere direction in a facet's local frame (`z` along the normal)
/// with its weight in the cosine-weighted (view-factor) measure. Weights of a
/// pattern sum to 1. Patterns are ordered so that samples `2k` and `2k+1`
/// have equal weights and neighbouring cells (paired for the error estimate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HemiSample {
    /// Unit direction, local frame (`z ≥ 0`).
    pub dir: Vec3,
    /// Weight in `∫ cos θ dω / π`.
    pub weight: f32,
}

/// DIRSIG's fixed hemisphere grid: zenith bands of `dz` degrees × azimuth
/// sectors of `da` degrees, one ray per cell, through the cell's
/// cosine-weighted median zenith angle (`sin²θ = (sin²θ₁ + sin²θ₂)/2`) and
/// centre azimuth. Cell weight = `(sin²θ₂ − sin²θ₁)/2 · Δφ/π`, the cell's
/// exact share of `∫cosθ dω/π` (Modest, *Radiative Heat Transfer*, 3rd ed.,
/// eq. 4.11). Cells are ordered band by band, azimuth fastest, so cells
/// `2k` and `2k+1` are azimuth neighbours in the same band (when the number
/// of sectors is even).
pub fn dirsig_grid(dz_deg: f32, da_deg: f32) -> Vec<HemiSample> {
    let nz = (90.0 / dz_deg).round().max(1.0) as u32;
    let na = (360.0 / da_deg).round().max(1.0) as u32;
    let dz = std::f64::consts::FRAC_PI_2 / nz as f64;
    let da = std::f64::consts::TAU / na as f64;
    let mut out = Vec::with_capacity((nz * na) as usize);
    for i in 0..nz {
        let (s1, s2) = ((i as f64 * dz).sin(), ((i + 1) as f64 * dz).sin());
        let w = 0.5 * (s2 * s2 - s1 * s1) * da / std::f64::consts::PI;
        let sin_t = (0.5 * (s1 * s1 + s2 * s2)).sqrt();
        let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
        for j in 0..na {
            let phi = (j as f64 + 0.5) * da;
            out.push(HemiSample {
                dir: Vec3::new(
                    (sin_t * phi.cos()) as f32,
                    (sin_t * phi.sin()) as f32,
                    cos_t as f32,
                ),
                weight: w as f32,
            });
        }
    }
    out
}

/// Side of the stratification grid used for `samples` stratified
/// cosine-weighted directions: `ceil(√samples)` rounded up to even (so that
/// strata pair up for the variance estimate), at least 2.
pub fn stratified_side(samples: u32) -> u32 {
    let m = (samples.max(1) as f64).sqrt().ceil() as u32;
    (m + (m & 1)).max(2)
}

/// Stratified cosine-weighted hemisphere directions (`m × m` strata of the
/// unit square, one jittered sample each, `m` = [`stratified_side`]), mapped
/// by `θ = acos √(1−u₁)`, `φ = 2π u₂` so that equal areas of the square are
/// equal shares of `∫cosθ dω/π` (Pharr, Jakob & Humphreys, *PBR* 4th ed.,
/// §A.5.3). Samples `2k`, `2k+1` are neighbouring strata. `rng` yields the
/// jitter in `[0, 1)`.
pub fn stratified_cosine(samples: u32, mut rng: impl FnMut() -> f32) -> Vec<HemiSample> {
    let m = stratified_side(samples);
    let jitter: Vec<(f32, f32)> = (0..m * m).map(|_| (rng(), rng())).collect();
    rotated_cosine(m, &jitter, (0.0, 0.0))
}

/// The `m × m` stratified cosine-weighted directions of
/// [`stratified_cosine`] with the sample of stratum `k` (row-major, zenith
/// rows) at offset `frac(jitter[k] + shift)` inside it: a fixed jittered
/// pattern under a Cranley–Patterson rotation by `shift` (Cranley &
/// Patterson 1976, SIAM J. Numer. Anal. 13(6):904–914). For any fixed
/// `jitter` and a shift uniform on `[0, 1)²` every stratum's sample is
/// uniform in it, so the estimate is unbiased; with the shifts of
/// neighbouring facets taken from a low-discrepancy sequence
/// ([`r2_shift`]) their errors partly cancel, so that an area's mean
/// converges faster than its facets' independent errors would.
pub fn rotated_cosine(m: u32, jitter: &[(f32, f32)], shift: (f32, f32)) -> Vec<HemiSample> {
    let mut out = Vec::with_capacity((m * m) as usize);
    rotated_cosine_into(m, jitter, shift, &mut out);
    out
}

/// [`rotated_cosine`] appended to `out` (a buffer reused from face to face).
pub fn rotated_cosine_into(
    m: u32,
    jitter: &[(f32, f32)],
    shift: (f32, f32),
    out: &mut Vec<HemiSample>,
) {
    let w = 1.0 / (m * m) as f32;
    for i in 0..m {
        for j in 0..m {
            let (a, b) = jitter[(i * m + j) as usize];
            let u1 = ((i as f32 + (a + shift.0).fract()) / m as f32).min(1.0 - f32::EPSILON);
            let u2 = (j as f32 + (b + shift.1).fract()) / m as f32;
            let sin_t = u1.sqrt();
            let cos_t = (1.0 - u1).sqrt();
            let phi = std::f32::consts::TAU * u2;
            out.push(HemiSample {
                dir: Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t),
                weight: w,
            });
        }
    }
}

/// Point `index` of the R2 sequence, the two-dimensional Kronecker sequence
/// of the plastic number `g` (`g³ = g + 1`): `frac(0.5 + index·(1/g, 1/g²))`
/// (M. Roberts, "The unreasonable effectiveness of quasirandom sequences",
/// 2018). Any run of consecutive indices covers `[0, 1)²` evenly; used as
/// the per-facet rotation of the hemisphere pattern ([`rotated_cosine`]).
pub fn r2_shift(index: u64) -> (f32, f32) {
    const G: f64 = 1.324_717_957_244_746;
    let (a1, a2) = (1.0 / G, 1.0 / (G * G));
    // Reduce the index first so that f64 keeps the fractional part.
    let k = (index % (1 << 40)) as f64;
    ((0.5 + k * a1).fract() as f32, (0.5 + k * a2).fract() as f32)
}

/// The jitter stream of one facet face for [`stratified_cosine`]: ChaCha8
/// (the generator of every seeded draw in irsig) with the 32-byte key holding
/// `seed` little-endian followed by zeros, on stream `key` (the facet face).
/// Each face's jitter depends only on `(seed, key)`, never on threads or on
/// the order faces are visited.
pub fn jitter_rng(seed: u64, key: u64) -> ChaCha8Rng {
    let mut k = [0u8; 32];
    k[..8].copy_from_slice(&seed.to_le_bytes());
    let mut rng = ChaCha8Rng::from_seed(k);
    rng.set_stream(key);
    rng
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;

    #[test]
    fn jitter_depends_only_on_seed_and_key() {
        let draw = |seed, key| {
            let mut r = jitter_rng(seed, key);
            (0..8).map(|_| r.random::<f32>()).collect::<Vec<_>>()
        };
        assert_eq!(draw(7, 3), draw(7, 3));
        assert_ne!(draw(7, 3), draw(7, 4));
        assert_ne!(draw(7, 3), draw(8, 3));
        assert!(draw(1, 2).iter().all(|u| (0.0..1.0).contains(u)));
        // Stratified directions stay unit, upward and equally weighted.
        let mut r = jitter_rng(1, 2);
        let p = stratified_cosine(16, || r.random::<f32>());
        assert_eq!(p.len(), 16);
        assert!(
            p.iter()
                .all(|s| (s.dir.length() - 1.0).abs() < 1e-5 && s.dir.z >= 0.0)
        );
        assert!((p.iter().map(|s| s.weight).sum::<f32>() - 1.0).abs() < 1e-6);
    }
}

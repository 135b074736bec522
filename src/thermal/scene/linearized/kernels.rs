//! The arithmetic kernels of the linearised solve: dot products and
//! Green's-matrix products in `f32`, in blocks that stay in registers
//! (vectorisable), and the emission curvature of the second order.
//!
//! Owns nothing but arithmetic on slices; knows no facets, references or
//! passes.
//!
//! The products run compiled for the widest vector instructions the CPU
//! has ([`crate::simd::vectorized`]); each lane does the same operations in
//! the same order on every path, so the results do not depend on it.

/// `y += Σ x_k G[:, k]` over the listed columns `(k, x_k)` of a
/// column-major `G` (`g[k·R + t]`, `R = y.len()`), in blocks of `y` that
/// stay in registers.
#[inline]
pub(super) fn matvec_cols(g: &[f32], cols: &[(u32, f32)], y: &mut [f32]) {
    crate::simd::vectorized(MatvecCols { g, cols, y })
}

crate::simd::simd_kernel!(MatvecCols<'a> { g: &'a [f32], cols: &'a [(u32, f32)], y: &'a mut [f32] } -> () => matvec_cols_impl);

#[inline(always)]
fn matvec_cols_impl(g: &[f32], cols: &[(u32, f32)], y: &mut [f32]) {
    let r = y.len();
    let mut t0 = 0;
    while t0 + 32 <= r {
        block::<32>(g, cols, r, t0, &mut y[t0..t0 + 32]);
        t0 += 32;
    }
    while t0 + 8 <= r {
        block::<8>(g, cols, r, t0, &mut y[t0..t0 + 8]);
        t0 += 8;
    }
    if t0 == r {
        return;
    }
    // The last rows: eight lanes read into the matrix's padding
    // ([`GREEN_PADDING`]) where it has it, the extra lanes dropped.
    let last = cols.iter().map(|&(k, _)| k as usize).max().unwrap_or(0);
    if last * r + t0 + 8 <= g.len() {
        let mut acc = [0.0f32; 8];
        acc[..r - t0].copy_from_slice(&y[t0..]);
        for &(k, x) in cols {
            let col = &g[k as usize * r + t0..k as usize * r + t0 + 8];
            for i in 0..8 {
                acc[i] += x * col[i];
            }
        }
        y[t0..].copy_from_slice(&acc[..r - t0]);
    } else {
        for (i, v) in y[t0..].iter_mut().enumerate() {
            let t = t0 + i;
            for &(k, x) in cols {
                *v += x * g[k as usize * r + t];
            }
        }
    }
}

/// Rows `t0..t0 + B` of [`matvec_cols`] (`y` those rows), accumulated in
/// registers.
#[inline(always)]
fn block<const B: usize>(g: &[f32], cols: &[(u32, f32)], r: usize, t0: usize, y: &mut [f32]) {
    let mut acc = [0.0f32; B];
    acc.copy_from_slice(y);
    for &(k, x) in cols {
        let col = &g[k as usize * r + t0..k as usize * r + t0 + B];
        for i in 0..B {
            acc[i] += x * col[i];
        }
    }
    y.copy_from_slice(&acc);
}

/// Zeros after the last column of a column-major Green's matrix, so that
/// [`matvec_cols`] reads its last rows eight lanes wide.
pub(super) const GREEN_PADDING: usize = 8;

/// `y[t] += Σ_j c_j·h_j[t]` over `items` `(j, c_j)` in order, `h_j` the
/// `j`-th history of `hist` (`R = y.len()` records each), or `y[t] += c_j`
/// where `j` is `u32::MAX`; in blocks of `y` that stay in registers.
#[inline]
pub(super) fn accumulate_rows(hist: &[f32], items: &[(u32, f32)], y: &mut [f32]) {
    crate::simd::vectorized(AccumulateRows { hist, items, y })
}

crate::simd::simd_kernel!(AccumulateRows<'a> { hist: &'a [f32], items: &'a [(u32, f32)], y: &'a mut [f32] } -> () => accumulate_rows_impl);

#[inline(always)]
fn accumulate_rows_impl(hist: &[f32], items: &[(u32, f32)], y: &mut [f32]) {
    const B: usize = 32;
    let r = y.len();
    let mut blocks = y.chunks_exact_mut(B);
    for (b, yb) in (&mut blocks).enumerate() {
        let t0 = b * B;
        let mut acc = [0.0f32; B];
        acc.copy_from_slice(yb);
        for &(j, c) in items {
            if j == u32::MAX {
                acc.iter_mut().for_each(|a| *a += c);
            } else {
                let h = &hist[j as usize * r + t0..j as usize * r + t0 + B];
                for i in 0..B {
                    acc[i] += c * h[i];
                }
            }
        }
        yb.copy_from_slice(&acc);
    }
    let tail = blocks.into_remainder();
    let t0 = r - tail.len();
    for (i, v) in tail.iter_mut().enumerate() {
        let mut a = *v;
        for &(j, c) in items {
            a += if j == u32::MAX {
                c
            } else {
                c * hist[j as usize * r + t0 + i]
            };
        }
        *v = a;
    }
}

/// The non-zero entries `(k, c·v_k)` of `c·v` into `out`.
#[inline]
pub(super) fn columns(v: impl Iterator<Item = f32>, c: f32, out: &mut Vec<(u32, f32)>) {
    out.clear();
    out.extend(
        v.enumerate()
            .filter(|&(_, x)| x != 0.0)
            .map(|(k, x)| (k as u32, c * x)),
    );
}

/// `a · b`, in eight lanes (vectorisable).
#[inline]
pub(super) fn dot(a: &[f32], b: &[f32]) -> f32 {
    crate::simd::vectorized(Dot { a, b })
}

crate::simd::simd_kernel!(Dot<'a> { a: &'a [f32], b: &'a [f32] } -> f32 => dot_impl);

#[inline(always)]
fn dot_impl(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    let tail: f32 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    acc.iter().sum::<f32>() + tail
}

/// `−R Δ²(6T² + 4TΔ + Δ²)`, the emission curvature (f32).
#[inline]
pub(super) fn curvature(r: f32, t: f32, d: f32) -> f32 {
    -r * d * d * (6.0 * t * t + 4.0 * t * d + d * d)
}

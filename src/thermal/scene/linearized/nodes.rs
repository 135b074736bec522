//! The curvature nodes of the second order: the records at which the
//! linearised solve's last pass evaluates a facet's first-order change and
//! the curvature it drives, with the curvature linear in time between them.
//!
//! # Why
//! The second-order correction of an image record `t` is
//! `Σ_k G[t][k] r_k` with `r_k = r(Δ_k)` the curvature at record `k` of the
//! first-order change `Δ = G ΔS` ([`super::kernels::curvature`],
//! [`crate::thermal::linear::latent_curvature`]). Evaluated at every record
//! it needs the facet's whole first-order history: `R × columns`
//! multiply-adds per node, most of the last pass. But `G[t][k]` is large
//! only for the records just before `t` (the surface's own time constant)
//! and small and slowly varying further back, where `r` is itself small
//! (second order in `Δ`). So `r` is taken at every record of the last
//! [`FULL_RECORDS`] before (and after) each image record and at every
//! `stride`-th record elsewhere, linear in between (hat functions `φ_n`):
//!
//! `Σ_k G[t][k] r_k ≈ Σ_n w_n r(Δ_n)`, `w_n = Σ_k G[t][k] φ_n(k)`,
//!
//! with `Δ_n` the rows `n` of `G ΔS` only. The first-order part `G[t]·ΔS`
//! stays exact. With `stride` 1 every record is a node and the sum is the
//! full one (the reference path, `passes::PassPlan::second_order_image`).
//!
//! # What it owns, takes and gives
//! Owns the choice of nodes and the hat weights; takes the record count and
//! the image records; knows no facets or Green's matrices.

/// Records before and after each image record that are all nodes.
pub(super) const FULL_RECORDS: usize = 8;

/// The curvature nodes of a history (module docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct CurvatureNodes {
    /// The node records, ascending; the first is 0 and the last `R − 1`.
    pub records: Vec<usize>,
    /// Per record `k`: `(j, λ)`, `k` lies between nodes `j` and `j + 1`
    /// with weight `1 − λ` on node `j` and `λ` on node `j + 1` (`λ = 0` on
    /// a node).
    pub hat: Vec<(u32, f64)>,
}

impl CurvatureNodes {
    /// The nodes of a history of `records` records with the given image
    /// records: every `stride`-th record, the first and last, every record
    /// within [`FULL_RECORDS`] of an image record, and the next nearest to
    /// one up to a multiple of eight nodes.
    pub fn new(records: usize, image_records: &[usize], stride: usize) -> CurvatureNodes {
        let stride = stride.max(1);
        let near = |k: usize| image_records.iter().map(|&t| k.abs_diff(t)).min();
        let mut nodes: Vec<usize> = (0..records)
            .filter(|&k| {
                k % stride == 0 || k + 1 == records || near(k).is_some_and(|d| d <= FULL_RECORDS)
            })
            .collect();
        // A multiple of eight nodes (the products' vector width): the
        // records next nearest to an image record join.
        let mut rest: Vec<usize> = (0..records).filter(|k| !nodes.contains(k)).collect();
        rest.sort_by_key(|&k| (near(k).unwrap_or(usize::MAX), usize::MAX - k));
        let extra = (8 - nodes.len() % 8) % 8;
        nodes.extend(rest.into_iter().take(extra));
        nodes.sort_unstable();
        let mut hat = Vec::with_capacity(records);
        let mut j = 0usize;
        for k in 0..records {
            while j + 1 < nodes.len() && nodes[j + 1] <= k {
                j += 1;
            }
            let lambda = if nodes[j] == k {
                0.0
            } else {
                (k - nodes[j]) as f64 / (nodes[j + 1] - nodes[j]) as f64
            };
            hat.push((j as u32, lambda));
        }
        CurvatureNodes {
            records: nodes,
            hat,
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// `w_n = Σ_k row[k] φ_n(k)`: the weights on the nodes of a row over
    /// the records (module docs).
    pub fn weights(&self, row: &[f64]) -> Vec<f64> {
        let mut w = vec![0.0; self.len()];
        for (&x, &(j, l)) in row.iter().zip(&self.hat) {
            w[j as usize] += (1.0 - l) * x;
            if l != 0.0 {
                w[j as usize + 1] += l * x;
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_cover_the_ends_the_stride_and_the_image_neighbourhood() {
        let n = CurvatureNodes::new(97, &[96], 4);
        assert_eq!(n.records[0], 0);
        assert_eq!(*n.records.last().unwrap(), 96);
        assert!((88..=96).all(|k| n.records.contains(&k)));
        // 0, 4, …, 84 and 88–96 are 31 nodes; 87 makes 32.
        assert!(n.records.iter().all(|&k| k % 4 == 0 || k >= 87));
        assert_eq!(n.len(), 32);
        assert!(n.records.windows(2).all(|w| w[0] < w[1]));
        // Every record is a node with stride 1.
        assert_eq!(
            CurvatureNodes::new(10, &[3], 1).records,
            (0..10).collect::<Vec<_>>()
        );
        assert_eq!(CurvatureNodes::new(50, &[20, 49], 6).len() % 8, 0);
    }

    #[test]
    fn hat_weights_reproduce_linear_functions_exactly() {
        // Σ_n w_n r(n) = Σ_k row[k] r(k) when r is linear in the record:
        // the hat functions interpolate linear functions exactly and sum
        // to one.
        let n = CurvatureNodes::new(50, &[20, 49], 6);
        let row: Vec<f64> = (0..50)
            .map(|k| ((k * 7919) % 13) as f64 / 13.0 - 0.3)
            .collect();
        let r = |k: usize| 0.25 * k as f64 - 3.0;
        let w = n.weights(&row);
        let by_nodes: f64 = w.iter().zip(&n.records).map(|(w, &k)| w * r(k)).sum();
        let full: f64 = row.iter().enumerate().map(|(k, x)| x * r(k)).sum();
        assert!((by_nodes - full).abs() < 1e-12, "{by_nodes} vs {full}");
        let ones: f64 = w.iter().sum();
        assert!((ones - row.iter().sum::<f64>()).abs() < 1e-12);
    }
}

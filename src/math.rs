//! Piecewise-linear table lookup: the one interpolator of irsig's tables
//! (emissivity and response spectra, atmosphere tables, weather records,
//! calibration series).
//!
//! Owns: bracketing a value in a sorted abscissa ([`bracket`]), the scalar
//! [`lerp`] `a + t·(b − a)`, and their composition [`interp1d`], which
//! clamps to the end values outside the table. Takes plain slices; gives
//! `f64`. Must not know what the tables hold or their units; domain
//! interpolation (whole weather records, spectra) builds on [`lerp`] and
//! [`bracket`] in its own module.

/// `a + t·(b − a)`: exact at `t = 0`, and constant when `a == b`.
#[inline]
pub fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + t * (b - a)
}

/// Bracket `x` in the increasing `xs`: `(i, j, t)` such that the value at
/// `x` is `lerp(v[i], v[j], t)`. Outside the table (and for one point)
/// `i == j` names the end point and `t = 0`; inside, `j = i + 1` and
/// `t = (x − xs[i]) / (xs[j] − xs[i])` in `[0, 1)`. At an abscissa
/// repeated inside the table, the last of the repeats is used. A NaN `x` gives a NaN `t`.
/// `xs` must not be empty.
#[inline]
pub fn bracket(xs: &[f64], x: f64) -> (usize, usize, f64) {
    let n = xs.len();
    if n == 1 || x <= xs[0] {
        return (0, 0, 0.0);
    }
    if x >= xs[n - 1] {
        return (n - 1, n - 1, 0.0);
    }
    let j = xs.partition_point(|&v| v <= x).clamp(1, n - 1);
    (j - 1, j, (x - xs[j - 1]) / (xs[j] - xs[j - 1]))
}

/// Linear interpolation of the table `(xs, ys)` at `x` (`xs` increasing),
/// clamped to `ys[0]` below `xs[0]` and to the last value above the last
/// abscissa; one point gives its value everywhere, an empty table NaN.
#[inline]
pub fn interp1d(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    match bracket(xs, x) {
        (i, j, _) if i == j => ys[i],
        (i, j, t) => lerp(ys[i], ys[j], t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_clamps() {
        let (xs, ys) = ([1.0, 2.0, 4.0], [10.0, 20.0, 0.0]);
        assert_eq!(interp1d(&xs, &ys, 1.5), 15.0);
        assert_eq!(interp1d(&xs, &ys, 3.0), 10.0);
        assert_eq!(interp1d(&xs, &ys, 2.0), 20.0);
        assert_eq!(interp1d(&xs, &ys, 0.0), 10.0);
        assert_eq!(interp1d(&xs, &ys, 1.0), 10.0);
        assert_eq!(interp1d(&xs, &ys, 4.0), 0.0);
        assert_eq!(interp1d(&xs, &ys, 9.0), 0.0);
        assert!(interp1d(&xs, &ys, f64::NAN).is_nan());
    }

    #[test]
    fn degenerate_tables() {
        assert!(interp1d(&[], &[], 1.0).is_nan());
        assert_eq!(interp1d(&[3.0], &[7.0], -1.0), 7.0);
        assert_eq!(interp1d(&[3.0], &[7.0], 9.0), 7.0);
        // Repeated abscissa: a step; at the step the later value holds.
        let (xs, ys) = ([0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 5.0, 5.0]);
        assert_eq!(interp1d(&xs, &ys, 1.0), 5.0);
        assert_eq!(interp1d(&xs, &ys, 0.5), 0.5);
    }

    #[test]
    fn bracket_names_the_segment() {
        let xs = [0.0, 1.0, 3.0];
        assert_eq!(bracket(&xs, -1.0), (0, 0, 0.0));
        assert_eq!(bracket(&xs, 2.0), (1, 2, 0.5));
        assert_eq!(bracket(&xs, 3.0), (2, 2, 0.0));
        assert_eq!(lerp(2.0, 2.0, 0.3), 2.0);
        assert_eq!(lerp(-1.0, 3.0, 0.25), 0.0);
    }

    /// The weather lerp was written `a + (b − a)·w`: same bits.
    #[test]
    fn lerp_matches_the_commuted_form() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
        let mut u = || rng.random::<f64>();
        for _ in 0..1000 {
            let (a, b, w) = (300.0 * u() - 100.0, 1e5 * u(), u());
            assert_eq!(lerp(a, b, w).to_bits(), (a + (b - a) * w).to_bits());
        }
    }
}

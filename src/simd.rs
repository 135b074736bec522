//! Runtime choice of the vector instructions of the hot arithmetic loops.
//!
//! irsig's release build targets the x86-64 baseline (SSE2: 4 lanes of
//! `f32`), so that one binary runs on any x86-64 CPU. The few loops that
//! dominate the scene thermal stage (Green's-matrix products, background
//! and reflected-shortwave sums, the tangent-linear model's steps and
//! folds in `f64`) run through [`vectorized`], which compiles them a second
//! time for AVX2 + FMA (8 lanes of `f32`, 4 of `f64`) and picks that copy
//! when the CPU has it — the runtime dispatch of the `pulp` crate, so no
//! `unsafe` here.
//!
//! Owns nothing but the dispatch. The loops must keep each lane's
//! operations in the same order on every path (no reassociation across
//! lanes, no fused multiply-add by hand), so the results are the same bit
//! for bit whichever copy runs.

pub use pulp::{Simd, WithSimd};

/// Runs `op`, inlined into a copy compiled for AVX2 + FMA when the CPU has
/// them (else the baseline). `op` is a struct whose
/// [`WithSimd::with_simd`] is `#[inline(always)]` and calls the loop, itself
/// `#[inline(always)]`, so that the loop is compiled inside the dispatched
/// copy (a closure is not reliably inlined there).
#[inline(always)]
pub fn vectorized<Op: WithSimd>(op: Op) -> Op::Output {
    pulp::Arch::new().dispatch(op)
}

/// Declares a struct of borrowed arguments whose [`WithSimd`] runs an
/// `#[inline(always)]` function on them (for [`vectorized`]).
macro_rules! simd_kernel {
    ($name:ident<$lt:lifetime> { $($field:ident : $ty:ty),* $(,)? } -> $out:ty => $f:path) => {
        struct $name<$lt> { $($field: $ty),* }
        impl $crate::simd::WithSimd for $name<'_> {
            type Output = $out;
            #[inline(always)]
            fn with_simd<S: $crate::simd::Simd>(self, _: S) -> $out {
                $f($(self.$field),*)
            }
        }
    };
}

pub(crate) use simd_kernel;

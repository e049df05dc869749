//! The cubic solvers of other Rust crates that a user would otherwise pick, called the way
//! `nlrt solvers` and nlrt-poly's criterion bench compare them with nlrt-poly: all roots of
//! `c[0] + c[1] x + c[2] x^2 + c[3] x^3` in `[lo, hi]`, increasing and distinct, as a [`Roots`].
//!
//! ```
//! use nlrt_oracle::peers::{kurbo_cubic, polycool_cubic, roots_crate_cubic};
//! // (x - 0.25)(x - 0.5)(x - 0.75)
//! let c = [-0.09375, 0.6875, -1.5, 1.0];
//! for roots in [kurbo_cubic(c, 0.0, 1.0), polycool_cubic(c, 0.0, 1.0)] {
//!     assert_eq!(roots.len(), 3);
//!     assert!((roots[1] - 0.5).abs() < 1e-12);
//! }
//! assert_eq!(roots_crate_cubic::<f32>([-0.09375, 0.6875, -1.5, 1.0], 0.0, 1.0).len(), 3);
//! ```

use nlrt_poly::{Real, Roots};

/// The values of `found` (at most three: a cubic's roots) in `[lo, hi]`, increasing and
/// distinct: a branch-free filter into a fixed array and [`Roots::from_unsorted`]'s
/// three-element sort, no allocation and no container conversion, so that a peer is timed on
/// its own work plus only what the same contract as nlrt-poly's needs (criterion's
/// `cubic_peer_wrapper` group measures this function alone). NaN is never in `[lo, hi]`.
#[inline(always)]
fn kept_in<T: Real>(found: &[T], lo: T, hi: T) -> Roots<T> {
    let mut inside = [T::ZERO; 3];
    let mut n = 0;
    for &x in found.iter().take(3) {
        // Written always, counted when inside: the slot is overwritten otherwise.
        inside[n] = x;
        n += usize::from(x >= lo && x <= hi);
    }
    Roots::from_unsorted(inside, n)
}

/// The peers' wrapper (the values of `found` in `[lo, hi]`, increasing and distinct) for a
/// caller that already holds a peer's whole-line roots: the wrapper's own cost, timed alone by
/// the criterion group `cubic_peer_wrapper`.
#[must_use]
#[inline]
pub fn roots_in<T: Real>(found: &[T], lo: T, hi: T) -> Roots<T> {
    kept_in(found, lo, hi)
}

/// The `roots` crate's `find_roots_cubic` (f32 and f64), whole line, then the roots in
/// `[lo, hi]`.
#[must_use]
#[inline]
pub fn roots_crate_cubic<T: Real + roots::FloatType>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    kept_in(
        roots::find_roots_cubic(c[3], c[2], c[1], c[0]).as_ref(),
        lo,
        hi,
    )
}

/// `kurbo::common::solve_cubic` (f64 only; Blinn's method), whole line, then the roots in
/// `[lo, hi]`.
#[must_use]
#[inline]
pub fn kurbo_cubic(c: [f64; 4], lo: f64, hi: f64) -> Roots<f64> {
    kept_in(&kurbo::common::solve_cubic(c[0], c[1], c[2], c[3]), lo, hi)
}

/// Target accuracy handed to polycool's interval solver: a few ulps of 1 in f64 (its roots
/// are judged to ulps like the others'; the looser 1e-12 of its examples would count as
/// misses).
pub const POLYCOOL_EPSILON: f64 = 1e-15;

/// `polycool::Poly::roots_between` (f64 only; Yuksel's method) on `[lo, hi]`. Its interval
/// must be finite and the cubic evaluable at its ends, so an infinite end is replaced by
/// Cauchy's bound on the real roots, `1 + max |c_i / c_3|` (what a user of it would pass), or
/// by `f64::MAX` where that bound is not finite.
#[must_use]
#[inline]
pub fn polycool_cubic(c: [f64; 4], lo: f64, hi: f64) -> Roots<f64> {
    let cauchy = 1.0
        + (c[0] / c[3])
            .abs()
            .max((c[1] / c[3]).abs())
            .max((c[2] / c[3]).abs());
    let bound = if cauchy.is_finite() { cauchy } else { f64::MAX };
    let (a, b) = (lo.max(-bound), hi.min(bound));
    kept_in(
        &polycool::Poly::new(c).roots_between(a, b, POLYCOOL_EPSILON),
        lo,
        hi,
    )
}

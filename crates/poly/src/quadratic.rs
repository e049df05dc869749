//! Real roots of `c[0] + c[1] x + c[2] x^2`.

use crate::eval::{
    horner_with_bound_scaled, normalize, rescale_variable, safe_coefficient_exponent,
};
use crate::{Real, Roots};

/// All distinct real roots of `c[0] + c[1] x + c[2] x^2`, in increasing order.
///
/// - Stable formulation: the discriminant is computed with Kahan's FMA correction (accurate
///   even when `b^2` and `4ac` nearly cancel), and the roots as `q / c[2]` and `c[0] / q` with
///   `q = -(b + sign(b) sqrt(D)) / 2`, so neither suffers cancellation.
/// - Coefficients and variable are rescaled by exact powers of two, so huge or tiny
///   coefficients neither overflow nor underflow on the way.
/// - `c[2] == 0` is the linear case; a double root is reported once.
/// - Roots whose value overflows the type are dropped.
/// - Non-finite coefficients, and the zero polynomial (every `x` is a root), give no roots.
///
/// ```
/// use nlrt_poly::solve_quadratic;
/// // x^2 - 3x + 2 = (x - 1)(x - 2)
/// assert_eq!(solve_quadratic([2.0f64, -3.0, 1.0]).as_slice(), &[1.0, 2.0]);
/// // Linear: 2x - 1
/// assert_eq!(solve_quadratic([-1.0f32, 2.0, 0.0]).as_slice(), &[0.5]);
/// // No cancellation for a tiny root next to a huge one.
/// let r = solve_quadratic([1.0f64, 1e10, 1.0]);
/// assert!((r[1] + 1e-10).abs() < 1e-25);
/// ```
#[must_use]
#[inline(always)]
pub fn solve_quadratic<T: Real>(c: [T; 3]) -> Roots<T> {
    let [c0, c1, c2] = c;
    // Fast path: finite, no coefficient outside [2^-S, 2^S] relative to 1, c0 and c2 non-zero
    // and within 2^S of each other: nothing can overflow or underflow, no rescaling needed.
    // (A NaN or infinity makes the sum fail the first test.)
    let (a0, a2) = (c0.abs(), c2.abs());
    let sum = a0 + c1.abs() + a2;
    let big = T::pow2(safe_coefficient_exponent::<T>());
    let small = T::pow2(-safe_coefficient_exponent::<T>());
    if sum <= big && sum >= small && a0 >= a2 * small && a2 >= a0 * small && a2 > T::ZERO {
        return roots_of_scaled(c0, c1, c2, 0);
    }
    solve_quadratic_general(c)
}

/// The careful path of [`solve_quadratic`]: special cases and rescaling.
#[inline(never)]
fn solve_quadratic_general<T: Real>(c: [T; 3]) -> Roots<T> {
    let [c0, c1, c2] = c;
    if !(c0.is_finite() && c1.is_finite() && c2.is_finite()) {
        return Roots::none();
    }
    if c2 == T::ZERO {
        return linear_root(c0, c1);
    }
    if c0 == T::ZERO {
        // x (c1 + c2 x): the root 0 and -c1/c2.
        let other = -c1 / c2;
        let mut roots = Roots::none();
        if other == T::ZERO || !other.is_finite() {
            roots.push(T::ZERO);
        } else if other < T::ZERO {
            roots.push(other);
            roots.push(T::ZERO);
        } else {
            roots.push(T::ZERO);
            roots.push(other);
        }
        return roots;
    }
    let (e0, e1, e2) = (c0.exponent(), c1.exponent(), c2.exponent());
    if c1 != T::ZERO && e0 + e2 + 4 + T::MANTISSA_DIGITS as i32 <= 2 * e1 {
        // The middle coefficient dominates: 4|c0 c2| < u c1^2, so sqrt(D) = |c1| (1 - d) with
        // d < u/2, and the roots are -c0/c1 and -c1/c2 to within a quarter ulp. Dividing the
        // original coefficients rounds each root once, even where one underflows to a
        // subnormal or both are far apart beyond any common scaling.
        let (small, large) = (-c0 / c1, -c1 / c2);
        let mut roots = Roots::none();
        for r in if small <= large {
            [small, large]
        } else {
            [large, small]
        } {
            if r.is_finite() && roots.last() != Some(&r) {
                roots.push(r);
            }
        }
        return roots;
    }
    // Balance the variable, x = 2^k y, so that |c0| ~ |c2| 2^(2k): the product of the roots is
    // then near 1 and neither b^2 nor 4ac can underflow to nothing. Only needed when the roots
    // are extreme; the common case skips it.
    let k = if (e0 - e2).abs() > safe_coefficient_exponent::<T>() {
        (e0 - e2) >> 1
    } else {
        0
    };
    // One exact power-of-two factor per coefficient (variable scaling and normalization
    // combined), so nothing passes through the subnormal range on the way.
    let [c0, c1, c2] = if k == 0 {
        normalize([c0, c1, c2])
    } else {
        rescale_variable([c0, c1, c2], k)
    };

    roots_of_scaled(c0, c1, c2, k)
}

/// Roots of `c0 + c1 y + c2 y^2` (both end coefficients non-zero, no overflow possible),
/// returned as `x = y 2^k`.
#[inline(always)]
fn roots_of_scaled<T: Real>(c0: T, c1: T, c2: T, k: i32) -> Roots<T> {
    let d = discriminant(c0, c1, c2);
    let mut roots = Roots::none();
    if d < T::ZERO {
        return roots;
    }
    let q = -(c1 + d.sqrt().copysign(c1)) * T::HALF;
    if d == T::ZERO {
        roots.push(unscale(q / c2, k));
        return roots;
    }
    let (r1, r2) = (unscale(q / c2, k), unscale(c0 / q, k));
    let (small, large) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
    for r in [small, large] {
        if r.is_finite() {
            roots.push(r);
        }
    }
    roots
}

/// Distinct real roots of `c[0] + c[1] x + c[2] x^2` in `[lo, hi]`, in increasing order.
///
/// Ends may be infinite. A root that rounding placed just outside the interval is reported
/// as the end it crossed when the polynomial at that end is indistinguishable from zero
/// (within the rounding-error bound of its evaluation), so a root lying exactly on an end
/// is never lost. An empty or NaN interval gives no roots.
///
/// ```
/// use nlrt_poly::solve_quadratic_in;
/// // (x - 1)(x - 2) on [1.5, 4]
/// assert_eq!(solve_quadratic_in([2.0f32, -3.0, 1.0], 1.5, 4.0).as_slice(), &[2.0]);
/// // Ends exactly on the roots keep them.
/// assert_eq!(solve_quadratic_in([2.0f64, -3.0, 1.0], 1.0, 2.0).as_slice(), &[1.0, 2.0]);
/// ```
#[must_use]
pub fn solve_quadratic_in<T: Real>(c: [T; 3], lo: T, hi: T) -> Roots<T> {
    if !(lo <= hi) {
        return Roots::none();
    }
    let all = solve_quadratic(c);
    let mut out = Roots::none();
    for &r in all.as_slice() {
        let kept = if r < lo {
            is_pseudo_root(&c, lo).then_some(lo)
        } else if r > hi {
            is_pseudo_root(&c, hi).then_some(hi)
        } else {
            Some(r)
        };
        if let Some(v) = kept
            && out.last() != Some(&v)
        {
            out.push(v);
        }
    }
    out
}

/// The range `(min, max)` of `c[0] + c[1] x + c[2] x^2` over `[lo, hi]`, as computed: the
/// values at the ends and, where the vertex lies strictly inside, at the vertex. (Deciding
/// that by the derivative's signs at the ends instead saves a division but measured no
/// faster in the box test.) The values carry the rounding of one Horner evaluation each; where the vertex is
/// within rounding of an end the two agree to second order, so callers' margins for the
/// evaluation cover the choice. NaN ends or coefficients give NaN bounds.
///
/// ```
/// use nlrt_poly::quadratic_range;
/// // (x - 1)^2 on [0, 3]: 0 at the vertex, 4 at x = 3.
/// assert_eq!(quadratic_range(&[1.0f64, -2.0, 1.0], 0.0, 3.0), (0.0, 4.0));
/// // Monotonic on [2, 3]: the ends.
/// assert_eq!(quadratic_range(&[1.0f32, -2.0, 1.0], 2.0, 3.0), (1.0, 4.0));
/// ```
#[must_use]
#[inline]
pub fn quadratic_range<T: Real>(c: &[T; 3], lo: T, hi: T) -> (T, T) {
    let at = |x: T| c[2].mul_add(x, c[1]).mul_add(x, c[0]);
    let (a, b) = (at(lo), at(hi));
    let (mut min, mut max) = (a.min(b), a.max(b));
    if c[2] != T::ZERO {
        let vertex = -c[1] / (T::TWO * c[2]);
        if vertex > lo && vertex < hi {
            let v = at(vertex);
            min = min.min(v);
            max = max.max(v);
        }
    }
    if a.is_nan() || b.is_nan() {
        return (T::NAN, T::NAN);
    }
    (min, max)
}

/// Whether `p(x)` is within the rounding-error bound of zero at a finite `x`.
#[inline]
fn is_pseudo_root<T: Real>(c: &[T; 3], x: T) -> bool {
    if !x.is_finite() {
        return false;
    }
    // Cheap rejection first: the unscaled evaluation rounds exactly like the scaled one
    // (which only multiplies by powers of two) unless something over- or underflows; far
    // from both (finite, bound above the normal range's floor) a value beyond 4x the bound
    // cannot be within the scaled bound either. Most out-of-range roots end here.
    let (v, bound) = crate::eval::horner_with_bound(c, x);
    if crate::eval::plainly_beyond_bound(v, bound) {
        return false;
    }
    let (v, bound) = horner_with_bound_scaled(c, x);
    v.abs() <= bound
}

/// `b^2 - 4ac` with Kahan's correction: the FMA residuals of both products are added back,
/// so the result is accurate to a few ulps even when the two products nearly cancel
/// (W. Kahan, "On the Cost of Floating-Point Computation Without Extra-Precise Arithmetic",
/// 2004; with FMA the residuals are exact).
#[must_use]
#[inline(always)]
pub fn discriminant<T: Real>(a0: T, a1: T, a2: T) -> T {
    let p = a1 * a1;
    let four_a2 = a2 * T::from_i32(4); // exact: a power-of-two scaling
    let q = four_a2 * a0;
    let dp = a1.mul_add(a1, -p);
    let dq = four_a2.mul_add(a0, -q);
    (p - q) + (dp - dq)
}

#[inline(always)]
fn unscale<T: Real>(y: T, k: i32) -> T {
    if k == 0 { y } else { y.scale_pow2(k) }
}

#[inline]
fn linear_root<T: Real>(c0: T, c1: T) -> Roots<T> {
    let mut roots = Roots::none();
    if c1 != T::ZERO {
        let r = -c0 / c1;
        if r.is_finite() {
            roots.push(r);
        }
    }
    roots
}

#[cfg(test)]
mod tests {
    macro_rules! quadratic_tests {
        ($($t:ident),*) => {$(
            mod $t {
                use crate::{solve_quadratic, solve_quadratic_in};
                type T = $t;

                /// The range holds the value at every sampled point of the interval and is
                /// reached (to rounding) at one of them, for vertices inside, outside and at
                /// an end.
                #[test]
                fn range_holds_every_sample() {
                    let cases: [([T; 3], T, T); 6] = [
                        ([1.0, -2.0, 1.0], 0.0, 3.0),
                        ([1.0, -2.0, 1.0], 1.0, 3.0),
                        ([-3.0, 5.0, -2.0], -1.0, 4.0),
                        ([0.5, 0.25, 0.0], -2.0, 2.0),
                        ([2.0, -3.0, 1.0], 1.5, 1.5),
                        ([1e-3, -7.0, 30.0], 0.0, 0.25),
                    ];
                    for (c, lo, hi) in cases {
                        let (min, max) = crate::quadratic_range(&c, lo, hi);
                        let (mut smin, mut smax) = (T::INFINITY, T::NEG_INFINITY);
                        for k in 0..=1000 {
                            let x = lo + (hi - lo) * (k as T / 1000.0);
                            let v = crate::horner(&c, x);
                            assert!(v >= min - 1e-5 && v <= max + 1e-5, "{c:?} at {x}: {v} not in [{min}, {max}]");
                            smin = smin.min(v);
                            smax = smax.max(v);
                        }
                        let tol = 1e-3 * (1.0 + smax.abs().max(smin.abs()));
                        assert!((min - smin).abs() <= tol && (max - smax).abs() <= tol, "{c:?}: [{min}, {max}] vs samples [{smin}, {smax}]");
                    }
                    let (a, b) = crate::quadratic_range::<T>(&[1.0, T::NAN, 1.0], 0.0, 1.0);
                    assert!(a.is_nan() && b.is_nan());
                }

                #[test]
                fn simple_roots() {
                    assert_eq!(solve_quadratic::<T>([2.0, -3.0, 1.0]).as_slice(), &[1.0, 2.0]);
                    assert_eq!(solve_quadratic::<T>([1.0, 0.0, 1.0]).len(), 0);
                    assert_eq!(solve_quadratic::<T>([1.0, -2.0, 1.0]).as_slice(), &[1.0]);
                    assert_eq!(solve_quadratic::<T>([0.0, 0.0, 1.0]).as_slice(), &[0.0]);
                    assert_eq!(solve_quadratic::<T>([0.0, -2.0, 1.0]).as_slice(), &[0.0, 2.0]);
                }

                #[test]
                fn degenerate_leading_coefficient_is_linear_not_inf() {
                    // cyPolynomial returns inf when a = 0.
                    assert_eq!(solve_quadratic::<T>([-4.0, 2.0, 0.0]).as_slice(), &[2.0]);
                    assert_eq!(solve_quadratic::<T>([1.0, 0.0, 0.0]).len(), 0);
                    assert_eq!(solve_quadratic::<T>([0.0, 0.0, 0.0]).len(), 0);
                }

                #[test]
                fn non_finite_input_gives_no_roots() {
                    for bad in [T::NAN, T::INFINITY, T::NEG_INFINITY] {
                        assert_eq!(solve_quadratic::<T>([bad, 1.0, 1.0]).len(), 0);
                        assert_eq!(solve_quadratic::<T>([1.0, bad, 1.0]).len(), 0);
                        assert_eq!(solve_quadratic::<T>([1.0, 1.0, bad]).len(), 0);
                    }
                    assert_eq!(solve_quadratic_in::<T>([2.0, -3.0, 1.0], T::NAN, 3.0).len(), 0);
                    assert_eq!(solve_quadratic_in::<T>([2.0, -3.0, 1.0], 3.0, 0.0).len(), 0);
                }

                #[test]
                fn extreme_magnitudes_do_not_overflow() {
                    let big = T::MAX / 4.0;
                    // big (x - 1)(x - 2)
                    let near = |r: &[T]| r.len() == 2
                        && (r[0] - 1.0).abs() <= 2.0 * T::EPSILON
                        && (r[1] - 2.0).abs() <= 4.0 * T::EPSILON;
                    let r = solve_quadratic::<T>([2.0 * (big / 8.0), -3.0 * (big / 8.0), big / 8.0]);
                    assert!(near(&r), "{:?}", r);
                    let tiny = T::MIN_POSITIVE * 64.0;
                    let r = solve_quadratic::<T>([2.0 * tiny, -3.0 * tiny, tiny]);
                    assert!(near(&r), "{:?}", r);
                }

                #[test]
                fn interval_ends_on_roots_keep_them() {
                    let c: [T; 3] = [2.0, -3.0, 1.0];
                    assert_eq!(solve_quadratic_in(c, 1.0, 2.0).as_slice(), &[1.0, 2.0]);
                    assert_eq!(solve_quadratic_in(c, 1.0, 1.0).as_slice(), &[1.0]);
                    // Ends one ulp inside the roots: within rounding of a root, so either no
                    // root or the end itself, never anything else.
                    let (lo, hi) = ((1.0 as T).next_up(), (2.0 as T).next_down());
                    for &r in solve_quadratic_in(c, lo, hi).iter() {
                        assert!(r == lo || r == hi, "{r}");
                    }
                    assert_eq!(solve_quadratic_in(c, 1.25, 1.75).len(), 0);
                    assert_eq!(solve_quadratic_in(c, T::NEG_INFINITY, T::INFINITY).len(), 2);
                }
            }
        )*};
    }
    quadratic_tests!(f32, f64);
}

//! Real roots of `c[0] + c[1] x + c[2] x^2 + c[3] x^3`, in the style of Yuksel 2022
//! ("High-Performance Polynomial Root Finding for Graphics"): the critical points split the
//! interval into monotonic pieces, and each piece with a sign change holds exactly one root,
//! found by a bracketed Newton iteration.
//!
//! Where this differs from the reference C++ (cyPolynomial.h), and why:
//! - Stopping rule: no absolute tolerance. Iteration stops when the value is within the
//!   rounding-error bound of Horner's rule (the root is then as accurate as the conditioning
//!   allows), or when quadratic convergence predicts an error below one ulp, or when the step
//!   is below one ulp.
//! - No deflation: every root is found on the original polynomial, so a large root cannot
//!   spoil the small ones.
//! - Exact power-of-two rescaling of the coefficients and, for huge arguments, of the variable:
//!   no overflow for any finite coefficients.
//! - Unbounded pieces are bracketed by Fujiwara's root bound instead of an outward search, and
//!   Newton starts on the side where `p * p'' > 0` (Fourier's condition), so it converges
//!   monotonically and never needs to be rejected.
//! - Tangential (double) roots: a critical point where `|p|` is within the evaluation's error
//!   bound is reported as a root instead of being dropped for lack of a sign change.

use crate::eval::{horner_with_bound, normalize, rescale_variable, safe_argument_exponent};
use crate::quadratic::{solve_quadratic, solve_quadratic_in};
use crate::{Real, Roots};

/// All distinct real roots of `c[0] + c[1] x + c[2] x^2 + c[3] x^3`, in increasing order.
///
/// Non-finite coefficients give no roots; `c[3] == 0` falls back to the quadratic; roots whose
/// value would overflow the type are dropped. A multiple root is reported once.
///
/// ```
/// use nlrt_poly::solve_cubic;
/// // (x + 1)(x - 1)(x - 1e6): roots of very different size, each to full precision.
/// let r = solve_cubic([1e6f64, -1.0, -1e6, 1.0]);
/// assert_eq!(r.as_slice(), &[-1.0, 1.0, 1e6]);
/// ```
#[must_use]
pub fn solve_cubic<T: Real>(c: [T; 4]) -> Roots<T> {
    cubic_roots::<T, false>(c, T::NEG_INFINITY, T::INFINITY)
}

/// Distinct real roots of the cubic in `[lo, hi]` (ends may be infinite), in increasing order.
///
/// This is the ray tracer's call: the height `h` of a hit is a root in `[h_in, h_out]`.
/// Reported roots always lie in `[lo, hi]`. A root within rounding error of an end is
/// reported as that end rather than lost. An empty or NaN interval gives no roots.
///
/// ```
/// use nlrt_poly::solve_cubic_in;
/// // x (x - 0.5)(x - 1) on [0, 1]: the roots on both ends are kept.
/// let roots = solve_cubic_in([0.0f32, 0.5, -1.5, 1.0], 0.0, 1.0);
/// assert_eq!(roots.as_slice(), &[0.0, 0.5, 1.0]);
/// ```
#[must_use]
pub fn solve_cubic_in<T: Real>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    cubic_roots::<T, false>(c, lo, hi)
}

/// The smallest root of the cubic in `[lo, hi]`: the nearest hit along a ray.
///
/// Stops after the first monotonic piece that holds a root, so it is cheaper than
/// [`solve_cubic_in`] when a root comes early.
///
/// ```
/// use nlrt_poly::first_cubic_root_in;
/// let c = [-6.0f64, 11.0, -6.0, 1.0]; // roots 1, 2, 3
/// assert_eq!(first_cubic_root_in(c, 1.5, 10.0), Some(2.0));
/// assert_eq!(first_cubic_root_in(c, 3.5, 10.0), None);
/// ```
#[must_use]
pub fn first_cubic_root_in<T: Real>(c: [T; 4], lo: T, hi: T) -> Option<T> {
    cubic_roots::<T, true>(c, lo, hi).first().copied()
}

/// Sign class of `p` at a point: +1, -1, or 0 when `|p|` is within its rounding-error bound.
type SignClass = i8;

#[inline(always)]
fn cubic_roots<T: Real, const FIRST: bool>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    if !(lo <= hi) || !(c[0].is_finite() && c[1].is_finite() && c[2].is_finite() && c[3].is_finite()) {
        return Roots::none();
    }
    if c[3] == T::ZERO {
        let roots = solve_quadratic_in([c[0], c[1], c[2]], lo, hi);
        return if FIRST { Roots::from_slice(&roots[..roots.len().min(1)]) } else { roots };
    }
    let c = normalize(c);

    // Critical points split [lo, hi] into at most three monotonic pieces.
    let critical = solve_quadratic([c[1], c[2] * T::TWO, c[3] * T::THREE]);
    let mut points = [T::ZERO; 4];
    let mut n = 0;
    points[n] = lo;
    n += 1;
    for &x in critical.iter() {
        if x > lo && x < hi {
            points[n] = x;
            n += 1;
        }
    }
    points[n] = hi;
    n += 1;

    let leading: SignClass = if c[3] > T::ZERO { 1 } else { -1 };
    let mut class: [SignClass; 4] = [0; 4];
    let mut residual = [T::ZERO; 4];
    for i in 0..n {
        let x = points[i];
        class[i] = if x == T::INFINITY {
            leading
        } else if x == T::NEG_INFINITY {
            -leading
        } else {
            let (v, bound) = eval_bounded(&c, x);
            residual[i] = v.abs();
            if v.abs() <= bound {
                0
            } else if v > T::ZERO {
                1
            } else {
                -1
            }
        };
    }

    let mut roots = Roots::none();
    for i in 0..n {
        if class[i] == 0 {
            // A point indistinguishable from a root. Two such points in a row (no sign change
            // can lie between them) belong to one multiple root: keep the smaller residual.
            if i > 0 && class[i - 1] == 0 {
                if residual[i] < residual[i - 1] {
                    roots.set_last(points[i]);
                }
            } else {
                roots.push(points[i]);
            }
            continue;
        }
        if FIRST && !roots.is_empty() {
            return roots; // a run of root-like points has ended
        }
        if i + 1 < n
            && class[i] * class[i + 1] < 0
            && let Some(r) = refine(&c, points[i], points[i + 1], class[i])
        {
            roots.push(r);
            if FIRST {
                return roots;
            }
        }
    }
    roots
}

/// `p(x)` and its error bound, rescaling the variable for huge `|x|` so nothing overflows.
/// Only the sign of the value is used, and rescaling by `2^(-3k)` keeps it.
#[inline(always)]
fn eval_bounded<T: Real>(c: &[T; 4], x: T) -> (T, T) {
    let e = x.exponent();
    if e <= safe_argument_exponent::<T>() {
        horner_with_bound(c, x)
    } else {
        horner_with_bound(&rescale_variable(*c, e), x.scale_pow2(-e))
    }
}

/// Fujiwara's bound on the roots' magnitude, rounded up to a power of two through exponents
/// only: every root satisfies `|x| < 2^e` (`i32::MIN` when all lower coefficients are 0).
#[inline]
fn root_bound_exponent<T: Real>(c: &[T; 4]) -> i32 {
    // |c_i / c_3| < 2^(e_i + 1 - e_3); Fujiwara: |x| <= 2 max_j |c_(3-j) / c_3|^(1/j).
    let e3 = c[3].exponent();
    let mut e = i32::MIN;
    for (i, &ci) in c.iter().take(3).enumerate() {
        if ci != T::ZERO {
            let j = 3 - i as i32;
            let t = (ci.exponent() + 1 - e3 + j - 1).div_euclid(j); // ceil division
            e = e.max(t);
        }
    }
    if e == i32::MIN { i32::MIN } else { e + 1 }
}

/// Iteration cap: each iteration either takes a Newton step that at least halves the step
/// before last, or bisects the bracket in representation order (halving the count of floats
/// in it); two bisections per bit of the format is more than enough.
#[inline(always)]
fn max_iterations<T: Real>() -> u32 {
    2 * T::BITS + 8
}

/// The single root in a monotonic piece `(a, b)` whose ends have opposite signs, `sign_a` at
/// `a`. Infinite ends are replaced by the root bound. `None` if the root is not representable.
#[inline]
fn refine<T: Real>(c: &[T; 4], a: T, b: T, sign_a: SignClass) -> Option<T> {
    let (mut a, mut b) = (a, b);
    if !a.is_finite() || !b.is_finite() {
        let e = root_bound_exponent(c);
        let bound = if e > T::MAX_EXPONENT { T::MAX } else { T::pow2(e.max(T::MIN_EXPONENT)) };
        let finite_abs = |x: T| if x.is_finite() { x.abs() } else { T::ZERO };
        let (abs_a, abs_b) = (finite_abs(a), finite_abs(b));
        if !a.is_finite() {
            a = -bound.max(abs_b);
        }
        if !b.is_finite() {
            b = bound.max(abs_a);
        }
        // Only where the bound was clipped to the type's range can the sign fail to change:
        // then the root lies beyond the largest finite value.
        if e > T::MAX_EXPONENT {
            let positive_at = |x: T| eval_bounded(c, x).0 > T::ZERO;
            if a == -T::MAX && positive_at(a) != (sign_a > 0) {
                return None;
            }
            if b == T::MAX && positive_at(b) == (sign_a > 0) {
                return None;
            }
        }
    }

    let (mut lo, mut hi) = (a, b);
    let lo_positive = sign_a > 0;
    let d = [c[1], c[2] * T::TWO, c[3] * T::THREE];
    let inflection = -c[2] / d[2];
    // Fourier's condition: Newton started where p * p'' > 0 converges monotonically.
    let start = if inflection > lo && inflection < hi {
        let f = eval_bounded(c, inflection).0;
        if f == T::ZERO {
            return Some(inflection);
        }
        if (f > T::ZERO) == lo_positive {
            lo = inflection;
        } else {
            hi = inflection;
        }
        inflection
    } else {
        let curvature_positive = (lo >= inflection) == (c[3] > T::ZERO);
        if lo_positive == curvature_positive { lo } else { hi }
    };

    let abs_c = [c[0].abs(), c[1].abs(), c[2].abs(), c[3].abs()];
    let bound_scale = T::from_i32(6) * T::UNIT_ROUNDOFF; // 2 n u with n = 3, as in `horner_with_bound`
    let safe = T::pow2(safe_argument_exponent::<T>());
    let mut x = start;
    let mut step_before_last = T::INFINITY;
    let mut last_step = T::INFINITY;
    let mut slow_steps = 0u32;
    for _ in 0..max_iterations::<T>() {
        let Step { f, df, magnitude, curvature_lo, curvature_hi, step } = if x.abs() <= safe {
            newton_step(c, &d, &abs_c, x, lo, hi)
        } else {
            // Huge argument: the same step on the polynomial rescaled to m = x / 2^k, exact.
            let k = x.exponent();
            let cs = rescale_variable(*c, k);
            let ds = [cs[1], cs[2] * T::TWO, cs[3] * T::THREE];
            let abs_cs = [cs[0].abs(), cs[1].abs(), cs[2].abs(), cs[3].abs()];
            let s = newton_step(&cs, &ds, &abs_cs, x.scale_pow2(-k), lo.scale_pow2(-k), hi.scale_pow2(-k));
            Step { step: s.step.scale_pow2(k), ..s }
        };
        if f == T::ZERO {
            return Some(x);
        }
        if (f > T::ZERO) == lo_positive {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - step;
        // Far from a root whose magnitude is much smaller than x, p behaves like a power of x
        // and Newton only shrinks x by a constant factor per step (many dozens of steps across
        // a bracket spanning many binades). Two such slow steps in a row trigger a bisection,
        // which halves the bracket in representation order.
        let slow = step.abs() * T::from_i32(4) > newton.abs();
        slow_steps = if slow { slow_steps + 1 } else { 0 };
        let accept = newton > lo
            && newton < hi
            && step.abs() * T::TWO <= step_before_last.abs()
            && slow_steps < 2;
        step_before_last = last_step;
        let next = if accept {
            last_step = step;
            // Quadratic convergence: the error after this step is about |p''| step^2 / (2|p'|),
            // with |p''| taken at its largest over the bracket (it is linear, so at an end).
            // Below half an ulp of the result, no further step can improve it. In rescaled
            // coordinates both sides scale alike, so the test is the same.
            let curvature = curvature_lo.abs().max(curvature_hi.abs());
            if curvature * step * step <= (df * newton).abs() * T::EPSILON || step.abs() <= newton.abs() * T::EPSILON {
                return Some(newton);
            }
            newton
        } else {
            // Newton failed. Where |p| is already within its rounding-error bound (a multiple
            // or clustered root, where Newton only converges linearly through noise), x is as
            // good as the conditioning allows: stop. Otherwise bisect.
            if f.abs() <= bound_scale * magnitude {
                return Some(x);
            }
            last_step = hi - lo;
            slow_steps = 0;
            midpoint(lo, hi)
        };
        if next == x || next == lo || next == hi {
            return Some(x); // the bracket is down to adjacent floats
        }
        x = next;
    }
    Some(x)
}

/// One Newton evaluation: value, derivative, the magnitude sum for the error bound, `p''` at
/// both bracket ends, and the Newton step `p / p'`.
struct Step<T> {
    f: T,
    df: T,
    magnitude: T,
    curvature_lo: T,
    curvature_hi: T,
    step: T,
}

#[inline(always)]
fn newton_step<T: Real>(c: &[T; 4], d: &[T; 3], abs_c: &[T; 4], x: T, lo: T, hi: T) -> Step<T> {
    let ax = x.abs();
    let f = c[3].mul_add(x, c[2]).mul_add(x, c[1]).mul_add(x, c[0]);
    let df = d[2].mul_add(x, d[1]).mul_add(x, d[0]);
    let magnitude = abs_c[3].mul_add(ax, abs_c[2]).mul_add(ax, abs_c[1]).mul_add(ax, abs_c[0]);
    let d2 = d[2] * T::TWO;
    Step {
        f,
        df,
        magnitude,
        curvature_lo: d2.mul_add(lo, d[1]),
        curvature_hi: d2.mul_add(hi, d[1]),
        step: f / df,
    }
}

/// Bisection point: the arithmetic mean within a factor of 4, otherwise the middle in
/// representation order so that a bracket spanning many binades still closes in
/// [`Real::BITS`] halvings.
#[inline(always)]
fn midpoint<T: Real>(lo: T, hi: T) -> T {
    let four = T::from_i32(4);
    if (lo > T::ZERO && hi <= lo * four) || (hi < T::ZERO && lo >= hi * four) {
        lo + (hi - lo) * T::HALF
    } else {
        T::bisect_ordered(lo, hi)
    }
}

#[cfg(test)]
mod tests {
    macro_rules! cubic_tests {
        ($($t:ident),*) => {$(
            mod $t {
                use crate::{first_cubic_root_in, solve_cubic, solve_cubic_in, Real};
                type T = $t;

                fn close(a: T, b: T, ulps: T) -> bool {
                    (a - b).abs() <= ulps * T::EPSILON * b.abs().max(T::MIN_POSITIVE)
                }

                #[test]
                fn three_simple_roots() {
                    let r = solve_cubic::<T>([-6.0, 11.0, -6.0, 1.0]);
                    assert_eq!(r.len(), 3);
                    for (x, e) in r.iter().zip([1.0, 2.0, 3.0]) {
                        assert!(close(*x, e, 2.0), "{x} vs {e}");
                    }
                }

                #[test]
                fn one_real_root() {
                    // x^3 + x + 1: one real root near -0.6823278
                    let r = solve_cubic::<T>([1.0, 1.0, 0.0, 1.0]);
                    assert_eq!(r.len(), 1);
                    assert!(close(r[0], -0.682_327_803_828_019_3 as T, 2.0), "{:?}", r);
                }

                #[test]
                fn cy_polynomial_failure_90x2_on_unit_interval() {
                    // cyPolynomial finds no root of 90 x^2 (a double root at 0) on [0, 1].
                    let r = solve_cubic_in::<T>([0.0, 0.0, 90.0, 0.0], 0.0, 1.0);
                    assert_eq!(r.as_slice(), &[0.0]);
                    // The cubic with the same double root: x^2 (x - 0.5)
                    let r = solve_cubic_in::<T>([0.0, 0.0, -0.5, 1.0], 0.0, 1.0);
                    assert_eq!(r.as_slice(), &[0.0, 0.5]);
                }

                #[test]
                fn tangential_double_root_is_reported() {
                    // (x - 0.25)^2 (x - 2): double root at 0.25 with no sign change.
                    let r = solve_cubic_in::<T>([-0.125, 1.0625, -2.5, 1.0], 0.0, 1.0);
                    assert_eq!(r.len(), 1, "{:?}", r);
                    assert!((r[0] - 0.25).abs() <= 2.0 * T::EPSILON.sqrt(), "{:?}", r);
                }

                #[test]
                fn first_root_is_the_nearest() {
                    let c: [T; 4] = [-6.0, 11.0, -6.0, 1.0];
                    assert!(close(first_cubic_root_in(c, 0.0, 10.0).unwrap(), 1.0, 2.0));
                    assert!(close(first_cubic_root_in(c, 2.5, 10.0).unwrap(), 3.0, 2.0));
                    assert_eq!(first_cubic_root_in(c, 3.5, 10.0), None);
                }

                #[test]
                fn bad_input_gives_no_roots() {
                    let c: [T; 4] = [-6.0, 11.0, -6.0, 1.0];
                    for bad in [T::NAN, T::INFINITY, T::NEG_INFINITY] {
                        for i in 0..4 {
                            let mut d = c;
                            d[i] = bad;
                            assert_eq!(solve_cubic(d).len(), 0);
                        }
                    }
                    assert_eq!(solve_cubic_in(c, T::NAN, 4.0).len(), 0);
                    assert_eq!(solve_cubic_in(c, 4.0, 0.0).len(), 0);
                    assert_eq!(solve_cubic::<T>([0.0; 4]).len(), 0);
                }

                #[test]
                fn huge_roots_do_not_overflow() {
                    // roots s, 2s, 4s with s^3 near the top of the range: x^3 overflows at the
                    // largest root unless the variable is rescaled. Coefficients are exact.
                    let s = T::pow2(T::MAX_EXPONENT / 3 - 1);
                    let (a, b, c) = (s, 2.0 * s, 4.0 * s);
                    let coeffs = [-8.0 * s * s * s, 14.0 * s * s, -7.0 * s, 1.0];
                    let r = solve_cubic::<T>(coeffs);
                    assert_eq!(r.len(), 3, "{:?}", r);
                    for (x, e) in r.iter().zip([a, b, c]) {
                        assert!(close(*x, e, 8.0), "{x} vs {e}");
                    }
                }
            }
        )*};
    }
    cubic_tests!(f32, f64);
}

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

/// A normalized cubic with what every evaluation needs, computed once per solve.
struct Cubic<T> {
    /// Coefficients, ascending.
    c: [T; 4],
    /// Derivative coefficients, ascending.
    d: [T; 3],
    /// `|c_i|`, for the rounding-error bound.
    abs_c: [T; 4],
}

impl<T: Real> Cubic<T> {
    #[inline(always)]
    fn new(c: [T; 4]) -> Self {
        Self {
            c,
            d: [c[1], c[2] * T::TWO, c[3] * T::THREE],
            abs_c: [c[0].abs(), c[1].abs(), c[2].abs(), c[3].abs()],
        }
    }

    #[inline(always)]
    fn value(&self, x: T) -> T {
        let c = &self.c;
        c[3].mul_add(x, c[2]).mul_add(x, c[1]).mul_add(x, c[0])
    }

    #[inline(always)]
    fn slope(&self, x: T) -> T {
        let d = &self.d;
        d[2].mul_add(x, d[1]).mul_add(x, d[0])
    }

    #[inline(always)]
    fn curvature(&self, x: T) -> T {
        (self.d[2] * T::TWO).mul_add(x, self.d[1])
    }

    /// `sum |c_i| |x|^i`; the rounding error of [`Self::value`] is below `6 u` times this
    /// (see `horner_with_bound`: `2 n u` with `n = 3`).
    #[inline(always)]
    fn magnitude(&self, x: T) -> T {
        let (a, ax) = (&self.abs_c, x.abs());
        a[3].mul_add(ax, a[2]).mul_add(ax, a[1]).mul_add(ax, a[0])
    }
}

/// `6 u`: the noise factor of a cubic's Horner evaluation (see [`Cubic::magnitude`]).
#[inline(always)]
fn noise_factor<T: Real>() -> T {
    T::from_i32(6) * T::UNIT_ROUNDOFF
}

#[inline(always)]
fn cubic_roots<T: Real, const FIRST: bool>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    if !(lo <= hi)
        || !(c[0].is_finite() && c[1].is_finite() && c[2].is_finite() && c[3].is_finite())
    {
        return Roots::none();
    }
    if c[3] == T::ZERO {
        let roots = solve_quadratic_in([c[0], c[1], c[2]], lo, hi);
        return if FIRST {
            Roots::from_slice(&roots[..roots.len().min(1)])
        } else {
            roots
        };
    }
    let k = balance_exponent(&c);
    if k == 0 {
        return balanced_cubic_roots::<T, FIRST>(&Cubic::new(normalize(c)), lo, hi);
    }
    // Roots far from unity in size: solve for y = x / 2^k, whose roots are near 1, so that the
    // terms of p near a root are neither all subnormal nor overflowing. Exact scaling.
    let p = Cubic::new(rescale_variable(c, k));
    let mut roots = balanced_cubic_roots::<T, FIRST>(&p, lo.scale_pow2(-k), hi.scale_pow2(-k));
    for r in roots.as_mut_slice() {
        *r = r.scale_pow2(k).max(lo).min(hi); // the clamp only acts on underflow rounding
    }
    roots
}

/// The exponent `k` that brings the roots' geometric size `|c_j / c_3|^(1 / (3 - j))` (`c_j`
/// the lowest non-zero coefficient) near 1 when it is beyond `2^(S / (3 - j))`; 0 otherwise.
#[inline(always)]
fn balance_exponent<T: Real>(c: &[T; 4]) -> i32 {
    let Some(j) = c.iter().position(|&v| v != T::ZERO).filter(|&j| j < 3) else { return 0 };
    let (aj, a3) = (c[j].abs(), c[3].abs());
    let window = T::pow2(crate::eval::safe_coefficient_exponent::<T>());
    if aj <= a3 * window && a3 <= aj * window {
        return 0;
    }
    (c[j].exponent() - c[3].exponent()).div_euclid(3 - j as i32)
}

/// Roots of a normalized cubic in `[lo, hi]`.
#[inline(always)]
fn balanced_cubic_roots<T: Real, const FIRST: bool>(p: &Cubic<T>, lo: T, hi: T) -> Roots<T> {
    // Critical points split [lo, hi] into at most three monotonic pieces.
    let critical = solve_quadratic(p.d);
    let mut points = [hi; 4];
    let mut n = 1;
    points[0] = lo;
    for &x in critical.iter() {
        if x > lo && x < hi {
            points[n] = x;
            n += 1;
        }
    }
    n += 1; // hi, already in place

    // The computed sign of p at each point, and whether |p| is within its rounding-error
    // bound there (then the sign may be wrong, and the point may stand for a root).
    let mut sign: [i8; 4] = [0; 4];
    let mut near_zero = [false; 4];
    let mut residual = [T::ZERO; 4];
    let safe = T::pow2(safe_argument_exponent::<T>());
    let sign_of = |v: T| -> i8 {
        if v > T::ZERO {
            1
        } else if v < T::ZERO {
            -1
        } else {
            0
        }
    };
    if lo >= -safe && hi <= safe {
        // Moderate arguments (the ray tracer's case): straight-line code over all four slots.
        let noise = noise_factor::<T>();
        let values = points.map(|x| p.value(x));
        let bounds = points.map(|x| noise * p.magnitude(x));
        residual = values.map(T::abs);
        for i in 0..4 {
            sign[i] = sign_of(values[i]);
            near_zero[i] = residual[i] <= bounds[i];
        }
    } else {
        let leading: i8 = if p.c[3] > T::ZERO { 1 } else { -1 };
        for i in 0..n {
            let x = points[i];
            if x == T::INFINITY {
                sign[i] = leading;
            } else if x == T::NEG_INFINITY {
                sign[i] = -leading;
            } else {
                let (v, bound) = eval_bounded(&p.c, x);
                residual[i] = v.abs();
                sign[i] = sign_of(v);
                near_zero[i] = residual[i] <= bound;
            }
        }
    }
    let changes = |i: usize| i + 1 < n && sign[i] * sign[i + 1] < 0;

    let guesses = Guesses::new(p, &critical);
    if !FIRST
        && n == 4
        && changes(0)
        && changes(1)
        && changes(2)
        && let Some(g) = guesses.roots
        && let Some(roots) = three_roots_fast(p, &points, g)
    {
        return roots;
    }
    let mut roots = Roots::none();
    let mut last_point: Option<usize> = None; // index of a point reported as a root just before
    for i in 0..n {
        // A point within rounding of zero with no sign change on either side stands for a
        // root (a tangency, or a root within rounding of an interval end). Where the computed
        // sign does change, the pieces' own roots are found below instead, so a near-double
        // root is reported as its two roots. Two such points in a row (nothing between them
        // but a monotonic piece within rounding of zero) are one root: keep the smaller
        // residual.
        let stands_for_root = near_zero[i] && (sign[i] == 0 || !(i > 0 && changes(i - 1)) && !changes(i));
        if stands_for_root {
            if let Some(j) = last_point.filter(|&j| j + 1 == i) {
                if residual[i] < residual[j] {
                    roots.set_last(points[i]);
                }
            } else {
                roots.push(points[i]);
            }
            last_point = Some(i);
            continue;
        }
        if FIRST && !roots.is_empty() {
            return roots; // a run of root-like points has ended
        }
        if changes(i)
            && let Some(r) = refine(p, points[i], points[i + 1], sign[i] > 0, guesses.for_piece(points[i], points[i + 1]))
        {
            roots.push(r);
            if FIRST {
                return roots;
            }
        }
    }
    roots
}

/// Starting points for the three roots of a cubic with three real roots, from the
/// trigonometric solution without trigonometry.
///
/// With the inflection point `xi` (midpoint of the critical points), the half-distance `s`
/// between the critical points and `cos(3 phi) = -p(xi) / (2 c3 s^3)`, the roots are
/// `xi + 2 s cos(phi + 2 pi k / 3)`. `cos(acos(c) / 3)` is written as `G(w) =
/// cos(2 acos(w) / 3)` with `w = sqrt((1 + c) / 2)`, which is analytic on `[0, 1]` (the square
/// root absorbs the branch point at a double root), and `G` is replaced by a degree-4
/// Chebyshev interpolant with error below 1.1e-5. From there Newton needs about two steps in
/// f64 and one in f32. Guesses only choose where Newton starts: which pieces hold a root, and
/// the bracket, still come from the certified sign tests.
#[derive(Clone, Copy)]
struct Guesses<T> {
    /// The critical points (meaningless when there are no guesses).
    x1: T,
    x2: T,
    roots: Option<[T; 3]>,
}

impl<T: Real> Guesses<T> {
    #[inline(always)]
    fn new(p: &Cubic<T>, critical: &Roots<T>) -> Self {
        let none = Self {
            x1: T::ZERO,
            x2: T::ZERO,
            roots: None,
        };
        if critical.len() != 2 {
            return none;
        }
        let (x1, x2) = (critical[0], critical[1]);
        // Only for moderate arguments, where s^3 and p(xi) cannot overflow.
        let safe = T::pow2(safe_argument_exponent::<T>());
        if !(x1.abs() <= safe && x2.abs() <= safe) {
            return none;
        }
        let s = (x2 - x1) * T::HALF;
        let xi = x1 + s;
        let cosine = -p.value(xi) / (T::TWO * p.c[3] * s * s * s);
        if !(cosine.abs() < T::ONE) {
            return none;
        }
        let g = |w: T| {
            // Chebyshev interpolant of cos(2 acos(w) / 3) on [0, 1], max error 1.06e-5.
            T::from_f64(-0.008_688_352_07)
                .mul_add(w, T::from_f64(0.038_352_908_4))
                .mul_add(w, T::from_f64(-0.106_493_987))
                .mul_add(w, T::from_f64(0.576_812_48))
                .mul_add(w, T::from_f64(0.500_010_608))
        };
        let two_s = s * T::TWO;
        let largest = two_s * g(((T::ONE + cosine) * T::HALF).sqrt());
        let smallest = -two_s * g(((T::ONE - cosine) * T::HALF).sqrt());
        let middle = -(largest + smallest);
        Self {
            x1,
            x2,
            roots: Some([xi + smallest, xi + middle, xi + largest]),
        }
    }

    /// The guess for the monotonic piece `(a, b)`: pieces left of, between and right of the
    /// critical points hold the smallest, middle and largest root.
    #[inline(always)]
    fn for_piece(&self, a: T, b: T) -> Option<T> {
        let r = self.roots?;
        Some(if b <= self.x1 {
            r[0]
        } else if a >= self.x2 {
            r[2]
        } else {
            r[1]
        })
    }
}

/// `p(x)` and its error bound, rescaling the variable for huge `|x|` so nothing overflows.
/// Only the sign of the value is used, and rescaling by a power of two keeps it.
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

/// Newton steps tried from a guess before falling back to the safeguarded iteration. From the
/// trigonometric guesses two suffice in f64 and one in f32; a third absorbs a guess near a
/// double root.
const FAST_STEPS: u32 = 3;

/// Whether a Newton step `step` to `next`, at slope `df`, has converged: quadratic convergence
/// puts the next error near `|p''| step^2 / (2 |p'|)` with `|p''| <= curvature` over the
/// bracket; below half an ulp of `next` (or for a step below one ulp) no further step helps.
/// The step must also not be larger than the result: `next = x - step` then rounds with an
/// error below one ulp of `next`, instead of `u |x|` after a cancellation (a root much closer
/// to 0 than the previous iterate).
#[inline(always)]
fn converged<T: Real>(curvature: T, step: T, df: T, next: T) -> bool {
    step.abs() <= next.abs()
        && (curvature * step * step <= (df * next).abs() * T::EPSILON
            || step.abs() <= next.abs() * T::EPSILON)
}

/// All three roots at once when each of the three pieces between `points` changes sign and
/// the trigonometric guesses are available: Newton on the three guesses side by side (the
/// lanes are independent, so they overlap in the pipeline or share SIMD registers), accepted
/// only when every lane has provably converged inside its own bracket. `None` sends the
/// caller to the piece-by-piece path.
#[inline(always)]
fn three_roots_fast<T: Real>(p: &Cubic<T>, points: &[T; 4], guesses: [T; 3]) -> Option<Roots<T>> {
    let safe = T::pow2(safe_argument_exponent::<T>());
    if !(points[0] >= -safe && points[3] <= safe) {
        return None;
    }
    let lo = [points[0], points[1], points[2]];
    let hi = [points[1], points[2], points[3]];
    let curvature: [T; 3] =
        core::array::from_fn(|i| p.curvature(lo[i]).abs().max(p.curvature(hi[i]).abs()));
    // A lane that has converged keeps its value, so each root is exactly what the
    // piece-by-piece path (and `first_cubic_root_in`) computes.
    let mut x = guesses;
    let mut done = [false; 3];
    for _ in 0..FAST_STEPS {
        let df = x.map(|x| p.slope(x));
        let f = x.map(|x| p.value(x));
        let mut inside = true;
        for i in 0..3 {
            let step = f[i] / df[i];
            let next = x[i] - step;
            inside &= done[i] || (next > lo[i] && next < hi[i]);
            if !done[i] {
                done[i] = converged(curvature[i], step, df[i], next);
                x[i] = next;
            }
        }
        if !inside {
            return None;
        }
        if done[0] && done[1] && done[2] {
            return Some(Roots::from_sorted(x));
        }
    }
    None
}

/// The single root in a monotonic piece `(a, b)` whose ends have opposite signs (`p(a) > 0`
/// iff `a_positive`), starting from `guess` when there is one. Infinite ends are replaced by
/// the root bound. `None` if the root is not representable.
#[inline]
fn refine<T: Real>(p: &Cubic<T>, a: T, b: T, a_positive: bool, guess: Option<T>) -> Option<T> {
    let safe = T::pow2(safe_argument_exponent::<T>());
    let mut start = None;
    if let Some(g) = guess
        && g > a
        && g < b
        && a >= -safe
        && b <= safe
    {
        // Fast path: plain Newton from a good guess, accepted once it provably converged
        // inside the bracket; anything else falls through to the safeguarded iteration.
        let curvature = p.curvature(a).abs().max(p.curvature(b).abs());
        let mut x = g;
        for _ in 0..FAST_STEPS {
            let df = p.slope(x);
            let step = p.value(x) / df;
            let next = x - step;
            if !(next > a && next < b) {
                break;
            }
            if converged(curvature, step, df, next) {
                return Some(next);
            }
            x = next;
        }
        start = Some(x);
    }
    let (mut a, mut b) = (a, b);
    if !a.is_finite() || !b.is_finite() {
        let e = root_bound_exponent(&p.c);
        let bound = if e > T::MAX_EXPONENT {
            T::MAX
        } else {
            T::pow2(e.max(T::MIN_EXPONENT))
        };
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
            let positive_at = |x: T| eval_bounded(&p.c, x).0 > T::ZERO;
            if a == -T::MAX && positive_at(a) != a_positive {
                return None;
            }
            if b == T::MAX && positive_at(b) == a_positive {
                return None;
            }
        }
    }
    Some(safeguarded_newton(p, a, b, a_positive, start))
}

/// Newton with a bracket that shrinks at every step, bisection when Newton leaves it or
/// stalls, and an exact rescaling of the variable for huge arguments.
fn safeguarded_newton<T: Real>(p: &Cubic<T>, a: T, b: T, a_positive: bool, start: Option<T>) -> T {
    let (mut lo, mut hi) = (a, b);
    let inflection = -p.c[2] / p.d[2];
    let start = if let Some(x) = start.filter(|&x| x > lo && x < hi) {
        x
    } else if inflection > lo && inflection < hi {
        // Fourier's condition: Newton started where p * p'' > 0 converges monotonically.
        // Across the inflection p'' changes sign: keep the half with the root, start there.
        let f = eval_bounded(&p.c, inflection).0;
        if f == T::ZERO {
            return inflection;
        }
        if (f > T::ZERO) == a_positive {
            lo = inflection;
        } else {
            hi = inflection;
        }
        inflection
    } else {
        let curvature_positive = (lo >= inflection) == (p.c[3] > T::ZERO);
        if a_positive == curvature_positive {
            lo
        } else {
            hi
        }
    };

    let safe = T::pow2(safe_argument_exponent::<T>());
    let mut x = start;
    let mut step_before_last = T::INFINITY;
    let mut last_step = T::INFINITY;
    let mut slow_steps = 0u32;
    for _ in 0..max_iterations::<T>() {
        let Step {
            f,
            df,
            magnitude,
            curvature,
            step,
        } = if x.abs() <= safe {
            Step::at(p, x, lo, hi)
        } else {
            // Huge argument: the same step on the polynomial rescaled to m = x / 2^k, exact.
            let k = x.exponent();
            let scaled = Cubic::new(rescale_variable(p.c, k));
            let s = Step::at(
                &scaled,
                x.scale_pow2(-k),
                lo.scale_pow2(-k),
                hi.scale_pow2(-k),
            );
            Step {
                step: s.step.scale_pow2(k),
                ..s
            }
        };
        if f == T::ZERO {
            return x;
        }
        if (f > T::ZERO) == a_positive {
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
            // In rescaled coordinates both sides of the test scale alike.
            if converged(curvature, step, df, newton) {
                return newton;
            }
            newton
        } else {
            // Newton failed. Where |p| is already within its rounding-error bound (a multiple
            // or clustered root, where Newton only converges linearly through noise), x is as
            // good as the conditioning allows: stop. Otherwise bisect.
            if f.abs() <= noise_factor::<T>() * magnitude {
                return x;
            }
            last_step = hi - lo;
            slow_steps = 0;
            midpoint(lo, hi)
        };
        if next == x || next == lo || next == hi {
            return x; // the bracket is down to adjacent floats
        }
        x = next;
    }
    x
}

/// One evaluation of the safeguarded iteration: value, slope, the magnitude sum of the error
/// bound, the largest `|p''|` over the bracket (it is linear, so at an end), and the step.
struct Step<T> {
    f: T,
    df: T,
    magnitude: T,
    curvature: T,
    step: T,
}

impl<T: Real> Step<T> {
    #[inline(always)]
    fn at(p: &Cubic<T>, x: T, lo: T, hi: T) -> Self {
        let (f, df) = (p.value(x), p.slope(x));
        Self {
            f,
            df,
            magnitude: p.magnitude(x),
            curvature: p.curvature(lo).abs().max(p.curvature(hi).abs()),
            step: f / df,
        }
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

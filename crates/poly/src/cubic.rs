//! Real roots of `c[0] + c[1] x + c[2] x^2 + c[3] x^3`, in the style of Yuksel 2022
//! ("High-Performance Polynomial Root Finding for Graphics"): the critical points split the
//! interval into monotonic pieces, and each piece whose ends have opposite signs holds exactly
//! one root, found by a bracketed Newton iteration.
//!
//! Where this differs from the reference C++ (cyPolynomial.h), and why:
//! - Stopping rule: no absolute tolerance. Newton stops when quadratic convergence predicts an
//!   error below half an ulp (and the last update did not cancel), when the step is below one
//!   ulp, or, once Newton stalls, when the value is within the rounding-error bound of Horner's
//!   rule (the root is then as accurate as its conditioning allows).
//! - No deflation: every root is found on the original polynomial, so a large root cannot
//!   spoil the small ones.
//! - No overflow or underflow for any finite coefficients: moderate inputs (the ray tracer's)
//!   take a fast path; anything else is evaluated with the coefficients and the variable
//!   rescaled by exact powers of two at each point (a local normalization), so a coefficient
//!   is only ever lost where its term is negligible.
//! - Unbounded pieces are bracketed by Fujiwara's root bound instead of an outward search, and
//!   Newton starts where `p * p'' > 0` (Fourier's condition), so it converges monotonically.
//! - Starting points for three real roots come from the trigonometric solution, evaluated
//!   without trigonometry (see [`Guesses`]); the three Newton iterations then run side by side.
//! - Tangential (double) roots: a critical point where `|p|` is within the evaluation's error
//!   bound, with no sign change on either side, is reported as a root instead of being dropped.

use crate::eval::{
    horner_with_bound_scaled, rescale_variable, safe_argument_exponent, safe_coefficient_exponent,
};
use crate::quadratic::{discriminant, solve_quadratic, solve_quadratic_in};
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

/// A cubic with what every evaluation needs, computed once per solve.
struct Cubic<T> {
    /// Coefficients, ascending.
    c: [T; 4],
    /// Derivative coefficients, ascending (meaningful when `moderate`).
    d: [T; 3],
    /// `|c_i|`, for the rounding-error bound.
    abs_c: [T; 4],
    /// `2 |p'''| = |4 d2| = |12 c3|`: twice the rate at which `p''` changes (see
    /// [`converged`]).
    bend_rate: T,
    /// All non-zero coefficients within `[2^-S, 2^S]`: for `|x| <= 2^R` plain Horner can
    /// neither overflow nor lose the terms to underflow (see `safe_coefficient_exponent`).
    moderate: bool,
    /// `c0 != 0`: then at tiny `|x|` the value is led by a normal-range term, and terms that
    /// underflow are negligible beside it; with `c0 = 0` every term can underflow.
    tiny_safe: bool,
}

impl<T: Real> Cubic<T> {
    #[inline(always)]
    fn new(c: [T; 4]) -> Self {
        let big = T::pow2(safe_coefficient_exponent::<T>());
        let small = T::pow2(-safe_coefficient_exponent::<T>());
        let abs_c = [c[0].abs(), c[1].abs(), c[2].abs(), c[3].abs()];
        // Non-short-circuit `&` / `|`: four independent compares, no branches.
        let moderate = abs_c.iter().fold(true, |ok, &a| {
            ok & (a <= big) & ((a >= small) | (a == T::ZERO))
        });
        Self {
            c,
            d: [c[1], c[2] * T::TWO, c[3] * T::THREE],
            abs_c,
            bend_rate: (c[3] * T::from_i32(12)).abs(),
            moderate,
            tiny_safe: c[0] != T::ZERO,
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

    /// Whether plain evaluation at `x` is safe: moderate coefficients, `|x| <= 2^R`, and, when
    /// `c0 = 0`, `x` zero or `|x| >= 2^-R`, so that no term overflows and the leading terms do
    /// not sink into subnormals.
    #[inline(always)]
    fn plain_at(&self, x: T) -> bool {
        let r = safe_argument_exponent::<T>();
        let ax = x.abs();
        self.moderate && ax <= T::pow2(r) && (self.tiny_safe || ax >= T::pow2(-r) || ax == T::ZERO)
    }

    /// [`Self::plain_at`] for every point of `[lo, hi]` at once (the upper bound only needs the
    /// ends).
    #[inline(always)]
    fn plain_on(&self, lo: T, hi: T, points: &[T; 4]) -> bool {
        let top = T::pow2(safe_argument_exponent::<T>());
        self.moderate
            && lo >= -top
            && hi <= top
            && (self.tiny_safe || points.iter().all(|&x| self.plain_at(x)))
    }

    /// `p(x)` and its rounding-error bound, both possibly scaled by one positive power of two
    /// (signs and the comparison of the two are exact under that scaling).
    #[inline(always)]
    fn value_and_bound(&self, x: T) -> (T, T) {
        if self.plain_at(x) {
            (self.value(x), noise_factor::<T>() * self.magnitude(x))
        } else {
            horner_with_bound_scaled(&self.c, x)
        }
    }

    /// The cubic in `m = x / 2^k`, locally normalized.
    #[inline]
    fn rescaled(&self, k: i32) -> Self {
        Self::new(rescale_variable(self.c, k))
    }

    /// For a moderate cubic: the critical points and the trigonometric guesses, sharing one
    /// square root and computed side by side (the guesses do not wait for the critical points'
    /// divisions). The critical points use the stable quadratic formula on `p'` (Kahan's
    /// discriminant; `q / a` as `q * (1 / a)`, one extra rounding, harmless for splitting
    /// points); the moderate window rules out overflow and underflow in it.
    #[inline(always)]
    fn critical_points_and_guesses(&self) -> (Roots<T>, Guesses<T>) {
        let [a0, a1, a2] = self.d;
        let disc = discriminant(a0, a1, a2);
        let inv_a2 = T::ONE / a2;
        let mut critical = Roots::none();
        if disc < T::ZERO {
            return (critical, Guesses::NONE);
        }
        if disc == T::ZERO {
            critical.push(-a1 * T::HALF * inv_a2);
            return (critical, Guesses::NONE);
        }
        let root = disc.sqrt();
        let q = -(a1 + root.copysign(a1)) * T::HALF;
        let (r1, r2) = (q * inv_a2, a0 / q);
        let (x1, x2) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
        critical.push(x1);
        critical.push(x2);
        // Roots of p' are xi -+ s with xi = -a1 / (2 a2) and s = sqrt(disc) / (2 |a2|).
        let half_inv = inv_a2 * T::HALF;
        let xi = -a1 * half_inv;
        let s = root * half_inv.abs();
        (
            critical,
            Guesses::from_parts(self, x1, x2, xi, s, disc * root),
        )
    }

    /// Critical points (roots of `p'`). Outside the moderate range the derivative is built from
    /// `c1..c3` scaled by one power of two that brings the largest to `[1, 2)`: exact when it
    /// scales up (subnormal coefficients keep every bit), and `3 c3` cannot overflow; what a
    /// downscale loses is below `2^-1074` of the largest, negligible for the quadratic solver,
    /// which balances the rest itself.
    #[inline(always)]
    fn critical_points(&self) -> Roots<T> {
        if self.moderate {
            return solve_quadratic(self.d);
        }
        let c = &self.c;
        let top = c[1].abs().max(c[2].abs()).max(c[3].abs());
        let e = if top == T::ZERO { 0 } else { top.exponent() };
        let [c1, c2, c3] = [c[1], c[2], c[3]].map(|v| v.scale_pow2(-e));
        solve_quadratic([c1, c2 * T::TWO, c3 * T::THREE])
    }
}

/// `6 u`: the noise factor of a cubic's Horner evaluation (see [`Cubic::magnitude`]).
#[inline(always)]
pub(crate) fn noise_factor<T: Real>() -> T {
    T::from_i32(6) * T::UNIT_ROUNDOFF
}

#[inline(always)]
fn sign_of<T: Real>(v: T) -> i8 {
    if v > T::ZERO {
        1
    } else if v < T::ZERO {
        -1
    } else {
        0
    }
}

#[inline(always)]
fn cubic_roots<T: Real, const FIRST: bool>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    if !(lo <= hi) {
        return Roots::none();
    }
    let p = Cubic::new(c);
    // Moderate coefficients are finite; only the others need the test.
    if !p.moderate && !c.iter().all(|v| v.is_finite()) {
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
    // Every root lies strictly inside Fujiwara's bound: an infinite end can be replaced by it,
    // so that moderate polynomials solved on the whole line take the fast path too. The
    // polynomial cannot vanish at the bound, so its sign there is that at infinity.
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        let e = root_bound_exponent(&p.c);
        if e == i32::MIN {
            // c3 x^3 alone: the only root is 0.
            (lo.max(T::ZERO), hi.min(T::ZERO))
        } else if e > T::MAX_EXPONENT {
            (lo, hi) // beyond the range: the unbounded pieces are bracketed in `refine`
        } else {
            let bound = T::pow2(e.max(T::MIN_EXPONENT));
            (lo.max(-bound), hi.min(bound))
        }
    };
    if !(lo <= hi) {
        return Roots::none();
    }

    // Critical points split [lo, hi] into at most three monotonic pieces.
    let (critical, early_guesses) = if p.moderate {
        p.critical_points_and_guesses()
    } else {
        (p.critical_points(), Guesses::NONE)
    };
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
    let mut values = [T::ZERO; 4];
    let fast = p.plain_on(lo, hi, &points);
    if fast {
        // Moderate input (the ray tracer's case): straight-line code over all four slots.
        values = points.map(|x| p.value(x));
        sign = values.map(sign_of);
    } else if T::MANTISSA_DIGITS < f64::MANTISSA_DIGITS {
        // A narrow type hands what it cannot evaluate plainly to f64 (see `solve_in_f64`).
        // Deciding here, after the critical points, rather than before them: an earlier exit
        // measured 20 ns slower on the plain three-root path (46 -> 67 ns in criterion, f32),
        // where it is never taken.
        return solve_in_f64::<T, FIRST>(c, lo, hi);
    } else {
        let leading: i8 = if p.c[3] > T::ZERO { 1 } else { -1 };
        for i in 0..n {
            let x = points[i];
            if x == T::INFINITY {
                sign[i] = leading;
            } else if x == T::NEG_INFINITY {
                sign[i] = -leading;
            } else {
                let (v, bound) = p.value_and_bound(x);
                residual[i] = v.abs() / bound.max(T::MIN_POSITIVE); // scale-free across points
                sign[i] = sign_of(v);
                near_zero[i] = v.abs() <= bound;
            }
        }
    }
    let changes = |i: usize| i + 1 < n && sign[i] * sign[i + 1] < 0;

    let guesses = if fast { early_guesses } else { Guesses::NONE };
    if !FIRST
        && n == 4
        && changes(0)
        && changes(1)
        && changes(2)
        && let Some(g) = guesses.roots
        && let Some(roots) = three_roots_fast(&p, &points, g)
    {
        return roots;
    }
    // The nearest root when the first piece changes sign: its guess alone, as `refine` starts
    // (its first check, after the fixed steps); what does not converge there takes `refine`.
    if FIRST
        && changes(0)
        && let Some(g) = guesses.for_piece(points[0], points[1])
        && let Some(root) = first_root_fast(&p, points[0], points[1], g)
    {
        return Roots::from_slice(&[root]);
    }
    if fast {
        residual = values.map(T::abs);
        if !FIRST {
            // All points' bounds at once, as straight-line code: the loop below visits every
            // point, and bounds formed point by point there measured slower (a branch per
            // point on data that differs from solve to solve).
            let noise = noise_factor::<T>();
            for i in 0..4 {
                near_zero[i] = residual[i] <= noise * p.magnitude(points[i]);
            }
        }
    }
    // The nearest root stops at its first root: there a point's bound is formed only where
    // its sign alone does not decide (no sign change on either side).
    let within_rounding = |i: usize| {
        if fast {
            residual[i] <= noise_factor::<T>() * p.magnitude(points[i])
        } else {
            near_zero[i]
        }
    };
    let mut roots = Roots::none();
    let mut last_point: Option<usize> = None; // index of a point reported as a root just before
    for i in 0..n {
        // A point within rounding of zero with no sign change on either side stands for a
        // root (a tangency, or a root within rounding of an interval end). Where the computed
        // sign does change, the pieces' own roots are found below instead, so a near-double
        // root is reported as its two roots. Two such points in a row (nothing between them
        // but a monotonic piece within rounding of zero) are one root: keep the smaller
        // residual.
        let undecided_by_signs = || sign[i] == 0 || !(changes(i) || (i > 0 && changes(i - 1)));
        let stands_for_root = if FIRST {
            undecided_by_signs() && within_rounding(i)
        } else {
            near_zero[i] && undecided_by_signs() // the cheaper test first
        };
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
            && let Some(r) = refine(
                &p,
                points[i],
                points[i + 1],
                sign[i] > 0,
                guesses.for_piece(points[i], points[i + 1]),
                fast.then(|| critical_end(&points, &values, i, n)).flatten(),
            )
        {
            // Two pieces meeting at a critical point within rounding of a double root may
            // both end their search on that point: one root, reported once.
            if roots.last().is_none_or(|&last| r > last) {
                roots.push(r);
            }
            if FIRST {
                return roots;
            }
        }
    }
    roots
}

/// The roots of a narrow-type cubic that plain evaluation in its own type cannot serve (roots
/// beyond `2^15` in f32, coefficients outside `2^-31 .. 2^31`, tiny critical points with
/// `c0 = 0`), found in f64 and rounded to the nearest `T`.
///
/// f64 holds every f32 cubic exactly, and evaluates it plainly wherever its roots lie within
/// `2^127` (f32's coefficients lie inside f64's moderate window), where f32 would rescale the
/// variable at every evaluation and bisect across binades: this is faster, and more accurate:
/// each root is the nearest f32 to a root found to f64 precision. Rounding is monotonic, so a
/// root in `[lo, hi]` stays there (the ends are `T` values); roots that round together are
/// reported once, and one beyond `T`'s range is dropped, as the contract says. Out of line
/// and cold: the plain path of the caller keeps the layout it was measured with.
#[cold]
#[inline(never)]
fn solve_in_f64<T: Real, const FIRST: bool>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    let (c, lo, hi) = (c.map(T::to_f64), lo.to_f64(), hi.to_f64());
    let mut wide = cubic_roots::<f64, FIRST>(c, lo, hi);
    if FIRST && wide.first().is_some_and(|&r| !T::from_f64(r).is_finite()) {
        // The nearest root lies beyond T's range: the first representable one is wanted.
        wide = cubic_roots::<f64, false>(c, lo, hi);
    }
    let mut roots = Roots::none();
    for &r in wide.iter() {
        let x = T::from_f64(r);
        if x.is_finite() && roots.last().is_none_or(|&last| x > last) {
            roots.push(x);
            if FIRST {
                break;
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
/// the bracket, still come from the sign tests.
#[derive(Clone, Copy)]
struct Guesses<T> {
    /// The critical points (meaningless when there are no guesses).
    x1: T,
    x2: T,
    roots: Option<[T; 3]>,
}

impl<T: Real> Guesses<T> {
    const NONE: Self = Self {
        x1: T::ZERO,
        x2: T::ZERO,
        roots: None,
    };

    /// Guesses from the critical points `x1 < x2`, their midpoint `xi` (the inflection), their
    /// half-distance `s` and `disc^(3/2)` (the discriminant of `p'` times its square root),
    /// for a moderate cubic (see [`Cubic::moderate`]).
    #[inline(always)]
    fn from_parts(p: &Cubic<T>, x1: T, x2: T, xi: T, s: T, disc_three_halves: T) -> Self {
        // Only for moderate arguments, where p(xi) cannot overflow.
        if !(p.plain_at(x1) && p.plain_at(x2)) {
            return Self::NONE;
        }
        // cos 3 phi = -p(xi) / (2 c3 s^3) with s = sqrt(disc) / (2 |a2|) and a2 = 3 c3:
        // -108 c3 |c3| p(xi) / disc^(3/2), one division. Dividing first keeps the product
        // in range (the quotient is about p(xi) / c^3, the factor about c^2); an overflow or
        // a vanishing disc^(3/2) gives a non-finite cosine, which takes no guesses below.
        let c3 = p.c[3];
        let cosine = (p.value(xi) / disc_three_halves) * (T::from_i32(-108) * c3 * c3.abs());
        // |cos 3 phi| > 1 means one real root (see `cardano_guess`). Just above 1 the formula
        // still places the real root well (two roots have merged into a complex pair near a
        // critical point), and rounding of a huge root spread lands here too: clamp. Cardano's
        // form takes over where the pair has clearly left the real line.
        let near_one = T::ONE + T::pow2(-10);
        if !(cosine.abs() < near_one) {
            return Self::NONE;
        }
        let cosine = cosine.max(-T::ONE).min(T::ONE);
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

/// A starting point for the single real root of a moderate cubic that has only one, from
/// Cardano's formula in its cancellation-free form (Numerical Recipes, 3rd ed., sec. 5.6): for
/// the depressed cubic `t^3 + P t + Q` with `D = (Q/2)^2 + (P/3)^3 > 0`,
/// `A = -sign(Q) cbrt(|Q|/2 + sqrt(D))` and `t = A - P / (3A)`. Only a guess: rounding in the
/// depressed coefficients does not matter, Newton polishes the result in its bracket.
#[inline]
fn cardano_guess<T: Real>(p: &Cubic<T>) -> Option<T> {
    let c = &p.c;
    let inv = T::ONE / c[3];
    let a = c[2] * inv;
    let third = T::ONE / T::THREE;
    let xi = -a * third;
    let depressed_p = (c[1] * inv) - a * a * third;
    let depressed_q = p.value(xi) * inv;
    let d = (depressed_q * T::HALF) * (depressed_q * T::HALF)
        + (depressed_p * third) * (depressed_p * third) * (depressed_p * third);
    if !(d > T::ZERO) {
        return None;
    }
    let big_a = -(depressed_q.abs() * T::HALF + d.sqrt())
        .cbrt()
        .copysign(depressed_q);
    if big_a == T::ZERO {
        return None;
    }
    let t = big_a - depressed_p * third / big_a;
    let x = xi + t;
    x.is_finite().then_some(x)
}

/// The critical-point end of piece `i` (interior points are critical points) with the value
/// there; of two, the one where `|p|` is smaller (the root is nearer to it).
#[inline(always)]
fn critical_end<T: Real>(points: &[T; 4], values: &[T; 4], i: usize, n: usize) -> Option<(T, T)> {
    let left = (i > 0).then(|| (points[i], values[i]));
    let right = (i + 2 < n).then(|| (points[i + 1], values[i + 1]));
    match (left, right) {
        (Some(l), Some(r)) => Some(if l.1.abs() <= r.1.abs() { l } else { r }),
        (l, r) => l.or(r),
    }
}

/// A starting point from the Taylor expansion at a critical point `c` (where `p' = 0`):
/// `p(c) + p''(c) (x - c)^2 / 2 = 0`, on the side of `c` inside `(a, b)`. Good where the root is
/// close to `c` compared with the scale of the cubic term, exactly where the trigonometric
/// guesses (accurate to about 1e-5 of the critical points' spacing) are not: one root far from
/// two others, as when the leading coefficient is tiny.
#[inline]
fn taylor_guess<T: Real>(p: &Cubic<T>, (c, value): (T, T), a: T, b: T) -> Option<T> {
    let d2 = -T::TWO * value / p.curvature(c);
    if !(d2 > T::ZERO) {
        return None;
    }
    let g = if c == a { c + d2.sqrt() } else { c - d2.sqrt() };
    (g > a && g < b).then_some(g)
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
/// double root or a root much closer to 0 than the guess.
pub(crate) const FAST_STEPS: u32 = 3;

/// Whether the Newton step `step` from `x` (slope `df`) lands on the root to within half an
/// ulp. Quadratic convergence puts the error after the step near `|p''| step^2 / (2 |p'|)`,
/// with `|p''|` bounded over `[x, x - 2 step]` (the step and as far again, where the root is
/// once that error is small) by `|p''(x)| + 2 |step| |p'''|` (`p''` is linear); below half an ulp
/// of the result (or for a step below one ulp) no further step helps. Two more conditions:
/// the step is no larger than the result, so `x - step` rounds with an error below one ulp
/// instead of `u |x|` after a cancellation (a root much closer to 0 than the iterate); and no
/// larger than `x`, so the step stays where a locally normalized evaluation at `x` is valid.
#[inline(always)]
fn converged<T: Real>(p: &Cubic<T>, x: T, step: T, df: T) -> bool {
    let (next, size) = (x - step, step.abs());
    if !(size <= next.abs() && size <= x.abs()) {
        return false;
    }
    // p'' is linear with slope p''' = 2 d2, so over [x - 2 step, x] it is at most
    // |p''(x)| + 2 |step| |p'''|: one evaluation instead of one at each end.
    let bend = size.mul_add(p.bend_rate, p.curvature(x).abs());
    bend * size * size <= (df * next).abs() * T::EPSILON || size <= next.abs() * T::EPSILON
}

/// Newton steps taken from a trigonometric or Cardano guess before convergence is first
/// checked: from the guesses' accuracy (about 1e-5 relative to the root spacing) one step
/// reaches f32 precision and two reach f64 precision. Taking them unconditionally lets the three
/// lanes of [`three_roots_fast`] run as straight-line (vectorizable) code.
#[inline(always)]
pub(crate) fn fixed_steps<T: Real>() -> u32 {
    if T::MANTISSA_DIGITS > 24 { 2 } else { 1 }
}

/// All three roots at once when each of the three pieces between `points` changes sign and
/// the trigonometric guesses are available: [`fixed_steps`] Newton steps on the three guesses
/// side by side, accepted only when every lane's last step has converged inside its own
/// bracket. The steps are those the piece-by-piece path takes, so each root is exactly what it
/// (and `first_cubic_root_in`) computes. `None` sends the caller to the piece-by-piece path.
#[inline(always)]
fn three_roots_fast<T: Real>(p: &Cubic<T>, points: &[T; 4], guesses: [T; 3]) -> Option<Roots<T>> {
    let mut x = guesses;
    let mut before = x;
    let mut df = [T::ZERO; 3];
    let mut step = [T::ZERO; 3];
    for _ in 0..fixed_steps::<T>() {
        before = x;
        df = x.map(|x| p.slope(x));
        let f = x.map(|x| p.value(x));
        step = core::array::from_fn(|i| f[i] / df[i]);
        x = core::array::from_fn(|i| x[i] - step[i]);
    }
    let mut ok = true;
    for i in 0..3 {
        ok &= x[i] > points[i] && x[i] < points[i + 1] && converged(p, before[i], step[i], df[i]);
    }
    ok.then(|| Roots::from_sorted(x))
}

/// [`refine`]'s fast path up to its first check: [`fixed_steps`] Newton steps from the guess
/// `g` (inside the piece `(a, b)`), the result if it lies in the piece and has converged.
#[inline(always)]
fn first_root_fast<T: Real>(p: &Cubic<T>, a: T, b: T, g: T) -> Option<T> {
    if !(g > a && g < b) {
        return None;
    }
    let mut x = g;
    let (mut before, mut step, mut df) = (x, T::ZERO, T::ZERO);
    for _ in 0..fixed_steps::<T>() {
        before = x;
        df = p.slope(x);
        step = p.value(x) / df;
        x = before - step;
    }
    (x > a && x < b && converged(p, before, step, df)).then_some(x)
}

/// The single root in a monotonic piece `(a, b)` whose ends have opposite signs (`p(a) > 0`
/// iff `a_positive`), starting from `guess` when there is one. Infinite ends are replaced by
/// the root bound. `None` if the root is not representable.
#[inline]
fn refine<T: Real>(
    p: &Cubic<T>,
    a: T,
    b: T,
    a_positive: bool,
    guess: Option<T>,
    critical: Option<(T, T)>,
) -> Option<T> {
    let mut start = None;
    let guess = if guess.is_none() && p.moderate && p.plain_at(a) && p.plain_at(b) {
        cardano_guess(p)
    } else {
        guess
    };
    // The closed-form guess first, then the Taylor guess at a critical end (when the piece is
    // plain-evaluable): each gets the fast path; what fails falls to the safeguarded iteration.
    // The Taylor guess is computed only once the first has failed (most solves end on it).
    let taylor = core::iter::once_with(|| critical.and_then(|c| taylor_guess(p, c, a, b)));
    for g in core::iter::once(guess).chain(taylor).flatten() {
        if !(g > a && g < b) {
            continue;
        }
        // Fast path (guesses exist only for moderate input): plain Newton from a good guess,
        // accepted once it converged inside the bracket; anything else falls through to the
        // safeguarded iteration.
        let mut x = g;
        let (mut before, mut last_step, mut step_before_last) = (x, T::INFINITY, T::INFINITY);
        for k in 0..FAST_STEPS {
            let df = p.slope(x);
            let step = p.value(x) / df;
            let next = x - step;
            // The first `fixed_steps` are taken unconditionally, as in `three_roots_fast`.
            if k + 1 >= fixed_steps::<T>() {
                if !(next > a && next < b) {
                    break;
                }
                if converged(p, x, step, df) {
                    return Some(next);
                }
            }
            (before, step_before_last, last_step) = (x, last_step, step);
            x = next;
        }
        if x > a && x < b {
            // Not converged: at a multiple root or a cluster of roots inside the noise, the
            // iterate is already as good as the safeguarded iteration would make it.
            // (`before` may be the unconditional first step's result, outside the piece.)
            if last_step.abs() * linear_ratio::<T>() > step_before_last.abs()
                && last_step.abs() <= before.abs() * T::pow2(cluster_width_exponent::<T>())
                && before > a
                && before < b
                && within_noise(p, before)
            {
                return Some(before);
            }
            if start.is_none() {
                start = Some((x, last_step));
            }
        }
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
            let positive_at = |x: T| p.value_and_bound(x).0 > T::ZERO;
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
/// stalls, and local normalization wherever plain evaluation is not safe.
///
/// `start` is where a fast path left off, with the Newton step that led there (it tells
/// whether the steps still shrink quadratically).
fn safeguarded_newton<T: Real>(
    p: &Cubic<T>,
    a: T,
    b: T,
    a_positive: bool,
    start: Option<(T, T)>,
) -> T {
    let (mut lo, mut hi) = (a, b);
    // -c2 / (3 c3) without overflow.
    let inflection = -(p.c[2] / p.c[3]) / T::THREE;
    let mut previous_step = T::INFINITY;
    let start = if let Some((x, step)) = start.filter(|&(x, _)| x > lo && x < hi) {
        previous_step = step;
        x
    } else if inflection > lo && inflection < hi {
        // Fourier's condition: Newton started where p * p'' > 0 converges monotonically.
        // Across the inflection p'' changes sign: keep the half with the root, start there.
        let f = p.value_and_bound(inflection).0;
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

    let mut x = start;
    let mut step_before_last = T::INFINITY;
    let mut last_step = T::INFINITY;
    let mut slow_steps = 0u32;
    for _ in 0..max_iterations::<T>() {
        let Step {
            f,
            near_zero,
            step,
            converges,
        } = if p.plain_at(x) {
            Step::at(p, x)
        } else if x == T::ZERO {
            // p(0) = c0 exactly; the step from 0 is -c0 / c1 (c1 = 0: an infinite step,
            // rejected below in favour of bisection).
            let step = p.c[0] / p.c[1];
            Step {
                f: p.c[0],
                near_zero: p.c[0] == T::ZERO,
                step,
                converges: false,
            }
        } else {
            // Locally normalized: the same step on the polynomial in m = x / 2^k (exact).
            let k = x.exponent();
            let s = Step::at(&p.rescaled(k), x.scale_pow2(-k));
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
        // Within the rounding noise and converging only linearly: a multiple root or a
        // cluster of roots inside the noise, where the steps only wander through the noise.
        // `x` is as good as the conditioning allows (the contract's attainable radius).
        if near_zero && step.abs() * linear_ratio::<T>() > previous_step.abs() {
            return x;
        }
        step_before_last = last_step;
        let next = if accept {
            last_step = step;
            previous_step = step;
            if converges {
                return newton;
            }
            newton
        } else {
            // Newton failed. Where |p| is already within its rounding-error bound (a multiple
            // or clustered root, where Newton only converges linearly through noise), x is as
            // good as the conditioning allows: stop. Otherwise bisect.
            if near_zero {
                return x;
            }
            last_step = hi - lo;
            previous_step = last_step;
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

/// Once Newton converges quadratically its steps shrink by far more than this factor per
/// step; a step larger than `1 / linear_ratio` of the one before means linear convergence, the
/// mark of a multiple root (ratio `(m - 1) / m` for multiplicity `m`: 1/2, 2/3) or of a
/// cluster of roots inside the rounding noise, where the computed steps are noise.
#[inline(always)]
fn linear_ratio<T: Real>() -> T {
    T::from_i32(4)
}

/// Newton's steps inside a cluster of roots within the rounding noise are no wider than the
/// cluster's pseudo-zero set: for three roots, where it is widest, `|x - r|^3 |c3| <= 6 u
/// sum |c_i| |x|^i`, about `(48 u)^(1/3) |x| < 2^(2 - p/3) |x|` for `p` mantissa bits (the
/// sum is at most `8 |c3| |x|^3` near a cluster at `x`). One more bit of margin gives the
/// exponent; a larger step is not noise, and the safeguarded iteration takes it.
#[inline(always)]
fn cluster_width_exponent<T: Real>() -> i32 {
    3 - T::MANTISSA_DIGITS as i32 / 3
}

/// Whether `|p(x)|` is within its rounding-error bound (plain evaluation only). Out of line:
/// only solves whose fast path did not converge ask.
#[cold]
#[inline(never)]
fn within_noise<T: Real>(p: &Cubic<T>, x: T) -> bool {
    p.plain_at(x) && p.value(x).abs() <= noise_factor::<T>() * p.magnitude(x)
}

/// One evaluation of the safeguarded iteration: the value, whether it is within its
/// rounding-error bound, the Newton step, and whether taking that step converges (judged in
/// the evaluation's own, possibly rescaled, coordinates).
struct Step<T> {
    f: T,
    near_zero: bool,
    step: T,
    converges: bool,
}

impl<T: Real> Step<T> {
    #[inline(always)]
    fn at(p: &Cubic<T>, x: T) -> Self {
        let (f, df) = (p.value(x), p.slope(x));
        let step = f / df;
        Self {
            f,
            near_zero: f.abs() <= noise_factor::<T>() * p.magnitude(x),
            step,
            converges: converged(p, x, step, df),
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
                    assert!(close(r[0], T::from_f64(-0.682_327_803_828_019_3), 2.0), "{:?}", r);
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
                fn a_double_root_at_a_critical_point_is_reported_once() {
                    // Three roots within 2e-6 of 1 (a fuzzing find): both pieces around the
                    // critical point inside the interval end their search on it.
                    let c = [-1.0000030000019984, 3.000006000002002, -3.0000030000000035, 1.0];
                    let (lo, hi) = (1.000001411885023, 1.0000022360909497);
                    let r = solve_cubic_in(c.map(T::from_f64), T::from_f64(lo), T::from_f64(hi));
                    assert!(r.windows(2).all(|w| w[0] < w[1]), "{:?}", r);
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

    /// f32 cubics outside f32's plain window are solved in f64 (`solve_in_f64`).
    mod narrow {
        use crate::{first_cubic_root_in, solve_cubic, solve_cubic_in};

        #[test]
        fn roots_beyond_the_plain_window_are_exact_when_representable() {
            // (x - 2^20)(x - 3 2^20)(x + 5 2^21): every coefficient is exact in f32, the roots
            // lie beyond 2^15, where f32 alone would rescale at every evaluation.
            let e20 = 1_048_576.0f32;
            let c = [30.0 * e20 * e20 * e20, -37.0 * e20 * e20, 6.0 * e20, 1.0];
            let r = solve_cubic(c);
            assert_eq!(r.as_slice(), &[-5.0 * 2.0 * e20, e20, 3.0 * e20]);
            assert_eq!(first_cubic_root_in(c, 0.0, f32::INFINITY), Some(e20));
            let inside = solve_cubic_in(c, 2.0 * e20, 4.0 * e20);
            assert_eq!(inside.as_slice(), &[3.0 * e20]);
        }

        #[test]
        fn the_nearest_root_skips_one_beyond_the_range() {
            // 90 x^2 + 1.6e-43 x^3: a double root at 0 and one near -5.5e44, beyond f32's
            // range (dropped) but found first in f64 (a fuzzing find).
            let c = [0.0f32, 0.0, 90.0, 1.64e-43];
            let all = solve_cubic(c);
            assert_eq!(all.as_slice(), &[0.0]);
            assert_eq!(
                first_cubic_root_in(c, f32::NEG_INFINITY, f32::INFINITY),
                Some(0.0)
            );
        }
    }
}

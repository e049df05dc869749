//! Polynomial evaluation with a running rounding-error bound, and exact power-of-two scaling.
//!
//! Coefficients are stored by ascending power: `c[i]` multiplies `x^i`.

use crate::Real;

/// `c[0] + c[1] x + ... + c[N-1] x^(N-1)` by Horner's rule, one FMA per step.
///
/// ```
/// use nlrt_poly::horner;
/// assert_eq!(horner(&[1.0f32, 2.0, 3.0], 2.0), 17.0);
/// ```
#[must_use]
#[inline(always)]
pub fn horner<T: Real, const N: usize>(c: &[T; N], x: T) -> T {
    let mut r = c[N - 1];
    let mut i = N - 1;
    while i > 0 {
        i -= 1;
        r = r.mul_add(x, c[i]);
    }
    r
}

/// Horner's value of the polynomial and a bound on its rounding error.
///
/// Returns `(value, bound)` with `|value - p(x)| <= bound` for the exact `p(x)` of these
/// (already rounded) coefficients, barring overflow. With FMA, Horner's rule rounds once per
/// step, so the error is at most `gamma_n * sum |c_i| |x|^i` with `gamma_n = n u / (1 - n u)`
/// (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., eq. 5.3 with FMA).
/// The bound uses `2 n u` in place of `gamma_n`: the factor 2 covers both the `1/(1 - n u)`
/// term and the rounding of the bound's own Horner sum (each below `1 + 2 n u`). One smallest
/// subnormal per step is added for underflow, where the relative model does not hold.
///
/// ```
/// use nlrt_poly::horner_with_bound;
/// // (x - 1)^2 at x = 1 + 2^-30: exact value 2^-60, far below the rounding noise.
/// let x = 1.0 + 2f64.powi(-30);
/// let (v, bound) = horner_with_bound(&[1.0, -2.0, 1.0], x);
/// assert!((v - 2f64.powi(-60)).abs() <= bound);
/// ```
#[must_use]
#[inline(always)]
pub fn horner_with_bound<T: Real, const N: usize>(c: &[T; N], x: T) -> (T, T) {
    let ax = x.abs();
    let mut r = c[N - 1];
    let mut m = c[N - 1].abs();
    let mut i = N - 1;
    while i > 0 {
        i -= 1;
        r = r.mul_add(x, c[i]);
        m = m.mul_add(ax, c[i].abs());
    }
    (r, error_bound(N as i32 - 1, m))
}

/// `2 n u m + n eta` (`eta` the smallest subnormal), the bound of [`horner_with_bound`] for
/// degree `n` and magnitude sum `m`, rounded once as one FMA, without a subnormal operand
/// where the result is normal.
///
/// A subnormal operand costs a microcode assist on x86 (about 30 ns for one FMA with a
/// subnormal addend on this project's Xeon, 60 times a normal one), and the plain formula has
/// one in every call: it made pseudo-root checks and sign decisions a quarter of a ray's
/// time. So the FMA is evaluated with both constants scaled up by `2^p` (`p` the significand
/// width), where `n eta 2^p = n 2^(MIN_EXPONENT + 1)` is normal, and the result scaled back.
/// Scaling by a power of two commutes with rounding while every value stays normal, so where
/// the scaled result is finite and above `2^(MIN_EXPONENT + p)` (the unscaled result then
/// normal: `m` beyond about `2^-100` in f32, `2^-970` in f64) it is the plain FMA's bits; the
/// rest (tiny or huge `m`) takes the plain formula.
#[must_use]
#[inline(always)]
fn error_bound<T: Real>(degree: i32, m: T) -> T {
    let p = T::MANTISSA_DIGITS as i32;
    let degree = T::from_i32(degree);
    let factor = T::TWO * degree * T::UNIT_ROUNDOFF;
    let scaled = (factor * T::pow2(p)).mul_add(m, degree * T::pow2(T::MIN_EXPONENT + 1));
    if scaled > T::pow2(T::MIN_EXPONENT + p) && scaled.is_finite() {
        return scaled * T::pow2(-p);
    }
    plain_error_bound(factor, degree, m)
}

/// The plain formula of [`error_bound`], out of line: inlined, the compiler evaluates it
/// alongside the scaled one and selects, which pays the assist on every call.
#[cold]
#[inline(never)]
fn plain_error_bound<T: Real>(factor: T, degree: T, m: T) -> T {
    factor.mul_add(m, degree * T::from_bits_u64(1))
}

/// Exponent window inside which coefficients need no rescaling: with `max |c_i| <= 2^S` and
/// `|x| <= 2^R` (see [`safe_argument_exponent`]) every Horner term of a cubic stays below
/// `2^(S + 3R + 2)`, far from overflow, and squares in the quadratic's discriminant stay below
/// `2^(2S + 2)`. S is a quarter of the exponent range: 31 for f32, 255 for f64.
#[must_use]
#[inline(always)]
pub(crate) fn safe_coefficient_exponent<T: Real>() -> i32 {
    T::MAX_EXPONENT / 4
}

/// Largest argument exponent R evaluated without rescaling the variable: an eighth of the
/// exponent range (15 for f32, 127 for f64), so that `S + 3R + 2 < MAX_EXPONENT`.
#[must_use]
#[inline(always)]
pub(crate) fn safe_argument_exponent<T: Real>() -> i32 {
    T::MAX_EXPONENT / 8
}

/// Scales all coefficients by one power of two (exact barring underflow of negligible ones)
/// so that the largest lies in `[1, 2)`, when the largest is outside the safe window. The
/// roots are unchanged.
#[must_use]
#[inline(always)]
pub(crate) fn normalize<T: Real, const N: usize>(mut c: [T; N]) -> [T; N] {
    let mut m = T::ZERO;
    for v in c {
        m = m.max(v.abs());
    }
    let s = safe_coefficient_exponent::<T>();
    if m > T::pow2(s) || m < T::pow2(-s) {
        let e = m.exponent();
        for v in &mut c {
            *v = v.scale_pow2(-e);
        }
    }
    c
}

/// Coefficients of `P(m) = p(m 2^k) / 2^E`: the same polynomial in the variable `m = x / 2^k`,
/// divided by the power of two `2^E` that brings its largest coefficient into `[1, 2)`, so that
/// evaluating it near `|m| <= 1` can neither overflow nor sink into subnormals. Each
/// coefficient is scaled once, by `2^(i k - E)`, so the result is exact unless a coefficient is
/// negligible against the largest; the roots scale exactly (`x = m 2^k`) and the sign of every
/// value is kept.
#[must_use]
#[inline]
pub(crate) fn rescale_variable<T: Real, const N: usize>(mut c: [T; N], k: i32) -> [T; N] {
    let mut top = i32::MIN;
    for (i, v) in c.iter().enumerate() {
        if *v != T::ZERO {
            top = top.max(v.exponent().saturating_add(i as i32 * k));
        }
    }
    if top == i32::MIN {
        return c;
    }
    for (i, v) in c.iter_mut().enumerate() {
        *v = v.scale_pow2((i as i32 * k).saturating_sub(top));
    }
    c
}

/// [`horner_with_bound`] at any finite `x` without overflow or underflow: the variable and the
/// coefficients are locally normalized (scaled by exact powers of two so that the largest term
/// at `x` is near 1), so value and bound come back multiplied by one and the same positive
/// power of two. Their signs, and the comparison of the two, are exact; use it to decide
/// whether `p(x)` is distinguishable from zero where plain evaluation would overflow or sink
/// into subnormals.
///
/// ```
/// use nlrt_poly::{horner, horner_with_bound_scaled};
/// // x^3 at x = 1e-120: the plain value underflows to 0, the scaled one keeps its sign.
/// let c = [0.0, 0.0, 0.0, 1.0f64];
/// assert_eq!(horner(&c, 1e-120), 0.0);
/// let (v, bound) = horner_with_bound_scaled(&c, 1e-120);
/// assert!(v > bound);
/// ```
#[must_use]
#[inline]
pub fn horner_with_bound_scaled<T: Real, const N: usize>(c: &[T; N], x: T) -> (T, T) {
    if x == T::ZERO {
        return (c[0], T::ZERO);
    }
    let k = x.exponent();
    horner_with_bound(&rescale_variable(*c, k), x.scale_pow2(-k))
}

/// Whether a plain [`horner_with_bound`] result `(v, bound)` already shows `|p(x)|` beyond
/// the bound of [`horner_with_bound_scaled`] at the same point: value and bound finite, the
/// bound above the smallest normal (so nothing sank into subnormals), and `|v|` beyond 4x the
/// bound (the two evaluations round alike up to the bound's underflow term).
#[must_use]
#[inline(always)]
pub(crate) fn plainly_beyond_bound<T: Real>(v: T, bound: T) -> bool {
    v.is_finite()
        && bound.is_finite()
        && bound > T::MIN_POSITIVE
        && v.abs() > T::from_i32(4) * bound
}

/// The sign of `p(x)` where the rounding-error bound of [`horner_with_bound_scaled`] decides
/// it: `Some(true)` for certainly positive, `Some(false)` for certainly negative, `None` where
/// `|p(x)|` is within the bound. The same answer as comparing that function's value with its
/// bound, usually without its rescaling: where plain evaluation neither overflows nor sinks
/// below the normal range (value and bound finite, bound above the smallest normal), the two
/// evaluations round alike (the scaled one only multiplies every step by one power of two)
/// and differ only in the bound's underflow term, so a value beyond 4x the plain bound is
/// beyond the scaled one too, with the same sign.
///
/// ```
/// use nlrt_poly::decided_sign;
/// // (x - 1)(x - 2): positive at 0, negative at 1.5, undecided at the root 1.
/// let c = [2.0f64, -3.0, 1.0];
/// assert_eq!(decided_sign(&c, 0.0), Some(true));
/// assert_eq!(decided_sign(&c, 1.5), Some(false));
/// assert_eq!(decided_sign(&c, 1.0), None);
/// ```
#[must_use]
#[inline]
pub fn decided_sign<T: Real, const N: usize>(c: &[T; N], x: T) -> Option<bool> {
    let (v, bound) = horner_with_bound(c, x);
    if plainly_beyond_bound(v, bound) {
        return Some(v > T::ZERO);
    }
    let (v, bound) = horner_with_bound_scaled(c, x);
    if v > bound {
        Some(true)
    } else if v < -bound {
        Some(false)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    macro_rules! eval_tests {
        ($($t:ident),*) => {$(
            mod $t {
                use super::*;
                type T = $t;

                #[test]
                fn bound_covers_cancellation() {
                    // (x - 1)^3 near x = 1: heavy cancellation, exact value known.
                    let c: [T; 4] = [-1.0, 3.0, -3.0, 1.0];
                    for k in 1..20 {
                        let x = 1.0 + (k as T) * T::EPSILON * 64.0;
                        let (v, b) = horner_with_bound(&c, x);
                        let exact = ((x as f64) - 1.0).powi(3);
                        assert!(((v as f64) - exact).abs() <= b as f64, "x={x}: {v} vs {exact}, bound {b}");
                    }
                }

                #[test]
                fn normalize_keeps_roots_and_scales_by_power_of_two() {
                    let big = T::MAX / 16.0;
                    let c = normalize([big, -big, big / 4.0]);
                    let ratio = c[0] / big;
                    assert_eq!(ratio, T::pow2(ratio.exponent()));
                    assert_eq!(c[0] / c[2], 4.0);
                    assert!(c[0] >= 1.0 && c[0] < 2.0);
                    let small = normalize([1.0 as T, 2.0, 3.0]);
                    assert_eq!(small, [1.0, 2.0, 3.0]);
                }

                /// `decided_sign` gives the scaled comparison's answer on cubics of every
                /// scale, at points near and far from their roots, and at 0.
                #[test]
                fn decided_sign_equals_the_scaled_comparison() {
                    let mut s = 0x5eedu64;
                    let mut r = move || {
                        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                        (s >> 11) as f64 / (1u64 << 53) as f64
                    };
                    let mut undecided = 0;
                    for _ in 0..20000 {
                        let e = |r: &mut dyn FnMut() -> f64| {
                            let span = (T::MAX_EXPONENT / 2) as f64;
                            T::pow2(((r() * 2.0 - 1.0) * span) as i32)
                        };
                        let (root, scale) = (r() * 4.0 - 2.0, e(&mut r));
                        // scale (x - root)(x - 1/3)(x + 2), with one coefficient sometimes 0.
                        let mut c: [T; 4] = [
                            (2.0 * root / 3.0) as T,
                            (-(root * 5.0 / 3.0) - 2.0 / 3.0) as T,
                            (5.0 / 3.0 - root) as T,
                            1.0,
                        ]
                        .map(|v| v * scale);
                        if r() < 0.1 {
                            c[(r() * 4.0) as usize % 4] = 0.0;
                        }
                        let x = match (r() * 4.0) as u32 {
                            0 => root as T,
                            1 => (root as T) * (1.0 + T::EPSILON * (r() * 64.0 - 32.0) as T),
                            2 => 0.0,
                            _ => (r() * 8.0 - 4.0) as T * e(&mut r),
                        };
                        let (v, b) = horner_with_bound_scaled(&c, x);
                        let want = if v > b { Some(true) } else if v < -b { Some(false) } else { None };
                        assert_eq!(decided_sign(&c, x), want, "{c:?} at {x}");
                        undecided += usize::from(want.is_none());
                    }
                    assert!(undecided > 100, "{undecided}");
                }

                #[test]
                fn error_bound_is_the_plain_fma_bit_for_bit() {
                    // Every binade of m (subnormal to the largest), several significands each,
                    // the edges of the scaled path, and the special values; degrees 1 to 3.
                    let mut state = 0x9e37_79b9_7f4a_7c15u64;
                    let mut next = || {
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        state
                    };
                    let check = |m: T| {
                        for degree in 1..=3 {
                            let d = degree as T;
                            let factor = 2.0 * d * (T::EPSILON / 2.0);
                            let plain = factor.mul_add(m, d * T::from_bits(1));
                            let fast = super::super::error_bound::<T>(degree, m);
                            assert_eq!(fast.to_bits(), plain.to_bits(), "degree {degree}, m {m:e}");
                        }
                    };
                    for m in [0.0, T::INFINITY, T::NAN, T::MAX, T::MIN_POSITIVE, T::from_bits(1)] {
                        check(m);
                    }
                    let bits = 8 * core::mem::size_of::<T>() as u32;
                    let significand = T::MANTISSA_DIGITS - 1;
                    for biased in 0..(1u64 << (bits - 1 - significand)) - 1 {
                        for _ in 0..16 {
                            let low = next() & ((1u64 << significand) - 1);
                            check(T::from_bits(((biased << significand) | low) as _));
                        }
                    }
                    // m where the scaled result crosses its threshold, for each degree.
                    for degree in 1..=3 {
                        let factor = 2.0 * degree as T * (T::EPSILON / 2.0);
                        let mut m = T::MIN_POSITIVE / factor;
                        for _ in 0..32 {
                            m = m.next_down();
                        }
                        for _ in 0..64 {
                            check(m);
                            m = m.next_up();
                        }
                    }
                }

                #[test]
                fn rescaled_variable_has_scaled_roots() {
                    // (x - 2^20)(x - 3 * 2^20): with k = 20 the roots become 1 and 3.
                    let s = (1u64 << 20) as T;
                    let c: [T; 3] = [3.0 * s * s, -4.0 * s, 1.0];
                    let m = rescale_variable(c, 20);
                    assert_eq!(horner(&m, 1.0), 0.0);
                    assert_eq!(horner(&m, 3.0), 0.0);
                }
            }
        )*};
    }
    eval_tests!(f32, f64);
}

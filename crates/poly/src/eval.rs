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
    let degree = T::from_i32(N as i32 - 1);
    let bound = (T::TWO * degree * T::UNIT_ROUNDOFF).mul_add(m, degree * T::from_bits_u64(1));
    (r, bound)
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

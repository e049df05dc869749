//! Eight quadratics at once: [`solve_quadratic_in`] for callers that solve several quadratics
//! on one interval (a ray against a texel's edge lines, its diagonal and the base triangle's
//! edges, Ogaki 2023 Eq. 9-10).
//!
//! The answers are those of [`solve_quadratic_in`], bit for bit, for every input. The vector
//! kernel follows the scalar solver's fast path operation by operation in eight lanes (one AVX
//! register of `f32` or two of `f64` where the build has AVX2 and FMA, eight scalars
//! otherwise; every operation is exact or correctly rounded in all of them): the
//! discriminant with Kahan's correction, the two stable root formulas (or the one root of a
//! linear polynomial), and the check of a root outside the interval against the
//! polynomial's value at the end it crossed. A lane it cannot decide exactly as the scalar
//! solver would (a reversed or NaN interval, coefficients outside the fast path's window, a
//! root outside the interval whose end value is not plainly beyond its rounding bound) is
//! handed to the scalar solver.

use crate::eval::safe_coefficient_exponent;
use crate::lanes::{LANES, LaneMask, Lanes};
use crate::{Real, Roots, solve_quadratic_in};

/// How many quadratics [`solve_quadratic_batch_in`] takes at once.
pub const QUADRATIC_BATCH: usize = LANES;

/// [`solve_quadratic_in`] for eight quadratics given by coefficient (`c[k][i]` is the
/// coefficient of `x^k` of quadratic `i`): `roots[i]` is `solve_quadratic_in([c[0][i],
/// c[1][i], c[2][i]], lo[i], hi[i])`, bit for bit.
///
/// ```
/// use nlrt_poly::{QUADRATIC_BATCH, solve_quadratic_batch_in, solve_quadratic_in};
/// // (x - 0.1 k)(x - 0.7) for k = 1..=8, on [0, 0.5].
/// let a: [f32; QUADRATIC_BATCH] = core::array::from_fn(|k| 0.1 * (k + 1) as f32);
/// let c = [a.map(|a| a * 0.7), a.map(|a| -(a + 0.7)), [1.0; QUADRATIC_BATCH]];
/// let roots = solve_quadratic_batch_in(&c, &[0.0; QUADRATIC_BATCH], &[0.5; QUADRATIC_BATCH]);
/// for k in 0..QUADRATIC_BATCH {
///     let scalar = solve_quadratic_in([c[0][k], c[1][k], c[2][k]], 0.0, 0.5);
///     assert_eq!(roots[k], scalar);
/// }
/// assert_eq!(roots[0].len(), 1);
/// assert_eq!(roots[7].len(), 0);
/// ```
#[must_use]
pub fn solve_quadratic_batch_in<T: Real>(
    c: &[[T; QUADRATIC_BATCH]; 3],
    lo: &[T; QUADRATIC_BATCH],
    hi: &[T; QUADRATIC_BATCH],
) -> [Roots<T>; QUADRATIC_BATCH] {
    let mut out = [Roots::none(); QUADRATIC_BATCH];
    solve_into::<T, T::Batch>(c, lo, hi, &mut out);
    out
}

/// Quadratics collected for one interval, each with a tag, solved eight at a time by
/// [`solve_quadratic_batch_in`]: for a caller that decides one by one which quadratics it
/// needs (a texel's edge lines, its diagonal, the base edges) and wants their roots together.
/// Holds up to [`QuadraticBatch::CAPACITY`].
///
/// ```
/// use nlrt_poly::QuadraticBatch;
/// let mut batch = QuadraticBatch::<f64>::default();
/// batch.add([2.0, -3.0, 1.0], 7); // roots 1, 2
/// batch.add([-0.25, 0.0, 1.0], 9); // roots -0.5, 0.5
/// let mut found = Vec::new();
/// batch.solve(0.0, 1.5, |root, tag| found.push((root, tag)));
/// assert_eq!(found, [(1.0, 7), (0.5, 9)]);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct QuadraticBatch<T: Real> {
    coefficients: [[[T; QUADRATIC_BATCH]; 3]; 2],
    tags: [u8; 2 * QUADRATIC_BATCH],
    len: usize,
}

impl<T: Real> Default for QuadraticBatch<T> {
    fn default() -> Self {
        Self {
            coefficients: [[[T::ZERO; QUADRATIC_BATCH]; 3]; 2],
            tags: [0; 2 * QUADRATIC_BATCH],
            len: 0,
        }
    }
}

impl<T: Real> QuadraticBatch<T> {
    /// The most quadratics one batch holds: two batches of eight.
    pub const CAPACITY: usize = 2 * QUADRATIC_BATCH;

    /// Adds the quadratic `q` (ascending coefficients) with `tag`.
    ///
    /// # Panics
    /// When [`QuadraticBatch::CAPACITY`] quadratics are already held.
    #[inline(always)]
    pub fn add(&mut self, q: [T; 3], tag: u8) {
        assert!(
            self.len < Self::CAPACITY,
            "QuadraticBatch holds at most {} quadratics",
            Self::CAPACITY
        );
        let (batch, lane) = (self.len / QUADRATIC_BATCH, self.len % QUADRATIC_BATCH);
        for (k, c) in q.into_iter().enumerate() {
            self.coefficients[batch][k][lane] = c;
        }
        self.tags[self.len] = tag;
        self.len += 1;
    }

    /// How many quadratics are held.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether none is held.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// `found(root, tag)` for each root in `[lo, hi]` of each quadratic, in the order they
    /// were added, each one's roots increasing: [`solve_quadratic_in`]'s roots, bit for bit.
    /// A batch of one quadratic is solved alone (the vector pass would leave seven lanes
    /// idle; from two on it measured faster in the texel test, `nlrt_accel`).
    #[inline(always)]
    pub fn solve(&self, lo: T, hi: T, mut found: impl FnMut(T, u8)) {
        let ends = ([lo; QUADRATIC_BATCH], [hi; QUADRATIC_BATCH]);
        for (batch, coefficients) in self.coefficients.iter().enumerate() {
            let first = batch * QUADRATIC_BATCH;
            let count = self.len.saturating_sub(first).min(QUADRATIC_BATCH);
            if count == 1 {
                let q = [coefficients[0][0], coefficients[1][0], coefficients[2][0]];
                for &r in solve_quadratic_in(q, lo, hi).iter() {
                    found(r, self.tags[first]);
                }
            } else if count > 1 {
                let roots = solve_quadratic_batch_in(coefficients, &ends.0, &ends.1);
                for (i, r) in roots[..count].iter().enumerate() {
                    for &r in r.iter() {
                        found(r, self.tags[first + i]);
                    }
                }
            }
        }
    }
}

/// The batch solve through lanes `L` into `out`; returns the lanes the vector kernel decided
/// (bit `i`), the others having been solved by [`solve_quadratic_in`].
#[inline(always)]
pub(crate) fn solve_into<T: Real, L: Lanes<T>>(
    c: &[[T; LANES]; 3],
    lo: &[T; LANES],
    hi: &[T; LANES],
    out: &mut [Roots<T>; LANES],
) -> u8 {
    let (c0, c1, c2) = (
        L::from_array(c[0]),
        L::from_array(c[1]),
        L::from_array(c[2]),
    );
    let (lo_l, hi_l) = (L::from_array(*lo), L::from_array(*hi));
    let zero = L::splat(T::ZERO);
    let max = L::splat(T::MAX);
    let finite = |x: L| x.abs().le(max);

    // `solve_quadratic`'s fast path: no coefficient outside [2^-S, 2^S] relative to 1, c0 and
    // c2 non-zero and within 2^S of each other (so no rescaling), and an interval.
    let (a0, a2) = (c0.abs(), c2.abs());
    let sum = a0 + c1.abs() + a2;
    let big = L::splat(T::pow2(safe_coefficient_exponent::<T>()));
    let small = L::splat(T::pow2(-safe_coefficient_exponent::<T>()));
    let fast = sum.le(big)
        & sum.ge(small)
        & a0.ge(a2 * small)
        & a2.ge(a0 * small)
        & a2.gt(zero)
        & lo_l.le(hi_l);

    // `roots_of_scaled` with k = 0.
    let d = discriminant_lanes::<T, L>(c0, c1, c2);
    let real = d.ge(zero);
    let double = d.eq(zero);
    let q = (-(c1 + L::select(real, d, zero).sqrt().copysign(c1))) * L::splat(T::HALF);
    let (r1, r2) = (q / c2, c0 / q);
    let ordered = r1.le(r2);
    // The candidates in the scalar solver's order: the double root alone (pushed as it is:
    // a non-finite one is left to the scalar solver), or the smaller then the larger, each
    // only where finite.
    let first = L::select(double, r1, L::select(ordered, r1, r2));
    let second = L::select(ordered, r2, r1);
    let has_first = real & finite(first);
    let has_second = real & !double & finite(second);
    let fast = fast & !(double & !finite(r1));

    // The linear case of `solve_quadratic_general` (`c[2] == 0`, the others finite): the
    // root `-c0 / c1` where `c1 != 0` and it is finite. A ray's curve is a straight line
    // wherever the prism's normals are parallel, so its quadratics are linear there.
    let linear = c2.eq(zero) & finite(c0) & finite(c1) & lo_l.le(hi_l);
    let root = (-c0) / c1;
    let has_root = c1.ne(zero) & finite(root);
    let first = L::select(linear, root, first);
    let has_first = (linear & has_root) | (!linear & has_first);
    let has_second = has_second & !linear;
    let fast = fast | linear;

    // `is_pseudo_root` at an end: decided here only where the plain evaluation is plainly
    // beyond its bound (then the end is no root); otherwise the scalar solver decides.
    let plainly_beyond = |x: L| {
        let ax = x.abs();
        let v = c2.mul_add(x, c1).mul_add(x, c0);
        let m = a2.mul_add(ax, c1.abs()).mul_add(ax, a0);
        // `error_bound(2, m)` where its scaled form applies.
        let p = T::MANTISSA_DIGITS as i32;
        let degree = T::TWO;
        let factor = T::TWO * degree * T::UNIT_ROUNDOFF;
        let scaled = L::splat(factor * T::pow2(p))
            .mul_add(m, L::splat(degree * T::pow2(T::MIN_EXPONENT + 1)));
        let scaled_ok = scaled.gt(L::splat(T::pow2(T::MIN_EXPONENT + p))) & finite(scaled);
        let bound = scaled * L::splat(T::pow2(-p));
        scaled_ok
            & finite(v)
            & finite(bound)
            & bound.gt(L::splat(T::MIN_POSITIVE))
            & v.abs().gt(L::splat(T::from_i32(4)) * bound)
    };
    let (beyond_lo, beyond_hi) = (plainly_beyond(lo_l), plainly_beyond(hi_l));
    // A candidate inside is kept; one outside needs its end decided.
    let decided = |has: L::Mask, r: L| {
        let below = r.lt(lo_l);
        let above = r.gt(hi_l);
        let ok = !has | !(below | above) | (below & beyond_lo) | (above & beyond_hi);
        (has & !below & !above, ok)
    };
    let (keep_first, ok_first) = decided(has_first, first);
    let (keep_second, ok_second) = decided(has_second, second);
    let handled = (fast & ok_first & ok_second).bits();
    // The scalar solver drops a second root equal to the first it kept.
    let keep_second = keep_second & !(keep_first & second.eq(first));
    let (keep_first, keep_second) = (keep_first.bits(), keep_second.bits());
    let (first, second) = (first.to_array(), second.to_array());
    for (i, o) in out.iter_mut().enumerate() {
        if handled >> i & 1 == 0 {
            *o = solve_quadratic_in([c[0][i], c[1][i], c[2][i]], lo[i], hi[i]);
            continue;
        }
        let mut roots = Roots::none();
        if keep_first >> i & 1 == 1 {
            roots.push(first[i]);
        }
        if keep_second >> i & 1 == 1 {
            roots.push(second[i]);
        }
        *o = roots;
    }
    handled
}

/// [`crate::discriminant`] lane by lane: `b^2 - 4ac` with Kahan's FMA correction, the same
/// operations in the same order (the batch solvers of quadratics and of cubics' critical
/// points share it).
#[inline(always)]
pub(crate) fn discriminant_lanes<T: Real, L: Lanes<T>>(a0: L, a1: L, a2: L) -> L {
    let p = a1 * a1;
    let four_a2 = a2 * L::splat(T::from_i32(4));
    let q = four_a2 * a0;
    let dp = a1.mul_add(a1, -p);
    let dq = four_a2.mul_add(a0, -q);
    (p - q) + (dp - dq)
}

#[cfg(test)]
mod tests {
    //! Batch == scalar, bit for bit, through every lane implementation this build has: on
    //! quadratics with roots at, near and across the interval's ends, double and nearly
    //! double roots, extreme coefficients and raw bit patterns; and how many lanes the vector
    //! kernel decided, so that the equality cannot hold through the scalar fallback alone.
    extern crate std;
    use super::solve_into;
    use crate::lanes::{LANES, Lanes, Portable};
    use crate::{Real, Roots, solve_quadratic_in};
    use nlrt_oracle::families::SplitMix64;
    use std::vec::Vec;

    type Input<T> = ([T; 3], T, T);

    /// Checks lanes `L` on `inputs` in batches of eight (the remainder padded with the first
    /// input); returns how many lanes the vector kernel decided.
    fn decided_by<T: Real, L: Lanes<T>>(inputs: &[Input<T>]) -> usize {
        let mut decided = 0;
        for chunk in inputs.chunks(LANES) {
            let pick = |i: usize| chunk.get(i).copied().unwrap_or(chunk[0]);
            let c: [[T; LANES]; 3] =
                core::array::from_fn(|k| core::array::from_fn(|i| pick(i).0[k]));
            let lo: [T; LANES] = core::array::from_fn(|i| pick(i).1);
            let hi: [T; LANES] = core::array::from_fn(|i| pick(i).2);
            let mut roots = [Roots::none(); LANES];
            let handled = solve_into::<T, L>(&c, &lo, &hi, &mut roots);
            for i in 0..chunk.len() {
                let scalar = solve_quadratic_in(pick(i).0, lo[i], hi[i]);
                let same = roots[i].len() == scalar.len()
                    && roots[i]
                        .iter()
                        .zip(scalar.iter())
                        .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(
                    same,
                    "{}: batch {:?} != scalar {:?} for {:?} on [{:e}, {:e}] (decided: {})",
                    T::NAME,
                    roots[i],
                    scalar,
                    pick(i).0,
                    lo[i],
                    hi[i],
                    handled >> i & 1
                );
                decided += usize::from(handled >> i & 1);
            }
        }
        decided
    }

    /// Quadratics `s (x - r1)(x - r2)` whose roots lie at, near and across the ends of
    /// their interval (ends placed at a root, one ulp either side, or far), with double and
    /// nearly double roots, and coefficients scaled over a wide exponent range.
    fn hard<T: Real>(rng: &mut SplitMix64, n: usize) -> Vec<Input<T>> {
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let unit = |rng: &mut SplitMix64| T::from_f64(rng.unit() * 2.0 - 1.0);
            let r1 = unit(rng);
            let r2 = match k % 4 {
                0 => r1,
                1 => r1.next_up().next_up(),
                2 => r1 + unit(rng) * T::from_f64(1e-3),
                _ => unit(rng) * T::from_f64(4.0),
            };
            let scale = T::from_f64(2f64.powi((rng.unit() * 40.0 - 20.0) as i32));
            let s = if k % 3 == 0 { -scale } else { scale };
            // Every fifth is linear, as a straight curve's (`c[2] == 0`).
            let c = if k % 5 == 4 {
                [-s * r1, s, T::ZERO]
            } else {
                [s * r1 * r2, -s * (r1 + r2), s]
            };
            let end = |rng: &mut SplitMix64, r: T| match rng.unit() {
                x if x < 0.2 => r,
                x if x < 0.35 => r.next_up(),
                x if x < 0.5 => r.next_down(),
                _ => unit(rng) * T::from_f64(2.0),
            };
            let (a, b) = (end(rng, r1), end(rng, r2));
            let (lo, hi) = if k % 7 == 0 {
                (b, a)
            } else {
                (a.min(b), a.max(b))
            };
            out.push((c, lo, hi));
        }
        out
    }

    /// Raw bit patterns and special values: NaN, infinities, zeros, subnormals, huge.
    fn raw<T: Real>(rng: &mut SplitMix64, n: usize) -> Vec<Input<T>> {
        let specials = [
            T::ZERO,
            -T::ZERO,
            T::ONE,
            T::NAN,
            T::INFINITY,
            T::NEG_INFINITY,
            T::MAX,
            T::MIN_POSITIVE,
            T::from_bits_u64(1),
        ];
        (0..n)
            .map(|k| {
                let mut value = |j: usize| {
                    if (k + j).is_multiple_of(5) {
                        specials[(k * 3 + j) % specials.len()]
                    } else {
                        T::from_bits_u64(rng.next_u64())
                    }
                };
                ([value(0), value(1), value(2)], value(3), value(4))
            })
            .collect()
    }

    /// Quadratics with random roots in `[-1, 1]` on random intervals (a quarter of them
    /// linear): ends rarely within rounding of a root, as in a ray's walk.
    fn typical<T: Real>(rng: &mut SplitMix64, n: usize) -> Vec<Input<T>> {
        (0..n)
            .map(|_| {
                let mut unit = || T::from_f64(rng.range(-1.0, 1.0));
                let (r1, r2, s) = (unit(), unit(), unit());
                let (a, b) = (unit(), unit());
                let c2 = if r1 > T::HALF { T::ZERO } else { s };
                ([s * r1 * r2, -s * (r1 + r2), c2], a.min(b), a.max(b))
            })
            .collect()
    }

    fn batch_equals_scalar<T: Real>() {
        let mut rng = SplitMix64::new(0x9e37_79b9);
        let typical = typical::<T>(&mut rng, 20_000);
        let hard = hard::<T>(&mut rng, 20_000);
        let raw = raw::<T>(&mut rng, 4_000);
        // The kernel decides nearly every typical lane; of the hard ones (a seventh with
        // reversed intervals, a third with ends placed on a root) about half go to the scalar
        // fallback, which is why only the typical share is asserted.
        let decided = decided_by::<T, Portable<T>>(&typical);
        assert!(
            decided * 100 >= typical.len() * 99,
            "{}: the vector kernel decided only {decided} of {} typical lanes",
            T::NAME,
            typical.len()
        );
        let decided_hard = decided_by::<T, Portable<T>>(&hard);
        assert!(
            decided_hard * 2 >= hard.len(),
            "{}: the vector kernel decided only {decided_hard} of {} hard lanes",
            T::NAME,
            hard.len()
        );
        decided_by::<T, Portable<T>>(&raw);
        assert_eq!(decided_by::<T, T::Batch>(&typical), decided);
        assert_eq!(decided_by::<T, T::Batch>(&hard), decided_hard);
        decided_by::<T, T::Batch>(&raw);
    }

    /// A [`super::QuadraticBatch`] of every size up to its capacity reports the scalar
    /// solver's roots, in the order the quadratics were added, with their tags.
    fn collected_batch_equals_scalar<T: Real>() {
        let mut rng = SplitMix64::new(0x51ed_270b);
        let inputs = typical::<T>(&mut rng, 64);
        let (lo, hi) = (T::from_f64(-0.5), T::from_f64(0.75));
        for size in 0..=super::QuadraticBatch::<T>::CAPACITY {
            let mut batch = super::QuadraticBatch::default();
            let mut expected = Vec::new();
            for (k, (q, _, _)) in inputs[size..2 * size].iter().enumerate() {
                batch.add(*q, k as u8);
                expected.extend(
                    solve_quadratic_in(*q, lo, hi)
                        .iter()
                        .map(|r| (r.to_bits(), k as u8)),
                );
            }
            assert_eq!(batch.len(), size);
            let mut found = Vec::new();
            batch.solve(lo, hi, |r, tag| found.push((r.to_bits(), tag)));
            assert_eq!(found, expected, "{}: {size} quadratics", T::NAME);
        }
    }

    #[test]
    fn collected_batch_equals_scalar_f32() {
        collected_batch_equals_scalar::<f32>();
    }

    #[test]
    fn collected_batch_equals_scalar_f64() {
        collected_batch_equals_scalar::<f64>();
    }

    #[test]
    #[should_panic(expected = "at most 16")]
    fn a_full_batch_refuses_another() {
        let mut batch = super::QuadraticBatch::<f32>::default();
        for k in 0..=16 {
            batch.add([1.0, 0.0, -1.0], k);
        }
    }

    #[test]
    fn batch_equals_scalar_f32() {
        batch_equals_scalar::<f32>();
    }

    #[test]
    fn batch_equals_scalar_f64() {
        batch_equals_scalar::<f64>();
    }
}

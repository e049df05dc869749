//! The one scalar trait of the workspace: every numeric kernel is written once, generic over
//! [`Real`], and instantiated for `f32` and `f64`.
//!
//! The trait is sealed: the solvers' error analysis (unit roundoff, exponent range, exact
//! power-of-two scaling) is only valid for IEEE-754 binary32 and binary64.

use core::fmt::{Debug, Display, LowerExp};
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, Sub, SubAssign};

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// An IEEE-754 binary floating-point type (`f32` or `f64`) with the operations the kernels need.
///
/// Math functions are routed to `std` when the `std` feature is on, and to the `libm` crate
/// otherwise. [`Real::mul_add`] is always a correctly rounded fused multiply-add; it is one
/// hardware instruction when the build enables the `fma` target feature (see
/// [`Real::FMA_IN_HARDWARE`]).
///
/// ```
/// use nlrt_poly::Real;
/// fn hypot_sq<T: Real>(a: T, b: T) -> T {
///     a.mul_add(a, b * b)
/// }
/// assert_eq!(hypot_sq(3.0f32, 4.0), 25.0);
/// assert_eq!(hypot_sq(3.0f64, 4.0), 25.0);
/// ```
pub trait Real:
    sealed::Sealed
    + Copy
    + Debug
    + Display
    + LowerExp
    + Default
    + PartialEq
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Rem<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Send
    + Sync
    + 'static
{
    /// The matching glam 2-vector (`Vec2` or `DVec2`).
    type Vec2: crate::Vector2<Self>;
    /// The matching glam 3-vector (`Vec3` or `DVec3`).
    type Vec3: crate::Vector3<Self>;
    /// The matching glam 3x3 matrix (`Mat3` or `DMat3`).
    type Mat3: Copy + Debug + PartialEq + Send + Sync + 'static;
    /// The unsigned integer of the same width, for bit manipulation.
    type Bits: Copy + Debug + Eq + Ord;
    /// Eight values side by side for the batch solvers (one AVX register of `f32` or two of
    /// `f64` where the build has AVX2 and FMA, eight scalars otherwise). An implementation
    /// detail of [`crate::solve_cubic_batch_in`].
    #[doc(hidden)]
    type Batch: crate::lanes::Lanes<Self>;
    /// Four values side by side for the walks' child steps (one SSE register of `f32` or one
    /// AVX register of `f64` where the build has AVX2 and FMA, four scalars otherwise).
    type Four: crate::Lanes4<Self>;

    /// 0
    const ZERO: Self;
    /// 1
    const ONE: Self;
    /// 2
    const TWO: Self;
    /// 3
    const THREE: Self;
    /// 0.5
    const HALF: Self;
    /// Machine epsilon: the distance from 1 to the next larger number, 2^(1-p).
    const EPSILON: Self;
    /// Unit roundoff u = 2^-p, the relative error bound of one correctly rounded operation.
    const UNIT_ROUNDOFF: Self;
    /// Largest finite value.
    const MAX: Self;
    /// Smallest positive normal value.
    const MIN_POSITIVE: Self;
    /// +infinity
    const INFINITY: Self;
    /// -infinity
    const NEG_INFINITY: Self;
    /// A quiet NaN.
    const NAN: Self;
    /// Significand precision p in bits, counting the implicit bit (24 or 53).
    const MANTISSA_DIGITS: u32;
    /// Unbiased exponent of [`Real::MAX`] (127 or 1023).
    const MAX_EXPONENT: i32;
    /// Unbiased exponent of [`Real::MIN_POSITIVE`] (-126 or -1022).
    const MIN_EXPONENT: i32;
    /// Storage width in bits.
    const BITS: u32;
    /// Name for reports: `"f32"` or `"f64"`.
    const NAME: &'static str;
    /// Whether this build computes [`Real::mul_add`] with a hardware FMA instruction.
    const FMA_IN_HARDWARE: bool = cfg!(target_feature = "fma");

    /// Rounds an `f64` to this type (exact for `f64`).
    #[must_use]
    fn from_f64(x: f64) -> Self;
    /// Widens to `f64` (always exact).
    #[must_use]
    fn to_f64(self) -> f64;
    /// Converts a small integer exactly (|i| < 2^24).
    #[must_use]
    fn from_i32(i: i32) -> Self;

    /// Absolute value.
    #[must_use]
    fn abs(self) -> Self;
    /// Correctly rounded square root.
    #[must_use]
    fn sqrt(self) -> Self;
    /// Cube root.
    #[must_use]
    fn cbrt(self) -> Self;
    /// `self * a + b` with one rounding.
    #[must_use]
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// Magnitude of `self` with the sign of `sign`.
    #[must_use]
    fn copysign(self, sign: Self) -> Self;
    /// Arc cosine (used by the closed-form baseline only).
    #[must_use]
    fn acos(self) -> Self;
    /// Cosine (used by the closed-form baseline only).
    #[must_use]
    fn cos(self) -> Self;
    /// Smaller of two values, ignoring a NaN operand.
    #[must_use]
    fn min(self, other: Self) -> Self;
    /// Larger of two values, ignoring a NaN operand.
    #[must_use]
    fn max(self, other: Self) -> Self;
    /// Neither infinite nor NaN.
    #[must_use]
    fn is_finite(self) -> bool;
    /// Is NaN.
    #[must_use]
    fn is_nan(self) -> bool;
    /// Sign bit set (true for -0.0 too).
    #[must_use]
    fn is_sign_negative(self) -> bool;
    /// Raw IEEE bits.
    #[must_use]
    fn to_bits(self) -> Self::Bits;
    /// From raw IEEE bits.
    #[must_use]
    fn from_bits(bits: Self::Bits) -> Self;
    /// Raw bits widened to `u64` (for decoding fuzz input and for reports).
    #[must_use]
    fn to_bits_u64(self) -> u64;
    /// From the low [`Real::BITS`] bits of a `u64`.
    #[must_use]
    fn from_bits_u64(bits: u64) -> Self;

    /// `floor(log2(|self|))` for finite non-zero values, subnormals included; `i32::MIN` for
    /// zero, `i32::MAX` for infinities and NaN.
    #[must_use]
    fn exponent(self) -> i32 {
        if self == Self::ZERO {
            return i32::MIN;
        }
        if !self.is_finite() {
            return i32::MAX;
        }
        let bits = self.to_bits_u64();
        let frac_bits = Self::MANTISSA_DIGITS - 1;
        let exp_mask = (1u64 << (Self::BITS - 1 - frac_bits)) - 1;
        let biased = ((bits >> frac_bits) & exp_mask) as i32;
        let bias = Self::MAX_EXPONENT;
        if biased != 0 {
            biased - bias
        } else {
            // Subnormal: the leading one of the fraction field sets the exponent.
            let frac = bits & ((1u64 << frac_bits) - 1);
            let top = 63 - frac.leading_zeros() as i32; // position of the leading one
            1 - bias - (frac_bits as i32 - top)
        }
    }

    /// `self * 2^n`, exact unless the result overflows or is subnormal (like C's `scalbn`).
    #[must_use]
    fn scale_pow2(self, n: i32) -> Self {
        // 2^k is only representable for MIN_EXPONENT <= k <= MAX_EXPONENT, so larger shifts
        // are applied in up to three steps; the final multiply rounds at most once.
        let mut x = self;
        let mut n = n;
        let max = Self::MAX_EXPONENT;
        let min = Self::MIN_EXPONENT;
        if n > max {
            x *= Self::pow2(max);
            n -= max;
            if n > max {
                x *= Self::pow2(max);
                n -= max;
                n = n.min(max);
            }
        } else if n < min {
            // Step by 2^(min + p - 1) so that intermediate results stay normal where possible.
            let step = min + Self::MANTISSA_DIGITS as i32 - 1;
            x *= Self::pow2(step);
            n -= step;
            if n < min {
                x *= Self::pow2(step);
                n -= step;
                n = n.max(min);
            }
        }
        x * Self::pow2(n)
    }

    /// 2^n for `MIN_EXPONENT <= n <= MAX_EXPONENT`, built from its bits.
    #[must_use]
    fn pow2(n: i32) -> Self {
        debug_assert!((Self::MIN_EXPONENT..=Self::MAX_EXPONENT).contains(&n));
        let biased = (n + Self::MAX_EXPONENT) as u64;
        Self::from_bits_u64(biased << (Self::MANTISSA_DIGITS - 1))
    }

    /// Maps the floats onto the integers monotonically (-0.0 and +0.0 both to 0), so that the
    /// difference of two keys counts the representable numbers between them.
    #[must_use]
    fn ordered_key(self) -> i64 {
        let bits = self.to_bits_u64();
        let sign = 1u64 << (Self::BITS - 1);
        if bits & sign != 0 {
            -((bits & !sign) as i64)
        } else {
            bits as i64
        }
    }

    /// Inverse of [`Real::ordered_key`].
    #[must_use]
    fn from_ordered_key(key: i64) -> Self {
        if key < 0 {
            Self::from_bits_u64((1u64 << (Self::BITS - 1)) | key.unsigned_abs())
        } else {
            Self::from_bits_u64(key as u64)
        }
    }

    /// The number halfway between `a` and `b` in representation order: a bisection on this
    /// point halves the count of floats in the bracket, so it ends after at most
    /// [`Real::BITS`] steps however wide the bracket is.
    #[must_use]
    fn bisect_ordered(a: Self, b: Self) -> Self {
        let (ka, kb) = (a.ordered_key(), b.ordered_key());
        // Floor of the mean without overflow.
        Self::from_ordered_key((ka >> 1) + (kb >> 1) + (ka & kb & 1))
    }

    /// The next representable value towards +infinity.
    #[must_use]
    fn next_up(self) -> Self {
        if self.is_nan() || self == Self::INFINITY {
            return self;
        }
        // Both zeros share key 0, so the step from the smallest negative subnormal is to zero
        // and the step from either zero is to the smallest positive subnormal.
        Self::from_ordered_key(self.ordered_key() + 1)
    }

    /// The next representable value towards -infinity.
    #[must_use]
    fn next_down(self) -> Self {
        -(-self).next_up()
    }
}

/// Implements [`Real`] for one float type; `$f` names the libm functions of that type.
macro_rules! impl_real {
    (
        $t:ident, $bits:ty, $vec2:ty, $vec3:ty, $mat3:ty, batch: $batch:ty, four: $four:ty,
        sqrt: $sqrt:ident, cbrt: $cbrt:ident, fma: $fma:ident, acos: $acos:ident, cos: $cos:ident,
        hw_fma: $hw_fma:ident, set: $set:ident, get: $get:ident
    ) => {
        impl Real for $t {
            type Vec2 = $vec2;
            type Vec3 = $vec3;
            type Mat3 = $mat3;
            type Bits = $bits;
            type Batch = $batch;
            type Four = $four;

            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const TWO: Self = 2.0;
            const THREE: Self = 3.0;
            const HALF: Self = 0.5;
            const EPSILON: Self = <$t>::EPSILON;
            const UNIT_ROUNDOFF: Self = <$t>::EPSILON * 0.5;
            const MAX: Self = <$t>::MAX;
            const MIN_POSITIVE: Self = <$t>::MIN_POSITIVE;
            const INFINITY: Self = <$t>::INFINITY;
            const NEG_INFINITY: Self = <$t>::NEG_INFINITY;
            const NAN: Self = <$t>::NAN;
            const MANTISSA_DIGITS: u32 = <$t>::MANTISSA_DIGITS;
            const MAX_EXPONENT: i32 = <$t>::MAX_EXP - 1;
            const MIN_EXPONENT: i32 = <$t>::MIN_EXP - 1;
            const BITS: u32 = <$bits>::BITS;
            const NAME: &'static str = stringify!($t);

            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn from_i32(i: i32) -> Self {
                i as $t
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                #[cfg(feature = "std")]
                {
                    <$t>::sqrt(self)
                }
                #[cfg(not(feature = "std"))]
                {
                    libm::$sqrt(self)
                }
            }
            #[inline(always)]
            fn cbrt(self) -> Self {
                #[cfg(feature = "std")]
                {
                    <$t>::cbrt(self)
                }
                #[cfg(not(feature = "std"))]
                {
                    libm::$cbrt(self)
                }
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                #[cfg(feature = "std")]
                {
                    <$t>::mul_add(self, a, b)
                }
                #[cfg(all(not(feature = "std"), target_arch = "x86_64", target_feature = "fma"))]
                {
                    // `core` has no stable `mul_add`; the FMA3 intrinsic is one instruction.
                    use core::arch::x86_64::{$get, $hw_fma, $set};
                    // SAFETY: the `fma` target feature is enabled for this build (cfg above).
                    unsafe { $get($hw_fma($set(self), $set(a), $set(b))) }
                }
                #[cfg(all(
                    not(feature = "std"),
                    not(all(target_arch = "x86_64", target_feature = "fma"))
                ))]
                {
                    libm::$fma(self, a, b)
                }
            }
            #[inline(always)]
            fn copysign(self, sign: Self) -> Self {
                <$t>::copysign(self, sign)
            }
            #[inline]
            fn acos(self) -> Self {
                #[cfg(feature = "std")]
                {
                    <$t>::acos(self)
                }
                #[cfg(not(feature = "std"))]
                {
                    libm::$acos(self)
                }
            }
            #[inline]
            fn cos(self) -> Self {
                #[cfg(feature = "std")]
                {
                    <$t>::cos(self)
                }
                #[cfg(not(feature = "std"))]
                {
                    libm::$cos(self)
                }
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline(always)]
            fn is_sign_negative(self) -> bool {
                <$t>::is_sign_negative(self)
            }
            #[inline(always)]
            fn to_bits(self) -> $bits {
                <$t>::to_bits(self)
            }
            #[inline(always)]
            fn from_bits(bits: $bits) -> Self {
                <$t>::from_bits(bits)
            }
            #[inline(always)]
            fn to_bits_u64(self) -> u64 {
                <$t>::to_bits(self) as u64
            }
            #[inline(always)]
            fn from_bits_u64(bits: u64) -> Self {
                <$t>::from_bits(bits as $bits)
            }
        }
    };
}

impl_real!(f32, u32, glam::Vec2, glam::Vec3, glam::Mat3, batch: crate::lanes::F32Lanes, four: crate::lanes4::F32Lanes4,
    sqrt: sqrtf, cbrt: cbrtf, fma: fmaf, acos: acosf, cos: cosf,
    hw_fma: _mm_fmadd_ss, set: _mm_set_ss, get: _mm_cvtss_f32);
impl_real!(f64, u64, glam::DVec2, glam::DVec3, glam::DMat3, batch: crate::lanes::F64Lanes, four: crate::lanes4::F64Lanes4,
    sqrt: sqrt, cbrt: cbrt, fma: fma, acos: acos, cos: cos,
    hw_fma: _mm_fmadd_sd, set: _mm_set_sd, get: _mm_cvtsd_f64);

#[cfg(test)]
mod tests {
    use super::Real;

    macro_rules! real_tests {
        ($($t:ident),*) => {$(
            mod $t {
                use super::Real;
                type T = $t;

                #[test]
                fn exponent_matches_log2() {
                    assert_eq!(T::ONE.exponent(), 0);
                    assert_eq!((3.0 as T).exponent(), 1);
                    assert_eq!((0.75 as T).exponent(), -1);
                    assert_eq!(T::MAX.exponent(), T::MAX_EXPONENT);
                    assert_eq!(T::MIN_POSITIVE.exponent(), T::MIN_EXPONENT);
                    let tiny = T::from_bits_u64(1); // smallest subnormal
                    assert_eq!(tiny.exponent(), T::MIN_EXPONENT - (T::MANTISSA_DIGITS as i32 - 1));
                    assert_eq!(T::ZERO.exponent(), i32::MIN);
                    assert_eq!(T::NAN.exponent(), i32::MAX);
                }

                #[test]
                fn scale_pow2_is_exact_across_the_range() {
                    // A shift wider than the exponent range of one power of two.
                    let span = T::MAX_EXPONENT - T::MIN_EXPONENT;
                    let x = T::MIN_POSITIVE * 1.5;
                    assert_eq!(x.scale_pow2(span), T::pow2(T::MAX_EXPONENT) * 1.5);
                    assert_eq!((T::pow2(T::MAX_EXPONENT) * 1.5).scale_pow2(-span), x);
                    assert_eq!(T::ONE.scale_pow2(T::MIN_EXPONENT - 3), T::MIN_POSITIVE / 8.0);
                    assert_eq!(T::ONE.scale_pow2(10), 1024.0);
                    assert_eq!(T::ONE.scale_pow2(10_000), T::INFINITY);
                    assert_eq!(T::ONE.scale_pow2(-10_000), 0.0);
                }

                #[test]
                fn ordered_keys_count_floats() {
                    assert_eq!(T::ONE.next_up().ordered_key() - T::ONE.ordered_key(), 1);
                    assert_eq!((-T::ZERO).ordered_key(), 0);
                    assert_eq!(T::ZERO.next_down(), -T::from_bits_u64(1));
                    assert_eq!((-T::ZERO).next_up(), T::from_bits_u64(1));
                    assert_eq!(T::from_bits_u64(1).next_down(), 0.0);
                    assert_eq!((-T::from_bits_u64(1)).next_up(), 0.0);
                    assert_eq!(T::ONE.next_up() - T::ONE, T::EPSILON);
                    let m = T::bisect_ordered(-T::ONE, T::ONE);
                    assert_eq!(m, 0.0);
                    let m = T::bisect_ordered(T::ONE, T::MAX);
                    assert!(m > 1.0e10 && m < T::MAX / 1.0e10);
                }

                #[test]
                fn mul_add_rounds_once() {
                    // (1 + eps)(1 - eps) = 1 - eps^2: a separate multiply rounds it to 1.
                    let a = T::ONE + T::EPSILON;
                    let b = T::ONE - T::EPSILON;
                    assert_eq!(a.mul_add(b, -T::ONE), -(T::EPSILON * T::EPSILON));
                }
            }
        )*};
    }
    real_tests!(f32, f64);
}

//! Four values of one [`Real`] type side by side, for the walks' child steps: a node's four
//! children tested in one vector step. One trait, a portable implementation (four scalars,
//! each operation the [`Real`] one) and, where the build has AVX2 and FMA, one over `__m128`
//! (`f32`) and one over `__m256d` (`f64`). Every operation is exact, correctly rounded or a
//! comparison, so a kernel written once over [`Lanes4`] gives the same bits through either
//! (the walks' tests check it).

use crate::Real;
use crate::lanes::{LaneMask, PortableMask};
use core::ops::{Add, Div, Mul, Neg, Sub};

/// Four lanes of `T` with the operations of the walks' child steps (IEEE semantics per lane).
pub trait Lanes4<T: Real>:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The comparison result (bit `i` of [`LaneMask::bits`] is lane `i`).
    type Mask: LaneMask;
    /// Every lane `v`.
    fn splat(v: T) -> Self;
    /// Lane `i` from `v[i]`.
    fn from_array(v: [T; 4]) -> Self;
    /// Lane `i` into element `i`.
    fn to_array(self) -> [T; 4];
    /// `self * a + b`, one rounding.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `|self|`
    fn abs(self) -> Self;
    /// `self` where `self < o`, else `o` (the second operand when either is NaN: the
    /// semantics of `minps`, and of `if a < b { a } else { b }`).
    fn lesser(self, o: Self) -> Self;
    /// `self` where `self > o`, else `o` (the second operand when either is NaN: `maxps`).
    fn greater(self, o: Self) -> Self;
    /// `self <= o`, false on NaN.
    fn le(self, o: Self) -> Self::Mask;
    /// `self >= o`, false on NaN.
    fn ge(self, o: Self) -> Self::Mask;
    /// `self > o`, false on NaN.
    fn gt(self, o: Self) -> Self::Mask;
}

/// Four scalars: the reference implementation of [`Lanes4`], and the one used without AVX2
/// (the eight-lane portable type at width four).
pub type Portable4<T> = crate::lanes::Portable<T, 4>;

impl<T: Real> Lanes4<T> for Portable4<T> {
    type Mask = PortableMask<4>;
    #[inline(always)]
    fn splat(v: T) -> Self {
        Self([v; 4])
    }
    #[inline(always)]
    fn from_array(v: [T; 4]) -> Self {
        Self(v)
    }
    #[inline(always)]
    fn to_array(self) -> [T; 4] {
        self.0
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        self.fused(a, b)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.magnitude()
    }
    #[inline(always)]
    fn lesser(self, o: Self) -> Self {
        Self(core::array::from_fn(|i| {
            if self.0[i] < o.0[i] {
                self.0[i]
            } else {
                o.0[i]
            }
        }))
    }
    #[inline(always)]
    fn greater(self, o: Self) -> Self {
        Self(core::array::from_fn(|i| {
            if self.0[i] > o.0[i] {
                self.0[i]
            } else {
                o.0[i]
            }
        }))
    }
    #[inline(always)]
    fn le(self, o: Self) -> PortableMask<4> {
        self.compare(o, |a, b| a <= b)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> PortableMask<4> {
        self.compare(o, |a, b| a >= b)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> PortableMask<4> {
        self.compare(o, |a, b| a > b)
    }
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub use avx2::{F32x4, F64x4};

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
mod avx2 {
    //! `__m128` and `__m256d` lanes. SAFETY (every `unsafe` block below): the module is
    //! compiled only when the build enables `avx2` and `fma` (cfg above), so the intrinsics are
    //! available; the transmutes are between `[f32; 4]` and `__m128`, and between `[f64; 4]`
    //! and `__m256d`, which have the same size and no invalid bit patterns.
    use super::{LaneMask, Lanes4};
    use core::arch::x86_64::*;
    use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

    /// Four `f32` lanes in one SSE register.
    #[derive(Clone, Copy, Debug)]
    pub struct F32x4(__m128);

    /// All-ones or all-zeros per lane of [`F32x4`].
    #[derive(Clone, Copy, Debug)]
    pub struct Mask4(__m128);

    /// Four `f64` lanes in one AVX register.
    #[derive(Clone, Copy, Debug)]
    pub struct F64x4(__m256d);

    /// All-ones or all-zeros per lane of [`F64x4`].
    #[derive(Clone, Copy, Debug)]
    pub struct Mask4d(__m256d);

    macro_rules! mask {
        ($mask:ident, $and:ident, $or:ident, $xor:ident, $ones:expr, $movemask:ident) => {
            impl BitAnd for $mask {
                type Output = Self;
                #[inline(always)]
                fn bitand(self, o: Self) -> Self {
                    Self(unsafe { $and(self.0, o.0) })
                }
            }
            impl BitOr for $mask {
                type Output = Self;
                #[inline(always)]
                fn bitor(self, o: Self) -> Self {
                    Self(unsafe { $or(self.0, o.0) })
                }
            }
            impl Not for $mask {
                type Output = Self;
                #[inline(always)]
                fn not(self) -> Self {
                    Self(unsafe { $xor(self.0, $ones) })
                }
            }
            impl LaneMask for $mask {
                #[inline(always)]
                fn bits(self) -> u8 {
                    (unsafe { $movemask(self.0) }) as u8
                }
            }
        };
    }
    mask!(
        Mask4,
        _mm_and_ps,
        _mm_or_ps,
        _mm_xor_ps,
        _mm_castsi128_ps(_mm_set1_epi32(-1)),
        _mm_movemask_ps
    );
    mask!(
        Mask4d,
        _mm256_and_pd,
        _mm256_or_pd,
        _mm256_xor_pd,
        _mm256_castsi256_pd(_mm256_set1_epi64x(-1)),
        _mm256_movemask_pd
    );

    macro_rules! binary {
        ($lanes:ident, $trait:ident, $f:ident, $intrinsic:ident) => {
            impl $trait for $lanes {
                type Output = Self;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    Self(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }
    binary!(F32x4, Add, add, _mm_add_ps);
    binary!(F32x4, Sub, sub, _mm_sub_ps);
    binary!(F32x4, Mul, mul, _mm_mul_ps);
    binary!(F32x4, Div, div, _mm_div_ps);
    binary!(F64x4, Add, add, _mm256_add_pd);
    binary!(F64x4, Sub, sub, _mm256_sub_pd);
    binary!(F64x4, Mul, mul, _mm256_mul_pd);
    binary!(F64x4, Div, div, _mm256_div_pd);

    impl Neg for F32x4 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            Self(unsafe { _mm_xor_ps(self.0, _mm_set1_ps(-0.0)) })
        }
    }
    impl Neg for F64x4 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            Self(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }

    impl Lanes4<f32> for F32x4 {
        type Mask = Mask4;
        #[inline(always)]
        fn splat(v: f32) -> Self {
            Self(unsafe { _mm_set1_ps(v) })
        }
        #[inline(always)]
        fn from_array(v: [f32; 4]) -> Self {
            Self(unsafe { core::mem::transmute::<[f32; 4], __m128>(v) })
        }
        #[inline(always)]
        fn to_array(self) -> [f32; 4] {
            unsafe { core::mem::transmute::<__m128, [f32; 4]>(self.0) }
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Self(unsafe { _mm_fmadd_ps(self.0, a.0, b.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Self(unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), self.0) })
        }
        #[inline(always)]
        fn lesser(self, o: Self) -> Self {
            // `minps a, b` is `a < b ? a : b`.
            Self(unsafe { _mm_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn greater(self, o: Self) -> Self {
            // `maxps a, b` is `a > b ? a : b`.
            Self(unsafe { _mm_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> Mask4 {
            Mask4(unsafe { _mm_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Mask4 {
            Mask4(unsafe { _mm_cmp_ps::<_CMP_GE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Mask4 {
            Mask4(unsafe { _mm_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
        }
    }

    impl Lanes4<f64> for F64x4 {
        type Mask = Mask4d;
        #[inline(always)]
        fn splat(v: f64) -> Self {
            Self(unsafe { _mm256_set1_pd(v) })
        }
        #[inline(always)]
        fn from_array(v: [f64; 4]) -> Self {
            Self(unsafe { core::mem::transmute::<[f64; 4], __m256d>(v) })
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            unsafe { core::mem::transmute::<__m256d, [f64; 4]>(self.0) }
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Self(unsafe { _mm256_fmadd_pd(self.0, a.0, b.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Self(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn lesser(self, o: Self) -> Self {
            Self(unsafe { _mm256_min_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn greater(self, o: Self) -> Self {
            Self(unsafe { _mm256_max_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> Mask4d {
            Mask4d(unsafe { _mm256_cmp_pd::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Mask4d {
            Mask4d(unsafe { _mm256_cmp_pd::<_CMP_GE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Mask4d {
            Mask4d(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) })
        }
    }
}

/// The lanes [`Real::Four`] uses for `f32`: one SSE register where the build has AVX2 and
/// FMA, four scalars otherwise.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub type F32Lanes4 = F32x4;
/// The lanes [`Real::Four`] uses for `f32`: one SSE register where the build has AVX2 and
/// FMA, four scalars otherwise.
#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
)))]
pub type F32Lanes4 = Portable4<f32>;

/// The lanes [`Real::Four`] uses for `f64`: one AVX register where the build has AVX2 and
/// FMA, four scalars otherwise.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub type F64Lanes4 = F64x4;
/// The lanes [`Real::Four`] uses for `f64`: one AVX register where the build has AVX2 and
/// FMA, four scalars otherwise.
#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
)))]
pub type F64Lanes4 = Portable4<f64>;

#[cfg(test)]
mod tests {
    //! The native lanes against the portable ones, operation by operation, on values that
    //! include NaN, infinities, signed zeros and subnormals.
    use super::*;

    fn specials<T: Real>() -> [T; 12] {
        [
            T::ZERO,
            -T::ZERO,
            T::ONE,
            -T::TWO,
            T::INFINITY,
            T::NEG_INFINITY,
            T::NAN,
            T::MIN_POSITIVE,
            T::MIN_POSITIVE * T::HALF,
            T::MAX,
            T::from_f64(0.1),
            T::from_f64(-3.75e7),
        ]
    }

    fn same<T: Real>(a: [T; 4], b: [T; 4]) -> bool {
        a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    fn agree<T: Real, L: Lanes4<T>>() {
        let s = specials::<T>();
        for i in 0..s.len() {
            for j in 0..s.len() {
                let a = [
                    s[i],
                    s[j],
                    s[(i + j) % s.len()],
                    s[(i + 2 * j + 1) % s.len()],
                ];
                let b = [
                    s[j],
                    s[i],
                    s[(3 * i + j + 2) % s.len()],
                    s[(i * j) % s.len()],
                ];
                let c = [s[(i + 5) % s.len()], s[j], s[i], s[(j + 7) % s.len()]];
                let (la, lb, lc) = (L::from_array(a), L::from_array(b), L::from_array(c));
                let (pa, pb, pc) = (
                    Portable4::from_array(a),
                    Portable4::from_array(b),
                    Portable4::from_array(c),
                );
                assert!(same((la + lb).to_array(), (pa + pb).to_array()));
                assert!(same((la - lb).to_array(), (pa - pb).to_array()));
                assert!(same((la * lb).to_array(), (pa * pb).to_array()));
                assert!(same((la / lb).to_array(), (pa / pb).to_array()));
                assert!(same((-la).to_array(), (-pa).to_array()));
                assert!(same(la.abs().to_array(), pa.abs().to_array()));
                assert_eq!(la.gt(lb).bits(), pa.gt(pb).bits());
                assert!(same(
                    la.mul_add(lb, lc).to_array(),
                    pa.mul_add(pb, pc).to_array()
                ));
                assert!(same(la.lesser(lb).to_array(), pa.lesser(pb).to_array()));
                assert!(same(la.greater(lb).to_array(), pa.greater(pb).to_array()));
                assert_eq!(la.le(lb).bits(), pa.le(pb).bits());
                assert_eq!(la.ge(lb).bits(), pa.ge(pb).bits());
                assert_eq!(
                    (la.le(lb) & !la.ge(lc)).bits(),
                    (pa.le(pb) & !pa.ge(pc)).bits()
                );
                assert_eq!(
                    (la.le(lb) | la.ge(lc)).bits(),
                    (pa.le(pb) | pa.ge(pc)).bits()
                );
                assert!(same(L::splat(s[i]).to_array(), [s[i]; 4]));
            }
        }
    }

    #[test]
    fn the_real_lanes_agree_with_the_portable_ones() {
        agree::<f32, <f32 as Real>::Four>();
        agree::<f64, <f64 as Real>::Four>();
    }
}

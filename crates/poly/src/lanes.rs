//! Eight values of one [`Real`] type side by side, for the batch solvers: one trait, a portable
//! implementation (eight scalars, each operation the [`Real`] one) and, where the build has
//! AVX2 and FMA, one over `__m256`. Every operation is exact or correctly rounded in both, so
//! a kernel written once over [`Lanes`] gives the same bits through either.

use crate::Real;
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Width of a batch.
pub const LANES: usize = 8;

/// A lane mask: bit `i` of [`LaneMask::bits`] is lane `i`.
pub trait LaneMask:
    Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    /// The lanes as bits.
    fn bits(self) -> u8;
}

/// Eight lanes of `T` with the operations the batch kernels need (IEEE semantics per lane).
pub trait Lanes<T: Real>:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The comparison result.
    type Mask: LaneMask;
    /// Every lane `v`.
    fn splat(v: T) -> Self;
    /// Lane `i` from `v[i]`.
    fn from_array(v: [T; LANES]) -> Self;
    /// Lane `i` into element `i`.
    fn to_array(self) -> [T; LANES];
    /// `self * a + b`, one rounding.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `|self|`
    fn abs(self) -> Self;
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `|self|` with the sign bit of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// `self < o`, false on NaN.
    fn lt(self, o: Self) -> Self::Mask;
    /// `self <= o`, false on NaN.
    fn le(self, o: Self) -> Self::Mask;
    /// `self > o`, false on NaN.
    fn gt(self, o: Self) -> Self::Mask;
    /// `self >= o`, false on NaN.
    fn ge(self, o: Self) -> Self::Mask;
    /// `self == o`, false on NaN.
    fn eq(self, o: Self) -> Self::Mask;
    /// `self != o`, true on NaN.
    fn ne(self, o: Self) -> Self::Mask;
    /// `a` where `m`, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;

    /// [`Real::max`] (the non-NaN operand when one is NaN; `self` for equal values, so signed
    /// zeros are not ordered: the kernels never compare `+0` with `-0`).
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self::select(self.ge(o) | o.ne(o), self, o)
    }

    /// [`Real::min`], with the same conventions as [`Lanes::max`].
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self::select(self.le(o) | o.ne(o), self, o)
    }
}

/// `N` scalars (eight by default): the reference implementation of [`Lanes`] (eight) and of
/// [`crate::Lanes4`] (four), and the ones used without AVX2.
#[cfg_attr(
    all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ),
    allow(
        dead_code,
        reason = "with AVX2 and FMA only the tests run the portable lanes"
    )
)]
#[derive(Clone, Copy, Debug)]
pub struct Portable<T, const N: usize = LANES>(pub(crate) [T; N]);

/// The mask of [`Portable`]: bit `i` lane `i`, no bit at or above `N`.
#[cfg_attr(
    all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ),
    allow(
        dead_code,
        reason = "with AVX2 and FMA only the tests run the portable lanes"
    )
)]
#[derive(Clone, Copy, Debug)]
pub struct PortableMask<const N: usize = LANES>(u8);

impl<const N: usize> BitAnd for PortableMask<N> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}
impl<const N: usize> BitOr for PortableMask<N> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}
impl<const N: usize> Not for PortableMask<N> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        // Only the `N` lanes' bits: a native mask has no others.
        Self(!self.0 & (u8::MAX >> (8 - N)))
    }
}
impl<const N: usize> LaneMask for PortableMask<N> {
    #[inline(always)]
    fn bits(self) -> u8 {
        self.0
    }
}

macro_rules! portable_binary {
    ($trait:ident, $f:ident, $op:tt) => {
        impl<T: Real, const N: usize> $trait for Portable<T, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(core::array::from_fn(|i| self.0[i] $op o.0[i]))
            }
        }
    };
}
portable_binary!(Add, add, +);
portable_binary!(Sub, sub, -);
portable_binary!(Mul, mul, *);
portable_binary!(Div, div, /);

impl<T: Real, const N: usize> Neg for Portable<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.0.map(|v| -v))
    }
}

#[cfg_attr(
    all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ),
    allow(
        dead_code,
        reason = "with AVX2 and FMA only the tests run the portable lanes"
    )
)]
impl<T: Real, const N: usize> Portable<T, N> {
    /// `f` of each lane pair as a mask.
    #[inline(always)]
    pub(crate) fn compare(self, o: Self, f: impl Fn(T, T) -> bool) -> PortableMask<N> {
        let mut bits = 0u8;
        for i in 0..N {
            bits |= u8::from(f(self.0[i], o.0[i])) << i;
        }
        PortableMask(bits)
    }

    /// `self * a + b` lane by lane, one rounding each.
    #[inline(always)]
    pub(crate) fn fused(self, a: Self, b: Self) -> Self {
        Self(core::array::from_fn(|i| self.0[i].mul_add(a.0[i], b.0[i])))
    }

    /// `|self|` lane by lane.
    #[inline(always)]
    pub(crate) fn magnitude(self) -> Self {
        Self(self.0.map(T::abs))
    }
}

impl<T: Real> Lanes<T> for Portable<T> {
    type Mask = PortableMask;
    #[inline(always)]
    fn splat(v: T) -> Self {
        Self([v; LANES])
    }
    #[inline(always)]
    fn from_array(v: [T; LANES]) -> Self {
        Self(v)
    }
    #[inline(always)]
    fn to_array(self) -> [T; LANES] {
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
    fn sqrt(self) -> Self {
        Self(self.0.map(T::sqrt))
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        Self(core::array::from_fn(|i| self.0[i].copysign(sign.0[i])))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a < b)
    }
    #[inline(always)]
    fn le(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a <= b)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a > b)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a >= b)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a == b)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> PortableMask {
        self.compare(o, |a, b| a != b)
    }
    #[inline(always)]
    fn select(m: PortableMask, a: Self, b: Self) -> Self {
        Self(core::array::from_fn(|i| {
            if m.0 >> i & 1 == 1 { a.0[i] } else { b.0[i] }
        }))
    }
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub use avx2::{F32x8, F64x8};

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
mod avx2 {
    //! `__m256` and `__m256d` lanes. SAFETY (every `unsafe` block below): the module is
    //! compiled only when the build enables `avx2` and `fma` (cfg above), so the intrinsics are
    //! available; the transmutes are between `[f32; 8]` and `__m256`, and between `[f64; 4]`
    //! and `__m256d`, which have the same size and no invalid bit patterns.
    use super::{LaneMask, Lanes};
    use core::arch::x86_64::*;
    use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

    /// Eight `f32` lanes in one AVX register.
    #[derive(Clone, Copy, Debug)]
    pub struct F32x8(__m256);

    /// All-ones or all-zeros per lane.
    #[derive(Clone, Copy, Debug)]
    pub struct Mask8(__m256);

    impl BitAnd for Mask8 {
        type Output = Self;
        #[inline(always)]
        fn bitand(self, o: Self) -> Self {
            Self(unsafe { _mm256_and_ps(self.0, o.0) })
        }
    }
    impl BitOr for Mask8 {
        type Output = Self;
        #[inline(always)]
        fn bitor(self, o: Self) -> Self {
            Self(unsafe { _mm256_or_ps(self.0, o.0) })
        }
    }
    impl Not for Mask8 {
        type Output = Self;
        #[inline(always)]
        fn not(self) -> Self {
            Self(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
        }
    }
    impl LaneMask for Mask8 {
        #[inline(always)]
        fn bits(self) -> u8 {
            (unsafe { _mm256_movemask_ps(self.0) }) as u8
        }
    }

    macro_rules! binary {
        ($trait:ident, $f:ident, $intrinsic:ident) => {
            impl $trait for F32x8 {
                type Output = Self;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    Self(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);
    binary!(Div, div, _mm256_div_ps);

    #[inline(always)]
    fn sign_bit() -> __m256 {
        unsafe { _mm256_set1_ps(-0.0) }
    }

    impl Neg for F32x8 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            Self(unsafe { _mm256_xor_ps(self.0, sign_bit()) })
        }
    }

    macro_rules! compare {
        ($f:ident, $predicate:ident) => {
            #[inline(always)]
            fn $f(self, o: Self) -> Mask8 {
                Mask8(unsafe { _mm256_cmp_ps::<$predicate>(self.0, o.0) })
            }
        };
    }

    impl Lanes<f32> for F32x8 {
        type Mask = Mask8;
        #[inline(always)]
        fn splat(v: f32) -> Self {
            Self(unsafe { _mm256_set1_ps(v) })
        }
        #[inline(always)]
        fn from_array(v: [f32; 8]) -> Self {
            Self(unsafe { core::mem::transmute::<[f32; 8], __m256>(v) })
        }
        #[inline(always)]
        fn to_array(self) -> [f32; 8] {
            unsafe { core::mem::transmute::<__m256, [f32; 8]>(self.0) }
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Self(unsafe { _mm256_fmadd_ps(self.0, a.0, b.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Self(unsafe { _mm256_andnot_ps(sign_bit(), self.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Self(unsafe { _mm256_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn copysign(self, sign: Self) -> Self {
            let s = sign_bit();
            Self(unsafe { _mm256_or_ps(_mm256_andnot_ps(s, self.0), _mm256_and_ps(s, sign.0)) })
        }
        compare!(lt, _CMP_LT_OQ);
        compare!(le, _CMP_LE_OQ);
        compare!(gt, _CMP_GT_OQ);
        compare!(ge, _CMP_GE_OQ);
        compare!(eq, _CMP_EQ_OQ);
        compare!(ne, _CMP_NEQ_UQ);
        #[inline(always)]
        fn select(m: Mask8, a: Self, b: Self) -> Self {
            Self(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
        }
    }

    /// Eight `f64` lanes in two AVX registers (lanes 0-3, then 4-7).
    #[derive(Clone, Copy, Debug)]
    pub struct F64x8(__m256d, __m256d);

    /// All-ones or all-zeros per lane, in the layout of [`F64x8`].
    #[derive(Clone, Copy, Debug)]
    pub struct Mask4x2(__m256d, __m256d);

    impl BitAnd for Mask4x2 {
        type Output = Self;
        #[inline(always)]
        fn bitand(self, o: Self) -> Self {
            unsafe { Self(_mm256_and_pd(self.0, o.0), _mm256_and_pd(self.1, o.1)) }
        }
    }
    impl BitOr for Mask4x2 {
        type Output = Self;
        #[inline(always)]
        fn bitor(self, o: Self) -> Self {
            unsafe { Self(_mm256_or_pd(self.0, o.0), _mm256_or_pd(self.1, o.1)) }
        }
    }
    impl Not for Mask4x2 {
        type Output = Self;
        #[inline(always)]
        fn not(self) -> Self {
            unsafe {
                let ones = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
                Self(_mm256_xor_pd(self.0, ones), _mm256_xor_pd(self.1, ones))
            }
        }
    }
    impl LaneMask for Mask4x2 {
        #[inline(always)]
        fn bits(self) -> u8 {
            let (low, high) = unsafe { (_mm256_movemask_pd(self.0), _mm256_movemask_pd(self.1)) };
            (low | high << 4) as u8
        }
    }

    macro_rules! binary_pd {
        ($trait:ident, $f:ident, $intrinsic:ident) => {
            impl $trait for F64x8 {
                type Output = Self;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    unsafe { Self($intrinsic(self.0, o.0), $intrinsic(self.1, o.1)) }
                }
            }
        };
    }
    binary_pd!(Add, add, _mm256_add_pd);
    binary_pd!(Sub, sub, _mm256_sub_pd);
    binary_pd!(Mul, mul, _mm256_mul_pd);
    binary_pd!(Div, div, _mm256_div_pd);

    #[inline(always)]
    fn sign_bit_pd() -> __m256d {
        unsafe { _mm256_set1_pd(-0.0) }
    }

    impl Neg for F64x8 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            let s = sign_bit_pd();
            unsafe { Self(_mm256_xor_pd(self.0, s), _mm256_xor_pd(self.1, s)) }
        }
    }

    macro_rules! compare_pd {
        ($f:ident, $predicate:ident) => {
            #[inline(always)]
            fn $f(self, o: Self) -> Mask4x2 {
                unsafe {
                    Mask4x2(
                        _mm256_cmp_pd::<$predicate>(self.0, o.0),
                        _mm256_cmp_pd::<$predicate>(self.1, o.1),
                    )
                }
            }
        };
    }

    impl Lanes<f64> for F64x8 {
        type Mask = Mask4x2;
        #[inline(always)]
        fn splat(v: f64) -> Self {
            unsafe { Self(_mm256_set1_pd(v), _mm256_set1_pd(v)) }
        }
        #[inline(always)]
        fn from_array(v: [f64; 8]) -> Self {
            let [a, b, c, d, e, f, g, h] = v;
            unsafe {
                Self(
                    core::mem::transmute::<[f64; 4], __m256d>([a, b, c, d]),
                    core::mem::transmute::<[f64; 4], __m256d>([e, f, g, h]),
                )
            }
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 8] {
            let (low, high) = unsafe {
                (
                    core::mem::transmute::<__m256d, [f64; 4]>(self.0),
                    core::mem::transmute::<__m256d, [f64; 4]>(self.1),
                )
            };
            [
                low[0], low[1], low[2], low[3], high[0], high[1], high[2], high[3],
            ]
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            unsafe {
                Self(
                    _mm256_fmadd_pd(self.0, a.0, b.0),
                    _mm256_fmadd_pd(self.1, a.1, b.1),
                )
            }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            let s = sign_bit_pd();
            unsafe { Self(_mm256_andnot_pd(s, self.0), _mm256_andnot_pd(s, self.1)) }
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            unsafe { Self(_mm256_sqrt_pd(self.0), _mm256_sqrt_pd(self.1)) }
        }
        #[inline(always)]
        fn copysign(self, sign: Self) -> Self {
            let s = sign_bit_pd();
            unsafe {
                Self(
                    _mm256_or_pd(_mm256_andnot_pd(s, self.0), _mm256_and_pd(s, sign.0)),
                    _mm256_or_pd(_mm256_andnot_pd(s, self.1), _mm256_and_pd(s, sign.1)),
                )
            }
        }
        compare_pd!(lt, _CMP_LT_OQ);
        compare_pd!(le, _CMP_LE_OQ);
        compare_pd!(gt, _CMP_GT_OQ);
        compare_pd!(ge, _CMP_GE_OQ);
        compare_pd!(eq, _CMP_EQ_OQ);
        compare_pd!(ne, _CMP_NEQ_UQ);
        #[inline(always)]
        fn select(m: Mask4x2, a: Self, b: Self) -> Self {
            unsafe {
                Self(
                    _mm256_blendv_pd(b.0, a.0, m.0),
                    _mm256_blendv_pd(b.1, a.1, m.1),
                )
            }
        }
    }
}

/// The lanes [`Real::Batch`] uses for `f64`: two AVX registers where the build has AVX2 and
/// FMA, eight scalars otherwise.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub type F64Lanes = F64x8;
/// The lanes [`Real::Batch`] uses for `f64`: two AVX registers where the build has AVX2 and
/// FMA, eight scalars otherwise.
#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
)))]
pub type F64Lanes = Portable<f64>;

/// The lanes [`Real::Batch`] uses for `f32`: one AVX register where the build has AVX2 and
/// FMA, eight scalars otherwise.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
pub type F32Lanes = F32x8;
/// The lanes [`Real::Batch`] uses for `f32`: one AVX register where the build has AVX2 and
/// FMA, eight scalars otherwise.
#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
)))]
pub type F32Lanes = Portable<f32>;

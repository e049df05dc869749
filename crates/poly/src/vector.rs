//! The vector operations the kernels above this crate need, on glam's types, written once for
//! both precisions; and the accurate difference of products they are built on.

use crate::Real;
use core::fmt::Debug;
use core::ops::{Add, Mul, Neg, Sub};

/// `a b - c d` with an error of at most about 1.5 ulps, even when the two products nearly
/// cancel (Kahan's algorithm: the rounding error of `c d`, recovered exactly by an FMA, is added
/// back). This is the error-free 2x2 determinant of the paper's Eq. 6 and of every cross
/// product here.
///
/// ```
/// use nlrt_poly::difference_of_products;
/// // (1 + 2^-30)^2 - (1 + 2^-29) = 2^-60 exactly; the naive formula gives 0 in f64.
/// let a = 1.0 + 2f64.powi(-30);
/// assert_eq!(a * a - (1.0 + 2f64.powi(-29)), 0.0);
/// assert_eq!(difference_of_products(a, a, 1.0 + 2f64.powi(-29), 1.0), 2f64.powi(-60));
/// ```
#[must_use]
#[inline(always)]
pub fn difference_of_products<T: Real>(a: T, b: T, c: T, d: T) -> T {
    let w = c * d;
    let error = (-c).mul_add(d, w); // w - c d, exact
    a.mul_add(b, -w) + error
}

/// A 3-vector of `T` (glam's `Vec3` for f32, `DVec3` for f64).
pub trait Vector3<T: Real>:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<T, Output = Self>
    + Neg<Output = Self>
    + Send
    + Sync
    + 'static
{
    /// From components.
    #[must_use]
    fn new(x: T, y: T, z: T) -> Self;
    /// x component.
    #[must_use]
    fn x(self) -> T;
    /// y component.
    #[must_use]
    fn y(self) -> T;
    /// z component.
    #[must_use]
    fn z(self) -> T;

    /// Component `i` (0, 1 or 2).
    #[must_use]
    #[inline(always)]
    fn get(self, i: usize) -> T {
        match i {
            0 => self.x(),
            1 => self.y(),
            _ => self.z(),
        }
    }

    /// Dot product with FMA.
    #[must_use]
    #[inline(always)]
    fn dot(self, o: Self) -> T {
        self.x()
            .mul_add(o.x(), self.y().mul_add(o.y(), self.z() * o.z()))
    }

    /// Cross product, each component an accurate difference of products.
    #[must_use]
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self::new(
            difference_of_products(self.y(), o.z(), self.z(), o.y()),
            difference_of_products(self.z(), o.x(), self.x(), o.z()),
            difference_of_products(self.x(), o.y(), self.y(), o.x()),
        )
    }

    /// Euclidean length.
    #[must_use]
    #[inline(always)]
    fn length(self) -> T {
        self.dot(self).sqrt()
    }

    /// The same vector in f64: exact, since f32 and f64 components widen without rounding.
    #[must_use]
    #[inline(always)]
    fn to_dvec3(self) -> glam::DVec3 {
        glam::DVec3::new(self.x().to_f64(), self.y().to_f64(), self.z().to_f64())
    }

    /// Index of the component with the largest magnitude.
    #[must_use]
    #[inline(always)]
    fn max_abs_axis(self) -> usize {
        let (ax, ay, az) = (self.x().abs(), self.y().abs(), self.z().abs());
        if ax >= ay && ax >= az {
            0
        } else if ay >= az {
            1
        } else {
            2
        }
    }
}

/// A 2-vector of `T` (glam's `Vec2` for f32, `DVec2` for f64).
pub trait Vector2<T: Real>:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<T, Output = Self>
    + Send
    + Sync
    + 'static
{
    /// From components.
    #[must_use]
    fn new(x: T, y: T) -> Self;
    /// x component (u).
    #[must_use]
    fn x(self) -> T;
    /// y component (v).
    #[must_use]
    fn y(self) -> T;

    /// The same vector in f64: exact, since f32 and f64 components widen without rounding.
    #[must_use]
    #[inline(always)]
    fn to_dvec2(self) -> glam::DVec2 {
        glam::DVec2::new(self.x().to_f64(), self.y().to_f64())
    }
}

macro_rules! impl_vectors {
    ($t:ty, $v2:ty, $v3:ty) => {
        impl Vector3<$t> for $v3 {
            #[inline(always)]
            fn new(x: $t, y: $t, z: $t) -> Self {
                <$v3>::new(x, y, z)
            }
            #[inline(always)]
            fn x(self) -> $t {
                self.x
            }
            #[inline(always)]
            fn y(self) -> $t {
                self.y
            }
            #[inline(always)]
            fn z(self) -> $t {
                self.z
            }
        }
        impl Vector2<$t> for $v2 {
            #[inline(always)]
            fn new(x: $t, y: $t) -> Self {
                <$v2>::new(x, y)
            }
            #[inline(always)]
            fn x(self) -> $t {
                self.x
            }
            #[inline(always)]
            fn y(self) -> $t {
                self.y
            }
        }
    };
}

impl_vectors!(f32, glam::Vec2, glam::Vec3);
impl_vectors!(f64, glam::DVec2, glam::DVec3);

#[cfg(test)]
mod tests {
    macro_rules! vector_tests {
        ($($t:ident: $v3:ty),*) => {$(
            mod $t {
                use crate::{Vector3, difference_of_products};
                type T = $t;
                type V = $v3;

                #[test]
                fn cross_is_orthogonal_and_accurate() {
                    let a = <V as Vector3<T>>::new(1.0, 2.0, 3.0);
                    let b = <V as Vector3<T>>::new(-2.0, 0.5, 4.0);
                    let c = a.cross(b);
                    assert_eq!(Vector3::dot(c, a), 0.0);
                    assert_eq!(Vector3::dot(c, b), 0.0);
                    assert_eq!(c, <V as Vector3<T>>::new(6.5, -10.0, 4.5));
                }

                #[test]
                fn difference_of_products_survives_cancellation() {
                    let e = T::EPSILON;
                    // (1 + e)(1 - e) - 1 = -e^2
                    assert_eq!(difference_of_products(1.0 + e, 1.0 - e, 1.0, 1.0), -(e * e));
                }

                #[test]
                fn max_abs_axis_picks_the_dominant_component() {
                    assert_eq!(<V as Vector3<T>>::new(0.1, -3.0, 2.0).max_abs_axis(), 1);
                    assert_eq!(<V as Vector3<T>>::new(-5.0, 3.0, 2.0).max_abs_axis(), 0);
                    assert_eq!(<V as Vector3<T>>::new(0.0, 0.0, 0.0).max_abs_axis(), 0);
                }

                /// Widening keeps every bit: a subnormal, a value that is not a short decimal,
                /// the largest finite value and a signed zero come back unchanged.
                #[test]
                fn widening_to_f64_is_exact() {
                    use crate::{Real, Vector2};
                    let tiny = T::MIN_POSITIVE / 3.0;
                    let v = <V as Vector3<T>>::new(tiny, 0.1, -T::MAX).to_dvec3();
                    assert_eq!([v.x, v.y, v.z], [tiny, 0.1, -T::MAX].map(|c: T| c.to_f64()));
                    assert_eq!(T::from_f64(v.x), tiny);
                    assert_eq!(T::from_f64(v.y), 0.1);
                    let w = <<T as Real>::Vec2 as Vector2<T>>::new(-0.0, 1.0 / 3.0).to_dvec2();
                    assert!(w.x == 0.0 && w.x.is_sign_negative());
                    assert_eq!(T::from_f64(w.y), 1.0 / 3.0);
                }
            }
        )*};
    }
    vector_tests!(f32: glam::Vec3, f64: glam::DVec3);
}
